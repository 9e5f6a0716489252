"""Reduction of a scene's model: none, given sizes, or sizes picked from a target error.

``reduction.method = "auto"`` builds one thermoelastic Craig–Bampton reductor with the
largest sizes allowed (``max_n_uv``, ``max_n_theta``) and keeps the smallest truncation of
its bases that meets ``target``:

* mechanical shapes: the first ``modes`` natural frequencies of the Craig–Bampton
  displacement basis (Rayleigh–Ritz on ``K``, ``M``, contact dofs free) against those of the
  full model, relative error <= target; ``n_uv`` = 2 × the number of modes kept;
* thermal modes: the contact-temperature response to the frictional heat input of the
  contacts, ``H_ii(s) = q_iᵀ (s C^θθ + K^θθ)⁻¹ q_i`` (the temperature of contact i heated
  by itself), of the Craig–Bampton temperature basis against the full one at ``s = 0``
  (static, exact by construction) and ``s = 1/t_end, 10/t_end``, largest relative error
  <= target. It converges slowly (the static shapes load the boundary with interior heat
  capacity) and the simulated temperature error is mostly set by the mechanical shapes, so
  the thermal target is often missed at ``max_n_theta``: the report says so.

The model is then reduced once more with the chosen sizes.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..fem import eigen
from ..scene.spec import SceneError, fail
from .blocks import contact_boundary, split_blocks
from .craig_bampton import ThermoelasticCraigBampton

__all__ = ["natural_frequencies", "reduce_model"]


def natural_frequencies(model, k: int) -> np.ndarray:
    """The ``k`` lowest natural frequencies (Hz) of a full model, contacts free."""
    b = split_blocks(model)
    return eigen.natural_frequencies(b.K, b.M, k)


def _freq_error(K, M, V, nb, k, ref, modes) -> float:
    Vk = V[:, : nb + k]
    if Vk.shape[1] < modes:
        return np.inf
    Kr, Mr = Vk.T @ (K @ Vk), Vk.T @ (M @ Vk)
    lam = sla.eigh(Kr, Mr, eigvals_only=True, subset_by_index=[0, modes - 1])
    f = np.sqrt(np.clip(lam, 0.0, None)) / (2.0 * np.pi)
    scale = np.maximum(ref, 1e-9 * ref.max() + 1e-300)
    return float(np.max(np.abs(f - ref) / scale))


def _thermal_errors(C, K, Q, T, ntb, n_max, svals) -> list[float]:
    full = []
    for s in svals:
        lu = spla.splu(sp.csc_matrix(s * C + K))
        full.append(np.einsum("ij,ij->j", Q, lu.solve(Q)))
    errs = []
    for k in range(n_max + 1):
        Tk = T[:, : ntb + k]
        Qk = Tk.T @ Q
        e = 0.0
        for s, H in zip(svals, full):
            Ar = Tk.T @ ((s * C + K) @ Tk)
            Hr = np.einsum("ij,ij->j", Qk, np.linalg.solve(Ar, Qk))
            e = max(e, float(np.max(np.abs(H - Hr) / np.maximum(np.abs(H), 1e-300))))
        errs.append(e)
    return errs


def _auto_sizes(model, opts: dict, t_end: float, report: dict) -> tuple[int, int]:
    L = model.layout
    mb, tb = contact_boundary(model)
    n_i, n_ti = L.n_u - mb.size, L.n_t - tb.size
    max_uv = min(opts["max_n_uv"], 2 * n_i) // 2 * 2
    max_t = min(opts["max_n_theta"], n_ti) if L.n_t else 0
    red = ThermoelasticCraigBampton(model, max_uv, max_t, projection=opts["projection"])
    b = split_blocks(model)
    target, modes = opts["target"], min(opts["modes"], L.n_u)
    ref = natural_frequencies(model, modes)
    V = red.mechanical_basis()
    errs = [_freq_error(b.K, b.M, V, mb.size, k, ref, modes) for k in range(max_uv // 2 + 1)]
    k_uv = next((k for k, e in enumerate(errs) if e <= target), len(errs) - 1)
    report.update(
        natural_frequencies_hz=ref.tolist(),
        frequency_error=errs[k_uv],
        frequency_target_met=bool(errs[k_uv] <= target),
    )
    n_theta = 0
    Q = model.contact.Ht[L.t] if (model.contact is not None and L.n_t) else np.zeros((L.n_t, 0))
    if max_t and Q.size and np.any(Q):
        svals = [0.0, 1.0 / t_end, 10.0 / t_end]
        terrs = _thermal_errors(b.Ctt, b.Ktt, Q, red.thermal_basis(), tb.size, max_t, svals)
        n_theta = next((k for k, e in enumerate(terrs) if e <= target), len(terrs) - 1)
        report.update(thermal_error=terrs[n_theta], thermal_target_met=terrs[n_theta] <= target)
    return 2 * k_uv, n_theta


def reduce_model(model, scene, log=None):
    """Reduce ``model`` as ``scene["reduction"]`` asks; return ``(model, reductor, report)``."""
    opts = scene["reduction"]
    method = opts["method"]
    if method == "none":
        return model, None, {"method": "none"}
    if model.layout.n_t and scene["material"]["conductivity"] == 0.0:
        fail(
            "material.conductivity",
            0.0,
            "the thermal Craig-Bampton reduction needs a "
            "conducting blade (K^θθ is singular); use > 0 or reduction.method = 'none'",
        )
    report = {"method": method, "projection": opts["projection"], "n_full": model.n_dofs}
    if log:
        log(f"reduction ({method}) of {model.n_dofs} dofs ...")
    if method == "auto":
        n_uv, n_theta = _auto_sizes(model, opts, scene["scheme"]["t_end"], report)
        report["target"] = opts["target"]
    else:
        n_uv, n_theta = opts["n_uv"], opts["n_theta"]
        if model.layout.n_t == 0 and n_theta:
            report["note"] = f"reduction.n_theta = {n_theta} ignored: no temperature dofs"
            n_theta = 0
    try:
        red = ThermoelasticCraigBampton(model, n_uv, n_theta, projection=opts["projection"])
    except ValueError as exc:
        text = str(exc)
        key = next((f"reduction.{k}" for k in ("n_theta", "n_uv") if k in text), None)
        raise SceneError(f"{key or f'reduction.method = {method!r}'}: {text}") from None
    reduced = red.reduce()
    report.update(
        n_uv=n_uv,
        n_theta=n_theta,
        n_reduced=reduced.n_dofs,
        n_boundary_u=int(red.boundary["u"].size),
        n_boundary_theta=int(red.boundary["theta"].size),
    )
    return reduced, red, report
