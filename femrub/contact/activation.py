"""Activation rules: which contacts take an impulse in a step, and under which law.

A step of an implicit scheme (θ-method, exponential integrator) from ``t_k`` to
``t_{k+1} = t_k + h`` gives ``X_{k+1} = X_p + Z P`` with the free prediction ``X_p`` and the
impulse ``P >= 0`` (paper Eq. 16a, ``P = h λ_{k+1}``). The gap and the gap velocity are then
affine in ``P``::

    g_{k+1} = g_p + GZ P          ġ_{k+1} = ġ_p + W P

(``GZ = Gᵀ Z``, Delassus operator ``W = Gvᵀ Z``). A rule turns ``(g_k, ġ_k, g_p, ġ_p)``
into the impulse. With the trapezoidal rule ``g_{k+1} − g_k = h (ġ_k + ġ_{k+1}) / 2``, so
the contact work of a step (:mod:`femrub.output.energy`) is::

    ΔW_c = Pᵀ (ġ_k + ġ_{k+1}) / 2 = Pᵀ (g_{k+1} − g_k) / h

Rules (``RULES``). Each keeps ``P > 0`` only where the step's contact work is ``<= 0``,
except ``"plain"``:

* ``"position"`` (default): Signorini's condition at ``t_{k+1}``, relative to a target gap::

      0 <= P  ⊥  g_{k+1} − g*  >= 0,        g* = min(g_k, 0) + e max(g_k, 0)

  An open contact whose free step crosses the casing lands on it (``g_{k+1} = 0`` for
  ``e = 0``; at ``e g_k`` for ``e > 0``, which for ``e = 1`` is Newton's elastic law); a
  closed contact is held where it is (``g_{k+1} = g_k``, the midpoint law). An open
  contact takes an impulse only when its free step ends inside the casing (``g_p < 0``). ``P > 0``
  implies ``g_{k+1} <= g_k``, so ``ΔW_c <= 0``, and ``g_{k+1} <= e max(g_k, 0)``: for
  ``e = 0`` no impulse ever acts at an open gap. Residual penetration comes only from the
  crossing step and round-off. It needs no activation set.
* ``"capped"``: Newton's law in velocity form, capped at the same target::

      0 <= P  ⊥  max(ġ_{k+1} + e ġ_k,  (2/h) (g_{k+1} − g*)) >= 0

  (approaching closed contacts stop, ``ġ_{k+1} = −e ġ_k``; penetration up to ``h |ġ| / 2``).
* ``"paper"``: active if closed at ``t_k`` or closed at ``t_{k+1}`` (``g_{k+1} <= 0``,
  paper Eq. 25b) iterated to a fixed point with the impulse; if no consistent set exists
  the contact is kept active. Newton's law on approaching contacts, ``e = 1`` on separating
  ones. At the crossing step it may stop the tip short of the casing (force at a distance).
* ``"plain"``: active if the free step's gap at ``t_{k+1}`` is closed (``g_p <= 0``),
  Newton's law on the velocity everywhere. Not energy-safe: stopping a separating contact
  lifts the gap (``ΔW_c = P (1 − e) ġ_k / 2 > 0``), and it may push at an open gap.
* ``"predicted"``: Moreau–Jean (Siconos) rule ``g_k + γ h ġ_k <= 0``, ``e = 1`` on
  separating contacts.

**With Coulomb friction** the impulses ``(P_n, P_t)`` solve Signorini–Coulomb with Newton's
law in velocity form (:mod:`femrub.contact.friction`) and the rule chooses the contacts of
that solve: ``"paper"`` (the default with friction, :data:`DEFAULT_FRICTIONAL_RULE`) and
``"predicted"`` (:data:`FRICTIONAL_RULES`, :func:`frictional_fixed_point`). ``"position"``
and ``"capped"`` state the normal law on the gap and ``"plain"`` on the free step, laws the
Coulomb solve does not state: :func:`rule_for` refuses them with friction (one line naming
the fix) rather than running another rule under their name.

Every rule takes an optional bound ``upper`` (n_c,) on the impulses, ``0 <= P <= upper``
(:func:`femrub.contact.impulses.cap`): an abradable coating yields at ``upper = h F_y``
(:mod:`femrub.contact.abradable`), and a contact held at its bound may penetrate the worn
surface by what the coating then loses. :func:`frictional_fixed_point` (compiled) passes
it to each frictional solve (``U``).

Measured accuracy of each on the paper case: ``docs/paper-reproduction.md``.
"""

