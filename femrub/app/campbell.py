"""Campbell diagram of a scene's blade: natural frequencies against rotation speed.

``femrub campbell SCENE --speeds 0:1800:10 -o DIR`` writes ``DIR/campbell.csv``,
``DIR/campbell.png`` and ``DIR/campbell.json``. The blade is built as for a run (mesh,
material, lumping; no contact), then:

1. the centrifugal prestress (``loads.centrifugal``; ``"auto"`` and ``"off"``: nonlinear,
   ``"off"`` being a choice for runs: a diagram without prestress has flat lines) is solved at
   ``samples`` speeds equally spaced in ``Ω²`` up to the largest speed asked for;
2. the lowest ``modes + 4`` clamped modes at every sample speed, M-orthonormalised
   together, span a reduced basis ``V``; ``K_T(Ω)`` is interpolated in ``s = Ω²`` on it,
   piecewise: the Lagrange polynomial through the (up to) three samples nearest in ``s``
   (with the three first samples, the quadratic through all of them);
3. at every speed the small problem ``Vᵀ K_T(Ω) V q = ω² q`` gives the frequencies, and
   each line follows its mode from one speed to the next by the largest MAC (an
   assignment, so lines may cross where modes veer);
4. the self-check: at the midpoint in ``Ω²`` of every interval between two samples (where
   an interpolation errs most) the full prestress and the full eigen-problem are solved,
   and the relative error of the ``modes`` interpolated frequencies is measured. A
   midpoint whose error exceeds ``tolerance`` (:data:`TOLERANCE`, 0.5 %) becomes a sample
   itself (its solve is kept: the basis gains its modes), and the two new intervals are
   checked in turn, until every check is within the tolerance or ``max_samples`` samples
   are spent; every check is measured again on the final basis and interpolation.

``--exact`` (``exact=True``) skips the interpolation: the full prestress, warm-started from
the previous speed's, and the full eigen-solve at every requested speed (status
``"exact"``; one prestress and one factorisation per speed). A nonlinear prestress asked at
no more speeds than the interpolation's fewest full solves (``2 samples − 1``: the samples
and their midpoint checks) is solved that way too: it costs no more, and needs no check.

The diagram's ``status`` (``campbell.json``): ``"ok"`` when every check is within the
tolerance, ``"failed"`` otherwise (``femrub campbell`` then exits 1 with a one-line error
and writes ``campbell-failed.csv`` and ``campbell-failed.png``, never the files of a
diagram that passed), ``"unchecked"`` with ``--no-check``, ``"exact"`` with ``--exact`` or
at rest only.

The tip growth (``tip_growth_*_m``, at ``tip_growth_speeds_rad_s``: the samples, or every
speed with ``--exact``) is measured as a run measures it:
the outward radial static displacement at the scene's contacts, at each node or as the
mean over its patch of tip face as ``contact.spread`` says
(:meth:`~femrub.fem.prestress.Prestress.growth`).

Engine-order lines ``f = k Ω / 2π`` are drawn with the modes.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.linalg as sla
from scipy.optimize import linear_sum_assignment

from ..contact.points import locate_contacts
from ..fem.discretisation import assemble, discretise
from ..fem.eigen import lowest_modes
from ..fem.linalg import sparse_lu
from ..fem.prestress import centrifugal_prestress
from ..fem.speed_family import lagrange_weights, sample_speeds
from ..scene.spec import SceneError
from . import translate as tr
from .blade import load_blade

__all__ = [
    "MAX_SAMPLES",
    "TOLERANCE",
    "CampbellResult",
    "campbell",
    "parse_speeds",
    "write_campbell",
]

#: extra modes per sample speed in the reduced basis
EXTRA_MODES = 4
#: largest relative error of a checked frequency (0.5 %)
TOLERANCE = 0.005
#: most prestress samples the self-check refines to
MAX_SAMPLES = 12
#: samples of the piecewise interpolation in Ω² (quadratic)
NODES = 3


@dataclass(frozen=True)
class CampbellResult:
    """Frequencies (Hz) of ``modes`` tracked lines at ``speeds`` (rad/s)."""

    speeds: np.ndarray
    frequencies: np.ndarray  # (n_speeds, modes)
    method: str
    samples: np.ndarray
    info: dict = field(default_factory=dict)


def parse_speeds(text: str) -> np.ndarray:
    """``"0:1800:10"`` (stop included) or ``"0,900,1800"`` -> speeds in rad/s."""
    try:
        if ":" in text:
            a, b, step = (float(x) for x in text.split(":"))
            if step <= 0 or b < a:
                raise ValueError
            return a + step * np.arange(int(np.floor((b - a) / step + 1e-9)) + 1)
        return np.array([float(x) for x in text.split(",") if x.strip()])
    except ValueError:
        raise SceneError(f"--speeds {text!r}: use START:STOP:STEP or A,B,C (rad/s)") from None


def _solver(K):
    """``K⁻¹`` for the shift-invert eigen-solve (Pardiso on large problems when installed)."""
    return sparse_lu(K, symmetric=True, what="prestressed stiffness").solve


def _m_orthonormal(V, M, tol=1e-10):
    G = V.T @ (M @ V)
    lam, W = sla.eigh(0.5 * (G + G.T))
    keep = lam > tol * lam.max()
    return V @ (W[:, keep] / np.sqrt(lam[keep]))


def _track(Q_prev, Q, n, gram=None):
    """Columns of ``Q`` following the ``n`` columns of ``Q_prev`` (largest MAC; in the inner
    product of ``gram`` when given)."""
    GQ = Q if gram is None else gram @ Q
    GP = Q_prev if gram is None else gram @ Q_prev
    norms = np.outer(np.sum(Q_prev * GP, axis=0), np.sum(Q * GQ, axis=0))
    mac = (Q_prev.T @ GQ) ** 2 / norms
    rows, cols = linear_sum_assignment(-mac[:n])
    return cols[np.argsort(rows)], mac[rows, cols].min()


def campbell(
    scene,
    speeds,
    *,
    modes: int = 6,
    samples: int = 3,
    check: bool = True,
    tolerance: float = TOLERANCE,
    max_samples: int = MAX_SAMPLES,
    exact: bool = False,
    log=None,
) -> CampbellResult:
    """Campbell diagram of ``scene`` at ``speeds`` (rad/s; module docstring).

    ``samples``: the first prestress samples (>= 2, equally spaced in Ω²); ``check``: run
    the self-check, refining the samples up to ``max_samples`` until every checked
    frequency is within ``tolerance`` (relative); the result's ``status`` says whether it
    is (``info["status"]``, ``info["message"]``). ``exact``: the full prestress (warm-started
    along the list) and eigen-solve at every speed instead, no interpolation.
    """
    speeds = _checked_speeds(speeds)
    if tr.is_bar(scene):
        raise SceneError("geometry.kind = 'bar': a Campbell diagram needs a 3D blade")
    if not 0.0 < float(tolerance) < 1.0:
        raise SceneError(f"--tolerance {tolerance!r}: give a relative error in (0, 1), e.g. 0.005")
    t0 = time.perf_counter()
    blade = load_blade(scene, log)
    disc = discretise(blade, scene["physics"]["order"])
    material = tr.material_of(scene)
    mats = assemble(disc, material, lumping=scene["physics"]["lumping"]).mechanical()
    method = _method(scene, log)
    if float(speeds.max()) == 0.0:
        method, check = "off", False
    k = min(modes + EXTRA_MODES, mats.n_u - 1)
    solve = _Solver(disc, material, mats, method, k, log)
    if method == "nonlinear" and check and speeds.size <= 2 * samples - 1 and not exact:
        exact = True  # no more full solves than the samples and their checks
        if log:
            log(f"{speeds.size} speeds: each solved in full (the interpolation needs as many)")
    growth = _Growth(disc, scene)
    if exact and method != "off":
        freqs, info = _exact_diagram(solve, speeds, modes, growth)
        method_samples = speeds
    else:
        first = [0.0] if method == "off" else sample_speeds(speeds.max(), samples)
        if method == "linear":  # K_T affine in Ω²: two samples
            first = sample_speeds(speeds.max(), 2)
        freqs, info = _interpolated_diagram(
            solve, first, speeds, modes, check, float(tolerance), max_samples, growth
        )
        method_samples = np.asarray(info["sample_speeds"])
    info["n_free_dofs"] = int(mats.n_u)
    info["seconds"] = time.perf_counter() - t0
    return CampbellResult(speeds, freqs, method, method_samples, info)


def _interpolated_diagram(solve, first, speeds, modes, check, tolerance, max_samples, growth):
    """The diagram from the interpolation and its self-check (module docstring)."""
    M = solve.mats.M
    taken = [solve(float(w)) for w in first]
    if check:
        interp, checks, errors = _self_check(
            taken, solve, M, modes, tolerance, max(int(max_samples), len(taken)), solve.log
        )
    else:
        interp, checks, errors = _Interpolation(taken, M), [], []
    freqs, worst = _lines(interp, speeds, modes)
    V = interp.V
    Kr0 = V.T @ (solve.mats.K @ V)
    rest = np.sqrt(lowest_modes(Kr0, np.eye(V.shape[1]), modes, vectors=False)) / (2 * np.pi)
    info = {
        "basis_size": int(V.shape[1]),
        "sample_speeds": interp.speeds.tolist(),
        "worst_tracking_mac": worst,
        "rest_frequencies_hz": rest.tolist(),
        **_verdict(solve.method, check, checks, errors, interp, modes, tolerance),
        **growth.of([x.state for x in interp.samples], interp.speeds),
    }
    return freqs, info


def _exact_diagram(solve, speeds, modes, growth):
    """Every speed solved in full (``--exact``): the prestress warm-started from the
    previous speed's, the lowest modes of its tangent; lines tracked by the MAC in the mass
    inner product. Only the last prestress is kept."""
    M = solve.mats.M
    freqs, states, prev, worst = [], [], None, 1.0
    for omega in speeds:
        x = solve(float(omega))
        solve.solved[:] = [x.state]
        order = np.arange(modes)
        if prev is not None:
            order, mac = _track(prev, x.shapes, modes, gram=M)
            worst = min(worst, float(mac))
        prev = x.shapes[:, order]
        freqs.append(x.hz[order])
        states.append(growth.at(x.state))
    rest = lowest_modes(solve.mats.K, M, modes, _solver(solve.mats.K), vectors=False)
    info = {
        "status": "exact",
        "message": (
            f"full prestress (warm-started along the list) and eigen-solve at each of the "
            f"{len(speeds)} speeds"
        ),
        "sample_speeds": np.asarray(speeds, dtype=float).tolist(),
        "worst_tracking_mac": worst,
        "rest_frequencies_hz": (np.sqrt(rest) / (2 * np.pi)).tolist(),
        **growth.table(np.array(states), speeds),
    }
    return np.array(freqs), info


def _checked_speeds(speeds) -> np.ndarray:
    speeds = np.asarray(speeds, dtype=float)
    if speeds.size == 0 or np.any(speeds < 0) or not np.all(np.isfinite(speeds)):
        raise SceneError("--speeds: give finite speeds >= 0 (rad/s)")
    return speeds


def _method(scene, log) -> str:
    """The prestress method of the diagram (``loads.centrifugal``; ``off``: nonlinear)."""
    mode = scene["loads"]["centrifugal"]
    if mode == "off" and log:  # e.g. the Rotor 37 scenes: off for their runs only
        log(
            "notice: loads.centrifugal = 'off' applies to runs; the Campbell diagram uses the "
            "nonlinear prestress (--set loads.centrifugal=linear for the linear one)"
        )
    return "nonlinear" if mode in ("auto", "off") else mode


@dataclass(frozen=True)
class _Solve:
    """The full solve at one speed: the prestress (``None`` without), its tangent ``K`` on
    the free dofs, the lowest mode shapes and their frequencies (Hz)."""

    omega: float
    state: object
    K: object
    shapes: np.ndarray
    hz: np.ndarray


class _Solver:
    """``omega -> _Solve``: prestress at Ω and the lowest ``k`` modes of its tangent. Each
    prestress is warm-started from the solved one nearest in Ω²
    (:func:`~femrub.fem.prestress.centrifugal_prestress` ``start``)."""

    def __init__(self, disc, material, mats, method: str, k: int, log):
        self.disc, self.material, self.mats = disc, material, mats
        self.method, self.k, self.log = method, k, log
        self.solved = []

    def __call__(self, omega: float) -> _Solve:
        state, K = None, self.mats.K
        if self.method != "off":
            start = min(self.solved, key=lambda p: abs(p.omega**2 - omega**2), default=None)
            if self.log:
                self.log(f"prestress ({self.method}) at {omega:g} rad/s ...")
            state = centrifugal_prestress(
                self.disc, self.material, omega, self.method, start=start, log=self.log
            )
            self.solved.append(state)
            K = state.K
        lam, shapes = lowest_modes(K, self.mats.M, self.k, _solver(K))
        return _Solve(omega, state, K, shapes, np.sqrt(np.clip(lam, 0.0, None)) / (2 * np.pi))


class _Interpolation:
    """``K_T(Ω)`` on the basis of the samples' modes, piecewise in ``Ω²`` through the
    :data:`NODES` samples nearest in ``Ω²`` (module docstring)."""

    def __init__(self, samples: list, M):
        self.samples = sorted(samples, key=lambda x: x.omega)
        self.speeds = np.array([x.omega for x in self.samples])
        self.V = _m_orthonormal(np.hstack([x.shapes for x in self.samples]), M)
        self.K = [self.V.T @ (x.K @ self.V) for x in self.samples]

    def stiffness_at(self, omega: float) -> np.ndarray:
        s, nodes = float(omega) ** 2, self.speeds**2
        near = np.sort(np.argsort(np.abs(nodes - s), kind="stable")[:NODES])
        w = lagrange_weights(nodes[near], s)
        return sum(wj * self.K[j] for wj, j in zip(w, near, strict=True))

    def modes_at(self, omega: float):
        """Frequencies (Hz, ascending) and reduced shapes at ``omega`` (rad/s)."""
        Kr = self.stiffness_at(omega)
        lam, Q = sla.eigh(0.5 * (Kr + Kr.T))
        return np.sqrt(np.clip(lam, 0.0, None)) / (2 * np.pi), Q

    def error(self, full: _Solve, modes: int) -> float:
        """Largest relative error of the ``modes`` lowest frequencies against ``full``."""
        f = self.modes_at(full.omega)[0][:modes]
        return float(np.max(np.abs(f - full.hz[:modes]) / full.hz[:modes]))


def _midpoints(samples: list, checks: list) -> list[float]:
    """Midpoints in Ω² of the intervals between samples that hold no check yet."""
    s = np.sort([x.omega for x in samples]) ** 2
    checked = np.array([c.omega**2 for c in checks])
    out = []
    for a, b in zip(s[:-1], s[1:], strict=True):
        if not np.any((checked > a) & (checked < b)):
            out.append(float(np.sqrt(0.5 * (a + b))))
    return out


def _self_check(samples, solve, M, modes, tolerance, max_samples, log):
    """The self-check and its refinement (module docstring, step 4): ``(interpolation,
    checks, errors)``, the errors measured on the final interpolation."""
    checks = []
    while True:
        interp = _Interpolation(samples, M)
        for omega in _midpoints(samples, checks):
            if log:
                log(f"checking the interpolation at {omega:.6g} rad/s (full prestress, modes)")
            checks.append(solve(omega))
        errors = [interp.error(c, modes) for c in checks]
        bad = sorted((i for i, e in enumerate(errors) if e > tolerance), key=lambda i: -errors[i])[
            : max_samples - len(samples)
        ]
        if not bad:
            return interp, checks, errors
        if log:
            log(
                f"interpolation error {100 * max(errors):.3g} % > {100 * tolerance:g} %: "
                f"{len(bad)} checked speed(s) become samples"
            )
        samples = samples + [checks[i] for i in bad]
        checks = [c for i, c in enumerate(checks) if i not in bad]


def _lines(interp: _Interpolation, speeds, modes: int):
    """Frequencies (n_speeds, modes) of the tracked lines and the worst tracking MAC."""
    freqs, q_prev, worst = [], None, 1.0
    for omega in speeds:
        f, Q = interp.modes_at(omega)
        if q_prev is None:
            order = np.arange(modes)
        else:
            order, mac = _track(q_prev, Q, modes)
            worst = min(worst, float(mac))
        q_prev = Q[:, order]
        freqs.append(f[order])
    return np.array(freqs), worst


def _verdict(method, check, checks, errors, interp, modes, tolerance) -> dict:
    """``status`` and ``message`` of the diagram and its checks (module docstring)."""
    if method == "off":
        return {"status": "exact", "message": "at rest: the full eigen-solve"}
    if not check or not checks:
        return {"status": "unchecked", "message": "interpolation not checked (--no-check)"}
    i = int(np.argmax(errors))
    worst, c = errors[i], checks[i]
    out = {
        "tolerance": tolerance,
        "check_speeds": [x.omega for x in checks],
        "check_errors": errors,
        "check_speed": c.omega,
        "check_full_hz": c.hz[:modes].tolist(),
        "check_interpolated_hz": interp.modes_at(c.omega)[0][:modes].tolist(),
        "check_max_relative_error": worst,
    }
    if worst <= tolerance:
        msg = (
            f"{len(checks)} checks between {interp.speeds.size} prestress samples, largest "
            f"frequency error {100 * worst:.2g} % (tolerance {100 * tolerance:g} %)"
        )
        return {"status": "ok", "message": msg, **out}
    msg = (
        f"self-check failed: interpolated frequencies off by {100 * worst:.3g} % at "
        f"{c.omega:.6g} rad/s (tolerance {100 * tolerance:g} %) with {interp.speeds.size} "
        "prestress samples; raise --max-samples or --samples"
    )
    return {"status": "failed", "message": msg, **out}


class _Growth:
    """Radial tip growth at the scene's contacts (m), as a run measures it (module
    docstring): ``at(state)`` per contact, ``table`` over speeds."""

    def __init__(self, disc, scene):
        self.points = locate_contacts(disc, spread=scene["contact"]["spread"])

    def at(self, state) -> np.ndarray:
        return np.zeros(self.points.n) if state is None else state.growth(self.points)

    def of(self, states: list, speeds) -> dict:
        return self.table(np.array([self.at(s) for s in states]), speeds)

    @staticmethod
    def table(g: np.ndarray, speeds) -> dict:
        return {
            "tip_growth_speeds_rad_s": np.asarray(speeds, dtype=float).tolist(),
            "tip_growth_min_m": g.min(axis=1).tolist(),
            "tip_growth_max_m": g.max(axis=1).tolist(),
            "tip_growth_mean_m": g.mean(axis=1).tolist(),
        }


def write_campbell(res: CampbellResult, out, *, engine_orders: int | None = None) -> dict:
    """Write ``campbell.csv``, ``campbell.json`` and ``campbell.png`` into ``out``; a
    diagram whose self-check failed as ``campbell-failed.csv`` and ``campbell-failed.png``,
    with ``"status": "failed"`` in ``campbell.json`` (module docstring)."""
    from ..output.campbell import plot_campbell

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    failed = res.info.get("status") == "failed"
    stem = "campbell-failed" if failed else "campbell"
    n = res.frequencies.shape[1]
    header = "speed_rad_s,speed_rpm," + ",".join(f"f{j + 1}_hz" for j in range(n))
    table = np.column_stack([res.speeds, res.speeds * 30 / np.pi, res.frequencies])
    np.savetxt(out / f"{stem}.csv", table, delimiter=",", header=header, comments="", fmt="%.8g")
    doc = {
        "method": res.method,
        "speeds_rad_s": [res.speeds.min(), res.speeds.max()],
        "n_speeds": int(res.speeds.size),
        "modes": n,
        "files": [f"{stem}.csv", f"{stem}.png"],
        **res.info,
    }
    (out / "campbell.json").write_text(json.dumps(doc, indent=2, default=float))
    title = f"Campbell diagram ({res.method} prestress)"
    if failed:
        title = f"FAILED self-check: {100 * res.info['check_max_relative_error']:.3g} % error"
    plot_campbell(
        res.speeds, res.frequencies, out / f"{stem}.png", engine_orders=engine_orders, title=title
    )
    return doc
