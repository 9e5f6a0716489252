"""Campbell diagram of a scene's blade: natural frequencies against rotation speed.

``femrub campbell SCENE --speeds 0:1800:10 -o DIR`` writes ``DIR/campbell.csv``,
``DIR/campbell.png`` and ``DIR/campbell.json``. The blade is built as for a run (mesh,
material, lumping; no contact), then:

1. the centrifugal prestress (``loads.centrifugal``; ``"auto"`` and ``"off"``: nonlinear,
   ``"off"`` being a choice for runs: a diagram without prestress has flat lines) is solved at
   ``samples`` speeds equally spaced in ``Ω²`` up to the largest speed asked for
   (:func:`~femrub.fem.speed_family.speed_family`);
2. the lowest ``modes + 4`` clamped modes at every sample speed, M-orthonormalised
   together, span a reduced basis ``V``; ``K_T(Ω)`` is interpolated in ``Ω²`` on it;
3. at every speed the small problem ``Vᵀ K_T(Ω) V q = ω² q`` gives the frequencies, and
   each line follows its mode from one speed to the next by the largest MAC (an
   assignment, so lines may cross where modes veer);
4. ``check``: at a speed between the samples the full prestress and full eigen-problem
   are solved and the largest relative error of the interpolated frequencies is reported.

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
from ..fem.speed_family import sample_speeds, speed_family
from ..scene.spec import SceneError
from . import translate as tr
from .blade import load_blade

__all__ = ["CampbellResult", "campbell", "parse_speeds", "write_campbell"]

#: extra modes per sample speed in the reduced basis
EXTRA_MODES = 4


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


def _track(Q_prev, Q, n):
    """Columns of ``Q`` following the ``n`` columns of ``Q_prev`` (largest MAC)."""
    mac = (Q_prev.T @ Q) ** 2 / np.outer(np.sum(Q_prev**2, axis=0), np.sum(Q**2, axis=0))
    rows, cols = linear_sum_assignment(-mac[:n])
    return cols[np.argsort(rows)], mac[rows, cols].min()


def campbell(
    scene, speeds, *, modes: int = 6, samples: int = 3, check: bool = True, log=None
) -> CampbellResult:
    """Campbell diagram of ``scene`` at ``speeds`` (module docstring)."""
    speeds = np.asarray(speeds, dtype=float)
    if speeds.size == 0 or np.any(speeds < 0) or not np.all(np.isfinite(speeds)):
        raise SceneError("--speeds: give finite speeds >= 0 (rad/s)")
    if tr.is_bar(scene):
        raise SceneError("geometry.kind = 'bar': a Campbell diagram needs a 3D blade")
    t0 = time.perf_counter()
    blade = load_blade(scene, log)
    disc = discretise(blade, scene["physics"]["order"])
    material = tr.material_of(scene)
    mats = assemble(disc, material, lumping=scene["physics"]["lumping"]).mechanical()
    mode = scene["loads"]["centrifugal"]
    method = "nonlinear" if mode in ("auto", "off") else mode
    if mode == "off" and log:  # e.g. the Rotor 37 scenes: off for their runs only
        log(
            "notice: loads.centrifugal = 'off' applies to runs; the Campbell diagram uses the "
            "nonlinear prestress (--set loads.centrifugal=linear for the linear one)"
        )
    top = float(speeds.max())
    if top == 0.0:
        method, samples = "off", 1
        from ..fem.speed_family import SpeedFamily

        fam = SpeedFamily(np.zeros(1), [mats.K], np.zeros((1, 0)), "off")
    else:
        samples = 2 if method == "linear" else max(int(samples), 2)
        fam = speed_family(disc, material, sample_speeds(top, samples), method, log=log)
    t_pre = time.perf_counter()
    k = min(modes + EXTRA_MODES, mats.n_u - 1)
    shapes = [lowest_modes(K, mats.M, k, _solver(K))[1] for K in fam.stiffness]
    V = _m_orthonormal(np.hstack(shapes), mats.M)
    red = fam.project(V) if method != "off" else None
    Kr0 = V.T @ (mats.K @ V)
    freqs, q_prev, worst = [], None, 1.0
    for omega in speeds:
        Kr = red.stiffness_at(omega) if red is not None else Kr0
        lam, Q = sla.eigh(0.5 * (Kr + Kr.T))
        f = np.sqrt(np.clip(lam, 0.0, None)) / (2 * np.pi)
        if q_prev is None:
            order = np.arange(modes)
        else:
            order, mac = _track(q_prev, Q, modes)
            worst = min(worst, float(mac))
        q_prev = Q[:, order]
        freqs.append(f[order])
    freqs = np.array(freqs)
    info = {
        "n_free_dofs": int(mats.n_u),
        "basis_size": int(V.shape[1]),
        "sample_speeds": fam.speeds.tolist(),
        "worst_tracking_mac": worst,
        "rest_frequencies_hz": (
            np.sqrt(lowest_modes(Kr0, np.eye(V.shape[1]), modes, vectors=False)) / (2 * np.pi)
        ).tolist(),
        "seconds_prestress": t_pre - t0,
    }
    if method != "off":
        pts = locate_contacts(disc)
        g = pts.normal_displacement(fam.displacement)
        info["tip_growth_max_m"] = g.max(axis=1).tolist()  # per sample speed
        info["tip_growth_mean_m"] = g.mean(axis=1).tolist()
    if check and method != "off" and samples > 1:
        info.update(_check(disc, material, mats, fam, red, method, modes, log))
    info["seconds"] = time.perf_counter() - t0
    return CampbellResult(speeds, freqs, method, fam.speeds, info)


def _check(disc, material, mats, fam, red, method, modes, log) -> dict:
    """Full prestress and eigen-solve between the two top samples against the interpolation."""
    s = fam.speeds**2
    omega = float(np.sqrt(0.5 * (s[-1] + s[-2])))
    if log:
        log(f"checking the interpolation at {omega:.6g} rad/s (full prestress and modes) ...")
    full = centrifugal_prestress(disc, material, omega, method, log=log)
    lam = lowest_modes(full.K, mats.M, modes, _solver(full.K), vectors=False)
    f_full = np.sqrt(lam) / (2 * np.pi)
    Kr = red.stiffness_at(omega)
    f_red = np.sqrt(np.clip(sla.eigh(0.5 * (Kr + Kr.T), eigvals_only=True)[:modes], 0, None))
    f_red /= 2 * np.pi
    err = float(np.max(np.abs(f_red - f_full) / f_full))
    return {
        "check_speed": omega,
        "check_full_hz": f_full.tolist(),
        "check_interpolated_hz": f_red.tolist(),
        "check_max_relative_error": err,
    }


def write_campbell(res: CampbellResult, out, *, engine_orders: int | None = None) -> dict:
    """Write ``campbell.csv``, ``campbell.json`` and ``campbell.png`` into ``out``."""
    from ..output.campbell import plot_campbell

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    n = res.frequencies.shape[1]
    header = "speed_rad_s,speed_rpm," + ",".join(f"f{j + 1}_hz" for j in range(n))
    table = np.column_stack([res.speeds, res.speeds * 30 / np.pi, res.frequencies])
    np.savetxt(out / "campbell.csv", table, delimiter=",", header=header, comments="", fmt="%.8g")
    doc = {
        "method": res.method,
        "speeds_rad_s": [res.speeds.min(), res.speeds.max()],
        "n_speeds": int(res.speeds.size),
        "modes": n,
        **res.info,
    }
    (out / "campbell.json").write_text(json.dumps(doc, indent=2, default=float))
    plot_campbell(
        res.speeds,
        res.frequencies,
        out / "campbell.png",
        engine_orders=engine_orders,
        title=f"Campbell diagram ({res.method} prestress)",
    )
    return doc
