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

These a-priori indicators are reported. This module never steps a model: the a-posteriori
choice (the sub-basis models of :func:`ladder` stepped in increasing order, the first whose
estimated error is within a share of ``reduction.tolerance`` kept; with given sizes the
reductor built at :func:`~femrub.reduction.estimate.reference_sizes` so that the run's
model is one of its sub-bases and its error can be estimated) is made by the analysis layer
(:func:`femrub.analysis.reduction_check.reduce_checked`) on :func:`prepare`'s reductor.

:func:`prepare` builds the one reductor and its a-priori sizes, :func:`finish` projects the
chosen model on the leading columns of its bases (``reductor.reduce(n_uv, n_theta)``):
nothing is factorised or solved twice. :func:`reduce_model` is both, without an estimate.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..fem import eigen
from ..scene.spec import SceneError, fail
from .craig_bampton import ThermoelasticCraigBampton
from .estimate import reference_sizes

__all__ = [
    "LADDER",
    "Prepared",
    "finish",
    "ladder",
    "natural_frequencies",
    "prepare",
    "reduce_model",
]

#: Sizes ``n`` tried by ``"auto"`` (``n_uv = n_θ = n``, within the largest).
LADDER = (2, 4, 8, 12, 16, 24, 32, 48, 64, 96, 128, 192, 256)
#: Accuracy of the reference frequencies relative to the target: far below what is judged.
REFERENCE_TOL_PER_TARGET = 1e-4


def natural_frequencies(model, k: int) -> np.ndarray:
    """The ``k`` lowest natural frequencies (Hz) of a full model's ``blocks``, contacts free."""
    return eigen.natural_frequencies(model.blocks.K, model.blocks.M, k)


def _freq_errors(K, M, V, nb, ref) -> list[float]:
    """Largest relative error of the ``ref.size`` lowest frequencies of ``V[:, :nb + k]``.

    One entry per ``k = 0 … V.shape[1] − nb`` (``inf`` while the basis has fewer columns
    than ``ref``); Rayleigh–Ritz on the leading block of ``Vᵀ K V``, ``Vᵀ M V``.
    """
    modes = ref.size
    Kr, Mr = V.T @ (K @ V), V.T @ (M @ V)
    scale = np.maximum(ref, 1e-9 * ref.max() + 1e-300)
    errs = []
    for n in range(nb, V.shape[1] + 1):
        if n < modes:
            errs.append(np.inf)
            continue
        lam = sla.eigh(Kr[:n, :n], Mr[:n, :n], eigvals_only=True, subset_by_index=[0, modes - 1])
        f = np.sqrt(np.clip(lam, 0.0, None)) / (2.0 * np.pi)
        errs.append(float(np.max(np.abs(f - ref) / scale)))
    return errs


def _thermal_errors(C, K, Q, T, ntb, svals) -> list[float]:
    """Largest relative error of ``H_ii(s)`` (module docstring) of ``T[:, :ntb + k]``.

    One entry per ``k = 0 … T.shape[1] − ntb``; Galerkin on the leading block of
    ``Tᵀ (s C + K) T`` against the full response.
    """
    errs = np.zeros(T.shape[1] - ntb + 1)
    for s in svals:
        D = sp.csc_matrix(s * C + K)
        H = np.einsum("ij,ij->j", Q, spla.splu(D).solve(Q))
        Dr, Qr = T.T @ (D @ T), T.T @ Q
        for k in range(errs.size):
            n = ntb + k
            Hr = np.einsum("ij,ij->j", Qr[:n], np.linalg.solve(Dr[:n, :n], Qr[:n]))
            err = np.max(np.abs(H - Hr) / np.maximum(np.abs(H), 1e-300))
            errs[k] = max(errs[k], err)
    return errs.tolist()


