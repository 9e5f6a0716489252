"""Compiled blocks of θ-method steps on contacts with a history (femrub.contact.rub_block).

The ``"power"`` heat fixed point on a thermoelastic model and the abradable coating's wear
map run inside the compiled blocks; the results, and the coating the run leaves (map,
history, worn volume, the start of the next sweep), must be those of the per-step path
(``block_steps = False``) to round-off, and the same code must run as Python under
``NUMBA_DISABLE_JIT=1``.
"""

import json
import math
import os
import pickle
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from femrub.contact.abradable import Abradable, CasingGrid
from femrub.contact.jit import compiled
from femrub.contact.wear_map import cut_sweeps, depth_under, positions

ROOT = Path(__file__).resolve().parents[1]

#: a coarse twisted blade, thermoelastic, power heat, a coating it cuts but never wears
#: through (cut depth ~190 µm of 400 µm), 300 steps
SCENE = {
    "geometry.h": 0.03,
    "geometry.n_sections": 2,
    "physics.thermal": "on",
    "contact.friction": 0.3,
    "scheme.t_end": 0.0006,
    "outputs.vtk_stride": 0,
    "contact.casing.depth": "200 um",
    "contact.casing.clearance": "5 um",
    "reduction.method": "craig-bampton",
    "reduction.n_uv": 12,
    "reduction.n_theta": 6,
    "contact.reach": "all",
    "contact.heat_law": "power",
    "contact.heat_partition": 0.5,
    "contact.abradable.thickness": "400 um",
    "contact.abradable.yield": 20.0,
}


def _close(a, b, rel):
    scale = max(float(np.abs(b).max()), 1e-300)
    np.testing.assert_allclose(a, b, rtol=0, atol=rel * scale)


@pytest.fixture(scope="module")
def blade(model_cache):
    from femrub.app import build
    from femrub.app.scheme import scheme_options
    from femrub.scene import load_scene

    scene = load_scene("twisted-naca", SCENE)
    sim = build(scene, log=lambda s: None, cache=model_cache)
    return sim.model, scene["scheme"], scheme_options(scene)


def _run(model, scheme, opts, blocks, **run):
    """A run (``run``: its options), the stepper, and a copy of the coating's state the run
    left."""
    from femrub.analysis import make_stepper

    st = make_stepper(scheme["name"], model, scheme["h"], **opts)
    st.block_steps = blocks
    res = st.run(scheme["t_end"], **run)
    w = st.model.contact.wear  # the run's own coating
    coat = None
    if w is not None:
        coat = {
            "depth": w.depth.copy(),
            "history": np.array(w.history),
            "max": w.max_depth,
            "volume": w.worn_volume,
            "last_t": w._last[0],
            "last_r": w._last[1].copy(),
            "incursion": w.incursion.copy(),
        }
    return res, st, coat


def _compare(model, scheme, opts, kind, **run):
    (a, sa, ca), (b, sb, cb) = (
        _run(model, scheme, opts, blocks, **run) for blocks in (True, False)
    )
    assert sa._block_kind == sb._block_kind == kind
    assert a.status == b.status == "ok", (a.message, b.message)
    assert int((a.contact_state > 0).any(axis=1).sum()) > 50  # rubs, several contacts
    _close(a.impulse, b.impulse, 1e-9)
    _close(a.friction_force, b.friction_force, 1e-9)
    _close(a.gap, b.gap, 1e-9)
    np.testing.assert_array_equal(a.contact_state, b.contact_state)
    for k in ("friction_heat", "heat_content"):
        _close(a.energy[k], b.energy[k], 1e-9)
    scale = np.abs(b.energy["kinetic"]).max() + np.abs(b.energy["elastic"]).max()
    np.testing.assert_allclose(
        a.energy["energy_error"], b.energy["energy_error"], atol=1e-9 * scale
    )
    _close(sa.X, sb.X, 1e-9)
    assert (sa.k, sa.t) == (sb.k, sb.t)
    # the stepper goes on from where the block left it, as after step() calls (each
    # stepper runs its own coating: both step from the state their runs left it in)
    _close(sa.step().X, sb.step().X, 1e-9)
    return a, sa, ca, cb


