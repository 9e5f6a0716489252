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

These a-priori indicators are reported. When the caller gives the scene's stepper
(``make_stepper``), the sizes are then picked a posteriori: the sub-basis models of
:data:`LADDER` (``n_uv = n_θ = n``) are stepped in increasing order and the first whose
estimated error (:mod:`femrub.reduction.estimate`, against the reductor's largest model)
is within ``SAFETY × reduction.tolerance`` is kept. With given sizes
(``"craig-bampton"``) the reductor is built at
:func:`~femrub.reduction.estimate.reference_sizes` and the run's model is one of its
sub-bases, so its error is estimated too (``report["error"]``).

The chosen model is then projected on the leading columns of that reductor's bases
(``reductor.reduce(n_uv, n_theta)``): nothing is factorised or solved twice.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..contact.casing import lobe_passing_frequency
from ..fem import eigen
from ..scene.spec import SceneError, fail
from .craig_bampton import ThermoelasticCraigBampton
from .estimate import estimate, reference_sizes, simulate, twin

__all__ = ["natural_frequencies", "reduce_model"]

#: Sizes ``n`` tried by ``"auto"`` (``n_uv = n_θ = n``, within the largest).
LADDER = (2, 4, 8, 12, 16, 24, 32, 48, 64, 96, 128, 192, 256)
#: ``"auto"`` keeps the first size whose estimate is within this share of the tolerance.
SAFETY = 0.5
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


def _ladder(most: tuple[int, int]) -> list[tuple[int, int]]:
    """Candidate sizes of ``"auto"``, increasing, ending at the reductor's largest."""
    out = []
    for n in LADDER:
        c = (min(n, most[0]) // 2 * 2, min(n, most[1]))
        if c not in out and c != most:
            out.append(c)
    return out + [most]


def _timed(*args, **kw):
    """:func:`~femrub.reduction.estimate.simulate`, with its wall seconds appended."""
    t0 = time.perf_counter()
    return (*simulate(*args, **kw), time.perf_counter() - t0)


def _checked(red, model, want, make_stepper, scene, report, log, limits, on_run=None):
    """Sizes to run and their a-posteriori estimate (``report["error"]``).

    ``want``: the sizes asked for (``None`` for ``"auto"``: the smallest of :func:`_ladder`
    whose estimate is within ``SAFETY × tolerance``). The reference is the reductor's largest
    model; the largest model itself is judged by its difference to the next smaller one.
    ``on_run(results, seconds, full states)`` receives the estimate's run of the chosen sizes
    (the run itself: same model, stepper and initial state, stepped to ``t_end`` with
    ``limits``; its states at the estimate's checkpoints, reconstructed).
    """
    t0 = time.perf_counter()
    tol, t_end = scene["reduction"]["tolerance"], scene["scheme"]["t_end"]
    window = lobe_passage(scene)
    most = (red.n_uv, red.n_theta)
    # a run that carries state outside X (wear, casing heat) is stepped again as the
    # scene's run (the estimate's later runs restart that state): every run here recorded
    # lean (Stepper.run(lean=1): only what estimate() reads, so that the runs it holds
    # together stay small); otherwise those that are never the run
    whole = model.contact is None or not model.contact.carried_state
    cands = [want] if want is not None else _ladder(most)
    lean = int(not whole or (want is not None and want != most))  # the reference
    *ref, ref_wall = _timed(red, most, make_stepper, t_end, limits=limits, lean=lean)
    chosen, err, tried, tw = None, None, [], None
    for c in cands:
        if c == most:
            break
        *run, wall = _timed(red, c, make_stepper, t_end, limits=limits, lean=int(not whole))
        kept = (run[0], wall, run[1])
        err = estimate((c, *run), (most, *ref), model, window=window)
        if err["estimate"] > SAFETY * tol:  # measure how sensitive the response is
            tw = tw or twin(red, most, make_stepper, t_end, limits=limits, lean=1)
            err = estimate((c, *run), (most, *ref), model, window=window, twin=tw, tolerance=tol)
        tried.append({"sizes": list(c), "estimate": err["estimate"]})
        if want is not None or err["estimate"] <= SAFETY * tol:
            chosen = c
            break
    if chosen is None:  # the largest: judged against the next smaller candidate
        chosen, kept = most, (ref[0], ref_wall, ref[1])
        if tried:
            err = dict(
                err,
                estimate=err["estimate"],
                judged="largest model: difference to "
                f"the next smaller one {tried[-1]['sizes']} (pessimistic)",
            )
        else:
            err = {"estimate": 0.0, "note": "the run's model is the reference (no estimate)"}
    err.update(tolerance=tol, tried=tried, seconds=time.perf_counter() - t0)
    report["error"] = err
    if on_run is not None:
        on_run(*kept)
    if log:
        log(f"reduction error estimate {100 * err['estimate']:.2g} % at sizes {list(chosen)}")
    return chosen


def lobe_passage(scene) -> float:
    """Duration (s) of one lobe passage of the casing (0 without lobes or rotation)."""
    w = lobe_passing_frequency(scene["contact"]["casing"], scene["loads"]["rotation_speed"])
    return 2.0 * np.pi / w if w else 0.0


def reduce_model(
    model,
    scene,
    log=None,
    make_stepper=None,
    reductor=None,
    limits=None,
    on_run=None,
    stiffness=None,
):
    """Reduce ``model`` as ``scene["reduction"]`` asks; return ``(model, reductor, report)``.

    ``reductor`` is the one reductor built (at the largest sizes for ``"auto"``, at
    :func:`~femrub.reduction.estimate.reference_sizes` of the sizes asked for otherwise);
    ``report["n_uv"]``, ``report["n_theta"]`` are the sizes of the returned model. With
    ``make_stepper`` (``model -> stepper`` of the scene's scheme) the run's error is
    estimated (``report["error"]``, :mod:`femrub.reduction.estimate`) and ``"auto"`` picks
    the sizes from that estimate. ``reductor``: one built by an earlier call for a model with
    the same matrices and the same ``reduction`` options (a point of a speed sweep): its
    bases are reused (:meth:`~femrub.reduction.craig_bampton.ThermoelasticCraigBampton.for_model`)
    with the operators projected on them, and only the estimate runs again. ``limits``: the
    run's stop limits (``Stepper.run``), applied to the estimate's runs: they compare the
    models over the part of the run that the run itself can reach. ``on_run(results,
    seconds, states)``: called with the estimate's run of the returned model's sizes (its
    :class:`~femrub.output.results.Results`, judged without the reduction rule, and its wall
    time), which is the scene's run: the caller need not step it again (lean, and to be
    stepped again, when the contact carries state outside ``X``:
    :attr:`~femrub.contact.gap.Contact.carried_state`). ``stiffness``: an
    :class:`~femrub.reduction.interior.InteriorStiffness` of the model's ``K_ii`` already
    factorised (its modal damping, :mod:`femrub.reduction.modal_damping`), for the reductor
    built here; released when unused.
    """
    opts = scene["reduction"]
    method = opts["method"]
    if stiffness is not None and (method == "none" or reductor is not None):
        stiffness.free()  # no reductor is built here
        stiffness = None
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
    want = None
    if method == "auto":
        n_uv, n_theta = _max_sizes(model, opts)
    else:
        want = n_uv, n_theta = opts["n_uv"], opts["n_theta"]
        if model.layout.n_t == 0 and n_theta:
            report["note"] = f"reduction.n_theta = {n_theta} ignored: no temperature dofs"
            want = n_uv, n_theta = n_uv, 0
        if make_stepper is not None:  # a richer reductor: the reference of the estimate
            L, bnd = model.layout, model.boundary
            cap = (2 * (L.n_u - len(bnd["u"])), L.n_t)
            if n_uv <= cap[0] and n_theta <= cap[1]:  # else the reductor names the key
                n_uv, n_theta = reference_sizes(n_uv, n_theta, cap)
    try:
        if reductor is not None:
            red = reductor.for_model(model)
            report["bases"] = "reused (same matrices and reduction options)"
        else:
            red = ThermoelasticCraigBampton(
                model,
                n_uv,
                n_theta,
                projection=opts["projection"],
                thermal=opts["thermal"],
                keep_solver=method == "auto",  # only "auto" solves again (_auto_sizes)
                stiffness=stiffness,
            )
            stiffness = None  # the reductor's now
    except ValueError as exc:
        text = str(exc)
        if stiffness is not None:
            stiffness.free()
        key = next((f"reduction.{k}" for k in ("n_theta", "n_uv") if k in text), None)
        raise SceneError(f"{key or f'reduction.method = {method!r}'}: {text}") from None
    if want is not None:
        want = (min(want[0], red.n_uv), min(want[1], red.n_theta))
    if method == "auto":
        n_uv, n_theta = _auto_sizes(red, model, opts, scene["scheme"]["t_end"], report)
        report["target"] = opts["target"]
    else:
        n_uv, n_theta = want
    red.solver.free()  # no more interior solves: release the factorisations' memory
    projection = red.project()  # once; every size is then a block of it (or projected)
    if make_stepper is not None:
        n_uv, n_theta = _checked(red, model, want, make_stepper, scene, report, log, limits, on_run)
    reduced = red.reduce(n_uv, n_theta)
    reduced.info["timings"]["projection"] += projection
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
    return reduced, red, report
