"""Scene files: one simulation described in TOML, validated, built and run.

``load_scene(path_or_builtin_name)`` -> :class:`Scene`; ``build(scene)`` -> :class:`Built`
(model, stepper, report of what was built and why); ``run_scene(scene, out)`` runs it into
a results folder. ``docs/scenes.md`` lists every key with its unit and default.
"""

from .build import Built, build
from .reduce import natural_frequencies
from .run import FINISHED, folder_status, run_scene
from .scene import (
    Scene,
    builtin_scenes,
    builtin_text,
    load_scene,
    loads_scene,
    parse_value,
    resolve_key,
)
from .schema import SCHEMA, schema_rows
from .spec import SceneError

__all__ = [
    "FINISHED",
    "SCHEMA",
    "Built",
    "Scene",
    "SceneError",
    "build",
    "builtin_scenes",
    "builtin_text",
    "folder_status",
    "load_scene",
    "loads_scene",
    "natural_frequencies",
    "parse_value",
    "resolve_key",
    "run_scene",
    "schema_rows",
]
