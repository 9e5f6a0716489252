"""Built models as data: a JSON tree and named arrays, never code (the cache's format).

:func:`encode` turns an object made of ``None``, booleans, integers, floats, complex numbers,
strings, lists, tuples, dictionaries, NumPy arrays and scalars (numeric dtypes only), SciPy
CSR/CSC/COO matrices and instances of femrub's model-building classes into a JSON tree
whose leaves name arrays, plus those arrays (stored in an ``.npz`` read with
``allow_pickle=False``). :func:`decode` rebuilds the object and refuses anything else: a
node of an unknown kind, an array of objects, a class outside :data:`CLASS_PACKAGES`, a
class with its own ``__new__``, an array name that is not in the file. An instance is
rebuilt as :mod:`pickle` rebuilds a plain object (``object.__new__`` and its attribute
dictionary) but no function, constructor or method named by the file is ever called. An
array the object holds in several places is stored once and decoded as one array, held in
those places again.

Node kinds (key ``"$"``): ``list``, ``tuple``, ``dict`` (keys and values, any encodable
keys), ``complex``, ``array`` and ``scalar`` (``ref``: the array's name), ``sparse``
(``format``, ``shape``, ``arrays``), ``object`` (``class``: ``module:QualName``,
``state``: attribute name to node). JSON strings, numbers, ``true``/``false``/``null``
stand for themselves.
"""

from __future__ import annotations

import importlib
import json

import numpy as np
import scipy.sparse as sp

__all__ = ["CLASS_PACKAGES", "decode", "encode"]

#: Packages whose classes an entry may hold (the model-building stages' objects).
CLASS_PACKAGES = ("femrub.fem", "femrub.model", "femrub.contact", "femrub.reduction")
_SPARSE = {"csr": ("data", "indices", "indptr"), "csc": ("data", "indices", "indptr")}
_SPARSE["coo"] = ("data", "row", "col")
_MAX_DEPTH = 200


def _allowed_module(name: str) -> bool:
    return any(name == p or name.startswith(p + ".") for p in CLASS_PACKAGES)


class _Encoder:
    def __init__(self):
        self.arrays: dict[str, np.ndarray] = {}
        self._names: dict[int, str] = {}  # id of each array stored (``arrays`` keeps it alive)

    def array(self, a: np.ndarray) -> str:
        """The name of ``a``, stored once however many times the object holds it (a
        Galerkin reductor's basis is its left basis and its map to the mesh too)."""
        name = self._names.get(id(a))
        if name is not None:
            return name
        if a.dtype.hasobject or a.dtype.kind not in "biufcSU":
            raise TypeError(f"array of dtype {a.dtype} cannot be stored as data")
        name = f"a{len(self.arrays)}"
        self.arrays[name] = a
        self._names[id(a)] = name
        return name

    def node(self, x, depth: int = 0):
        if depth > _MAX_DEPTH:
            raise TypeError("object nested too deeply to store")
        if x is None or isinstance(x, bool | str):
            return x
        if isinstance(x, np.generic):
            return {"$": "scalar", "ref": self.array(np.asarray(x))}
        if isinstance(x, int | float):
            return x
        if isinstance(x, complex):
            return {"$": "complex", "re": x.real, "im": x.imag}
        if isinstance(x, np.ndarray):
            return {"$": "array", "ref": self.array(x)}
        if sp.issparse(x):
            return self.sparse(x)
        return self.container(x, depth + 1)

    def sparse(self, x) -> dict:
        fmt = x.format if x.format in _SPARSE else "csr"
        m = x if x.format == fmt else x.asformat(fmt)
        refs = {name: self.array(np.asarray(getattr(m, name))) for name in _SPARSE[fmt]}
        kind = "array" if isinstance(x, sp.sparray) else "matrix"
        return {"$": "sparse", "format": fmt, "kind": kind, "shape": list(m.shape), "arrays": refs}

    def container(self, x, depth: int):
        if type(x) is list:
            return {"$": "list", "items": [self.node(v, depth) for v in x]}
        if type(x) is tuple:
            return {"$": "tuple", "items": [self.node(v, depth) for v in x]}
        if type(x) is dict:
            keys = [self.node(k, depth) for k in x]
            return {"$": "dict", "keys": keys, "values": [self.node(v, depth) for v in x.values()]}
        cls = type(x)
        if not _allowed_module(cls.__module__) or not hasattr(x, "__dict__"):
            raise TypeError(f"{cls.__module__}.{cls.__qualname__} cannot be stored as data")
        if cls.__new__ is not object.__new__:
            raise TypeError(f"{cls.__qualname__} has its own __new__; not stored")
        state = {k: self.node(v, depth) for k, v in vars(x).items()}
        return {"$": "object", "class": f"{cls.__module__}:{cls.__qualname__}", "state": state}


