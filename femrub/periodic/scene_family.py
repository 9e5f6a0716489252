"""The models of a scene along one numeric key (``femrub periodic SCENE --param KEY=A:B``).

``loads.rotation_speed`` moves the scene's model to each speed with
:meth:`~femrub.model.first_order.FirstOrderModel.with_parameters` (its matrices shared; the
reduced model of the scene keeps its basis); any other numeric key builds the scene with
``--set KEY=value`` through one :class:`~femrub.app.simulation.SceneBuilds` (the mesh, the
blocks and the reductor kept between builds).
"""

from __future__ import annotations

import re

from ..scene import SceneError, parse_value, resolve_key

__all__ = ["parse_range", "scene_family"]

_RANGE = re.compile(r"^\s*([^:]+?)\s*:\s*([^:]+?)\s*$")
_NUMBER_UNIT = re.compile(r"^([-+]?[0-9.]+(?:[eE][-+]?[0-9]+)?)\s*(\S*)$")


def _si(scene, key: str, text: str) -> float:
    """``text`` (a number, optionally with a unit) as the scene reads it for ``key`` (SI)."""
    value = scene.with_changes({key: parse_value(text.strip())})
    for part in key.split("."):
        value = value[part]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SceneError(f"--param {key}: not a numeric key (value {value!r})")
    return float(value)


def parse_range(text: str, scene) -> tuple[str, float, float]:
    """``"KEY=A:B"`` -> ``(dotted key, A, B)`` in SI (units as in ``femrub sweep``: each end
    may carry one, or the last one applies to both, e.g. ``20000rpm:40000rpm``); the scene
    validates each end (key, unit, bounds) before any build."""
    if "=" not in text:
        raise SceneError(f"--param {text!r}: use KEY=START:STOP, e.g. rotation_speed=2000:3000rpm")
    key, spec = (s.strip() for s in text.split("=", 1))
    key = resolve_key(key)
    m = _RANGE.match(spec)
    if not m:
        raise SceneError(f"--param {text!r}: use KEY=START:STOP (two values)")
    a, b = m.groups()
    ua, ub = _NUMBER_UNIT.match(a), _NUMBER_UNIT.match(b)
    if ua and ub and ub.group(2) and not ua.group(2):
        a = f"{a} {ub.group(2)}"
    lo, hi = _si(scene, key, a), _si(scene, key, b)
    if lo == hi:
        raise SceneError(f"--param {text!r}: START and STOP are equal")
    return key, lo, hi


def scene_family(scene, key: str, *, log=None, cache=None):
    """``p -> model`` of ``scene`` along ``key`` (module docstring); ``p`` in SI; ``cache``:
    a :class:`~femrub.app.cache.ModelCache` of built models, or ``None``."""
    from ..app.simulation import SceneBuilds

    builds = SceneBuilds(cache)
    base = builds.build(scene, log=log).model
    if key == "loads.rotation_speed" and base.sweep is not None:
        return lambda p: base.with_parameters(rotation_speed=p)

    def model_at(p: float):
        return builds.build(scene.with_changes({key: float(p)}), log=log).model

    return model_at
