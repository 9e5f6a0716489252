"""Abradable coating: a bar cutting the coating against the hand-derived removal depth."""

import json
import math

import numpy as np
import pytest

from femrub.app.run import run_scene
from femrub.contact.abradable import Abradable, CasingGrid
from femrub.contact.activation import RULES, impulse_one, impulses
from femrub.contact.friction import SLIP, solve_frictional_contact
from femrub.contact.gap import Contact
from femrub.contact.impulses import solve_impulses
from femrub.scene import SceneError, load_scene

E, A, L = 110e9, 1e-6, 0.30
K_TIP = E * A / L  # static tip stiffness of the clamped bar (N/m)
F, F_Y, D = 7.0, 2.0, 5e-6  # tip force, coating yield force (N), cold gap (m)

SCENE = """
name = "bar-abradable"
[geometry]
kind = "bar"
n_elements = 10
[contact]
casing = {{ kind = "concentric", clearance = "5 um" }}
abradable = {{ thickness = {e}, yield = 2.0, n_angle = 1, n_axial = 1 }}
[loads]
tip_force = {{ law = "ramp", amplitude = 7.0, ramp_time = 0.1 }}
[physics]
damping_ratio = 0.05
damping_modes = [1, 2]
[scheme]
name = "theta"
h = 2e-5
t_end = 0.15
[outputs]
plots = false
"""


def _run(tmp_path, e):
    path = tmp_path / f"bar-{e:g}.toml"
    path.write_text(SCENE.format(e=e))
    out = tmp_path / f"out-{e:g}"
    res, built = run_scene(load_scene(str(path)), out)
    return res, json.loads((out / "summary.json").read_text()), out


def test_bar_cuts_the_coating_to_the_hand_derived_depth(tmp_path):
    """Quasi-static: the coating holds F_y, so k x = F − F_y, wear = x − d = (F − F_y)/k − d."""
    res, summary, out = _run(tmp_path, 50e-6)
    expected = (F - F_Y) / K_TIP - D
    assert summary["status"] == "ok"
    assert summary["max_wear_depth"] == pytest.approx(expected, rel=0.02)
    assert summary["worn_volume"] > 0
    hist = np.loadtxt(out / "wear_history.csv", delimiter=",", skiprows=1)
    assert np.all(np.diff(hist[:, 1]) >= 0) and hist[:, 1].min() >= 0  # monotone, >= 0
    assert (out / "wear_map.png").exists() and (out / "wear_map.csv").exists()
    # while cutting, the contact force is the yield force
    force = res.force.sum(axis=1)
    assert force.max() == pytest.approx(F_Y, rel=0.02)


def test_wear_never_deeper_than_the_coating(tmp_path):
    """A 4 µm coating is worn through; the rigid casing behind it then takes the force."""
    e = 4e-6
    res, summary, out = _run(tmp_path, e)
    assert summary["max_wear_depth"] == pytest.approx(e, rel=1e-12)
    hist = np.loadtxt(out / "wear_history.csv", delimiter=",", skiprows=1)
    assert hist[:, 1].max() <= e
    # mean over the last steps: the default position rule's held impulse alternates from one
    # step to the next (trapezoidal rule on a held contact) about the static force
    final = res.force.sum(axis=1)[-100:].mean()
    assert final == pytest.approx(F - K_TIP * (D + e), rel=0.02)  # > F_Y: the casing holds


def test_bounded_impulses_one_and_several_contacts():
    W = np.array([[2.0, 0.5], [0.5, 1.0]])
    q = np.array([-4.0, -3.0])
    free = solve_impulses(W, q, np.ones(2, bool))
    capped = solve_impulses(W, q, np.ones(2, bool), upper=np.array([0.5, np.inf]))
    assert capped[0] == 0.5 and free[0] > 0.5
    # the uncapped contact is solved with the capped one's impulse known
    assert capped[1] == pytest.approx((3.0 - 0.5 * 0.5) / 1.0)


