"""The application: a scene built into a simulation, run into a folder, swept, from the CLI.

``Simulation.from_scene(scene)`` is the single pipeline (scene -> mesh -> discretisation ->
Eq. 2 blocks -> contact points -> first-order model -> reduced model -> stepper);
``run_scene(scene, out)`` runs it into a results folder; ``run_sweep`` runs a grid of scenes.
"""

from .._lazy import lazy_attributes

# imported on first use (PEP 562): `femrub --help` and `femrub scenes` stay fast
_LAZY = {
    "FINISHED": ".run",
    "folder_status": ".run",
    "run_scene": ".run",
    "Simulation": ".simulation",
    "build": ".simulation",
}

__all__ = ["FINISHED", "Simulation", "build", "folder_status", "run_scene"]


__getattr__, __dir__ = lazy_attributes(__name__, _LAZY, __all__)