from __future__ import annotations

import numpy as np

from .coulomb import FIXED_POINT, PREDICTED, frictional_fixed_point
from .impulses import solve_impulses
from .theta_block import ONE_RULES, impulse_one_code

__all__ = [
    "RULES",
    "DEFAULT_RULE",
    "DEFAULT_FRICTIONAL_RULE",
    "FRICTIONAL_RULES",
    "check_rule",
    "frictionless_only",
    "rule_for",
    "frictional_fixed_point",
    "rule_code",
    "impulse_one",
    "impulses",
    "compile_kernels",
    "KERNEL_KINDS",
]

RULES = ("position", "capped", "paper", "plain", "predicted")
DEFAULT_RULE = "position"
#: the rules with a frictional form: they choose the contacts of the frictional solve
FRICTIONAL_RULES = ("paper", "predicted")
#: the rule of frictional contacts when none is asked for
DEFAULT_FRICTIONAL_RULE = "paper"


def check_rule(rule: str) -> str:
    """Return ``rule`` or raise a one-line error naming the valid rules."""
    if rule not in RULES:
        raise ValueError(f"unknown activation rule {rule!r}; use one of {', '.join(RULES)}")
    return rule


def frictionless_only(rule: str) -> str | None:
    """Why ``rule`` cannot run with friction (the fix in words), or ``None`` if it can."""
    if rule in FRICTIONAL_RULES:
        return None
    law = "position-level" if rule in ("position", "capped") else "free-step"
    return (
        f"the {law} rule {rule!r} has no frictional form; use "
        f"{' or '.join(map(repr, FRICTIONAL_RULES))} (the default with friction)"
    )


def rule_for(rule: str | None, frictional: bool) -> str:
    """The rule a step runs: ``rule``, or when ``None`` the default of the contacts
    (:data:`DEFAULT_FRICTIONAL_RULE` with friction, else :data:`DEFAULT_RULE`). A rule
    without a frictional form on frictional contacts raises a one-line ``ValueError``."""
    if rule is None:
        return DEFAULT_FRICTIONAL_RULE if frictional else DEFAULT_RULE
    check_rule(rule)
    why = frictionless_only(rule) if frictional else None
    if why:
        raise ValueError(f"activation {rule!r} with friction μ > 0: {why}, or μ = 0")
    return rule


def impulse_one(rule, g_k, gd_k, g_p, gd_p, w, gz, e, h, gamma, upper=np.inf) -> float:
    """Impulse of a single contact (scalar closed form of :func:`impulses`).

    ``w = ∂ġ_{k+1}/∂P > 0`` and ``gz = ∂g_{k+1}/∂P > 0``; ``upper``: bound on the impulse.
    The arithmetic is :func:`femrub.contact.theta_block.impulse_one_code` (compiled).
    """
    P = impulse_one_code(
        ONE_RULES[rule],
        float(g_k),
        float(gd_k),
        float(g_p),
        float(gd_p),
        float(w),
        float(gz),
        float(e),
        float(h),
        float(gamma),
    )
    return min(P, upper)