def test_wear_map_cells_and_volume():
    grid = CasingGrid([0.0, np.pi], [0.0, 0.01], 0.5, 100.0, n_angle=4, n_axial=2)
    wear = Abradable(1e-4, 10.0, grid)
    wear.update(0.0, np.array([-2e-5, -5e-4]), np.array([True, True]))
    assert wear.depth_at(0.0) == pytest.approx([2e-5, 1e-4])  # second one worn through
    assert np.isinf(wear.impulse_cap(0.0, 1e-6)[1]) and wear.impulse_cap(0.0, 1e-6)[
        0
    ] == pytest.approx(1e-5)
    wear.update(0.0, np.array([+1e-5, -1e-5]), np.array([True, False]))  # no removal
    assert wear.max_depth == 1e-4
    assert wear.worn_volume == pytest.approx(np.sum(wear.depth * wear.cell_area[None, :]))


def test_yield_is_required(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(SCENE.format(e=1e-5).replace("yield = 2.0", "yield = 0.0"))
    with pytest.raises(SceneError, match="contact.abradable.yield"):
        load_scene(str(path))


@pytest.mark.parametrize("rule", RULES)
def test_every_activation_rule_honours_the_bound(rule):
    """The wear cap: 0 <= P <= upper under every rule; one contact: the capped closed form;
    several: a box LCP (held at the bound only where the residual asks for more)."""
    rng = np.random.default_rng(3)
    h, gamma = 1e-4, 0.5
    for _ in range(100):
        n = int(rng.integers(1, 5))
        a = rng.normal(size=(n, n))
        W = a @ a.T + 0.5 * np.eye(n)
        g_k, gd_k, gd_p = rng.normal(0, 1e-6, n), rng.normal(0, 1e-2, n), rng.normal(0, 1e-2, n)
        g_p = g_k + 0.5 * h * (gd_k + gd_p)
        e = rng.choice([0.0, 1.0], n)
        args = (rule, g_k, gd_k, g_p, gd_p, W, 0.5 * h * W, e, h, gamma)
        free = impulses(*args)
        upper = 0.5 * free + 1e-9 * rng.uniform(size=n)
        P = impulses(*args, upper=upper)
        assert np.all(P >= 0.0) and np.all(P <= upper)
        if n == 1:
            one = impulse_one(
                rule,
                g_k[0],
                gd_k[0],
                g_p[0],
                gd_p[0],
                W[0, 0],
                0.5 * h * W[0, 0],
                e[0],
                h,
                gamma,
                upper[0],
            )
            assert P[0] == pytest.approx(min(free[0], upper[0]), rel=1e-9, abs=1e-18)
            assert one == pytest.approx(P[0], rel=1e-9, abs=1e-18)


def test_box_lcp_conditions():
    rng = np.random.default_rng(4)
    for _ in range(200):
        n = int(rng.integers(2, 6))
        a = rng.normal(size=(n, n))
        W = a @ a.T + 0.2 * np.eye(n)
        q = rng.normal(size=n)
        upper = rng.uniform(0.0, 1.0, n)
        P = solve_impulses(W, q, np.ones(n, bool), upper=upper)
        r = W @ P + q
        tol = 1e-9 * (1 + np.abs(q).max())
        assert np.all(P >= 0) and np.all(P <= upper)
        at0, atU = P <= 1e-14, P >= upper - 1e-14
        inside = ~at0 & ~atU
        assert np.all(r[at0 & ~atU] >= -tol) and np.all(r[atU & ~at0] <= tol)
        assert np.all(np.abs(r[inside]) <= tol)


def test_frictional_solve_caps_the_normal_impulse_and_its_cone():
    """With friction the normal impulse is capped at U and |P_t| <= μ P_n, = μ U when the
    contact slides at its bound."""
    rng = np.random.default_rng(5)
    for _ in range(100):
        n = int(rng.integers(1, 5))
        a = rng.normal(size=(3 * n, 3 * n))
        W = a @ a.T + 0.05 * np.eye(3 * n)
        q, mu = rng.normal(size=(n, 3)), rng.uniform(0.05, 1.0, n)
        free = solve_frictional_contact(W, q, mu, np.ones(n, bool))
        U = 0.5 * free.P[:, 0] + 1e-3
        r = solve_frictional_contact(W, q, mu, np.ones(n, bool), upper=U)
        P, u = r.P, r.u
        assert np.all(P[:, 0] >= 0.0) and np.all(P[:, 0] <= U * (1 + 1e-12))
        inside = (P[:, 0] > 1e-12) & (P[:, 0] < U * (1 - 1e-9))
        assert np.all(np.abs(u[inside, 0]) <= 1e-8)  # Signorini below the bound
        at = P[:, 0] >= U * (1 - 1e-9)
        assert np.all(u[at, 0] <= 1e-8)  # at the bound: approaching (the coating yields)
        nt = np.linalg.norm(P[:, 1:], axis=1)
        assert np.all(nt <= mu * P[:, 0] * (1 + 1e-10) + 1e-14)
        slip = r.state == SLIP
        np.testing.assert_allclose(nt[slip], mu[slip] * P[slip, 0], rtol=1e-10)


#: the twisted NACA blade with friction cutting a 30 µm coating that yields at 5 N, full model
COATED_BLADE = {
    "geometry.h": 0.03,
    "geometry.n_sections": 2,
    "contact.reach": "all",
    "contact.friction": 0.15,
    "contact.abradable.thickness": "30 um",
    "contact.abradable.yield": 5.0,
    "loads.centrifugal": "off",
    "reduction.method": "none",
    "scheme.t_end": 1.5e-3,
    "outputs.vtk_stride": 0,
    "outputs.plots": False,
}


def test_frictional_blade_cuts_the_coating_at_the_yield_force(tmp_path):
    """3D blade, Coulomb friction and frictional heat (θ-method, frictional solve with the
    bound): the normal force never exceeds the coating's yield, Coulomb's law holds with the
    capped normal force, coating is removed, the balances close."""
    changes = COATED_BLADE
    res, _ = run_scene(load_scene("twisted-naca", changes), tmp_path / "out")
    s = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert s["status"] == "ok", s.get("message")
    assert s["max_contact_force"] == pytest.approx(5.0, rel=1e-9)  # held at the yield
    assert 0.0 < s["max_wear_depth"] <= 30e-6
    c = s["coulomb_check"]
    assert c["cone"] <= 1e-8 and c["slip_equality"] <= 1e-8 and c["slip_steps"] > 0


def test_worn_surface_rate_enters_the_gap_rate():
    """The worn surface is the quadratic B-spline of the map: a contact sliding towards a
    less worn centre meets the coating approaching at ``Ω ∂w/∂ψ`` (hand-derived spline)."""
    grid = CasingGrid([0.0], [0.0], 0.3, 100.0, n_angle=4, n_axial=1)
    wear = Abradable(1e-3, 10.0, grid)
    c0 = 2e-4
    wear.reset(h=1e-3)
    wear.depth[0, 0] = c0  # the coefficient at 45 deg, the others 0
    t = (math.pi / 2) / 100.0  # the contact at 90 deg: half way between the centres
    # x = 1/2: nearest centre 1, u = -1/2, weights (1/2, 1/2, 0) on centres (0, 1, 2)
    assert wear.depth_at(t) == pytest.approx([c0 / 2], rel=1e-12)
    # at t - h (0.1 rad earlier): x = 1/2 - 0.2/pi, nearest centre 0, weight 3/4 - u^2
    u = 0.5 - 0.2 / math.pi
    assert wear.rate_at(t) == pytest.approx([(c0 / 2 - (0.75 - u * u) * c0) / 1e-3], rel=1e-9)
    # the spline's slope at the knot, -c0 per cell, is the limit of the rate as h -> 0
    slope = -c0 / (math.pi / 2)  # d w / d psi (m/rad)
    wear.reset(h=1e-7)
    wear.depth[0, 0] = c0
    assert wear.rate_at(t) == pytest.approx([100.0 * slope], rel=1e-5)
    assert wear.rate_at(1.25 * math.pi / 100.0) == pytest.approx([0.0], abs=1e-12)  # 225 deg
    c = Contact(G=[[1.0]], Gv=[[1.0]], Hm=[[1.0]], Ht=[[0.0]], gap0=0.0, wear=wear)
    assert c.rate_at(t) == pytest.approx([100.0 * slope], rel=1e-5)
    assert c.gap_at(t) == pytest.approx([c0 / 2])


def test_worn_surface_has_a_continuous_slope():
    """At the knots (half way between centres) and at the centres the one-sided slopes of
    the worn surface agree (a piecewise-linear map jumps there): no impact at a centre."""
    rng = np.random.default_rng(7)
    n = 12
    grid = CasingGrid([0.0], [0.0], 0.3, 1.0, n_angle=n, n_axial=1)
    c = rng.uniform(0.0, 1e-4, n)
    cell = 2 * math.pi / n
    eps = 1e-7 * cell
    for k in range(n):
        for psi in ((k + 0.5) * cell, (k + 1.0) * cell):  # a centre, a knot
            left = (grid.interpolate(c, psi) - grid.interpolate(c, psi - eps)) / eps
            right = (grid.interpolate(c, psi + eps) - grid.interpolate(c, psi)) / eps
            scale = np.abs(np.diff(c)).max() / cell
            assert abs(left[0] - right[0]) <= 1e-5 * scale
    assert grid.interpolate(c, rng.uniform(0, 2 * math.pi)).item() <= c.max()


def test_a_contact_retracing_its_cut_does_not_meet_the_coating():
    """A contact cutting along a curved reach (a groove deepening then receding, many steps
    per cell) leaves a surface at or beyond its reach all along its path: the same path
    again finds a gap >= 0 everywhere (the map does not undercut between the centres)."""
    omega, h, n_angle = 100.0, 2e-5, 360  # 0.002 rad per step, ~8.7 steps per cell
    grid = CasingGrid([0.0], [0.0], 0.3, omega, n_angle=n_angle, n_axial=1)
    wear = Abradable(1e-3, 10.0, grid)
    wear.reset(h=h)
    steps = 400
    reach = lambda k: 3e-4 * math.sin(math.pi * k / steps)  # noqa: E731
    wear.update(0.0, np.array([-reach(0)]), np.array([False]))
    for k in range(1, steps + 1):
        wear.update(k * h, wear.depth_at(k * h) - reach(k), np.array([True]))
    for k in range(steps + 1):
        for s in (0.0, 0.25, 0.5, 0.75):  # between step ends too (reach linear there)
            t = (k + s) * h
            r = (1 - s) * reach(k) + s * reach(min(k + 1, steps))
            assert wear.depth_at(t)[0] - r >= -1e-18
    # and the cut stays local: no more than two cells beyond either end of the groove
    cut = np.flatnonzero(wear.depth[:, 0] > 0)
    assert cut.size <= steps * omega * h / (2 * math.pi / n_angle) + 5


def test_max_depth_is_the_surface_s_deepest_point():
    """``max_depth`` is the deepest point of the B-spline surface (a piece's vertex, not a
    coefficient), ``surface`` its depth at the centres."""
    rng = np.random.default_rng(11)
    grid = CasingGrid([0.0, 1.0], [0.0, 0.01], 0.3, 100.0, n_angle=24, n_axial=2)
    wear = Abradable(1e-3, 10.0, grid)
    wear.depth[:] = rng.uniform(0, 5e-4, wear.depth.shape)
    psi = np.linspace(0, 2 * math.pi, 24 * 400, endpoint=False)
    dense = max(grid.interpolate(wear.depth.ravel(), p / 100.0).max() for p in psi)
    assert wear.max_depth == pytest.approx(dense, rel=1e-6)
    assert wear.max_depth < wear.depth.max()
    centres = wear.surface
    assert centres[3, 0] == pytest.approx(
        (wear.depth[2, 0] + 6 * wear.depth[3, 0] + wear.depth[4, 0]) / 8, rel=1e-14
    )


@pytest.mark.parametrize("n_angle", [36, 360, 3600])
def test_a_sweep_cuts_every_centre_it_crosses(n_angle):
    """A contact that yields at a constant reach over a quarter turn wears the same volume
    whatever the number of cells it crosses per step, and ends on its own cut (g >= 0)."""
    omega, h, reach = 100.0, 1e-3, 3e-5  # 0.1 rad per step
    grid = CasingGrid([0.0], [0.0], 0.3, omega, n_angle=n_angle, n_axial=1)
    wear = Abradable(1e-4, 10.0, grid)
    wear.reset(h=h)
    steps = int(round((math.pi / 2) / (omega * h)))
    wear.update(0.0, np.array([-reach]), np.array([False]))  # the sweep starts at 0 rad
    for k in range(1, steps + 1):
        t = k * h
        gap = wear.depth_at(t) - reach
        wear.update(t, gap, np.array([True]))
        assert wear.depth_at(t) - reach >= -1e-18  # on the new surface
    d = wear.depth[:, 0]
    assert d.max() == pytest.approx(reach) and d.min() == 0.0
    swept = steps * omega * h  # rad
    n_cut = np.count_nonzero(d)  # every centre swept, and the supports' reach at each end
    assert swept / (2 * math.pi / n_angle) - 1 <= n_cut <= swept / (2 * math.pi / n_angle) + 4
    width = grid.z_edges[1] - grid.z_edges[0]
    assert wear.worn_volume == pytest.approx(
        reach * 0.3 * swept * width, rel=4.0 / (swept / (2 * math.pi / n_angle))
    )


def test_the_bound_of_a_step_entering_the_coating_is_the_part_of_the_step_on_it():
    """``h F_y`` for a contact closed at ``t_k``; ``F_y`` times the part of the step after the
    free motion reaches the worn surface for one open at ``t_k``; ``inf`` worn through."""
    cell = 2 * math.pi / 16
    grid = CasingGrid(
        (np.arange(0, 16, 4) + 0.5) * cell, [0.0] * 4, 0.3, 100.0, n_angle=16, n_axial=1
    )
    wear = Abradable(1e-4, 10.0, grid)
    wear.reset(h=1e-6)
    wear.depth[11:14, 0] = 1e-4  # around the fourth contact (centre 12) at t = 0: worn through
    g_k = np.array([3e-6, -1e-7, 2e-6, 1e-6])
    g_p = np.array([-1e-6, -2e-6, 1e-6, -1e-6])
    U = wear.impulse_cap(0.0, 1e-6, g_k, g_p)
    assert U[0] == pytest.approx(1e-5 * 0.25, rel=1e-14)  # a quarter of the step on it
    assert U[1] == pytest.approx(1e-5) and U[2] == pytest.approx(1e-5)
    assert np.isinf(U[3])
    np.testing.assert_array_equal(wear.bound(0.0, 1e-6), U)  # the yield test's bound
    assert wear.bound(1e-6, 1e-6)[0] == pytest.approx(1e-5)  # another step: h F_y


def test_a_mass_entering_the_coating_is_held_only_after_it_reaches_it():
    """A free mass m at speed v meets a fresh coating (yield F_y) at t_c inside a step: that
    step's impulse is F_y (t_{k+1} − t_c), then F_y h per step until the mass has lost m v;
    the cut depth is the plastic stopping distance m v² / (2 F_y) to O(h v)."""
    from femrub.analysis import make_stepper
    from femrub.model.first_order import FirstOrderModel, Layout

    m, v, F_y, d, h = 2.0, 0.5, 400.0, 1.3e-6, 1e-6  # stops in m v / F_y = 2.5 ms
    grid = CasingGrid([0.0], [0.0], 0.3, 0.0, n_angle=1, n_axial=1)
    wear = Abradable(1e-2, F_y, grid)
    c = Contact(
        G=[[-1.0], [0.0]],
        Gv=[[0.0], [-1.0]],
        Hm=[[0.0], [-1.0]],
        Ht=[[0.0], [0.0]],
        gap0=d,
        wear=wear,
    )
    A = np.diag([1.0, m])
    B = np.array([[0.0, 1.0], [0.0, 0.0]])
    model = FirstOrderModel(A, B, Layout(n_u=1, n_v=1, n_t=0), contact=c, x0=np.array([0.0, v]))
    st = make_stepper("theta", model, h)
    P = np.array([st.step().impulse[0] for _ in range(3000)])
    k = int(np.flatnonzero(P > 0)[0])
    t_c = d / v
    assert k * h < t_c <= (k + 1) * h
    assert P[k] == pytest.approx(F_y * ((k + 1) * h - t_c), rel=1e-9)
    assert np.all(P[k + 1 : k + 2000] == pytest.approx(F_y * h, rel=1e-12))
    assert P.sum() == pytest.approx(m * v, rel=1e-3)  # stopped: its momentum
    worn = st.model.contact.wear  # the run's coating
    assert worn.max_depth == pytest.approx(m * v**2 / (2 * F_y), abs=2 * h * v)


@pytest.mark.parametrize("cells", [0.3, 1.0, 2.7, 10.0])
def test_a_footprint_reads_the_mean_of_the_surface_over_it(cells):
    """``W = (1/β) ∫ w`` over the footprint, against a dense quadrature of the point read;
    the weights sum to 1; a zero footprint is the point read."""
    n, radius, t = 64, 0.3, 0.37
    foot = cells * 2 * math.pi * radius / n
    point = CasingGrid([0.1], [0.0], radius, 1.0, n_angle=n, n_axial=1)
    grid = CasingGrid([0.1], [0.0], radius, 1.0, n_angle=n, n_axial=1, footprint=foot)
    assert grid.beta == pytest.approx(cells, rel=1e-12)
    c = np.random.default_rng(0).uniform(0, 1e-4, n)
    s = (np.arange(20000) + 0.5) / 20000 - 0.5  # midpoint rule over the footprint
    dense = np.mean([point.interpolate(c, t + ds * foot / radius)[0] for ds in s])
    assert grid.interpolate(c, t)[0] == pytest.approx(dense, rel=1e-7)
    assert grid.interpolate(np.ones(n), t)[0] == pytest.approx(1.0, rel=1e-14)
    zero = CasingGrid([0.1], [0.0], radius, 1.0, n_angle=n, n_axial=1, footprint=0.0)
    assert zero.interpolate(c, t)[0] == point.interpolate(c, t)[0]
    with pytest.raises(ValueError, match="footprint"):
        CasingGrid([0.1], [0.0], radius, 1.0, n_angle=n, footprint=-1e-3)


def test_a_footprint_ends_on_its_own_cut():
    """Cutting a groove (a half sine, several cells per step and several steps per cell),
    the footprint's mean of the new surface is at or beyond the reach after every step."""
    for n_angle, h in ((360, 2e-5), (3600, 2e-5), (360, 4e-4)):
        grid = CasingGrid([0.0], [0.0], 0.3, 100.0, n_angle=n_angle, n_axial=1, footprint=4e-3)
        wear = Abradable(1e-3, 10.0, grid)
        wear.reset(h=h)
        reach = lambda k: 3e-4 * math.sin(math.pi * k / 100)  # noqa: E731
        wear.update(0.0, np.array([-reach(0)]), np.array([False]))
        for k in range(1, 101):
            wear.update(k * h, wear.depth_at(k * h) - reach(k), np.array([True]))
            assert wear.depth_at(k * h)[0] - reach(k) >= -1e-12 * 3e-4  # round-off


def test_steppers_of_one_coated_model_each_run_their_own_coating(tmp_path):
    """The coating's wear is each run's own state: a stepper built before another stepper of
    the same model ran still starts on a fresh coating (the time-step check builds its h/2
    stepper before it runs at h), the model's coating is never worn, and steppers that
    interleave their steps do as they do one after the other."""
    from femrub.analysis import make_stepper
    from femrub.app.scheme import scheme_options
    from femrub.app.simulation import build

    path = tmp_path / "bar.toml"
    path.write_text(SCENE.format(e=50e-6))
    scene = load_scene(str(path))
    model = build(scene, stepper=False).model
    make = lambda: make_stepper("theta", model, 2e-5, **scheme_options(scene))  # noqa: E731
    t_end = 0.07  # the cut starts at 0.055 s (F = F_y + k d): 750 steps of cutting
    early = make()
    first = make()
    reference = first.run(t_end)
    assert first.model.contact.wear.max_depth > 1e-7  # the reference run wore its coating
    assert model.contact.wear.max_depth == 0.0  # the model's: untouched
    again = early.run(t_end)
    assert again.status == reference.status == "ok"
    np.testing.assert_array_equal(again.impulse, reference.impulse)
    np.testing.assert_array_equal(early.model.contact.wear.depth, first.model.contact.wear.depth)
    a, b = make(), make()
    for _ in range(a.steps_to(t_end)):
        np.testing.assert_array_equal(b.step().X, a.step().X)
    depth = first.model.contact.wear.depth  # the run's compiled blocks: equal to round-off
    assert depth.max() > 1e-7
    np.testing.assert_allclose(a.model.contact.wear.depth, depth, rtol=0, atol=1e-9 * depth.max())
    np.testing.assert_allclose(a.X, first.X, rtol=0, atol=1e-9 * np.abs(first.X).max())


def test_contacts_reading_a_coating_at_points_are_warned_with_their_width(tmp_path, model_cache):
    """Several contacts with ``footprint = 0`` (point reads, whose later-revolution wear
    keeps changing with the map): a warning names the width each contact stands for (their
    span around the casing over their number less one); one contact, or a footprint, none."""
    from test_rub_blocks import SCENE as BLADE

    from femrub.app.casing import footprint_warning
    from femrub.app.simulation import build

    scene = load_scene("twisted-naca", {**BLADE, "outputs.plots": False})
    with pytest.warns(UserWarning, match="contact.abradable.footprint = 0"):
        sim = build(scene, stepper=False, cache=model_cache)
    grid = sim.full.contact.wear.grid
    phi = np.sort(np.mod(grid.angles, 2 * np.pi))
    assert grid.angles.size > 1 and phi[-1] - phi[0] < np.pi  # one blade's tip: no wrap
    width = (phi[-1] - phi[0]) / (np.unique(phi).size - 1) * grid.radius
    (msg,) = [w for w in sim.report["warnings"] if "footprint" in w]
    assert f"about {1e3 * width:.3g} mm" in msg
    grid.footprint = width
    assert footprint_warning(scene, grid) is None
    with pytest.warns(UserWarning, match="footprint"):  # summary.json lists it first
        run_scene(scene, tmp_path / "blade", cache=model_cache)  # the blade built above
    summary = json.loads((tmp_path / "blade" / "summary.json").read_text())
    assert "contact.abradable.footprint = 0" in summary["warnings"][0]
    path = tmp_path / "bar.toml"
    path.write_text(SCENE.format(e=50e-6))  # one contact
    assert "warnings" not in build(load_scene(str(path)), stepper=False).report