def _auto_sizes(red, model, opts: dict, t_end: float, report: dict) -> tuple[int, int]:
    """Smallest sizes whose sub-bases of ``red`` (built at the largest sizes) meet the target."""
    L, b = model.layout, model.blocks
    nb, ntb = red.boundary["u"].size, red.n_theta_b
    target, modes = opts["target"], min(opts["modes"], L.n_u)
    solve = red.stiffness_solver()  # no factorisation of K
    tol = REFERENCE_TOL_PER_TARGET * opts["target"]
    ref = eigen.angular_frequencies(b.K, b.M, modes, solve, tol=tol) / (2.0 * np.pi)
    errs = _freq_errors(b.K, b.M, red.mechanical_basis(), nb, ref)
    k_uv = next((k for k, e in enumerate(errs) if e <= target), len(errs) - 1)
    report.update(
        natural_frequencies_hz=ref.tolist(),
        frequency_error=errs[k_uv],
        frequency_target_met=bool(errs[k_uv] <= target),
    )
    n_theta = 0
    Q = model.contact.Ht[L.t] if (model.contact is not None and L.n_t) else np.zeros((L.n_t, 0))
    if red.n_theta and Q.size and np.any(Q):
        svals = [0.0, 1.0 / t_end, 10.0 / t_end]
        terrs = _thermal_errors(b.Ctt, b.Ktt, Q, red.thermal_basis(), ntb, svals)
        n_theta = next((k for k, e in enumerate(terrs) if e <= target), len(terrs) - 1)
        report.update(thermal_error=terrs[n_theta], thermal_target_met=terrs[n_theta] <= target)
    return 2 * k_uv, n_theta


def _max_sizes(model, opts: dict) -> tuple[int, int]:
    """``max_n_uv`` (even) and ``max_n_theta`` bounded by the interior dofs of ``model``."""
    L, bnd = model.layout, model.boundary
    n_i, n_ti = L.n_u - len(bnd["u"]), L.n_t - len(bnd["theta"])
    return min(opts["max_n_uv"], 2 * n_i) // 2 * 2, min(opts["max_n_theta"], n_ti)