def test_power_heat_and_wear_blocks_equal_the_steps(blade):
    model, scheme, opts = blade
    a, sa, ca, cb = _compare(model, scheme, opts, "rub")
    assert a.energy["friction_heat"][-1] > 0  # the power heat enters the blade
    w = model.contact.wear
    cap = sa.h * w.yield_force
    assert int(np.sum(a.impulse >= (1 - 1e-9) * cap)) > 100  # the coating yields, often
    assert 0 < ca["max"] < w.thickness  # cut, never worn through
    # the coating's state, as the per-step path leaves it (summary.json and the wear map)
    assert len(ca["history"]) == len(cb["history"]) > 100
    np.testing.assert_array_equal(ca["history"][:, 0], cb["history"][:, 0])
    _close(ca["history"][:, 1], cb["history"][:, 1], 1e-9)
    _close(ca["depth"], cb["depth"], 1e-9)
    assert ca["max"] == pytest.approx(cb["max"], rel=1e-9)
    assert ca["volume"] == pytest.approx(cb["volume"], rel=1e-9)
    assert ca["last_t"] == cb["last_t"]
    _close(ca["last_r"], cb["last_r"], 1e-9)
    # each contact's incursion below the unworn surface: the surface is no deeper than what
    # the contacts reached, and the cutting contacts reached into the coating
    _close(ca["incursion"], cb["incursion"], 1e-9)
    assert ca["max"] <= ca["incursion"].max() * (1 + 1e-9)
    assert ca["incursion"].max() < w.thickness


def test_footprint_blocks_equal_the_steps(blade):
    """A coating read through a footprint 2.5 cells wide: the compiled blocks cut and read
    it as the per-step path does."""
    model, scheme, opts = blade
    w = model.contact.wear
    g = w.grid
    cell = 2 * math.pi * g.radius / g.n_angle
    grid = CasingGrid(
        g.angles, g.axial, g.radius, g.omega, g.n_angle, g.n_axial, footprint=2.5 * cell
    )
    c = replace(model.contact, wear=Abradable(w.thickness, w.yield_force, grid))
    a, sa, ca, cb = _compare(model.with_(contact=c), scheme, opts, "rub")
    assert sa._bgrid[4] == pytest.approx(2.5, rel=1e-12)
    assert len(ca["history"]) == len(cb["history"]) > 50
    _close(ca["depth"], cb["depth"], 1e-9)
    assert ca["volume"] == pytest.approx(cb["volume"], rel=1e-9)


def test_power_heat_without_a_coating(blade):
    model, scheme, opts = blade
    bare = model.with_(contact=replace(model.contact, wear=None))
    # without the coating the tips pass the default 1500 K stop limit before t_end: the
    # paths are compared over the whole run
    a, _, ca, _ = _compare(bare, scheme, opts, "rub", default_limits=False)
    assert ca is None and a.energy["friction_heat"][-1] > 0


def test_alpha_heat_with_a_coating(blade):
    """The ``"alpha"`` law (heat ``α P_n`` folded into the impulse columns) and a coating."""
    model, scheme, opts = blade
    c = replace(model.contact, heat_law="alpha", heat_coefficient=np.full(model.contact.n, 2.0))
    a, sa, ca, cb = _compare(model.with_(contact=c), scheme, opts, "rub")
    assert not sa._bpower and a.energy["friction_heat"][-1] > 0
    assert len(ca["history"]) == len(cb["history"]) > 100
    _close(ca["depth"], cb["depth"], 1e-9)


