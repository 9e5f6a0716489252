"""Orders of convergence, measured: slopes of the error against the step or mesh size.

Measured slopes when written (docs/testing.md): θ-method on the smooth forced bar 1.99 (tip
displacement) and 1.6 (temperature); Carpenter 1.9; θ-method with contact 1.23 (least-squares
slope over eight steps); P2 blade frequencies 3.1 and 3.2 (modes 1, 2). The asserted
bounds keep a margin below the theoretical orders (2, 2, 1, 4 on a singularity-free clamp).
"""

from dataclasses import replace

import numpy as np
import pytest
import skfem as fem
from scipy.optimize import brentq

import femrub as fr
from femrub.fem.discretisation import assemble, discretise
from femrub.fem.eigen import angular_frequencies
from femrub.geometry.blade_mesh import BladeMesh

OMEGA = fr.PAPER.force_frequency


def _smooth_start(model):
    """The paper's tip force with sin³ instead of sin: its first two derivatives vanish at
    t = 0, so the unresolved high bar modes are not kicked by the start of the load."""
    return model.with_(loads=[replace(model.loads[0], signal=lambda t: np.sin(OMEGA * t) ** 3)])


def _run(model, scheme, h, t_end):
    res = fr.make_stepper(scheme, model, h).run(t_end, energy=False)
    temp = res.signal("tip_temperature") if "tip_temperature" in res.signals else None
    return res.t, res.signal("tip_displacement"), temp


def _slope(hs, errs):
    return float(np.polyfit(np.log(hs), np.log(errs), 1)[0])


@pytest.fixture(scope="module")
def smooth_reference():
    model = _smooth_start(fr.bar_model(gap=1.0, alpha=0.0, strain_heating=True))
    return model, _run(model, "theta", 6.25e-7, 0.01)


def test_theta_method_is_second_order_without_contact(smooth_reference):
    model, (tr, ur, Tr) = smooth_reference
    assert model.layout.n_t > 0 and np.abs(Tr).max() > 0  # coupled, strain heating on
    hs = np.array([4e-5, 2e-5, 1e-5, 5e-6])
    eu, et = [], []
    for h in hs:
        _, u, T = _run(model, "theta", h, 0.01)
        s = int(round(h / 6.25e-7))
        eu.append(np.abs(u - ur[::s]).max())
        et.append(np.abs(T - Tr[::s]).max())
    assert _slope(hs, eu) > 1.85
    assert _slope(hs, et) > 1.3


def test_carpenter_is_second_order_without_contact():
    model = _smooth_start(fr.bar_model(gap=1.0, alpha=0.0, coupling="none"))
    tr, ur, _ = _run(model, "theta", 6.25e-7, 0.01)
    hs = np.array([2e-5, 1e-5, 5e-6, 2.5e-6])
    errs = []
    for h in hs:
        _, u, _ = _run(model, "carpenter", h, 0.01)
        errs.append(np.abs(u - ur[:: int(round(h / 6.25e-7))]).max())
    assert _slope(hs, errs) > 1.75


def test_theta_method_with_contact_is_at_least_first_order():
    model = fr.bar_model(alpha=3.0)  # the paper case: one contact phase within 20 ms
    tr, ur, _ = _run(model, "theta", 2.5e-7, 0.02)
    hs = np.geomspace(4e-5, 2.5e-6, 8)  # steps not multiples of each other: impacts fall
    errs = []  # anywhere within a step, so the fit averages over their positions
    for h in hs:
        t, u, _ = _run(model, "theta", h, 0.02)
        errs.append(np.sqrt(np.mean((u - np.interp(t, tr, ur)) ** 2)))
    assert _slope(hs, errs) > 1.0


def _tensor_blade(n, span=0.06, chord=0.02, thickness=0.01):
    mesh = fem.MeshTet.init_tensor(
        np.linspace(0, chord, 2 * n + 1),
        np.linspace(-thickness / 2, thickness / 2, n + 1),
        np.linspace(0, span, 3 * n + 1),
    )
    z = mesh.p[2]
    root, tip = np.flatnonzero(np.isclose(z, 0.0)), np.flatnonzero(np.isclose(z, span))
    return BladeMesh(
        mesh=mesh,
        node_sets={"root": root, "tip": tip, "contact": tip[:1]},
        contact_points=mesh.p[:, tip[:1]],
        radial_axis="x",
        source=f"structured box, n = {n}",
    )


def test_p2_blade_frequencies_converge_at_high_order():
    # ν = 0: the clamped root face then has no corner singularity, so the P2 eigenvalues
    # converge at their smooth-solution order h⁴ (with ν > 0 the clamp's corners cap it near 2)
    mat = fr.Material(young=110e9, rho=4500.0, poisson=0.0)
    ns = (1, 2, 3)
    w = {}
    for lumping in ("consistent", "auto"):
        rows = []
        for n in ns:
            m = assemble(discretise(_tensor_blade(n)), mat, coupling="none", lumping=lumping)
            rows.append(angular_frequencies(m.K, m.M, 2))
        w[lumping] = np.array(rows)
    wc = w["consistent"]
    assert np.all(np.diff(wc, axis=0) < 0)  # consistent mass: from above, monotonically
    h = 1.0 / np.array(ns)
    for k in range(2):
        ratio = (wc[0, k] - wc[1, k]) / (wc[1, k] - wc[2, k])

        def mismatch(p, r=ratio):
            return (h[0] ** p - h[1] ** p) / (h[1] ** p - h[2] ** p) - r

        p = brentq(mismatch, 0.1, 10)
        assert p > 2.5, f"mode {k + 1}: order {p:.2f}"
        # Richardson limit; HRZ (the default lumping) converges to it too
        limit = wc[2, k] - (wc[1, k] - wc[2, k]) / ((h[1] / h[2]) ** p - 1)
        assert abs(w["auto"][2, k] / limit - 1) < 3 * abs(w["auto"][1, k] / limit - 1) + 1e-3
        assert abs(w["auto"][2, k] / limit - 1) < 5e-3
