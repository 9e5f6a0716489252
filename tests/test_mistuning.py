"""A mistuned bladed disk (``rotor.mistuning``): its forced response against Whitehead's bound.

The reduced wheel of a scene (the 6-blade wheel of ``small_wheel.py``, rigid casing, no
contact) is excited in engine order ``k``: the same circumferential tip force on every blade
with the phase ``e^{i k s 2π/N}`` on blade ``s``. Its linear forced response over a band
around the first blade family is solved with dense linear algebra on the reduced model
(``(K − ω² M + i ω C) x = f``, ``M = I``); the amplitude read is each blade's mean
circumferential tip displacement.

Whitehead's bound: the largest amplitude of any blade of a mistuned wheel is at most
``(1 + √N) / 2`` times the tuned wheel's peak (Whitehead 1966, 1998). Its premise: one mode
per blade (an isolated family: the band holds the first family only, the next one six times
higher), the same damping in every mode of the family, and mistuning that is small
(``|δ_s| ≪ 1``: a blade's own stiffness change barely changes its amplitude). The
amplification it bounds comes from the coupling between the blades: a mistuned blade
gathers the energy of the waves of the other nodal diameters, which needs mistuning of the
order of the coupling (the family's spread of frequency over the nodal diameters) and
damping below both.

The small wheel's coupling is weak: its stiff 15 mm disk carries a 30 mm blade whose first
family spreads over less than 1e-4 of its frequency. Mistuning of 2-5 % (about a hundred
times that) leaves every blade vibrating alone, each at its own frequency, and the peak
differs from the tuned one only by the blade's own stiffness (``ω̄ / ω_s``, the damping
fixed): the regime the bound is about is not reached, and such patterns test only the
localisation (:func:`test_large_mistuning_of_a_weakly_coupled_wheel_localises`). The bound is
checked where its premise applies and the amplification it bounds appears: mistuning of a
standard deviation of the order of the family's spread, and a damping ratio a tenth of it.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
import scipy.linalg as sla
import tomli_w
from scipy.optimize import minimize_scalar
from small_wheel import scene_tables

from femrub.app.explain import explain
from femrub.app.modes import ModesResult, write_modes_folder
from femrub.app.wheel import _model, _report, transfer, wheel_parts
from femrub.model.cyclic import ModeTable
from femrub.model.wheel import mistuning_stiffness
from femrub.reduction.cyclic_ritz import cyclic_bases
from femrub.scene import SceneError, loads_scene

N = 6
ALPHA = 2.0 * math.pi / N
WHITEHEAD = (1.0 + math.sqrt(N)) / 2.0
FACTORS = [0.03, -0.02, 0.0, 0.01, -0.04, 0.05]
SCENE = {
    "name": "wheel6-mistuned",
    "casing": {"ring": {"clearance": 1e-3}},
    "loads": {"rotation_speed": 1000.0, "centrifugal": "off"},
    "scheme": {"h": 1e-6, "t_end": 1e-3},
    "outputs": {"plots": False},
}


def _scene(mistuning=None, sectors=N):
    """The wheel's scene: 3 families, 2 contacts a blade, damping ratio 0.001, rigid casing."""
    rotor = dict(families=3, contacts=2, damping_ratio=0.001, mistuning=mistuning)
    tables = scene_tables(**{k: v for k, v in rotor.items() if v is not None})
    if sectors is None:
        del tables["rotor"]["sectors"]
    return loads_scene(tomli_w.dumps({**SCENE, **tables}))


@pytest.fixture(scope="module")
def wheel():
    """The scene's parts (mistuned by ``FACTORS``), its disk basis (3 modes per nodal
    diameter), the rows of every blade's mean circumferential tip displacement ``(N, n)``
    and the richer basis of the reduction error estimate (``3 + 2`` modes)."""
    parts = wheel_parts(_scene(FACTORS))
    disk, richer = cyclic_bases(parts.disk, [3, 5], parts.rows)
    nc = parts.contacts.n
    circumferential = parts.rows[nc + 1 :: 2]  # tangent rows: axial, circumferential per contact
    rows = disk.sector_rows(circumferential).mean(axis=1)
    return parts, disk, rows, richer


def _with(parts, factors=None, damping=None):
    """``parts`` mistuned by ``factors`` (``None``: tuned), with the disk's damping ratio."""
    config = parts.config if damping is None else replace(parts.config, disk_damping=damping)
    factors = None if factors is None else tuple(factors)
    return replace(parts, mistuning=factors, config=config)


