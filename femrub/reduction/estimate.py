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

Both models are stepped with the scene's scheme and step, and stop at the run's stop limits
(the estimate covers what the run itself can reach), by the analysis layer
(:mod:`femrub.analysis.reduction_check`); this module only compares given results. The same
comparison against the full model is :func:`compare` (benchmarks/reduction_convergence_3d.py).

*Sensitive (chaotic) responses.* A long frictional rub can be sensitive to its initial
state: on Rotor 37 a 1e-15 m perturbation grows tenfold every five revolutions and the two
trajectories differ by 5–15 % after 25. Two runs of the same model then differ as much as
two sizes do, and a pointwise difference measures the chaos, not the reduction. When the
pointwise estimate fails, a twin of the reference (same model, displacement perturbed by
:data:`PERTURBATION` m, :func:`perturbed`) is stepped. Its distance to the reference is the
``sensitivity`` floor; the *predictability horizon* ``t_p`` is the first stored time at
which the twin's signals differ from the reference's by more than :data:`HORIZON_SHARE` of
the tolerance or have grown :data:`AMPLIFICATION` times past their difference over the
first lobe passage (beyond, the dynamics amplify any difference between two models: on
Rotor 37 tenfold every 1.5 revolutions), or at which the run's own difference to the
reference has grown :data:`AMPLIFICATION` times past its value over the first lobe passage
(two models start further apart than the twin, so the dynamics amplify their difference
sooner: with the twin's horizon alone a richer, closer basis could be judged pointwise
longer, into its amplified difference, and fail where a coarser one passed). The estimate
is then

* pointwise (as above) on ``[0, t_p]`` (``contact_force`` per lobe passage, signals), and
* statistical on ``[t_p, t_end]``: per contact, the mean and largest normal force and the
  RMS and largest value of each contact signal (``statistics``),

and the run is judged by the larger of the two (``"method"`` says which was used).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = [
    "QUANTITIES",
    "compare",
    "compare_windows",
    "estimate",
    "field_norms",
    "perturbed",
    "reference_sizes",
    "statistics",
]

#: Relative errors reported (``summary.json["reduction_error"]``); the first three decide.
QUANTITIES = (
    "contact_force",
    "contact_temperature",
    "displacement",
    "temperature",
    "displacement_end",
    "temperature_end",
)
DECISIVE = (
    "contact_force",
    "contact_temperature",
    "displacement",
    "displacement_end",
    "temperature_end",
)
#: displacement perturbation (m, random on the u-coordinates) of the sensitivity twin
PERTURBATION = 1e-15
#: the predictable horizon ends where the twin differs by this share of the tolerance
HORIZON_SHARE = 0.1
#: ... or where its difference has grown this many times past the first lobe passage's:
#: beyond, any difference between two models is amplified by the dynamics, not the reduction's
AMPLIFICATION = 10.0
#: signals compared statistically after the horizon (those present)
SIGNALS = ("contact_displacement", "contact_temperature", "tip_displacement")


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


def _temperature_key(res) -> str:
    """The contact temperature signal compared: each contact's, else the tip's mean."""
    return "contact_temperature" if "contact_temperature" in res.signals else "tip_temperature"


def _rel(diff: float, ref: float) -> float:
    return float(diff / ref) if ref > 0 else (0.0 if diff == 0 else float("inf"))


def _impulse_error(run, ref, window: float, k1: int | None = None) -> float:
    """``‖ΔI‖_F / ‖I_ref‖_F`` of the impulses per window of steps ``:k1`` (module docstring)."""
    Ia = _windows(run.t[:k1], run.impulse[:k1], window)
    Ib = _windows(ref.t[:k1], ref.impulse[:k1], window)
    n = min(len(Ia), len(Ib))
    return _rel(np.linalg.norm(Ia[:n] - Ib[:n]), np.linalg.norm(Ib[:n]))


def compare(run, ref, fields_run, fields_ref, norms: dict, window: float) -> dict:
    """Relative differences of ``run`` against ``ref`` (module docstring).

    ``fields_*``: (m, N_full) full states at the stored times of each result (the same
    times); ``norms``: :func:`field_norms` of the full model.
    """
    out = {}
    m = min(fields_run.shape[0], fields_ref.shape[0])
    fields_run, fields_ref = fields_run[:m], fields_ref[:m]
    out["contact_force"] = _impulse_error(run, ref, window)
    key = _temperature_key(ref)
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


