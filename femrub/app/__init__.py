"""The application: a scene built into a simulation, run into a folder, swept, from the CLI.

``Simulation.from_scene(scene)`` is the single pipeline (scene -> mesh -> discretisation ->
Eq. 2 blocks -> contact points -> first-order model -> reduced model -> stepper);
``run_scene(scene, out)`` runs it into a results folder; ``run_sweep`` runs a grid of scenes.
"""

from .run import FINISHED, folder_status, run_scene
from .simulation import Simulation, build

__all__ = ["FINISHED", "Simulation", "build", "folder_status", "run_scene"]
