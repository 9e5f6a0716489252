"""Compiled blocks of frictional θ-method steps whose contacts carry a history.

:func:`femrub.contact.theta_block.friction_block` advances steps whose contact terms are
known before the block. Two things make a step depend on the steps before it inside the
block, and :func:`rub_block` adds them to the same step (the same functions:
:func:`~femrub.contact.theta_block.friction_step`, :func:`femrub.contact.coulomb.power_heat`,
:mod:`femrub.contact.wear_map`):

* **Frictional heat with the ``"power"`` law on a thermoelastic model.** The blade receives
  ``Q_i = η_i (−P_t,i · w_t,i^mid)``, ``w_t^mid = (w_t,k + w_t,k+1) / 2``, in the same step;
  through the thermal coupling it shifts the local velocities by ``W_θ Q`` (``W_θ`` the
  local rows of ``D⁻¹ H_t``), so the step is the fixed point
  :func:`femrub.contact.coulomb.power_heat` (the one implementation, also run by the
  per-step path and the exponential stepper's impulses), and
  ``X_{k+1} = X_p + Z P + D⁻¹ H_t Q``.
* **An abradable coating** (:mod:`femrub.contact.abradable`). The gap is read on the worn
  surface and its rate over the step, ``g0 += w(t)``, ``ġ0 += (w(t) − w(t − h)) / h``
  (:func:`~femrub.contact.wear_map.depth_under`), the normal impulses are bounded,
  ``0 <= P_n <= U = h F_y`` (``U = ∞`` where the coating is worn through; less for a contact
  entering the coating within the step, :func:`~femrub.contact.wear_map.entry_bounds`), and
  after each step the contacts that yielded (``P_n >= (1 − 10⁻⁹) U``) cut the map along their sweep
  (:func:`~femrub.contact.wear_map.cut_sweeps`), in place, with the gap at the step's end.

The casing terms of step ``k`` at ``t_k`` are those computed for it as the previous step's
end, before that step's cut (as ``ThetaMethod._casing`` keeps them); the cut uses the times
``t0 + (k + 1) h`` at which the per-step path calls ``Contact.after_step``.
"""

from __future__ import annotations

import math

import numpy as np

from .coulomb import power_heat
from .jit import njit
from .theta_block import _predict, friction_step
from .wear_map import cut_sweeps, depth_under, positions

__all__ = ["rub_block", "WEAR_GRID"]

#: entries of the float vector ``grid`` of :func:`rub_block`
WEAR_GRID = ("omega", "scale", "thickness", "cap", "footprint")


@njit
def _wear_cut(depth, GT, X, P, t, g0, angles, axial_cell, grid, dims, last_r, wstate, U):
    """``Abradable.update`` at ``t`` after a step (``g0`` (n,): the casing profile's gap at
    ``t``): the contacts that yielded (at their bound ``U`` of the step) cut the map;
    ``last_r`` ``(2, n)`` carries the previous call's reach (row 0) and each contact's
    largest reach so far, its incursion (row 1), ``wstate`` ``(called before, its time,
    deepest wear)``. Returns the deepest wear after the cut, or ``nan`` when nothing was
    cut."""
    omega, scale, thickness = grid[0], grid[1], grid[2]
    n_angle, n_axial = dims[0], dims[1]
    n = angles.size
    x1 = positions(t, angles, omega, scale)
    d = depth_under(depth, x1, axial_cell, n_angle, n_axial, grid[4])
    gx = np.dot(GT, X)
    reach = np.empty(n)
    cut = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        reach[i] = d[i] - ((g0[i] + d[i]) + gx[i])
        cut[i] = P[i, 0] >= (1.0 - 1e-9) * U[i] and reach[i] > d[i]
    out = math.nan
    idx = np.flatnonzero(cut)
    if idx.size:
        r1, xe, r0, x0 = reach[idx], x1[idx], reach[idx], x1[idx]
        if wstate[0] > 0.0 and t > wstate[1]:
            x0 = positions(wstate[1], angles, omega, scale)[idx]
            r0 = last_r[0][idx]
        deepest = cut_sweeps(
            depth, axial_cell[idx], x0, xe, r0, r1, thickness, n_angle, n_axial, grid[4]
        )
        wstate[2] = max(wstate[2], deepest)
        out = wstate[2]
    last_r[0, :] = reach
    for i in range(n):
        last_r[1, i] = max(last_r[1, i], reach[i])
    wstate[0], wstate[1] = 1.0, t
    return out