def compare_windows(run, refs, windows, fields_run, fields_ref, norms: dict, window: float):
    """Relative differences of ``run`` against references stepped over ``windows`` only.

    Each reference ``refs[j]`` started from the run's own state at the step ``windows[j][0]``
    (its :class:`~femrub.output.results.Snapshot`) and ran to the step ``windows[j][1]``,
    its states stored at both ends (on the run's steps: ``lean`` rows). What a window
    measures is what the models add over it from one state, the error a run makes per
    window rather than its accumulation: ``contact_force`` the impulse per lobe passage of
    every window together; ``contact_temperature`` and ``temperature`` the difference over
    the temperature each window adds (the rise of the reference over it: the temperature of
    a long run is its whole history's sum); ``displacement`` the fields at the windows' ends;
    ``displacement_end`` the last window's; ``temperature_end`` the windows' differences
    summed over what they add (the relative error of the temperature a run sums up).
    ``fields_*``: full states of rows of reduced states (each called once, on every
    window's states together).
    """
    snaps = {s.step: s for s in run.snapshots}
    bins, temp, ends, fields = [], [], [], []
    for (k0, k1), ref in zip(windows, refs, strict=False):
        n = min(k1 - k0, len(ref.t) - 1, len(run.t) - 1 - k0)
        if n < 1:
            break
        a = slice(k0 + 1, k0 + n + 1)
        bins.append(
            (
                _windows(run.t[a], run.impulse[a], window),
                _windows(ref.t[1 : n + 1], ref.impulse[1 : n + 1], window),
            )
        )
        key = _temperature_key(ref)
        if key in ref.signals and key in run.signals:
            x, y = run.signals[key][k0 : k0 + n + 1], ref.signals[key][: n + 1]
            temp.append((np.abs(x - y).max(), np.abs(y - y[0]).max()))
        if n == k1 - k0 and ref.states is not None and len(ref.states) >= 2 and k1 in snaps:
            ends.append((snaps[k0].X, snaps[k1].X, ref.states[-1]))
    if ends:  # one product with each basis for every window (reading a basis is the cost)
        run_ends = fields_run(np.stack([x for start, end, _ in ends for x in (start, end)]))
        ref_ends = fields_ref(np.stack([x for *_, x in ends]))
        fields = [(run_ends[2 * j], run_ends[2 * j + 1], ref_ends[j]) for j in range(len(ends))]
    out = {"contact_force": _binned_error(bins)}
    if temp:
        out["contact_temperature"] = _rel(max(d for d, _ in temp), max(r for _, r in temp))
    for name, field in (("displacement", "u"), ("temperature", "theta")):
        if field in norms and fields:
            out.update(_window_fields(name, field, fields, norms[field]))
    return out


def _binned_error(bins) -> float:
    """``‖ΔI‖_F / ‖I_ref‖_F`` over the lobe passages of every window."""
    if not bins:
        return 0.0
    diff = sum(
        float(np.sum((a[: min(len(a), len(b))] - b[: min(len(a), len(b))]) ** 2)) for a, b in bins
    )
    ref = sum(float(np.sum(b**2)) for _, b in bins)
    return _rel(np.sqrt(diff), np.sqrt(ref))


def _window_fields(name: str, field: str, fields, norm) -> dict:
    """The field measures of :func:`compare_windows`: at the windows' ends, relative to the
    field (displacement) or to what the window added to it (temperature)."""
    sl, W = norm
    rise = field == "theta"

    def size(v):
        return float(np.sqrt(v[sl] @ (W @ v[sl])))

    diff = [size(end - ref) for _, end, ref in fields]
    scale = [size(ref - start) if rise else size(ref) for start, _, ref in fields]
    # the temperature a run ends with is the sum of what its windows add: their errors
    # summed over what they add (a window that adds little heat weighs little)
    end = _rel(sum(diff), sum(scale)) if rise else _rel(diff[-1], scale[-1])
    return {name: _rel(max(diff), max(scale)), name + "_end": end}


def perturbed(model):
    """``model`` with :data:`PERTURBATION` (m) of random displacement added to its initial
    state (the round-off twin of a sensitive response)."""
    x0 = np.array(model.x0, dtype=float)
    x0[model.layout.u] += PERTURBATION * np.random.default_rng(0).standard_normal(model.layout.n_u)
    return model.with_(x0=x0)


def _signal_pairs(a, b, k1: int):
    """``(x, y)``: each contact signal (:data:`SIGNALS`) of ``a`` and ``b`` on steps ``:k1``."""
    k1 = min(k1, len(a.t), len(b.t))
    for key in SIGNALS:
        if key in a.signals and key in b.signals:
            yield a.signals[key][:k1], b.signals[key][:k1]


def _signal_gap(a, b, k1: int) -> float:
    """Largest relative difference of the contact signals of ``a`` and ``b`` on steps ``:k1``
    (each signal relative to its largest reference value)."""
    out = 0.0
    for x, y in _signal_pairs(a, b, k1):
        if len(y):
            out = max(out, _rel(np.abs(x - y).max(), np.abs(y).max()))
    return out