def test_casing_heat_and_alpha_of_time_keep_the_per_step_path(blade):
    from femrub.analysis import make_stepper
    from femrub.contact.casing_heat import CasingHeat
    from femrub.steppers.theta_blocks import block_kind

    model, scheme, opts = blade
    c = model.contact
    heat = CasingHeat(c.wear.grid, 2e-3, 100.0, 100.0, 0.5, 1e-4, 0.5, np.ones(c.n))
    for changes in (
        {"casing_heat": heat},
        {"heat_law": "alpha", "heat_coefficient": lambda t: np.ones(c.n)},
        {"friction": np.r_[0.0, np.full(c.n - 1, 0.3)]},
    ):
        st = make_stepper(
            scheme["name"], model.with_(contact=replace(c, **changes)), scheme["h"], **opts
        )
        assert block_kind(st) is None and st.block_writer() is None


def test_a_failed_solve_in_a_rub_block_keeps_the_coating_of_the_steps_before(blade, monkeypatch):
    """A contact solve failing inside a block ends the run ``unstable`` after the steps
    before it, and the coating holds their cuts only."""
    import femrub.steppers.theta_blocks as tb

    model, scheme, opts = blade
    ref, _, cref = _run(model, scheme, opts, False)
    real = tb.rub_block

    def block(*args):
        *head, out = args
        rows = tuple(a[:250] for a in out)  # the rows: stop after 250 steps
        done, status, res, warm = real(*head, rows)
        return done, 1, 0.5, warm  # NOT_SOLVED

    monkeypatch.setattr(tb, "rub_block", block)
    res, st, coat = _run(model, scheme, opts, True)
    assert res.status == "unstable" and "not solved" in res.message
    assert res.steps == st.k == 250
    n_cut = int(np.sum(cref["history"][:, 0] <= 250 * scheme["h"] * (1 + 1e-12)))
    assert 100 < len(coat["history"]) == n_cut < len(cref["history"])
    assert coat["last_t"] == pytest.approx(250 * scheme["h"], rel=1e-12)


def test_wear_kernels_equal_the_grid_and_a_vectorised_cut():
    """``depth_under`` is ``CasingGrid.interpolate`` (bitwise); ``cut_sweeps`` is the
    vectorised cut along the sweeps (coefficients ``⌊min x + 1/2⌋ − 1 .. ⌊max x + 1/2⌋ + 1``,
    each to the largest reach of the sweep over its support ``|x − k| <= 3/2``) and returns
    the deepest point of the surface over the pieces it changed."""
    rng = np.random.default_rng(3)
    grid = CasingGrid(rng.uniform(0, 6.3, 9), rng.uniform(0, 0.01, 9), 0.3, 500.0, 37, 4)
    w = Abradable(1e-3, 10.0, grid)
    flat = rng.uniform(0, 1e-3, 37 * 4)
    scale = grid.n_angle / (2 * math.pi)
    for t in (0.0, 1e-3, 0.0123, 7.5):
        x = positions(t, grid.angles, grid.omega, scale)
        np.testing.assert_array_equal(x, grid.position(t))
        d = depth_under(flat, x, grid.axial_cell, grid.n_angle, grid.n_axial, 0.0)
        np.testing.assert_array_equal(d, grid.interpolate(flat, t))
    x0, x1 = grid.position(0.001), grid.position(0.0013)
    x1[2] = x0[2]  # a contact that did not move
    r0, r1 = rng.uniform(0, 2e-3, 9), rng.uniform(0, 2e-3, 9)
    got = flat.copy()
    deepest = cut_sweeps(got, grid.axial_cell, x0, x1, r0, r1, w.thickness, 37, 4, 0.0)
    ref = flat.copy()
    lo, hi = np.minimum(x0, x1), np.maximum(x0, x1)
    for a in range(9):
        k = np.arange(np.floor(lo[a] + 0.5) - 1, np.floor(hi[a] + 0.5) + 2).astype(int)
        dx = x1[a] - x0[a]
        if dx == 0:
            top = np.full(k.size, r1[a])
        else:  # the reach is linear along the sweep: its largest value at an end
            ends = np.stack([np.maximum(lo[a], k - 1.5), np.minimum(hi[a], k + 1.5)])
            top = (r0[a] + np.clip((ends - x0[a]) / dx, 0, 1) * (r1[a] - r0[a])).max(axis=0)
        np.maximum.at(ref, np.mod(k, 37) * 4 + grid.axial_cell[a], np.minimum(w.thickness, top))
    np.testing.assert_array_equal(got, ref)
    changed = np.flatnonzero(got != flat)
    assert changed.size and np.all(got >= flat)
    # the surface over the changed pieces, densely sampled: the deepest is ``deepest``
    u = np.linspace(-0.5, 0.5, 2001)[:, None]
    bm, b0, bp = 0.5 * (0.5 - u) ** 2, 0.75 - u * u, 0.5 * (0.5 + u) ** 2
    top = -np.inf
    for flat_index in changed:
        j, a = divmod(int(flat_index), 4)
        for p in (j - 1, j, j + 1):
            cm, c0, cp = (got[np.mod(q, 37) * 4 + a] for q in (p - 1, p, p + 1))
            top = max(top, float(np.max(bm * cm + b0 * c0 + bp * cp)))
    assert deepest == pytest.approx(top, rel=1e-6)
    # the recorder's rows of gaps and rates on the worn surface: one broadcast, the same
    # values as one call per time
    from femrub.contact.gap import Contact

    w.reset(h=1e-4)
    w.depth.ravel()[:] = got
    c = Contact(
        G=np.ones((1, 9)),
        Gv=np.ones((1, 9)),
        Hm=np.ones((1, 9)),
        Ht=np.zeros((1, 9)),
        gap0=np.full(9, 1e-4),
        wear=w,
    )
    t = 0.0123 + 1e-4 * np.arange(50)
    np.testing.assert_array_equal(c.gap_at(t), np.array([c.gap_at(ti) for ti in t]))
    np.testing.assert_array_equal(c.rate_at(t), np.array([c.rate_at(ti) for ti in t]))


