"""Branches of periodic orbits by pseudo-arclength continuation in one parameter.

The unknowns are ``y = (X0, p)``: the orbit's start and the parameter (a rotation speed
Ω in rad/s, a clearance in m, ...), in scaled form ``z = (X0 / a, p / s_p)``, ``a = s √N``
with ``s`` the orbit's size per state block (:func:`~femrub.periodic.shooting.state_scale`),
``N`` the size of the state and ``s_p`` the parameter range: a step ``Δs`` is a
root-mean-square relative change of the state (the same for 2 or 200 coordinates) against a
fraction of the range. A branch point solves the shooting residual (``R``, Eq. 1 of
:mod:`femrub.periodic.shooting`) and the arclength condition (Keller's pseudo-arclength;
Seydel 2010, Sec. 4.5)::

    R(X0, p) = Φ_T(X0; p) − X0 = 0
    τ_kᵀ (z − z_k) − Δs = 0                                            (1)

from the predictor ``z_k + Δs τ_k`` along the unit tangent ``τ_k``, the null vector of the
scaled Jacobian ``[R_X diag(a), R_p s_p]`` (rows over ``s``) oriented as the step before
(the first one towards ``stop``). ``R_X = M − I`` is the monodromy of Eq. (2) there; ``R_p``
is a finite difference in ``p`` at the same number of steps per period. Newton's method on
Eq. (1) passes folds, where ``R_X`` is singular but the bordered matrix is not; a correction
that moves farther than ``2 Δs`` from its predictor is refused (it jumped to another part of
the branch), each Newton step is halved until the residual decreases, and the step shortened
after a failed correction. The branch keeps its number of steps per period ``N`` (the step
``T(p) / N`` follows ``p``), so the residual is smooth in ``p`` through its corrections,
until that step leaves ``FINEST h`` to ``h``; the point is then converged again at the same
``p`` with ``N = ceil(T(p) / h)``. After each point the orbit's start moves to put its main
impact mid-step (:mod:`femrub.periodic.phase`; one-contact maps only), and the point is
converged again from there. The tangent and the Floquet multipliers take the monodromy with
the impact-time terms (:mod:`femrub.periodic.sensitivity`, Eq. 2), Newton the step
Jacobians' product alone. The step ``Δs`` grows by 1.3 after a quick correction (at most 3
Newton iterations) up to ``ds_max``, shrinks by 0.7 after a slow one and halves after a
failed one, down to ``ds_min`` (then the branch stops, ``failed``). The first point is found
at ``start`` by natural-parameter shooting from the state reached after ``warmup`` periods
of time integration. The branch ends at the first point beyond ``start``–``stop``, replaced
by the orbit exactly at that end.

Each point carries its Floquet multipliers (:mod:`femrub.periodic.floquet`), the summary
measures of one period (:func:`measures`) and the special point the step to it passed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .floquet import multipliers, special_point, stable
from .period import Orbit, PeriodMap
from .phase import new_start, state_later
from .shooting import (
    FD_STEP,
    STALL_TOLERANCE,
    TOLERANCE,
    Broyden,
    Shooting,
    _norm,
    stalled,
    state_scale,
)

__all__ = ["Branch", "BranchPoint", "check_model", "continue_branch", "measures"]

#: largest scaled distance between an orbit and the same orbit re-converged on another
#: grid (a new start, a new number of steps): farther, Newton went to another orbit
SAME_ORBIT = 0.05
#: Broyden corrections counted as one Newton iteration with fresh derivatives (for the
#: largest number of corrections and the step control)
BROYDEN_COST = 3
#: smallest step ``T(p) / N``, as a fraction of ``h``, before a branch chooses ``N`` again
FINEST = 0.75


def check_model(model) -> None:
    """Refuse, in one line, a model whose periodic orbits this method does not compute.

    Raises
    ------
    ValueError
        A thermal model (its heat modes, far slower than a period, put Floquet multipliers
        on the unit circle and the orbit's temperature drifts over thousands of periods),
        or a contact with a history outside the state (an abradable coating's wear, the
        casing's heat: not periodic).
    """
    if model.layout.n_t:
        raise ValueError(
            "physics.thermal: periodic orbits are computed on mechanical models only (the "
            "slow heat modes have Floquet multipliers at |mu| = 1 and the temperature "
            "drifts over many periods); use --set physics.thermal=off"
        )
    c = model.contact
    if c is not None and c.carried_state:
        raise ValueError(
            "contact: an abradable coating or casing heat changes the casing from period "
            "to period (no periodic orbit); use contact.coating = 'none' and casing heat off"
        )


def measures(model, orbit: Orbit, h: float) -> dict:
    """Summary measures of one period of ``orbit`` (SI): ``max_<signal>`` (largest
    magnitude of each observed signal; ``max_tip_displacement`` in m), ``rms_<signal>``
    of the displacements, ``max_contact_force`` (N, the largest impulse over ``h``),
    ``mean_contact_force`` (N, the impulses of the period over the period) and ``min_gap``
    (m, the smallest gap of any contact; ``nan`` without contact)."""
    out = {}
    for name, O in model.observations.items():
        y = np.asarray(O @ orbit.X.T)
        out[f"max_{name}"] = float(np.abs(y).max())
        if "displacement" in name:
            out[f"rms_{name}"] = float(np.sqrt(np.mean(y[:, 1:] ** 2)))
    c, T = model.contact, orbit.t[-1] - orbit.t[0]
    if c is None:
        out.update(max_contact_force=0.0, mean_contact_force=0.0, min_gap=math.nan)
        return out
    P = orbit.P[1:]
    out["max_contact_force"] = float(P.max() / h) if P.size else 0.0
    out["mean_contact_force"] = float(P.sum(axis=0).max() / T) if P.size else 0.0
    out["min_gap"] = float(np.min(c.gap(orbit.t, orbit.X)))
    return out


@dataclass(frozen=True)
class BranchPoint:
    """One periodic orbit of a branch.

    Attributes
    ----------
    parameter : the parameter's value (SI).
    X0 : the orbit's state at ``t0`` (N,).
    residual : scaled shooting residual (:data:`~femrub.periodic.shooting.TOLERANCE`).
    iterations : Newton iterations of its correction.
    converged : the residual is below the tolerance.
    multipliers : Floquet multipliers, largest modulus first.
    steps, h, period : θ-method steps per period, their size (s), the period (s).
    measures : :func:`measures` of its period.
    special : what the step to it passed (:data:`~femrub.periodic.floquet.SPECIAL`) or ``""``.
    t0 : the orbit's start (s).
    unsettled : columns of its finite-difference monodromy that depend on the step
        (:func:`~femrub.periodic.shooting.checked_differences`); above 0 its multipliers,
        ``stable`` and the special points next to it are uncertain.
    """

    parameter: float
    X0: np.ndarray
    residual: float
    iterations: int
    converged: bool
    multipliers: np.ndarray
    steps: int
    h: float
    period: float
    measures: dict
    special: str = ""
    t0: float = 0.0
    unsettled: int = 0

    @property
    def stable(self) -> bool:
        return stable(self.multipliers)

    @property
    def max_floquet_modulus(self) -> float:
        return float(np.abs(self.multipliers).max()) if self.multipliers.size else 0.0


@dataclass
class Branch:
    """A branch of periodic orbits (:func:`continue_branch`).

    ``status``: ``"ok"`` when every point converged and the branch reached ``stop``,
    ``"inaccurate"`` when so but some points' multipliers are uncertain
    (``BranchPoint.unsettled``), ``"failed"`` otherwise (``message`` says why; the points
    found are kept), ``"interrupted"`` after Ctrl-C. ``orbits``: one period of selected points
    (index -> :class:`~femrub.periodic.period.Orbit`).
    """

    key: str
    points: list = field(default_factory=list)
    status: str = "ok"
    message: str = ""
    orbits: dict = field(default_factory=dict)

    @property
    def parameter(self) -> np.ndarray:
        return np.array([p.parameter for p in self.points])

    def column(self, name: str) -> np.ndarray:
        """A summary measure (``measures`` key) over the points."""
        return np.array([p.measures.get(name, math.nan) for p in self.points])


class _Problem:
    """The shooting residual of a family of models ``p -> model`` (period maps kept)."""

    def __init__(self, family, h, options):
        self.family, self.h, self.options = family, float(h), options
        self._maps = {}
        self.t0 = 0.0  # the orbits' start (s): :mod:`femrub.periodic.phase`

    def holds(self, steps: int, p: float) -> bool:
        """``N = steps`` still fits the orbit's period at ``p``: ``FINEST h <= T(p) / N <= h``."""
        h = self.map(p).period / steps
        return FINEST * self.h <= h <= self.h * (1.0 + 1e-12)

    def map(self, p: float, steps: int | None = None) -> PeriodMap:
        key = (float(p), steps, self.t0)
        if key not in self._maps:
            if len(self._maps) > 8:
                self._maps.pop(next(iter(self._maps)))
            model = self.family(float(p))
            check_model(model)
            self._maps[key] = PeriodMap(model, self.h, steps=steps, t0=self.t0, **self.options)
        return self._maps[key]

    def derivatives(self, X, p, steps, s, dp_scale, floquet=False):
        """``(orbit, M, R_p, unsettled)`` at ``(X, p)`` with ``N = steps``; ``floquet``: ``M``
        of the Floquet multipliers (:meth:`~femrub.periodic.shooting.Shooting.
        floquet_monodromy`: the impact-time terms, or checked differences), else Newton's."""
        pm = self.map(p, steps)
        orbit = pm.orbit(X)
        shooting = Shooting(pm)
        if floquet:
            M, unsettled = shooting.floquet_monodromy(X, s, orbit)
        else:
            M, unsettled = shooting.monodromy(X, s, orbit), 0
        dp = FD_STEP * max(abs(p), dp_scale)
        Rp = (self.map(p + dp, steps)(X) - orbit.X[-1]) / dp
        self._maps.pop((float(p + dp), steps, self.t0), None)
        return orbit, M, Rp, unsettled


def _tangent(M, Rp, s, a, sp, previous=None):
    """Unit null vector of the scaled ``[R_X diag(a), R_p s_p]`` (rows scaled by ``1/s``),
    oriented as ``previous`` (``(τ, det sign of the bordered matrix)``)."""
    J = np.hstack([(M - np.eye(s.size)) * (a[None, :] / s[:, None]), (Rp * sp / s)[:, None]])
    tau = np.linalg.svd(J)[2][-1]
    if previous is not None and tau @ previous < 0:
        tau = -tau
    sign = np.sign(np.linalg.slogdet(np.vstack([J, tau]))[0])
    return tau, J, sign


@dataclass
class _Settings:
    ds: float = 0.02
    ds_min: float = 1e-5
    ds_max: float = 0.05
    max_points: int = 400
    max_corrections: int = 10
    tolerance: float = TOLERANCE
    stall_tolerance: float = STALL_TOLERANCE


class _Continuation:
    """Eq. (1) along a branch (module docstring); ``run`` fills a :class:`Branch`."""

    def __init__(self, problem: _Problem, key, start, stop, settings: _Settings, log):
        self.pb, self.set, self.log = problem, settings, log or (lambda text: None)
        self.start, self.stop = float(start), float(stop)
        self.sp = abs(self.stop - self.start) or max(abs(self.start), 1.0)
        self.branch = Branch(key)
        self._orbits = {}
        self.direction = 1.0 if self.stop >= self.start else -1.0

    def _shooting(self, pm) -> Shooting:
        return Shooting(pm, tolerance=self.set.tolerance, stall_tolerance=self.set.stall_tolerance)

    def first(self, x0, warmup: int) -> tuple:
        """The orbit at ``start`` by natural-parameter shooting after ``warmup`` periods."""
        pm = self.pb.map(self.start)
        X = pm.model.x0.copy() if x0 is None else np.asarray(x0, dtype=float)
        drift = math.nan
        for k in range(warmup):
            X, before = pm(X), X
            if k == warmup - 1:
                drift = _norm(X - before, state_scale(pm.model.layout, np.vstack([X, before])))
        res = self._shooting(pm).solve(X, monodromy=False)
        if not res.converged:
            raise RuntimeError(
                f"no periodic orbit at {self.branch.key} = {self.start:g} (scaled residual "
                f"{res.residual:.2e} after {res.iterations} Newton iterations)"
                + _settling(warmup, drift, self.pb.options.get("multiple", 1))
            )
        return res.X0, self.start, pm.steps, res.iterations

    def _point(self, X, p, steps, iterations, previous, forced=False):
        """A :class:`BranchPoint` at a solution, with its tangent and the special point."""
        pm = self.pb.map(p, steps)
        orbit0 = pm.orbit(X)
        s = state_scale(pm.model.layout, orbit0.X)
        a = s * math.sqrt(s.size)  # the unknowns' scale: Δs is a root-mean-square change
        orbit, M, Rp, unsettled = self.pb.derivatives(X, p, steps, s, self.sp, floquet=True)
        if previous is None:
            tau, J, sign = _tangent(M, Rp, s, a, self.sp)
            tau = tau if tau[-1] * self.direction >= 0 else -tau
            sign = -sign if tau[-1] * self.direction < 0 else sign
        else:
            tau, J, sign = _tangent(M, Rp, s, a, self.sp, previous["tau"])
        mu = multipliers(M)
        info = {"mu": mu, "dp": tau[-1], "det_sign": sign, "tau": tau, "s": s, "a": a, "J": J}
        info.update(steps=pm.steps, exact=Shooting(pm).exact)
        special = "" if previous is None or forced else special_point(previous, info)
        r = _norm(orbit.X[-1] - X, s)
        point = BranchPoint(
            p,
            X.copy(),
            r,
            iterations,
            r <= max(self.set.tolerance, self.set.stall_tolerance),
            mu,
            pm.steps,
            pm.h,
            pm.period,
            measures(pm.model, orbit, pm.h),
            special,
            pm.t0,
            unsettled,
        )
        return point, info, orbit

    def correct(self, X, p, info, ds):
        """Damped Newton on Eq. (1) from the predictor ``z_k + Δs τ_k`` (each step halved
        until the residual decreases, within ``2 Δs`` of the predictor); ``(X, p, steps,
        iterations)`` once converged or stalled below the stall tolerance, else ``None``.
        Where ``R_X`` comes from finite differences, the corrections start from the previous
        point's ``[R_X, R_p]`` and update it by Broyden's formula in the scaled unknowns
        (:class:`~femrub.periodic.shooting.Broyden`, unit weights)."""
        s, a, tau = info["s"], info["a"], info["tau"]
        zp = np.append(X / a, p / self.sp) + ds * tau
        steps = info["steps"]
        z, history, last = zp.copy(), [], None
        jacobian = Broyden(self._bordered(s, a), info["exact"], info["J"])
        limit = self.set.max_corrections * (1 if jacobian.exact else BROYDEN_COST)
        for k in range(limit + 1):
            Xk, pk = z[:-1] * a, z[-1] * self.sp
            try:
                R = (self.pb.map(pk, steps)(Xk) - Xk) / s
            except (ValueError, FloatingPointError):
                return None
            history.append(float(np.abs(R).max()))
            if last is not None:
                jacobian.update(z - last[0], R - last[1], history[-1] / history[-2])
            last = (z, R)
            if history[-1] <= self.set.tolerance:
                return Xk, pk, steps, k
            if stalled(history, self.set.stall_tolerance) and not jacobian.renew():
                return Xk, pk, steps, k
            try:
                J = jacobian.at(Xk, pk, steps)
            except (ValueError, FloatingPointError):
                return None
            dz = np.linalg.solve(np.vstack([J, tau]), -np.append(R, tau @ (z - zp)))
            z = self._damped(z, dz, history[-1], (zp, ds, s, a, steps))
            if z is None:
                return None
        return None

    def _bordered(self, s, a):
        """``(X, p, steps) -> J``: the scaled ``[R_X diag(a), R_p s_p]`` (rows over ``s``) of
        the corrections, from fresh derivatives."""

        def take(X, p, steps):
            _, M, Rp, _ = self.pb.derivatives(X, p, steps, s, self.sp)
            return _tangent(M, Rp, s, a, self.sp)[1]

        return take

    def _damped(self, z, dz, r, frame):
        """``z + α dz`` for the first ``α = 1, 1/2, …`` that lowers the residual ``r``, else
        the best of the tries; ``None`` when every try leaves ``2 Δs`` of the predictor or
        the model's domain."""
        zp, ds, s, a, steps = frame
        best, alpha = None, 1.0
        for _ in range(6):
            zt = z + alpha * dz
            alpha *= 0.5
            if np.linalg.norm(zt - zp) > 2.0 * abs(ds):  # left for another branch
                continue
            Xt, pt = zt[:-1] * a, zt[-1] * self.sp
            try:
                rt = _norm(self.pb.map(pt, steps)(Xt) - Xt, s)
            except (ValueError, FloatingPointError):
                continue
            if rt < r:
                return zt
            if best is None or rt < best[0]:
                best = (rt, zt)
        return None if best is None else best[1]

    def remesh(self, X, p, info):
        """The orbit at ``p`` again with ``N = ceil(T(p) / h)`` steps per period (natural
        shooting from ``X``), and its tangent, where the predictor's step left ``FINEST h``
        to ``h``."""
        pm = self.pb.map(p)
        res = self._shooting(pm).solve(X, info["s"], monodromy=False)
        if not res.converged or _norm(res.X0 - X, info["s"]) > SAME_ORBIT:
            raise RuntimeError(
                f"no orbit at {self.branch.key} = {p:g} with {pm.steps} steps per period "
                f"(scaled residual {res.residual:.2e})"
            )
        self.log(f"{self.branch.key} = {p:.6g}: {pm.steps} steps per period from here")
        _, new, _ = self._point(res.X0, p, pm.steps, res.iterations, info, forced=True)
        return res.X0, new

    def rephase(self, X, p, info, orbit):
        """The orbit at ``p`` from a start ``t0`` that puts its main impact mid-step
        (:func:`~femrub.periodic.phase.new_start`), re-converged there, and its tangent;
        ``(X, info)`` unchanged when the impact is already inside its step, when Newton from
        the new start does not converge to the same orbit (:data:`SAME_ORBIT`), or when the
        map has no step Jacobians (several contacts or friction: the other impacts and the
        stick-slip switches keep jumping wherever the start is, and a new start would cost
        a finite-difference monodromy)."""
        if not info["exact"]:
            return X, info
        pm = self.pb.map(p, info["steps"])
        start = new_start(pm.model, orbit, pm.h)
        if start is None:
            return X, info
        j, delta = start
        opts = self.pb.options
        Xd = state_later(pm.model, orbit.X[j], orbit.t[j], delta, opts["gamma"], opts["activation"])
        before, self.pb.t0 = self.pb.t0, float(orbit.t[j] + delta)
        res = self._shooting(self.pb.map(p, info["steps"])).solve(Xd, info["s"], monodromy=False)
        if not res.converged or _norm(res.X0 - Xd, info["s"]) > SAME_ORBIT:
            self.pb.t0 = before
            return X, info
        _, new, _ = self._point(res.X0, p, info["steps"], res.iterations, info, forced=True)
        return res.X0, new

    def inside(self, p: float) -> bool:
        lo, hi = sorted((self.start, self.stop))
        return lo - 1e-12 * self.sp <= p <= hi + 1e-12 * self.sp

    def end_point(self, X, p, Xn, pn, previous):
        """The orbit exactly at the end crossed between ``p`` and ``pn``."""
        end = self.stop if abs(pn - self.stop) < abs(pn - self.start) else self.start
        w = (end - p) / (pn - p)
        pm = self.pb.map(end)
        res = self._shooting(pm).solve((1 - w) * X + w * Xn, previous["s"], monodromy=False)
        if not res.converged:
            return None
        return self._point(res.X0, end, pm.steps, res.iterations, previous)

    def run(self, x0, warmup: int) -> Branch:
        X, p, steps, it = self.first(x0, warmup)
        point, info, orbit = self._point(X, p, steps, it, None)
        self._accept(point, orbit)
        X, info = self.rephase(X, p, info, orbit)
        ds = self.set.ds
        while len(self.branch.points) < self.set.max_points:
            if not self.pb.holds(info["steps"], p + ds * info["tau"][-1] * self.sp):
                X, info = self.remesh(X, p, info)
            got = self.correct(X, p, info, ds)
            if got is None:
                ds *= 0.5
                if ds < self.set.ds_min:
                    return self._fail(f"the continuation step fell below {self.set.ds_min:g}")
                continue
            Xn, pn, steps, it = got
            if not self.inside(pn):
                end = self.end_point(X, p, Xn, pn, info)
                if end is None:
                    return self._fail(f"no orbit found at the end {self.branch.key} = {pn:g}")
                self._accept(end[0], end[2])
                return self.branch
            point, info, orbit = self._point(Xn, pn, steps, it, info)
            self._accept(point, orbit)
            X, p = Xn, pn
            X, info = self.rephase(X, p, info, orbit)
            it = it if info["exact"] else it / BROYDEN_COST
            ds = min(ds * 1.3, self.set.ds_max) if it <= 3 else ds * (0.7 if it > 5 else 1.0)
        return self._fail(f"{self.set.max_points} points without reaching the end")

    def _accept(self, point: BranchPoint, orbit: Orbit) -> None:
        self.branch.points.append(point)
        self._orbits[len(self.branch.points) - 1] = orbit
        self.log(
            f"{self.branch.key} = {point.parameter:.6g}: max |tip| "
            f"{point.measures.get('max_tip_displacement', math.nan):.4g}, max |mu| "
            f"{point.max_floquet_modulus:.4f}, {point.iterations} it, "
            f"{point.steps} steps of h = {point.h:.6g} s per period"
            + (f", {point.special}" if point.special else "")
        )

    def _fail(self, message: str) -> Branch:
        self.branch.status, self.branch.message = "failed", message
        return self.branch


def _settling(warmup: int, drift: float, multiple: int) -> str:
    """What the time integration before the first Newton iteration says: the scaled change
    ``max_j |Φ_T(X)_j − X_j| / s_j`` of its state over its last period (``drift``); a
    time integration that has not settled (drift above the stall tolerance) starts Newton
    far from any orbit of that period and suggests that none attracts it."""
    if not warmup or not math.isfinite(drift) or drift <= STALL_TOLERANCE:
        return ""
    return (
        f"; the time integration over {warmup} periods has not settled (its state still "
        f"changes by {drift:.2g} of its size per period of {multiple} forcing period(s)): "
        "the response there is not periodic with that period"
    )


def _selected(branch: Branch, orbits: dict, count: int) -> dict:
    """The orbits kept with a branch: its ends, its special points and the ``count`` points
    of largest tip displacement (or of largest first measure)."""
    n = len(branch.points)
    if not n:
        return {}
    name = "max_tip_displacement"
    if name not in branch.points[0].measures:
        name = next(iter(branch.points[0].measures))
    keep = {0, n - 1} | {i for i, p in enumerate(branch.points) if p.special}
    keep |= set(np.argsort(-np.nan_to_num(branch.column(name)))[:count].tolist())
    return {i: orbits[i] for i in sorted(keep) if i in orbits}


def _family(source, key: str):
    """``p -> model`` of a model (its ``with_parameters``) or of a callable."""
    if callable(source) and not hasattr(source, "with_parameters"):
        return source
    if key != "rotation_speed":
        raise ValueError(
            f"a model is continued in its parameter rotation_speed only (got {key!r}); "
            "continue a scene (femrub.periodic.scene_family) for any other key"
        )
    return lambda p: source.with_parameters(rotation_speed=p)


def continue_branch(  # noqa: PLR0913 (keyword-only options of a public entry point)
    source,
    start: float,
    stop: float,
    *,
    h: float,
    key: str = "rotation_speed",
    x0=None,
    warmup: int = 50,
    multiple: int = 1,
    gamma: float = 0.5,
    activation: str | None = None,
    ds: float = 0.02,
    ds_max: float = 0.05,
    max_points: int = 400,
    tolerance: float = TOLERANCE,
    stall_tolerance: float = STALL_TOLERANCE,
    keep_orbits: int = 3,
    log=None,
) -> Branch:
    """The branch of periodic orbits from ``start`` to ``stop`` (module docstring).

    Parameters
    ----------
    source : a :class:`~femrub.model.first_order.FirstOrderModel` (continued in its
        ``rotation_speed``, rad/s) or a callable ``p -> model`` (e.g.
        :func:`femrub.periodic.scene_family` of a scene key).
    start, stop : the parameter's range (SI).
    h : largest θ-method step (s); each period is a whole number of steps of at most ``h``.
    key : the parameter's name (the branch's column).
    x0 : state the first point's time integration starts from (default ``model.x0``).
    warmup : periods integrated before the first Newton iteration.
    multiple : the orbits' period in periods of the excitation.
    gamma, activation : the θ-method's options.
    ds, ds_max : first and largest pseudo-arclength step (scaled: the parameter range is 1).
    max_points : most points of the branch.
    tolerance : scaled shooting residual of a converged orbit.
    stall_tolerance : scaled residual accepted where Newton stalls (the period map is only
        piecewise continuous; :data:`~femrub.periodic.shooting.STALL_TOLERANCE`).
    keep_orbits : orbits of largest tip displacement kept (beside the ends and special
        points) in ``Branch.orbits``.
    log : callable receiving one line per point.

    Returns
    -------
    Branch
        Its points, ``status`` (``ok`` only if every point converged and the branch reached
        the end) and the selected orbits. A Ctrl-C returns the points found, ``interrupted``.
    """
    family = _family(source, key)
    settings = _Settings(ds, ds_max=ds_max, max_points=max_points, tolerance=tolerance)
    settings.stall_tolerance = stall_tolerance
    options = {"multiple": multiple, "gamma": gamma, "activation": activation}
    cont = _Continuation(_Problem(family, h, options), key, start, stop, settings, log)
    try:
        branch = cont.run(x0, warmup)
    except KeyboardInterrupt:
        branch = cont.branch
        branch.status, branch.message = "interrupted", "interrupted (Ctrl-C); points kept"
    except RuntimeError as exc:
        branch = cont.branch
        branch.status, branch.message = "failed", str(exc)
    if branch.status == "ok" and not all(p.converged for p in branch.points):
        branch.status, branch.message = "failed", "a point did not converge"
    uncertain = sum(p.unsettled > 0 for p in branch.points)
    if branch.status == "ok" and uncertain:
        branch.status = "inaccurate"
        branch.message = (
            f"{uncertain} of {len(branch.points)} points have uncertain Floquet multipliers: "
            "their period map switches contacts within every finite-difference step tried "
            "(branch.csv column unsettled_columns); their stability is not established"
        )
    if branch.status == "ok":
        loose = sum(p.residual > tolerance for p in branch.points)
        branch.message = f"{len(branch.points)} periodic orbits, every one converged" + (
            f" ({loose} closed to a scaled residual between {tolerance:g} and "
            f"{stall_tolerance:g}, where Newton stalls)"
            if loose
            else ""
        )
    branch.orbits = _selected(branch, cont._orbits, keep_orbits)
    return branch
