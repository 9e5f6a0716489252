"""The application: a scene built into a simulation, run into a folder, swept, from the CLI.

``Simulation.from_scene(scene)`` is the single pipeline (scene -> mesh -> discretisation ->
Eq. 2 blocks -> contact points -> first-order model -> reduced model -> stepper);
``run_scene(scene, out)`` runs it into a results folder; ``run_sweep`` runs a grid of scenes.
"""

from importlib import import_module as _import

# imported on first use (PEP 562): `femrub --help` and `femrub scenes` stay fast
_LAZY = {
    "FINISHED": ".run",
    "folder_status": ".run",
    "run_scene": ".run",
    "Simulation": ".simulation",
    "build": ".simulation",
}

__all__ = ["FINISHED", "Simulation", "build", "folder_status", "run_scene"]


def __getattr__(name):
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(_import(_LAZY[name], __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