_CHILD = """
import json, pickle, sys
import numpy as np
from femrub.contact.jit import compiled
from femrub.analysis import make_stepper
d = pickle.load(open(sys.argv[1], "rb"))
st = make_stepper(d["scheme"]["name"], d["model"], d["scheme"]["h"], **d["opts"])
r = st.run(d["scheme"]["t_end"])
w = st.model.contact.wear
print(json.dumps({"jit": compiled(), "kind": st._block_kind, "P": r.impulse.tolist(),
                  "Pt": r.friction_force.tolist(), "depth": w.depth.tolist(),
                  "heat": r.energy["friction_heat"].tolist(), "history": w.history}))
"""


@pytest.mark.skipif(not compiled(), reason="kernels not compiled (NUMBA_DISABLE_JIT)")
def test_rub_blocks_run_as_python_without_jit(blade, tmp_path):
    model, scheme, opts = blade
    scheme = {**scheme, "t_end": 200 * scheme["h"]}  # 200 steps: cuts, as Python loops
    path = tmp_path / "model.pkl"
    path.write_bytes(pickle.dumps({"model": model, "scheme": scheme, "opts": opts}))
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    out = {}
    for jit in (False, True):
        if not jit:
            env["NUMBA_DISABLE_JIT"] = "1"
        else:
            env.pop("NUMBA_DISABLE_JIT")
        run = subprocess.run(
            [sys.executable, "-c", _CHILD, str(path)],
            env=env,
            cwd=ROOT,
            capture_output=True,
            text=True,
            check=True,
        )
        out[jit] = json.loads(run.stdout.splitlines()[-1])
    py, jt = out[False], out[True]
    assert not py["jit"] and jt["jit"] and py["kind"] == jt["kind"] == "rub"
    assert len(py["history"]) == len(jt["history"]) > 50
    for k in ("P", "Pt", "depth", "heat", "history"):
        _close(np.array(py[k]), np.array(jt[k]), 1e-9)
