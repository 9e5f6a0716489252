"""Dimensional scene values outside physical bounds are refused, naming the key and the range."""

import copy

import pytest

from femrub.scene import SceneError
from femrub.scene.bounds import PHYSICAL_BOUNDS
from femrub.scene.schema import schema_rows
from femrub.scene.validate import normalize

BASE = {"geometry": {"kind": "bar"}, "scheme": {"h": 1e-5, "t_end": 1e-4}}


def _doc(key, value):
    doc = copy.deepcopy(BASE)
    *path, last = key.split(".")
    node = doc
    for p in path:
        node = node.setdefault(p, {})
    node[last] = value
    return doc


@pytest.mark.parametrize(
    "key,value,words",
    [
        ("geometry.length", 1e-200, "geometry.length = 1e-200: outside the physical range 1e-09"),
        ("geometry.length", 3.9e-254, "geometry.length"),
        ("geometry.area", 1e300, "geometry.area"),
        ("material.young", 1e-300, "material.young = 1e-300: outside the physical range 1000"),
        ("material.density", 1e30, "material.density"),
        ("material.conductivity", 1e300, "material.conductivity"),
        ("material.reference_temperature", 1e-200, "material.reference_temperature"),
        ("loads.rotation_speed", 1e300, "loads.rotation_speed"),
        ("contact.casing.clearance", 1e4, "clearance = 10000.0: outside the physical range at"),
        ("loads.tip_force", {"law": "constant", "amplitude": 1e300}, "loads.tip_force.amplitude"),
        ("scheme.h", 1e-300, "scheme.h"),
    ],
)
def test_out_of_bounds_values_name_the_key_and_the_bound(key, value, words):
    with pytest.raises(SceneError, match=words.replace("(", r"\(").replace(".", r"\.")) as exc:
        normalize(_doc(key, value))
    assert "\n" not in str(exc.value) and "check the unit" in str(exc.value)


def test_zero_and_ordinary_values_pass():
    for key, value in [
        ("contact.casing.clearance", 0.0),
        ("contact.casing.clearance", 1e-30),  # may be zero: a tiny value is a zero
        ("geometry.length", "30 cm"),
        ("material.young", "110 GPa"),
        ("loads.rotation_speed", "2000 rpm"),
    ]:
        normalize(_doc(key, value))


def test_every_default_is_inside_its_bounds():
    for key, spec, _ in schema_rows():
        bounds = PHYSICAL_BOUNDS.get(getattr(spec, "dim", None))
        default = getattr(spec, "default", None)
        if bounds is None or not isinstance(default, int | float) or isinstance(default, bool):
            continue
        assert default == 0 or bounds[0] <= abs(default) <= bounds[1], key
