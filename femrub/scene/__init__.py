"""Scene files: one simulation described in TOML (pure configuration).

``load_scene(path_or_builtin_name)`` -> :class:`Scene` (validated, defaults filled in, SI
units). Building and running a scene is :mod:`femrub.app`. ``docs/scenes.md`` lists every
key with its unit and default.
"""

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
    "SCHEMA",
    "Scene",
    "SceneError",
    "builtin_scenes",
    "builtin_text",
    "load_scene",
    "loads_scene",
    "parse_value",
    "resolve_key",
    "schema_rows",
]
