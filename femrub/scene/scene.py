"""Scene objects: load (file, text or built-in name), change keys, dump back to TOML.

A :class:`Scene` holds the normalised data (:func:`~femrub.scene.validate.normalize`:
every section present, defaults filled in, SI floats) and the folder its relative paths
start from. ``load → dump → load`` gives an equal scene.
"""

from __future__ import annotations

import copy
import sys
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import tomli_w

from .schema import SCHEMA, TOP, schema_rows
from .spec import SceneError, Variant
from .validate import check_files, normalize, resolve_path

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = [
    "Scene",
    "builtin_scenes",
    "builtin_text",
    "load_scene",
    "loads_scene",
    "parse_value",
    "resolve_key",
]


@dataclass(eq=False)
class Scene:
    """A validated scene (see ``docs/scenes.md``); compare with ``==`` on the data.

    Made by :func:`load_scene` or :func:`loads_scene`, never by hand: every key checked
    against the schema (its reference lists each key's type, unit, default and bounds),
    defaults filled in, quantities converted to SI units (``"2000 rpm"`` → rad/s).

    Attributes
    ----------
    data : dict
        The normalised scene, sections as nested dicts (SI units); ``scene["loads.gap"]``
        reads a dotted key.
    source : str
        Where the scene came from (a file name or ``built-in scene NAME``).
    base_dir : pathlib.Path
        Where the scene's relative paths start.
    given : frozenset
        The dotted keys the file or a change set wrote (the others are defaults).
    """

    data: dict
    source: str = "<scene>"
    base_dir: Path = field(default_factory=Path.cwd)
    #: dotted ``section.key`` names the scene file or a change set (the others are defaults)
    given: frozenset = frozenset()

    def __eq__(self, other) -> bool:
        return isinstance(other, Scene) and self.data == other.data

    __hash__ = None

    @property
    def name(self) -> str:
        return self.data["name"]

    def __getitem__(self, dotted: str):
        node = self.data
        for part in dotted.split("."):
            node = node[part]
        return node

    def get(self, dotted: str, default=None):
        try:
            return self[dotted]
        except (KeyError, TypeError):
            return default

    def with_changes(self, changes: dict) -> Scene:
        """A new scene with dotted keys set (``{"loads.rotation_speed": 300.0}``), revalidated.

        Changing a selector (``contact.casing.kind``) drops the keys the new variant lacks.
        """
        data = copy.deepcopy(self.data)
        for key, value in changes.items():
            key = resolve_key(key)
            *path, last = key.split(".")
            node, spec = data, {**TOP, **SCHEMA}
            for part in path:
                spec = (spec if isinstance(spec, dict) else spec.keys_for(node["_"]))[part]
                node = node.setdefault(part, {})
                if isinstance(spec, Variant):
                    node["_"] = node.get(spec.selector, spec.default)
            node[last] = value
            if isinstance(spec, Variant) and last == spec.selector and value in spec.variants:
                allowed = {spec.selector, *spec.keys_for(value)}
                for k in [k for k in node if k not in allowed and k != "_"]:
                    del node[k]
        _strip_marks(data)
        given = self.given | {resolve_key(k) for k in changes}
        return Scene(normalize(data), self.source, self.base_dir, given)

    def dumps(self) -> str:
        """TOML text of the normalised scene (SI units, every default written)."""
        return tomli_w.dumps(_without_none(self.data))

    def path(self, text: str) -> Path:
        """Resolve a path of the scene (``{shared}/...`` or relative to the scene file)."""
        return resolve_path(text, self.base_dir)

    def check_files(self) -> None:
        """Raise :class:`SceneError` when a referenced mesh or section file is missing."""
        check_files(self.data, self.base_dir)


def _strip_marks(node) -> None:
    if isinstance(node, dict):
        node.pop("_", None)
        for v in node.values():
            _strip_marks(v)


def _without_none(node):
    if isinstance(node, dict):
        return {k: _without_none(v) for k, v in node.items() if v is not None}
    return node