def _response(model, rows, k: int, omega) -> np.ndarray:
    """``(n_freq, N)`` complex tip displacements (m) of every blade under a 1 N tip force on
    every blade with the phase ``e^{i k s α}`` (engine order ``k``), at ``omega`` (rad/s)."""
    b = model.blocks
    M, C, K = (x.toarray() for x in (b.M, b.C, b.K))
    omega = np.atleast_1d(omega)[:, None, None]
    force = np.exp(1j * k * ALPHA * np.arange(N)) @ rows  # Σ_s e^{iksα} rows_sᵀ · 1 N
    A = K - omega**2 * M + 1j * omega * C
    x = np.linalg.solve(A, np.broadcast_to(force, (A.shape[0], force.size))[..., None])
    return x[..., 0] @ rows.T


def _family(model) -> np.ndarray:
    """The first family's ``N`` angular frequencies (rad/s) of the model (``M = I``)."""
    lam = sla.eigvalsh(model.blocks.K.toarray())
    return np.sqrt(lam[:N])


def _peak(model, rows, k: int, zeta: float):
    """``(amplitude, ω, blades)``: the largest blade amplitude over the band of the first
    family (its frequencies widened by 20 half-power widths), the frequency of that peak and
    every blade's complex amplitude there."""
    family = _family(model)
    lo, hi = family.min() * (1.0 - 20.0 * zeta), family.max() * (1.0 + 20.0 * zeta)
    grid = np.linspace(lo, hi, max(int((hi - lo) / (0.1 * zeta * lo)), 200))
    amp = np.abs(_response(model, rows, k, grid)).max(axis=1)
    i = int(np.clip(amp.argmax(), 1, grid.size - 2))
    best = minimize_scalar(
        lambda w: -np.abs(_response(model, rows, k, w)).max(),
        bounds=(grid[i - 1], grid[i + 1]),
        method="bounded",
        options={"xatol": 1e-4 * zeta * lo},
    )
    return -best.fun, best.x, _response(model, rows, k, best.x)[0]


def _spread(disk) -> float:
    """The first family's relative spread of frequency over the nodal diameters."""
    first = np.array([h.omega[0] for h in disk.harmonics])
    return (first.max() - first.min()) / first.mean()


# -- the scene key ------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("mistuning", "says"),
    [
        ([0.01, 0.02], "rotor.mistuning = [0.01, 0.02]: give one factor δ_s per blade: 6 numbers"),
        ([0.0, 0.0, -1.0, 0.0, 0.0, 0.0], "rotor.mistuning[2] = -1.0: must be > -1"),
        ([0.0, "stiff", 0, 0, 0, 0], "rotor.mistuning[1] = 'stiff': expected a number"),
        (0.03, "rotor.mistuning = 0.03: must be a non-empty list of numbers > -1"),
    ],
)
def test_bad_mistuning_is_refused_in_one_line_when_loaded(mistuning, says):
    with pytest.raises(SceneError) as err:
        _scene(mistuning)
    assert str(err.value).startswith(says) and "\n" not in str(err.value)


def test_mistuning_of_a_single_blade_is_refused():
    with pytest.raises(SceneError, match=r"rotor.mistuning = \[0.01\]: .* set rotor.sectors"):
        _scene([0.01], sectors=None)


def test_the_scenes_mistuning_reaches_the_model_and_its_report(wheel):
    parts, disk, _, richer = wheel
    assert parts.mistuning == tuple(FACTORS)
    added = mistuning_stiffness(parts.disk, disk, FACTORS, parts.material, 0.045)
    mistuned, _ = _model(parts, disk, None)
    tuned, _ = _model(_with(parts), disk, None)
    difference = (mistuned.blocks.K - tuned.blocks.K).toarray()
    np.testing.assert_allclose(difference, added, rtol=0, atol=1e-12 * np.abs(added).max())
    assert np.abs(added).max() > 1e-3 * disk.omega.min() ** 2
    # the reduction estimate's richer wheel, mistuned alike: on the run's coordinates (which
    # its basis spans) its stiffness is the run's
    reference, _ = _model(parts, richer, None)
    T = transfer(disk, richer, parts.disk.M)
    K = mistuned.blocks.K.toarray()
    restricted = T.T @ reference.blocks.K.toarray() @ T
    np.testing.assert_allclose(restricted, K, rtol=0, atol=1e-9 * np.abs(K).max())
    report = _report(_scene(FACTORS), parts, mistuned)
    assert report["bladed_disk"]["mistuning"] == {"factors": FACTORS, "max_abs": 0.05}
    report["reduction"] = {"error": {"estimate": 0.0, "reference_sizes": [], "tolerance": 0.0}}
    report["scheme"] = {"name": "theta", "h": 1e-6, "steps": 1000}
    assert "mistuned: blade s's stiffness times 1 + δ_s, max |δ_s| = 5 %" in explain(report)