def _departure(a, ref) -> np.ndarray:
    """Relative difference of the contact signals of ``a`` and ``ref`` at each step (each
    signal relative to its largest reference value)."""
    n = min(len(a.t), len(ref.t))
    d = np.zeros(n)
    for x, y in _signal_pairs(a, ref, n):
        scale = np.abs(y).max()
        if scale > 0:
            d = np.maximum(d, np.abs(x - y).reshape(n, -1).max(axis=1) / scale)
    return d


def _horizon(tw, ref, share: float, first: int) -> int:
    """Predictability horizon (a step): where the twin's signals have grown
    :data:`AMPLIFICATION` times past their largest difference over the first ``first``
    steps, or leave the reference by ``share``, whichever comes first (or the end)."""
    d = _departure(tw, ref)
    bound = min(share, AMPLIFICATION * d[: max(1, first)].max())
    off = np.flatnonzero(d > bound)
    return max(int(off[0]) if off.size else len(d), first)


def _amplified(run, ref, first: int) -> int:
    """Where the difference of ``run`` to ``ref`` has grown :data:`AMPLIFICATION` times past
    its largest value over the first ``first`` steps (or the end): on a sensitive response
    the dynamics amplify a small difference between two models as they amplify the twin's
    round-off perturbation, only sooner (they start further apart)."""
    d = _departure(run, ref)
    early = d[: max(1, first)].max()
    off = np.flatnonzero(d > AMPLIFICATION * early) if early > 0 else np.array([], dtype=int)
    return max(int(off[0]) if off.size else len(d), first)


def statistics(res, k0: int = 0, k1: int | None = None) -> dict:
    """Per-contact statistics of steps ``k0:k1``: mean and largest normal force, RMS and
    largest magnitude of each contact signal (module docstring)."""
    out = {}
    k1 = len(res.t) if k1 is None else min(k1, len(res.t))
    if k1 <= k0:
        return out
    f = res.force[k0:k1] if res.force.size else np.zeros((0, 0))
    if f.size:
        out["mean_force"], out["max_force"] = f.mean(axis=0), f.max(axis=0)
    for key in SIGNALS:
        if key in res.signals:
            y = res.signals[key][k0:k1].reshape(k1 - k0, -1)
            if y.size:
                out[f"rms_{key}"] = np.sqrt(np.mean(y**2, axis=0))
                out[f"max_{key}"] = np.abs(y).max(axis=0)
    return out


def _statistical(run, ref, k0: int) -> dict:
    k1 = min(len(run.t), len(ref.t))
    a, b = statistics(run, k0, k1), statistics(ref, k0, k1)
    return {k: _rel(np.linalg.norm(a[k] - b[k]), np.linalg.norm(b[k])) for k in b if k in a}


def estimate(run, ref, fom, *, window=0.0, twin=None, tolerance=None) -> dict:
    """Estimated relative errors of ``run`` against the richer ``ref`` (module docstring).

    ``run``, ``ref``: ``(sizes, results, full states at the checkpoints)``; ``fom``: the
    full model (field norms). Returns the errors (:data:`QUANTITIES`), ``estimate`` (the
    largest of the decisive ones) and what they were measured on.
    """
    (sa, a, Xa), (sb, b, Xb) = run, ref
    errs = compare(a, b, Xa, Xb, field_norms(fom), window)
    decisive = [errs[k] for k in DECISIVE if k in errs]
    method = "hierarchical: difference to a richer sub-basis model of the same reductor"
    value = float(max(decisive)) if decisive else 0.0
    extra = {}
    if twin is not None:
        tw, Xt = twin
        floor = compare(tw, b, Xt, Xb, field_norms(fom), window)
        sens = max(floor[k] for k in DECISIVE if k in floor)
        extra["sensitivity"] = float(sens)
        if tolerance is not None and sens > HORIZON_SHARE * tolerance:  # chaotic: split
            first = int(np.searchsorted(b.t, b.t[0] + (window or 0.0)))
            kp = min(_horizon(tw, b, HORIZON_SHARE * tolerance, first), _amplified(a, b, first))
            early = max(_impulse_error(a, b, window, kp), _signal_gap(a, b, kp))
            stats = _statistical(a, b, kp)
            late = max(stats.values()) if stats else 0.0
            value = float(max(early, late))
            method = (
                "sensitive response (a round-off twin of the reference departs by "
                f"{100 * sens:.3g} %): pointwise difference to the richer model up to the "
                "predictability horizon, per-contact statistics after it"
            )
            extra.update(
                predictability_horizon=float(b.t[min(kp, len(b.t) - 1)]),
                pointwise_before_horizon=float(early),
                statistics_after_horizon={k: float(v) for k, v in stats.items()},
            )
    return {
        **errs,
        **extra,
        "estimate": value,
        "method": method,
        "sizes": list(sa),
        "reference_sizes": list(sb),
        "checkpoints": [float(x) for x in a.state_times],
        "window": float(window),
        "status_run": a.status,
        "status_reference": b.status,
    }