def ladder(most: tuple[int, int]) -> list[tuple[int, int]]:
    """Candidate sizes of ``"auto"``, increasing, ending at the reductor's largest."""
    out = []
    for n in LADDER:
        c = (min(n, most[0]) // 2 * 2, min(n, most[1]))
        if c not in out and c != most:
            out.append(c)
    return out + [most]


@dataclass
class Prepared:
    """The one reductor of a scene's model and its sizes (:func:`prepare`)."""

    #: the reductor (at the largest sizes for ``"auto"``, at the reference sizes of the sizes
    #: asked for when they are to be checked)
    reductor: ThermoelasticCraigBampton
    #: the a-priori sizes ``(n_uv, n_theta)`` (``"auto"``: from the indicators)
    sizes: tuple[int, int]
    #: the sizes asked for (``"craig-bampton"``), within the reductor's; ``None``: ``"auto"``
    want: tuple[int, int] | None
    report: dict
    #: seconds of the largest model's projection
    projection: float


def _refuse_insulated(model, scene) -> None:
    if model.layout.n_t and scene["material"]["conductivity"] == 0.0:
        fail(
            "material.conductivity",
            0.0,
            "the thermal Craig-Bampton reduction needs a "
            "conducting blade (K^θθ is singular); use > 0 or reduction.method = 'none'",
        )


def _asked_sizes(model, opts: dict, report: dict, reference: bool):
    """``(sizes the reductor is built at, sizes asked for or None)`` of ``opts``."""
    if opts["method"] == "auto":
        return _max_sizes(model, opts), None
    want = n_uv, n_theta = opts["n_uv"], opts["n_theta"]
    if model.layout.n_t == 0 and n_theta:
        report["note"] = f"reduction.n_theta = {n_theta} ignored: no temperature dofs"
        want = n_uv, n_theta = n_uv, 0
    if reference:  # a richer reductor: the reference of the estimate
        L, bnd = model.layout, model.boundary
        cap = (2 * (L.n_u - len(bnd["u"])), L.n_t)
        if n_uv <= cap[0] and n_theta <= cap[1]:  # else the reductor names the key
            n_uv, n_theta = reference_sizes(n_uv, n_theta, cap)
    return (n_uv, n_theta), want


def _reductor(model, opts: dict, sizes, reductor, stiffness, report: dict):
    """The reductor at ``sizes`` (or ``reductor``'s bases reused for ``model``)."""
    if reductor is not None:
        report["bases"] = "reused (same matrices and reduction options)"
        return reductor.for_model(model)
    try:
        return ThermoelasticCraigBampton(
            model,
            *sizes,
            projection=opts["projection"],
            thermal=opts["thermal"],
            keep_solver=opts["method"] == "auto",  # only "auto" solves again (_auto_sizes)
            stiffness=stiffness,
        )
    except ValueError as exc:
        text = str(exc)
        if stiffness is not None:
            stiffness.free()
        method = opts["method"]
        key = next((f"reduction.{k}" for k in ("n_theta", "n_uv") if k in text), None)
        raise SceneError(f"{key or f'reduction.method = {method!r}'}: {text}") from None


def prepare(model, scene, log=None, reductor=None, stiffness=None, reference=False) -> Prepared:
    """The reductor of ``model`` as ``scene["reduction"]`` asks (not ``"none"``) and its
    a-priori sizes.

    ``reference``: the sizes asked for will be checked a posteriori, build the reductor at
    their :func:`~femrub.reduction.estimate.reference_sizes`. ``reductor``: one built by an
    earlier call for a model with the same matrices and the same ``reduction`` options (a
    point of a speed sweep): its bases are reused
    (:meth:`~femrub.reduction.craig_bampton.ThermoelasticCraigBampton.for_model`) with the
    operators projected on them. ``stiffness``: an
    :class:`~femrub.reduction.interior.InteriorStiffness` of the model's ``K_ii`` already
    factorised (its modal damping), for the reductor built here; released when unused.
    """
    opts = scene["reduction"]
    if stiffness is not None and reductor is not None:
        stiffness.free()  # no reductor is built here
        stiffness = None
    _refuse_insulated(model, scene)
    method = opts["method"]
    report = {"method": method, "projection": opts["projection"], "n_full": model.n_dofs}
    if log:
        log(f"reduction ({method}) of {model.n_dofs} dofs ...")
    sizes, want = _asked_sizes(model, opts, report, reference)
    red = _reductor(model, opts, sizes, reductor, stiffness, report)
    if want is not None:
        want = sizes = (min(want[0], red.n_uv), min(want[1], red.n_theta))
    else:
        sizes = _auto_sizes(red, model, opts, scene["scheme"]["t_end"], report)
        report["target"] = opts["target"]
    red.solver.free()  # no more interior solves: release the factorisations' memory
    projection = red.project()  # once; every size is then a block of it (or projected)
    return Prepared(red, sizes, want, report, projection)


def finish(prepared: Prepared, sizes: tuple[int, int]):
    """The reduced model of ``sizes`` of a :func:`prepare`'d reductor; its report completed."""
    red, report = prepared.reductor, prepared.report
    n_uv, n_theta = sizes
    reduced = red.reduce(n_uv, n_theta)
    reduced.info["timings"]["projection"] += prepared.projection
    if "error" in report:  # energy the reduced dynamics can create (verdict rule ``reduction``)
        report["error"]["energy_growth_rate"] = reduced.info["energy_growth_rate"]
    report.update(
        n_uv=n_uv,
        n_theta=n_theta,
        n_reduced=reduced.n_dofs,
        n_boundary_u=int(red.boundary["u"].size),
        n_boundary_theta=int(red.n_theta_b),
        thermal=red.thermal,
    )
    return reduced


def reduce_model(model, scene, log=None, reductor=None, stiffness=None):
    """Reduce ``model`` as ``scene["reduction"]`` asks, at its a-priori sizes; return
    ``(model, reductor, report)`` (``report["n_uv"]``, ``report["n_theta"]``: the sizes of
    the returned model). See :func:`prepare`; with an a-posteriori estimate:
    :func:`femrub.analysis.reduction_check.reduce_checked`.
    """
    if scene["reduction"]["method"] == "none":
        if stiffness is not None:
            stiffness.free()  # no reductor is built here
        return model, None, {"method": "none"}
    prepared = prepare(model, scene, log, reductor, stiffness)
    return finish(prepared, prepared.sizes), prepared.reductor, prepared.report
