"""Key specifications of scene files: type, unit, default, allowed values, one-line errors.

A :class:`Spec` checks and normalises one value (:meth:`Spec.check`); a :class:`Variant`
is a table whose allowed keys depend on a selector key (``geometry.kind``, ``scheme.name``,
...). Every error is a :class:`SceneError` (a ``ValueError``) whose one-line message names
the key, the value given and what is allowed.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, field

from .units import SI_LABEL, to_si

__all__ = [
    "NONNEG",
    "POS",
    "REQUIRED",
    "SceneError",
    "Spec",
    "Variant",
    "fail",
    "float_spec",
    "unknown_key",
]

REQUIRED = object()
#: bounds of a positive and of a non-negative value (``Spec`` keywords)
POS = {"lo": 0.0, "lo_open": True}
NONNEG = {"lo": 0.0}


class SceneError(ValueError):
    """Invalid scene: the message is one line naming the key, the value and what is allowed.

    A :class:`ValueError`, raised before any expensive work by :func:`load_scene`,
    :func:`loads_scene`, :meth:`Scene.with_changes` and the build of a scene.
    """

    def __init__(self, message: str) -> None:
        super().__init__(" ".join(str(message).split()))


def fail(key: str, value, allowed: str):
    """Raise :class:`SceneError` ``"key = value: allowed"``."""
    raise SceneError(f"{key} = {_show(value)}: {allowed}")


def _show(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def unknown_key(key: str, allowed) -> SceneError:
    """Error for an unknown key, with a close match when there is one."""
    allowed = sorted(allowed)
    name = key.rsplit(".", 1)[-1]
    close = difflib.get_close_matches(name, allowed, n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    return SceneError(f"unknown key {key}{hint}; allowed here: {', '.join(allowed) or 'none'}")


@dataclass(frozen=True)
class Spec:
    """One scene key.

    Parameters
    ----------
    kind : ``"float"``, ``"int"``, ``"bool"``, ``"str"``, ``"choice"``, ``"vec3"``,
        ``"pair"`` (two floats), ``"ints"`` (list of int), ``"floats"`` (a non-empty list
        of numbers, each within the bounds), ``"strs"`` (list of str), ``"tables"`` (an
        array of tables, each checked against ``items``).
    default : value used when the key is absent (``REQUIRED``: must be given; ``None``:
        left to the builder).
    dim : unit dimension of a float (:mod:`femrub.scene.units`).
    lo, hi : bounds of a number; ``lo_open`` / ``hi_open`` exclude them.
    choices : allowed strings of a ``choice``, or words accepted besides a number
        (``reach = "auto"``) or a list (``signals = "all"``).
    doc : one-line description (docs/scenes.md).
    items : the keys of each table of a ``"tables"`` key (name -> :class:`Spec`).
    """

    kind: str
    default: object = None
    dim: str = "none"
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    choices: tuple = ()
    doc: str = ""
    items: dict | None = None

    @property
    def unit(self) -> str:
        return (
            SI_LABEL.get(self.dim, "-") if self.kind in ("float", "pair", "vec3", "floats") else "-"
        )

    def _bounds(self, key, value, x):
        if not math.isfinite(x):
            fail(key, value, f"must be a finite number{self._range()}")
        if self.lo is not None and (x < self.lo or (self.lo_open and x == self.lo)):
            fail(key, value, f"must be{self._range()}")
        if self.hi is not None and (x > self.hi or (self.hi_open and x == self.hi)):
            fail(key, value, f"must be{self._range()}")

    def _range(self) -> str:
        parts = []
        if self.lo is not None:
            parts.append(f"{'>' if self.lo_open else '>='} {self.lo:g}")
        if self.hi is not None:
            parts.append(f"{'<' if self.hi_open else '<='} {self.hi:g}")
        unit = f" {self.unit}" if self.unit != "-" else ""
        return (
            (" " + " and ".join(parts) + unit) if parts else (f" (in {unit.strip()})" * bool(unit))
        )

    def _number(self, key, value) -> float:
        try:
            x = to_si(value, self.dim)
        except ValueError as exc:
            fail(key, value, f"{exc}{self._words(', or one of ')}")
        self._bounds(key, value, x)
        return x

    def check(self, key: str, value):
        """Normalised value of ``key`` (SI floats, lists), or raise :class:`SceneError`."""
        if self.choices and self.kind not in ("choice", "str") and isinstance(value, str):
            if value in self.choices:
                return value
            if self.kind != "float":
                other = "an integer" if self.kind == "int" else "a list"
                fail(key, value, f"use one of {', '.join(map(repr, self.choices))} or {other}")
        check = getattr(self, f"_check_{self.kind}", None)
        if check is None:  # pragma: no cover
            raise AssertionError(self.kind)
        return check(key, value)

    def _words(self, prefix: str) -> str:
        """``prefix`` and the words accepted besides the value, or nothing."""
        return f"{prefix}{', '.join(map(repr, self.choices))}" if self.choices else ""

    def _check_float(self, key, value) -> float:
        return self._number(key, value)

    def _check_int(self, key, value) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            fail(key, value, f"must be an integer{self._range()}{self._words(', or ')}")
        self._bounds(key, value, value)
        return int(value)

    def _check_bool(self, key, value) -> bool:
        if not isinstance(value, bool):
            fail(key, value, "must be true or false")
        return value

    def _check_str(self, key, value) -> str:
        if not isinstance(value, str):
            fail(key, value, "must be a string")
        return value

    def _check_choice(self, key, value) -> str:
        if value not in self.choices:
            fail(key, value, f"use one of {', '.join(map(repr, self.choices))}")
        return value

    def _numbers(self, key, value, n: int) -> list:
        if not isinstance(value, list) or len(value) != n:
            fail(key, value, f"must be a list of {n} numbers{self._words(' or one of ')}")
        return [self._number(f"{key}[{i}]", v) for i, v in enumerate(value)]

    def _check_vec3(self, key, value) -> list:
        return self._numbers(key, value, 3)

    def _check_pair(self, key, value) -> list:
        return self._numbers(key, value, 2)

    def _check_ints(self, key, value) -> list:
        ok = isinstance(value, list) and value
        if not ok or any(isinstance(v, bool) or not isinstance(v, int) for v in value):
            fail(key, value, "must be a non-empty list of integers")
        return [int(v) for v in value]

    def _check_floats(self, key, value) -> list:
        """Each number checked as a float key ``key[i]`` of the same unit and bounds; an error
        also says what the list means (``doc``)."""
        if not isinstance(value, list) or not value:
            fail(key, value, f"must be a non-empty list of numbers{self._range()}: {self.doc}")
        try:
            return [self._number(f"{key}[{i}]", v) for i, v in enumerate(value)]
        except SceneError as exc:
            raise SceneError(f"{exc} ({key}: {self.doc})") from None

    def _check_tables(self, key, value) -> list:
        """Each table's keys checked (unknown, required, defaults); absent keys left out."""
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            fail(key, value, "must be an array of tables, e.g. [{ name = ... }, ...]")
        return [self._table(f"{key}[{i}]", table) for i, table in enumerate(value)]

    def _table(self, key: str, table: dict) -> dict:
        for k in table:
            if k not in self.items:
                raise unknown_key(f"{key}.{k}", self.items)
        out = {}
        for k, spec in self.items.items():
            if k in table:
                out[k] = spec.check(f"{key}.{k}", table[k])
            elif spec.default is REQUIRED:
                raise SceneError(f"{key}.{k} is required: {spec.doc}")
            elif spec.default is not None:
                out[k] = spec.default
        return out

    def _check_strs(self, key, value) -> list:
        if not isinstance(value, list) or not value or not all(isinstance(v, str) for v in value):
            fail(key, value, f"must be a non-empty list of strings{self._words(' or one of ')}")
        return list(value)


@dataclass(frozen=True)
class Variant:
    """A table whose keys depend on the value of ``selector`` (e.g. ``geometry.kind``)."""

    selector: str
    variants: dict
    default: str
    common: dict = field(default_factory=dict)
    doc: str = ""

    def keys_for(self, choice: str) -> dict:
        return {**self.common, **self.variants[choice]}


def float_spec(default, dim, doc, **kw) -> Spec:
    """A float key of dimension ``dim`` (``Spec("float", default, dim, doc=doc, **kw)``)."""
    return Spec("float", default, dim, doc=doc, **kw)