@njit
def rub_block(X, prediction, contact, warm, use_warm, heating, wearing, out):
    """``Xout.shape[0]`` frictional steps with the ``"power"`` heat fixed point (``power``)
    and/or the wear map (``wear``) (module docstring). The arguments come in groups
    (tuples: one compiled signature, no copies):

    * ``prediction = (T, Y1, Y0, sig, h, gamma)``: ``X_p = T X_k + Y1 s_{k+1} + Y0 s_k``;
    * ``contact = (S, off, Z, W, GZ, code, mu, e3, U3, alpha, tol, max_iter)``: the local
      rows ``S``, the casing terms ``off`` (m + 1, 4 n_c) at ``t_k``, then the casing
      profile's at each step's end ``t1`` (the worn surface is added here, in place), the
      impulse columns, the rule's code, the Coulomb solve's parameters;
    * ``heating = (power, Zt, W3t, eta, max_heat)``: the ``"power"`` heat fixed point;
    * ``wearing = (wear, t1, ta, g0a, GT, depth, angles, axial_cell, grid, dims, last_r,
      wstate)``: ``ta``, ``g0a`` (m, n_c) the times of the cuts and the profile's gap there;
      ``depth`` the flat wear map (cut in place); ``grid``: :data:`WEAR_GRID`; ``dims``:
      ``(n_angle, n_axial)``;
    * ``out = (Xout, Pout, Ptout, heat_out, state_out, hist)``: the rows written, ``hist``
      (m,) the deepest wear after each step's cut (``nan``: none).

    Returns ``(steps done, status, residual, warm)``; a step whose solve failed is not
    written (nor cut), and the block stops there.
    """
    T, Y1, Y0, sig, h, gamma = prediction
    S, off, Z, W, GZ, code, mu, e3, U3, alpha, tol, max_iter = contact
    power, Zt, W3t, eta, max_heat = heating
    wear, t1, ta, g0a, GT, depth, angles, axial_cell, grid, dims, last_r, wstate = wearing
    Xout, Pout, Ptout, heat_out, state_out, hist = out
    n = mu.size
    omega, scale, thickness, cap = grid[0], grid[1], grid[2], grid[3]
    U = U3.copy()
    w_k = np.empty((n, 2))
    Xk = X
    for j in range(Xout.shape[0]):
        Xp = _predict(T, Y1, Y0, sig, j, Xk)
        if wear:
            d1 = depth_under(
                depth, positions(t1[j], angles, omega, scale), axial_cell, dims[0], dims[1], grid[4]
            )
            d0 = depth_under(
                depth,
                positions(t1[j] - h, angles, omega, scale),
                axial_cell,
                dims[0],
                dims[1],
                grid[4],
            )
            for i in range(n):
                off[j + 1, i] += d1[i]
                off[j + 1, n + 3 * i] += (d1[i] - d0[i]) / h
                U[i] = math.inf if d1[i] >= thickness else cap
        yk, q, e, gdk, active, P, u, st, res, status = friction_step(
            Xk,
            Xp,
            S,
            off[j],
            off[j + 1],
            GZ,
            W,
            code,
            mu,
            e3,
            U,
            warm,
            use_warm,
            h,
            gamma,
            tol,
            max_iter,
        )
        if status != 0:
            return j, status, res, warm
        heat = np.zeros(n)
        if power:
            for i in range(n):
                w_k[i, 0], w_k[i, 1] = yk[n + 3 * i + 1], yk[n + 3 * i + 2]
            P, u, st, heat, res, status = power_heat(
                P, u, st, w_k, eta, W, q, W3t, mu, e, gdk, U, active, tol, max_iter, max_heat
            )
            if status != 0:
                return j, status, res, warm
        else:
            for i in range(n):
                heat[i] = alpha[i] * P[i, 0]
        warm, use_warm = P, True
        Xk = Xp + np.dot(Z, P.reshape(-1)) if active.any() else Xp
        if power:
            Xk = Xk + np.dot(Zt, heat)
        Xout[j] = Xk
        for i in range(n):
            Pout[j, i] = P[i, 0]
            Ptout[j, i, 0], Ptout[j, i, 1] = P[i, 1], P[i, 2]
            heat_out[j, i] = heat[i]
            state_out[j, i] = st[i]
        hist[j] = math.nan
        if wear:
            hist[j] = _wear_cut(
                depth, GT, Xk, P, ta[j], g0a[j], angles, axial_cell, grid, dims, last_r, wstate, U
            )
    return Xout.shape[0], 0, 0.0, warm