def encode(obj) -> tuple[bytes, dict[str, np.ndarray]]:
    """``(tree, arrays)``: the JSON tree (UTF-8) of ``obj`` and the arrays it names.

    Raises ``TypeError`` for anything that is not data (a function, an array of objects,
    a class outside :data:`CLASS_PACKAGES`).
    """
    enc = _Encoder()
    tree = enc.node(obj)
    return json.dumps(tree, separators=(",", ":")).encode(), enc.arrays


def _resolve(name) -> type:
    """The class ``module:QualName`` of an allowed package (its module imported by name)."""
    if not isinstance(name, str) or name.count(":") != 1:
        raise ValueError(f"bad class name {name!r}")
    module, qualname = name.split(":")
    if not _allowed_module(module):
        raise ValueError(f"class {name!r} is outside {', '.join(CLASS_PACKAGES)}")
    obj = importlib.import_module(module)
    for part in qualname.split("."):
        if part.startswith("__"):
            raise ValueError(f"bad class name {name!r}")
        obj = getattr(obj, part, None)
    if not isinstance(obj, type) or obj.__module__ != module:
        raise ValueError(f"{name!r} is not a class of {module}")
    if obj.__new__ is not object.__new__:
        raise ValueError(f"{name!r} has its own __new__")
    return obj


class _Decoder:
    def __init__(self, arrays):
        self.arrays = arrays

    def array(self, ref) -> np.ndarray:
        if not isinstance(ref, str) or ref not in self.arrays:
            raise ValueError(f"entry names a missing array {ref!r}")
        return self.arrays[ref]

    def node(self, x, depth: int = 0):
        if depth > _MAX_DEPTH:
            raise ValueError("entry nested too deeply")
        if x is None or isinstance(x, bool | int | float | str):
            return x
        if isinstance(x, list):
            raise ValueError("bare JSON list in an entry")
        if not isinstance(x, dict):
            raise ValueError(f"unknown node {type(x).__name__}")
        kind = x.get("$")
        method = getattr(self, f"_{kind}", None) if kind in _KINDS else None
        if method is None:
            raise ValueError(f"unknown node kind {kind!r}")
        return method(x, depth + 1)

    def _items(self, x, depth):
        items = x["items"]
        if not isinstance(items, list):
            raise ValueError("items must be a list")
        return [self.node(v, depth) for v in items]

    def _list(self, x, depth):
        return self._items(x, depth)

    def _tuple(self, x, depth):
        return tuple(self._items(x, depth))

    def _dict(self, x, depth):
        keys, values = x["keys"], x["values"]
        if not (isinstance(keys, list) and isinstance(values, list) and len(keys) == len(values)):
            raise ValueError("dict node needs keys and values of one length")
        return {self.node(k, depth): self.node(v, depth) for k, v in zip(keys, values)}

    def _complex(self, x, depth):
        return complex(float(x["re"]), float(x["im"]))

    def _array(self, x, depth):
        return self.array(x["ref"])

    def _scalar(self, x, depth):
        a = self.array(x["ref"])
        if a.ndim != 0:
            raise ValueError("scalar node names an array")
        return a[()]

    def _sparse(self, x, depth):
        fmt, shape, refs = x["format"], x["shape"], x["arrays"]
        if fmt not in _SPARSE or not isinstance(refs, dict):
            raise ValueError(f"bad sparse node {fmt!r}")
        if not (isinstance(shape, list) and len(shape) == 2):
            raise ValueError("bad sparse shape")
        shape = tuple(int(n) for n in shape)
        parts = [self.array(refs[name]) for name in _SPARSE[fmt]]
        if fmt == "coo":
            args = (parts[0], (parts[1], parts[2]))
        else:
            args = tuple(parts)
        make = getattr(sp, f"{fmt}_{'array' if x.get('kind') == 'array' else 'matrix'}")
        return make(args, shape=shape)

    def _object(self, x, depth):
        cls = _resolve(x["class"])
        state = x["state"]
        if not isinstance(state, dict):
            raise ValueError("object state must be a mapping")
        obj = object.__new__(cls)
        obj.__dict__.update({str(k): self.node(v, depth) for k, v in state.items()})
        return obj


_KINDS = ("list", "tuple", "dict", "complex", "array", "scalar", "sparse", "object")


def decode(tree: bytes, arrays) -> object:
    """The object of :func:`encode`'s ``tree`` and ``arrays``; ``ValueError`` when the tree
    is not one (an unknown node, class or array)."""
    try:
        parsed = json.loads(tree)
    except (ValueError, RecursionError) as exc:
        raise ValueError(f"entry tree is not JSON ({exc})") from None
    try:
        return _Decoder(arrays).node(parsed)
    except (KeyError, TypeError, AttributeError, RecursionError, ImportError) as exc:
        raise ValueError(f"malformed entry ({type(exc).__name__}: {exc})") from None
