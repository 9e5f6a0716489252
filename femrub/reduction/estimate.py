"""A-posteriori error estimate of a reduced run, on sub-bases of one reductor.

A reduced model of sizes ``(n_uv, n_θ)`` is a truncation of the bases of a reductor built
at larger sizes ``(N_uv, N_θ)``. Its error against the full model is estimated by the
difference with the richer model of the same reductor (hierarchical estimate, saturation
assumption: the richer model is much closer to the full one than the run's)::

    e_run ≈ ‖y_run − y_ref‖ / ‖y_ref‖,     y = R_sizes X̄_sizes (reconstructed on the mesh)

for the quantities users read:

* ``contact_force``: the contact impulse of each contact summed over each lobe passage
  (``window`` seconds; the whole run when no lobe), ``‖ΔI‖_F / ‖I_ref‖_F``;
* ``contact_temperature``: the contact temperatures ``Qᵀ θ`` at every step,
  ``max_t ‖ΔT_c‖_∞ / max_t ‖T_c,ref‖_∞``;
* ``displacement`` and ``temperature``: the fields at ``checkpoints`` times,
  ``max_k ‖Δu(t_k)‖_M / max_k ‖u_ref(t_k)‖_M`` (mass-weighted L2 over the blade; heat
  capacity for θ), and at the final checkpoint ``‖Δu(t_end)‖_M / ‖u_ref(t_end)‖_M``
  (``displacement_end``, ``temperature_end``: the fields a user looks at when the run ends,
  whose norm can be a fraction of the largest).

Both models are stepped with the scene's scheme and step. The same comparison against the
full model is :func:`compare` (benchmarks/reduction_convergence_3d.py).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["QUANTITIES", "compare", "estimate", "field_norms", "reference_sizes", "simulate"]

#: Relative errors reported (``summary.json["reduction_error"]``); the first three decide.
QUANTITIES = (
    "contact_force",
    "contact_temperature",
    "displacement",
    "temperature",
    "displacement_end",
    "temperature_end",
)
DECISIVE = ("contact_force", "contact_temperature", "displacement", "displacement_end",
            "temperature_end")  # fmt: skip


def reference_sizes(n_uv: int, n_theta: int, most: tuple[int, int]) -> tuple[int, int]:
    """Sizes of the reference model: twice the run's (at least 4 more shapes), within ``most``."""
    r_uv = min(max(2 * n_uv, n_uv + 4), most[0]) // 2 * 2
    return max(r_uv, min(n_uv, most[0])), min(max(2 * n_theta, n_theta + 4), most[1])


def field_norms(full) -> dict:
    """Weights of the field norms on a full model's state: ``M`` on u, ``C^θθ`` on θ."""
    b, L = full.blocks, full.layout
    out = {"u": (L.u, sp.csr_matrix(b.M))}
    if L.n_t:
        out["theta"] = (L.t, sp.csr_matrix(b.Ctt))
    return out


def _windows(t: np.ndarray, impulse: np.ndarray, window: float) -> np.ndarray:
    """Impulse of each contact summed over consecutive windows of ``window`` seconds."""
    if impulse.size == 0:
        return np.zeros((1, 0))
    if not window or window <= 0 or not np.isfinite(window):
        return impulse.sum(axis=0, keepdims=True)
    k = np.floor((t - t[0]) / window * (1 - 1e-12)).astype(int)
    out = np.zeros((k.max() + 1, impulse.shape[1]))
    np.add.at(out, k, impulse)
    return out


def _rel(diff: float, ref: float) -> float:
    return float(diff / ref) if ref > 0 else (0.0 if diff == 0 else float("inf"))


def compare(run, ref, fields_run, fields_ref, norms: dict, window: float) -> dict:
    """Relative differences of ``run`` against ``ref`` (module docstring).

    ``fields_*``: (m, N_full) full states at the stored times of each result (the same
    times); ``norms``: :func:`field_norms` of the full model.
    """
    out = {}
    m = min(fields_run.shape[0], fields_ref.shape[0])
    fields_run, fields_ref = fields_run[:m], fields_ref[:m]
    Ia, Ib = _windows(run.t, run.impulse, window), _windows(ref.t, ref.impulse, window)
    n = min(len(Ia), len(Ib))
    out["contact_force"] = _rel(np.linalg.norm(Ia[:n] - Ib[:n]), np.linalg.norm(Ib[:n]))
    key = "contact_temperature" if "contact_temperature" in ref.signals else "tip_temperature"
    if key in ref.signals and key in run.signals:
        k = min(len(run.t), len(ref.t))
        a, b = run.signals[key][:k], ref.signals[key][:k]
        out["contact_temperature"] = _rel(np.abs(a - b).max(), np.abs(b).max())
    for name, field in (("displacement", "u"), ("temperature", "theta")):
        if field not in norms:
            continue
        sl, W = norms[field]
        A, B = fields_run[:, sl], fields_ref[:, sl]
        D = A - B
        dn = np.sqrt(np.einsum("ij,ij->i", D, (W @ D.T).T))
        bn = np.sqrt(np.einsum("ij,ij->i", B, (W @ B.T).T))
        out[name] = _rel(dn.max(), bn.max())
        out[name + "_end"] = _rel(dn[-1], bn[-1])
    return out


def simulate(reductor, sizes, make_stepper, t_end, checkpoints=5):
    """Step ``reductor.reduce(*sizes)``; return the results and the full states stored."""
    st = make_stepper(reductor.reduce(*sizes))
    every = max(1, st.steps_to(t_end) // checkpoints)
    res = st.run(t_end, store_every=every)
    return res, reductor.reconstruct(res.states, *sizes)


def estimate(run, ref, fom, *, window=0.0) -> dict:
    """Estimated relative errors of ``run`` against the richer ``ref`` (module docstring).

    ``run``, ``ref``: ``(sizes, results, full states)`` of :func:`simulate`; ``fom``: the
    full model (field norms). Returns the errors (:data:`QUANTITIES`), ``estimate`` (the
    largest of the decisive ones) and what they were measured on.
    """
    (sa, a, Xa), (sb, b, Xb) = run, ref
    errs = compare(a, b, Xa, Xb, field_norms(fom), window)
    decisive = [errs[k] for k in DECISIVE if k in errs]
    return {
        **errs,
        "estimate": float(max(decisive)) if decisive else 0.0,
        "method": "hierarchical: difference to a richer sub-basis model of the same reductor",
        "sizes": list(sa),
        "reference_sizes": list(sb),
        "checkpoints": [float(x) for x in a.state_times],
        "window": float(window),
        "status_run": a.status,
        "status_reference": b.status,
    }