def impulses(rule, g_k, gd_k, g_p, gd_p, W, GZ, e, h, gamma, warm=None, upper=None):
    """Impulses of all contacts for one step under ``rule`` (see module docstring).

    Parameters
    ----------
    g_k, gd_k : gap and gap velocity at ``t_k``, shape ``(n_c,)``.
    g_p, gd_p : gap and gap velocity of the free step at ``t_{k+1}``.
    W, GZ : ``∂ġ_{k+1}/∂P`` and ``∂g_{k+1}/∂P``, shape ``(n_c, n_c)``.
    e : restitution coefficients, ``(n_c,)``.
    warm : previous step's ``P > 0`` (warm start of the LCP), or ``None``.
    upper : (n_c,) bound on the impulses (``None``: unbounded).

    Returns
    -------
    (n_c,) impulses ``P``.
    """
    if rule == "capped":
        return _capped(g_k, gd_k, g_p, gd_p, W, GZ, e, h, warm, upper)
    if rule == "position":
        q = (2.0 / h) * (g_p - _target(g_k, e))
        M = (2.0 / h) * GZ
        closed = g_k <= 0.0
        active = (q < 0.0) & (closed | (g_p < 0.0))
        while True:  # add contacts that the others' impulses pull below their target
            P = solve_impulses(M, q, active, warm, upper)
            r = M @ P + q
            low = ~active & (r < -1e-12 * np.abs(q).max()) & (closed | (g_p + GZ @ P < 0.0))
            if not low.any():
                return P
            active |= low
    if rule == "plain":
        return solve_impulses(W, gd_p + e * gd_k, g_p <= 0.0, warm, upper)
    e = np.where(gd_k > 0.0, 1.0, e)  # midpoint law on separating contacts
    q = (gd_p + e * gd_k) / (1.0 + e)
    Wn = W / (1.0 + e)[:, None]
    if rule == "predicted":
        return solve_impulses(Wn, q, g_k + gamma * h * gd_k <= 0.0, warm, upper)
    closed = g_k <= 0.0
    active = closed | (g_p <= 0.0)
    seen = []
    while True:
        P = solve_impulses(Wn, q, active, warm, upper)
        new = closed | (g_p + GZ @ P <= 0.0)
        if np.array_equal(new, active):
            return P
        if any(np.array_equal(new, a) for a in seen):  # no consistent set: keep impulse
            return solve_impulses(Wn, q, new | active, warm, upper)
        seen.append(active)
        active = new


def _capped(g_k, gd_k, g_p, gd_p, W, GZ, e, h, warm, upper=None):
    """``0 <= P ⊥ max(r_v, r_g) >= 0`` by switching each contact's binding row.

    ``r_v = W P + ġ_p + e ġ_k`` (Newton) and ``r_g = (2/h)(GZ P + g_p − g*)``
    (cap, ``g*`` of :func:`_target`). Each row choice is an LCP; a contact with ``P > 0``
    whose other residual is positive switches rows, until the choice is consistent.
    """
    qv = gd_p + e * gd_k
    qg = (2.0 / h) * (g_p - _target(g_k, e))
    Wg = (2.0 / h) * GZ
    # a contact whose free step stays above the cap, or open and off the casing, takes none
    cand = (qg < 0.0) & ((g_k <= 0.0) | (g_p < 0.0))
    if not cand.any():
        return np.zeros(g_k.size)
    use_g = np.zeros(g_k.size, dtype=bool)
    for _ in range(2 * g_k.size + 2):
        M = np.where(use_g[:, None], Wg, W)
        q = np.where(use_g, qg, qv)
        P = solve_impulses(M, q, cand, warm, upper)
        other = np.where(use_g, W @ P + qv, Wg @ P + qg)
        if upper is not None:  # a contact at its bound is not limited by either row
            other = np.where(P >= upper, -np.inf, other)
        switch = cand & (P > 0.0) & (other > 1e-10 * np.maximum(np.abs(qv), np.abs(qg)))
        if not switch.any():
            return P
        use_g ^= switch
    return P


def _target(g_k, e):
    """Highest gap an impulse may lift a contact to: ``g* = min(g_k, 0) + e max(g_k, 0)``."""
    return np.minimum(g_k, 0.0) + e * np.maximum(g_k, 0.0)


def rule_code(rule: str) -> int:
    """Code of ``rule`` for :func:`frictional_fixed_point` (``"predicted"`` or the rest)."""
    return PREDICTED if check_rule(rule) == "predicted" else FIXED_POINT


#: the kernel families a run may need: ``"one"`` (one frictionless contact on a fixed
#: obstacle, the impulse in closed form), ``"friction"`` (the frictional fixed point and its
#: block) and ``"rub"`` (the block with the power heat fixed point and the wear map's cut)
KERNEL_KINDS = ("one", "friction", "rub")