def test_modes_say_the_mistuning_is_not_applied(tmp_path):
    """``femrub modes`` gives the tuned wheel's modes by nodal diameter: its summary says so."""
    table = ModeTable(np.arange(4), np.ones(4, dtype=int), np.full(4, 1120.0), 1000.0)
    summary = write_modes_folder(ModesResult({"disk": table}), tmp_path, _scene(FACTORS))
    assert summary["mistuning"].startswith("not applied: the modes by nodal diameter are the tuned")
    assert "mistuning" not in write_modes_folder(ModesResult({"disk": table}), tmp_path, _scene())


# -- the forced response ------------------------------------------------------------------


@pytest.mark.parametrize("k", [1, 2])
def test_tuned_wheel_responds_alike_on_every_blade_up_to_the_travelling_phase(wheel, k):
    parts, disk, rows, _ = wheel
    model, _ = _model(_with(parts), disk, None)
    _, _, blades = _peak(model, rows, k, parts.config.disk_damping)
    np.testing.assert_allclose(np.abs(blades), np.abs(blades[0]), rtol=1e-9)
    travelling = blades * np.exp(-1j * k * ALPHA * np.arange(N))
    np.testing.assert_allclose(travelling, travelling[0], rtol=1e-9)


def test_uniform_mistuning_only_shifts_the_frequency(wheel):
    """``δ_s = δ`` on every blade keeps the wheel cyclic: the tuned response's shape, its
    peak at the stiffer family's frequency, its amplitude that of the tuned peak scaled by
    the frequencies' ratio (the damping kept: ``|x| = f / (c ω)``)."""
    parts, disk, rows, _ = wheel
    delta, k, zeta = 0.04, 2, parts.config.disk_damping
    tuned, _ = _model(_with(parts), disk, None)
    stiffer, _ = _model(_with(parts, [delta] * N), disk, None)
    a0, w0, _ = _peak(tuned, rows, k, zeta)
    a1, w1, blades = _peak(stiffer, rows, k, zeta)
    travelling = blades * np.exp(-1j * k * ALPHA * np.arange(N))
    np.testing.assert_allclose(travelling, travelling[0], rtol=1e-6)  # round-off, Q = 500
    assert 1.0 + 0.8 * delta < (w1 / w0) ** 2 < 1.0 + delta  # the blade's share of the energy
    assert a1 * w1 == pytest.approx(a0 * w0, rel=2e-3)


def test_mistuned_peak_stays_under_whiteheads_bound(wheel):
    """Patterns whose standard deviation is of the order of the family's spread, damping a
    tenth of it (the premise of the module docstring): every pattern's peak over the tuned
    peak is at most ``(1 + √N) / 2``, and mistuning amplifies the response (by far more than
    the blades' own stiffness changes, below 1e-3)."""
    parts, disk, rows, _ = wheel
    spread = _spread(disk)
    assert spread < 1e-3  # the weak coupling of the module docstring
    second = min(h.omega[1] for h in disk.harmonics)
    assert second > 5.0 * max(h.omega[0] for h in disk.harmonics)  # an isolated family
    zeta = 0.1 * spread
    rng = np.random.default_rng(7)
    tuned, _ = _model(_with(parts, damping=zeta), disk, None)
    ratios = []
    for k in (1, 2):
        a0, _, _ = _peak(tuned, rows, k, zeta)
        for std in (1.0 * spread, 3.0 * spread):
            for factors in rng.normal(0.0, std, (4, N)):
                model, _ = _model(_with(parts, factors, zeta), disk, None)
                ratios.append(_peak(model, rows, k, zeta)[0] / a0)
    assert max(ratios) <= WHITEHEAD
    assert max(ratios) > 1.1


def test_large_mistuning_of_a_weakly_coupled_wheel_localises(wheel):
    """About 3 % mistuning, a hundred times the coupling, its factors apart by more than
    the half-power width: every blade vibrates alone, the largest peak is the softest
    blade's, ``ω̄ / ω_s`` times the tuned one to 0.5 % (the damping fixed; the shape of the
    blade's mode changes it a little), far under the bound."""
    parts, disk, rows, _ = wheel
    zeta = parts.config.disk_damping
    tuned, _ = _model(_with(parts), disk, None)
    a0, w0, _ = _peak(tuned, rows, 1, zeta)
    for factors in (np.array(FACTORS), -np.array(FACTORS)):
        model, _ = _model(_with(parts, factors), disk, None)
        a, _, blades = _peak(model, rows, 1, zeta)
        softest = _family(model).min()
        assert np.argmax(np.abs(blades)) == np.argmin(factors)
        assert np.sort(np.abs(blades))[-2] < 0.2 * a
        assert a / a0 == pytest.approx(w0 / softest, rel=5e-3)
        assert 1.0 < a / a0 <= WHITEHEAD
