"""Campbell diagram of a scene's blade: natural frequencies against rotation speed.

``femrub campbell SCENE --speeds 0:1800:10 -o DIR`` writes ``DIR/campbell.csv``,
``DIR/campbell.png`` and ``DIR/campbell.json``. The blade is built as for a run (mesh,
material, lumping; no contact), then:

1. the centrifugal prestress (``loads.centrifugal``; ``"auto"`` and ``"off"``: nonlinear,
   ``"off"`` being a choice for runs: a diagram without prestress has flat lines) is solved
   at every requested speed on a reduced basis whose full residual is certified at each
   speed (:mod:`femrub.fem.prestress_rom`);
2. the lowest ``modes + 4`` modes of the full prestressed tangent at ``samples`` speeds
   (equally spaced in ``Ω²``: by default at rest, halfway in ``Ω²`` and at the largest speed),
   M-orthonormalised together, span a Ritz basis ``W``; at every speed the small problem
   ``Wᵀ K_T(Ω) W y = ω² y`` (the tangent of that speed's prestress, projected exactly) gives
   the frequencies, and each line follows its mode from one speed to the next by the
   largest MAC among the ``modes`` lowest (an assignment, so lines may cross where modes
   veer);
3. the self-check: at every speed the residual of each Ritz pair on the full mesh bounds
   the relative error of its frequency (:mod:`femrub.fem.speed_modes`: Kato–Temple in the
   norm of the nearest factorised tangent). Where a bound exceeds ``tolerance``
   (:data:`TOLERANCE`, 0.5 %), the full modes at the worst speed join ``W`` and every speed
   is evaluated again, up to ``max_samples`` samples.

``--exact`` (``exact=True``) skips the interpolation: the full prestress, warm-started from
the previous speed's, and the full eigen-solve at every requested speed (status
``"exact"``; one prestress and one factorisation per speed).

The diagram's ``status`` (``campbell.json``): ``"ok"`` when every frequency's bound is
within the tolerance (``max_error_bound``, per speed ``error_bounds``), ``"failed"``
otherwise (``femrub campbell`` then exits 1 with a one-line error
and writes ``campbell-failed.csv`` and ``campbell-failed.png``, never the files of a
diagram that passed), ``"unchecked"`` with ``--no-check``, ``"exact"`` with ``--exact`` or
at rest only.

The tip growth (``tip_growth_*_m``, at every speed ``tip_growth_speeds_rad_s``) is measured
as a run measures it:
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
from scipy.optimize import linear_sum_assignment

from ..contact.points import locate_contacts
from ..fem.discretisation import assemble, discretise
from ..fem.eigen import lowest_modes
from ..fem.linalg import sparse_lu
from ..fem.prestress import centrifugal_prestress
from ..fem.speed_modes import EXTRA_MODES, speed_modes
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

#: largest relative error of a checked frequency (0.5 %)
TOLERANCE = 0.005
#: most full modal samples the self-check adds up to
MAX_SAMPLES = 12


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

    ``samples``: the first full modal samples (>= 2, equally spaced in Ω²); ``check``:
    bound every frequency's error by its residual, adding samples up to ``max_samples``
    until every bound is within ``tolerance`` (relative); the result's ``status`` says
    whether it is (``info["status"]``, ``info["message"]``). ``exact``: the full prestress
    (warm-started along the list) and eigen-solve at every speed instead.
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
    growth = _Growth(disc, scene)
    if exact and method != "off":
        k = min(modes + EXTRA_MODES, mats.n_u - 1)
        solve = _Solver(disc, material, mats, method, k, log)
        freqs, info = _exact_diagram(solve, speeds, modes, growth)
        method_samples = speeds
    else:
        options = {
            "samples": samples,
            "tolerance": float(tolerance),
            "max_samples": max(int(max_samples), int(samples)),
            "check": check,
        }
        freqs, info = _reduced_diagram(
            (disc, material, mats, method), speeds, modes, options, growth, log
        )
        method_samples = np.asarray(info["sample_speeds"])
    info["n_free_dofs"] = int(mats.n_u)
    info["seconds"] = time.perf_counter() - t0
    return CampbellResult(speeds, freqs, method, method_samples, info)


def _reduced_diagram(blade_parts, speeds, modes, options, growth, log):
    """The diagram from the certified reduced prestress and Ritz basis (module docstring)."""
    disc, material, mats, method = blade_parts
    sm = speed_modes(
        disc,
        material,
        mats,
        "nonlinear" if method == "off" else method,
        speeds,
        modes=modes,
        samples=options["samples"],
        tolerance=options["tolerance"],
        max_samples=options["max_samples"],
        check=options["check"],
        log=log,
    )
    freqs, worst = _lines(sm, modes)
    growths = np.array([growth.at_displacement(u) for u in sm.displacements])
    info = {
        "basis_size": sm.ritz_basis,
        "prestress_basis_size": sm.static_basis,
        "prestress_residual_max": float(sm.eta.max()),
        "sample_speeds": sm.sample_speeds,
        "worst_tracking_mac": worst,
        "rest_frequencies_hz": sm.rest_frequencies.tolist(),
        **_verdict(method, options, sm, speeds),
        **growth.table(growths, speeds),
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


def _lines(sm, modes: int):
    """Frequencies (n_speeds, modes) of the tracked lines (MAC among the ``modes`` lowest
    Ritz pairs from one speed to the next) and the worst tracking MAC; the bounds follow."""
    freqs, q_prev, worst = [], None, 1.0
    for f, Q in zip(sm.frequencies, sm.shapes, strict=True):
        if q_prev is None:
            order = np.arange(modes)
        else:
            order, mac = _track(q_prev, Q, modes)
            worst = min(worst, float(mac))
        q_prev = Q[:, order]
        freqs.append(f[order])
    return np.array(freqs), worst


def _verdict(method, options, sm, speeds) -> dict:
    """``status`` and ``message`` of the diagram and its certificate (module docstring)."""
    if method == "off":
        return {"status": "exact", "message": "at rest: the full eigen-solve"}
    if not options["check"]:
        return {"status": "unchecked", "message": "frequency bounds not computed (--no-check)"}
    tolerance = options["tolerance"]
    per_speed = sm.bounds.max(axis=1)
    i = int(np.argmax(per_speed))
    out = {
        "tolerance": tolerance,
        "error_bounds": per_speed.tolist(),
        "max_error_bound": float(per_speed[i]),
        "error_bound_speed": float(speeds[i]),
    }
    samples = len(sm.sample_speeds)
    if per_speed[i] <= tolerance:
        msg = (
            f"every frequency within {100 * per_speed[i]:.2g} % (tolerance "
            f"{100 * tolerance:g} %) by its residual bound and the prestress estimate, "
            f"{samples} full modal samples"
        )
        return {"status": "ok", "message": msg, **out}
    msg = (
        f"self-check failed: a frequency bound of {100 * per_speed[i]:.3g} % at "
        f"{speeds[i]:.6g} rad/s exceeds the tolerance {100 * tolerance:g} % with {samples} "
        "modal samples; raise --max-samples"
    )
    return {"status": "failed", "message": msg, **out}


class _Growth:
    """Radial tip growth at the scene's contacts (m), as a run measures it (module
    docstring): ``at(state)`` per contact, ``table`` over speeds."""

    def __init__(self, disc, scene):
        self.points = locate_contacts(disc, spread=scene["contact"]["spread"])

    def at(self, state) -> np.ndarray:
        return np.zeros(self.points.n) if state is None else state.growth(self.points)

    def at_displacement(self, u) -> np.ndarray:
        return self.points.normal_displacement(u)

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
        title = f"FAILED self-check: error bound {100 * res.info['max_error_bound']:.3g} %"
    plot_campbell(
        res.speeds, res.frequencies, out / f"{stem}.png", engine_orders=engine_orders, title=title
    )
    return doc