def compile_kernels(kinds=KERNEL_KINDS) -> None:
    """Compile (or load from numba's on-disk cache) the contact kernels of ``kinds``
    (:data:`KERNEL_KINDS`) for the argument types of a run, so that its first contact step
    does not pay for it; no step is taken (blocks of zero rows). Only what a run needs is
    compiled: a fresh machine's first frictionless run compiles one family, not three.
    Without compilation (``NUMBA_DISABLE_JIT=1``) a no-op.
    """
    from .jit import compiled, wait_background

    unknown = sorted(set(kinds) - set(KERNEL_KINDS))
    if unknown:
        raise ValueError(f"unknown kernel kinds {unknown}; known: {list(KERNEL_KINDS)}")
    if not compiled():
        return
    wait_background()  # a build's child compiling them (jit.compile_in_background)
    for kind in KERNEL_KINDS:
        if kind in kinds:
            _COMPILE[kind]()


def _compile_one() -> None:
    from .theta_block import one_contact_block

    N, E = 2, np.empty
    T, Y, sig = np.eye(N), np.zeros((N, 0)), np.zeros((1, 0))
    one_contact_block(
        np.zeros(N),
        T,
        Y,
        Y,
        sig,
        0,
        1.0,
        np.ones(N),
        np.ones(N),
        np.ones(N),
        1.0,
        1.0,
        0.0,
        1.0,
        0.5,
        np.inf,
        E((0, N)),
        E((0, 1)),
    )


def _block_arguments() -> tuple:
    """Arguments of a frictional block of zero rows: ``(head, rows)``."""
    N, E, one = 2, np.empty, np.ones(1)
    T, Y, sig = np.eye(N), np.zeros((N, 0)), np.zeros((1, 0))
    rows = (E((0, N)), E((0, 1)), E((0, 1, 2)), E((0, 1)), E((0, 1), dtype=np.int8))
    head = (
        np.zeros(N),
        T,
        Y,
        Y,
        sig,
        np.zeros((4, N)),
        np.zeros((1, 4)),
        np.zeros((N, 3)),
        np.eye(3),
        np.zeros((1, 3)),
        FIXED_POINT,
        one,
        one * 0.0,
        one * np.inf,
        np.zeros((1, 3)),
        False,
        1.0,
        0.5,
        one * 0.0,
        1e-12,
        60,
    )
    return head, rows


def _compile_friction() -> None:
    from .friction import solve_frictional_contact
    from .theta_block import friction_block

    one, z, W = np.ones(1), np.zeros(1), np.eye(3)
    q = np.array([[-1.0, 0.0, 0.0]])
    for code in (FIXED_POINT, PREDICTED):
        frictional_fixed_point(
            code,
            -one,
            -one,
            -one,
            np.ones((1, 3)),
            W,
            q,
            one * 0.1,
            z,
            z.copy(),
            np.full(1, np.inf),
            np.zeros((1, 3)),
            False,
            1.0,
            0.5,
            1e-12,
            60,
        )
    solve_frictional_contact(W, q, 0.1, np.ones(1, dtype=bool))
    head, rows = _block_arguments()
    friction_block(*head, *rows)


def _compile_rub() -> None:
    from .rub_block import rub_block
    from .wear_map import cut_sweeps

    head, rows = _block_arguments()
    N, E, one, z = 2, np.empty, np.ones(1), np.zeros(1)
    ints = np.zeros(1, dtype=np.int64)
    X0, T, Y1, Y0, sig, S, off, Z, W, GZ, code, mu, e3, U3, warm, use_warm, h, gamma = head[:18]
    alpha, tol, max_iter = head[18:]
    rub_block(
        X0,
        (T, Y1, Y0, sig, h, gamma),
        (S, off, Z, W, GZ, code, mu, e3, U3, alpha, tol, max_iter),
        warm,
        use_warm,
        (True, np.zeros((N, 1)), np.zeros((3, 1)), one * 0.5, 20),
        (
            True,
            E(0),
            E(0),
            np.zeros((0, 1)),
            np.zeros((1, N)),
            z.copy(),
            z.copy(),
            ints,
            np.ones(5),
            np.ones(2, dtype=np.int64),
            np.zeros((2, 1)),
            np.zeros(3),
        ),
        (*rows, E(0)),
    )
    cut_sweeps(z.copy(), ints, z.copy(), one * 0.5, z.copy(), z.copy(), 1.0, 1, 1, 0.0)


_COMPILE = {"one": _compile_one, "friction": _compile_friction, "rub": _compile_rub}