def loads_scene(text: str, source: str = "<string>", base_dir=None) -> Scene:
    """Parse and validate TOML text; relative paths start at ``base_dir`` (default cwd).

    Parameters
    ----------
    text : str
        The scene as TOML.
    source : str
        Its name in error messages.
    base_dir : str or pathlib.Path, optional
        Where relative paths start (default: the working directory).

    Returns
    -------
    Scene
        Validated, defaults filled in, SI units.

    Raises
    ------
    SceneError
        Invalid TOML or an invalid key or value.
    """
    try:
        doc = tomllib.loads(text)
        data = normalize(doc)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{source}: not valid TOML: {exc}") from None
    except RecursionError:
        raise SceneError(
            f"{source}: tables nested too deeply (a scene needs at most 3 levels)"
        ) from None
    given = frozenset(
        f"{sec}.{key}" for sec, tbl in doc.items() if isinstance(tbl, dict) for key in tbl
    )
    return Scene(data, source, Path(base_dir) if base_dir else Path.cwd(), given)


def _builtin_dir():
    return resources.files("femrub.scene") / "builtin"


def builtin_scenes() -> dict[str, str]:
    """Built-in scene names and their one-line descriptions.

    Returns
    -------
    dict of str to str
        ``{name: description}``, sorted by name (``femrub scenes`` prints it); each name
        loads with :func:`load_scene`.
    """
    out = {}
    for entry in sorted(_builtin_dir().iterdir(), key=lambda p: p.name):
        if entry.name.endswith(".toml"):
            doc = tomllib.loads(entry.read_text(encoding="utf-8"))
            out[entry.name[:-5]] = doc.get("description", "")
    return out


def builtin_text(name: str) -> str:
    """The TOML text of a built-in scene (with its comments)."""
    names = builtin_scenes()
    if name not in names:
        raise SceneError(f"no built-in scene {name!r}; built-ins: {', '.join(names)}")
    return (_builtin_dir() / f"{name}.toml").read_text(encoding="utf-8")


def load_scene(ref, changes: dict | None = None) -> Scene:
    """Load a scene file, or a built-in scene by name, and apply dotted ``changes``.

    Parameters
    ----------
    ref : str or pathlib.Path
        A TOML scene file, or the name of a built-in scene (:func:`builtin_scenes`).
    changes : dict, optional
        Dotted keys to set, e.g. ``{"loads.rotation_speed": "1200 rpm"}`` (units as in a
        scene file; SI when a bare number).

    Returns
    -------
    Scene
        Validated, defaults filled in, SI units.

    Raises
    ------
    SceneError
        One line naming the key, the value and the fix.
    """
    path = Path(ref)
    if path.is_file():
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise SceneError(f"cannot read scene file {str(path)!r}: {exc}") from None
        scene = loads_scene(text, str(path), path.resolve().parent)
    elif str(ref) in builtin_scenes():
        scene = loads_scene(builtin_text(str(ref)), f"built-in scene {ref}", Path.cwd())
    else:
        raise SceneError(
            f"scene {str(ref)!r}: no such file and no built-in scene of that name "
            f"(built-ins: {', '.join(builtin_scenes())}; `femrub scenes` lists them)"
        )
    return scene.with_changes(changes) if changes else scene


_KEYS = None


def resolve_key(key: str) -> str:
    """Full dotted key of ``key``, which may be a unique suffix (``rotation_speed``)."""
    global _KEYS
    if _KEYS is None:
        _KEYS = sorted({k for k, _, _ in schema_rows() if "[]" not in k})  # not in a table array
    if key in _KEYS:
        return key
    matches = [k for k in _KEYS if k.endswith("." + key)]
    if len(matches) == 1:
        return matches[0]
    if not matches:
        raise SceneError(f"unknown key {key!r}; give a dotted key such as loads.rotation_speed")
    raise SceneError(f"key {key!r} is ambiguous: {', '.join(matches)}")


def parse_value(text: str):
    """A command-line value: a TOML value (``1e-5``, ``true``, ``[1, 2]``) or a bare string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text
    except RecursionError:
        raise SceneError(f"value {text[:40]!r}...: nested too deeply") from None
