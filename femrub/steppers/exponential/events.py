"""Contact events inside a step of the exponential stepper, located on its exact flows.

The exact gaps ``g = g0(t) + Gᵀ X``, the multipliers ``λ_S`` of held contacts and the slips of
held contacts sliding with friction (:mod:`~.friction`) are checked on
a grid of ``probes`` points per step (probe rows: one product per step,
:meth:`~.flows.FlowFamily.probe`); at the first sign change of a gap below
``min(g(a), 0)`` (a closing), of a multiplier (a release) or of a slip (a stick) the time is
found on the exact flow by :func:`~.flows.first_zero` (cubic Hermite start,
safeguarded Newton), each evaluation composed of cached sub-step flows from the latest state
computed before it (:meth:`~.flows.FlowFamily.advance_z`); an event function
linear on the augmented state (every one but a closing on a moving or worn casing) in one
compiled call (:func:`~.kernels.first_zero_row`). Event times are exact to
``1e-10 h``. A part step's check rows are one compiled call too
(:func:`~.kernels.part_rows`).
"""

from __future__ import annotations

import math

import numpy as np

from .flows import LEVEL_MIN, first_zero
from .kernels import first_zero_row, part_rows, quiet

__all__ = ["EventLocation"]

_XTOL = 1e-10  # relative tolerance (of h) on an event time


class EventLocation:
    """Event location of :class:`~femrub.steppers.exponential.ExponentialMoreau` (mixin: it
    reads the stepper's model, ``h``, ``t``, ``probes``, its flows and load polynomials)."""

    # -- events --------------------------------------------------------------------------------
    def _event(self, S, Xa, a, Xe, b, V=None):
        """Earliest closing or release in ``(a, h]``: ``(τ, kind, i, X(τ), P_S(a..τ))``.

        The exact gaps and held multipliers are checked on a grid of spacing ``h / probes``
        (at a step start: the rows ``V`` of :meth:`_grid_rows`, computed with the flight;
        on a part step: probe rows and cached sub-step flows); the first sign change is then
        located on the exact flow (cached sub-step flows over ``h / probes × 2^e``).
        """
        h, q, n_s = self.h, self.probes, len(S)
        if a == 0.0 and V is not None:  # the whole step's grid, read off the flight
            if self._quiet(S, V):
                return None
            grid = np.append(h / q * np.arange(q), h)
            states = {0: (Xa, np.zeros(n_s))}
        else:
            grid, V, states = self._part_grid(S, Xa, a, Xe, b)
        cand = self._closings(S, V, b)
        if cand is None:  # the common case: free flight, nothing closes
            return None
        held = self._held_events(S, V, b)
        if held and held[0] == 0:  # pulled away (or stopped sliding) already: now
            return a, held[1], held[2], Xa, np.zeros(n_s)
        cand += held[1:] if held else []
        if not cand:
            return None
        return self._locate(S, cand, grid, states, b)

    def _closings(self, S, V, b):
        """Closing candidates on the grid rows ``V``: the gap falls below ``min(g(a), 0)``
        after having been above it. Each candidate is ``(bracket j, kind, contact,
        f(τ, X) -> (value, d/dτ), row)`` with ``row = (r, c0)`` when ``f`` is linear on the
        augmented state, ``f = r·z + c0`` (a compiled root search). ``None``: no held
        contact and nothing closes (no other event can happen)."""
        c, h, t, flows = self.model.contact, self.h, self.t, self._flows
        gv = V[:, : c.n]
        f_cl = gv - np.minimum(gv[0], 0.0)
        closing = (f_cl[1:] < 0.0).any(axis=0)
        if S:
            closing[list(S)] = False
        elif not closing.any():
            return None
        g0 = self._fixed_gap()
        cand = []
        for i in np.flatnonzero(closing):
            ref = min(gv[0, i], 0.0)
            row = None if g0 is None else (self._z_row(S, x=c.GT[i]), g0[i] - ref)

            def f(tau, X, i=i, ref=ref):
                rate = c.rate_at(t + tau)[i] if callable(c.gap_rate) else 0.0
                dX = flows.rate(S, X, self._loads.u(b, tau / h))
                return c.gap(t + tau, X)[i] - ref, rate + c.GT[i] @ dX

            cand.append((1 + int(np.argmax(f_cl[1:, i] < 0.0)), "closing", int(i), f, row))
        return cand

    def _held_events(self, S, V, b):
        """Release (a held multiplier turns negative) and stick (a held slide's slip turns
        negative) candidates on the grid rows ``V``, as :meth:`_closings`; a first entry
        ``(0, kind, contact)`` when one is negative at the part step's start already."""
        if not S:
            return []
        n_s = len(S)
        slides = self._flows.sliding(S)
        lv = V[:, self.model.contact.n :]
        cand = [None]
        for k in np.flatnonzero(np.any(lv < 0.0, axis=0)):
            j = int(np.argmax(lv[:, k] < 0.0))
            i = S[k] if k < n_s else slides[k - n_s]  # a multiplier, or a slip (stick)
            kind = "release" if k < n_s else "stick"
            if j == 0:
                return [0, kind, i]
            f, row = self._slip_event(S, i, b) if k >= n_s else self._release_event(S, k, b)
            cand.append((j, kind, i, f, row))
        return cand

    def _release_event(self, S, k, b):
        """``(f, row)`` of the ``k``-th held multiplier ``λ_k = l_x·X + l_u·u``."""
        h, flows, c_n = self.h, self._flows, self.model.n_dofs
        lam = flows.generator(S)[2]
        lx, lu = lam[k, :c_n], lam[k, c_n:]

        def f(tau, X):
            u, du = self._loads.u(b, tau / h), self._loads.du(b, tau / h)
            val = lx @ X + (lu @ u if lu.size else 0.0)
            return val, lx @ flows.rate(S, X, u) + (lu @ du if lu.size else 0.0)

        return f, (self._z_row(S, x=lx, u=lu), 0.0)

    def _slip_event(self, S, i, b):
        """``(f, row)`` of the slip ``σ = R_σ X + σ0`` of held contact ``i`` sliding."""
        h, flows = self.h, self._flows
        r, off = flows.slip[0][i], flows.slip[1][i]

        def f(tau, X):
            return r @ X + off, r @ flows.rate(S, X, self._loads.u(b, tau / h))

        return f, (self._z_row(S, x=r), off)

    def _locate(self, S, cand, grid, states, b):
        """The earliest zero among the candidates of the first bracket that has any:
        ``(τ, kind, i, X(τ), P_S(a..τ))`` or ``None``."""
        flows, d = self._flows, self.h / self.probes
        j = min(x[0] for x in cand)
        if j - 1 not in states:  # march the cached flows to the bracket
            k = max(states)
            Xk, Pk = states[k]
            Xj, Pj = flows.advance(S, Xk, grid[k], grid[j - 1], b, d)
            states[j - 1] = (Xj, Pk + Pj)
        X0, P0 = states[j - 1]
        best = None
        for jj, kind, i, f, row in cand:
            if jj != j:
                continue
            found = self._root(S, f, grid[j - 1], grid[j], X0, b, row)
            if found is not None and (best is None or found[0] < best[0]):
                best = (*found, kind, i)
        if best is None:
            return None
        tau, X, Pl, kind, i = best
        return tau, kind, i, X, P0 + Pl

    def _part_grid(self, S, Xa, a, Xe, b):
        """The check grid of a part step ``(a, h]``: ``(grid, V, states)``, ``V`` the rows
        ``[g; λ_S; σ]`` at ``grid`` (``a``, the next multiples of ``h / probes`` (the first
        reached with cached sub-step flows, the others by probe rows), ``h``; compiled,
        :func:`~.kernels.part_rows`), ``states`` the states known on it."""
        c, h, t, flows, q = self.model.contact, self.h, self.t, self._flows, self.probes
        n, n_s, d = self.model.n_dofs, len(S), h / self.probes
        i1 = math.floor(a / d * (1.0 + 1e-12)) + 1  # first grid index after a
        mid, k1, nj, start = False, 0, 0, 0.0
        if i1 < q:
            mid, start = a > 0.0, (i1 * d if a > 0.0 else 0.0)
            if mid:  # part step: to the grid with cached sub-step flows (as advance_z)
                k1 = int((start - a) / d * 2.0**-LEVEL_MIN * (1.0 + 1e-12))
            if q - i1 > 1 or a == 0.0:
                nj = q - 1 - (i1 if mid else 0)  # probe points before h
        R, Rz = flows.check_rows(S, c.GT, q)
        Z = flows.levels(S, d)
        k1 = min(k1, (1 << len(Z)) - 1)
        zero = np.zeros(n_s)
        za = np.concatenate([Xa, zero, flows.chain(b, a / h)])
        zh = np.concatenate([Xe, zero, flows.chain(b, 1.0)])
        V, z1 = part_rows(Z, R, Rz, za, k1, mid, nj, zh)
        grid = np.concatenate([[a], [start] if mid else [], start + d * np.arange(1, nj + 1), [h]])
        V[:, : c.n] += c.gap_at(t + grid) if self._fixed_gap() is None else c.gap0
        if flows.sliding(S):
            V[:, c.n :] += flows.check_offsets(S)
        states = {0: (Xa, zero)}
        if mid:
            states[1] = (z1[:n], z1[n : n + n_s])
        return grid, V, states

    def _grid_rows(self, S, flow) -> np.ndarray:
        """``R`` (cached per held set): ``R u`` are the rows ``[Gᵀ X; λ_S]`` at
        ``τ_j = j h / q``, j = 0 … q (``q = probes``), for the inputs ``u = [X; w]`` of the
        step's exact flight ``flow`` (``w_l = l! b_l``, :class:`~.flows.Flow`): end rows at
        both ends (the end state ``X(h) = [Φ Ψ]_X u``), probe rows between
        (:meth:`~.flows.FlowFamily.probe`, load coefficients ``b_l = w_l / l!``)."""
        key = ("grid", S)
        if key not in self._probe_rows:
            c, flows, q = self.model.contact, self._flows, self.probes
            n = self.model.n_dofs
            Ex, Eu = flows.end_rows(S, c.GT)
            r, n_in = Ex.shape[0], n + flow.Psi.shape[1]
            R = np.zeros((q + 1, r, n_in))
            R[0, :, :n] = Ex
            R[q] = Ex @ np.hstack([flow.Phi[:n], flow.Psi[:n]])
            m, p1 = flows.G.shape[1], flows.degree + 1
            inv = np.repeat([1.0 / math.factorial(j) for j in range(p1)], m)  # b = w / l!
            if Eu is not None:  # λ_S's load terms: s(0) = w_0, s(h) = Σ w_l / l!
                R[0, :, n : n + m] += Eu
                R[q, :, n:] += np.tile(Eu, p1) * inv
            if q > 1:
                Rx, Rb = flows.probe(S, c.GT, q)
                R[1:q, :, :n] = Rx.reshape(q - 1, r, n)
                if Rb.shape[1]:
                    R[1:q, :, n:] = (Rb * inv).reshape(q - 1, r, -1)
            self._probe_rows[key] = R.reshape((q + 1) * r, n_in)
        return self._probe_rows[key]

    def _quiet(self, S, V) -> bool:
        """A whole step without event: on the grid ``V`` (rows ``[g; λ_S]`` at ``j h / q``)
        no free gap falls below ``min(g(0), 0)`` and no held multiplier is negative (the
        common case; compiled, :func:`~.kernels.quiet`)."""
        return quiet(V, self.model.contact.n, self._held(S))

    def _fixed_gap(self):
        """The casing's gaps ``g0`` (n_c,) when they are constant (fixed casing, no wear, no
        casing heat: a closing is then a row event), else ``None``."""
        c = self.model.contact
        if callable(c.gap0) or c.gap_rate is not None or c.wear is not None:
            return None
        if c.casing_heat is not None:
            return None
        if getattr(self, "_g0_fixed", None) is None:
            self._g0_fixed = np.broadcast_to(np.asarray(c.gap0, dtype=float), (c.n,))
        return self._g0_fixed

    def _z_row(self, S, x, u=None) -> np.ndarray:
        """A row ``r`` on the augmented state ``z = [X; P_S; s, …]`` of held set ``S``:
        ``r·z = x·X + u·s`` (``s``: the load signals, the chain's first block)."""
        n, nz = self.model.n_dofs, self.model.n_dofs + len(S)
        r = np.zeros(self._flows.generator_z(S).shape[0])
        r[:n] = x
        if u is not None and u.size:
            r[nz : nz + u.size] = u
        return r

    def _root(self, S, f, lo, hi, X_lo, b, row=None):
        """First zero of ``f`` in ``(lo, hi]`` on the exact flow from ``(lo, X_lo)``
        (:func:`~.flows.first_zero`): ``(τ, X(τ), P_S(lo..τ))`` or ``None``.
        Each evaluation starts from the latest state already computed before it (the open
        side of the bracket), so Newton's shrinking corrections compose few sub-step flows.
        A row event ``f = r·z + c0`` (``row = (r, c0)``) is searched in one compiled call
        (:func:`~.kernels.first_zero_row`, the same iteration)."""
        h, flows, d = self.h, self._flows, self.h / self.probes
        n, s = self.model.n_dofs, len(S)
        z_lo = np.concatenate([X_lo, np.zeros(s), flows.chain(b, lo / h)])
        if row is not None:
            r, c0 = row
            Z = flows.levels(S, d)
            rM = r @ flows.generator_z(S)
            found, tau, z = first_zero_row(
                Z, z_lo, r, rM, float(c0), lo, hi, _XTOL * h, d * 2.0**LEVEL_MIN
            )
            return (tau, z[:n], z[n : n + s]) if found else None
        known = [(lo, z_lo)]

        def at(tau):
            t0, z0 = max((k for k in known if k[0] <= tau), key=lambda k: k[0])
            z = flows.advance_z(S, z0, tau - t0, d)
            X = z[:n]
            val, dval = f(tau, X)
            if val > 0.0:
                known.append((tau, z))
            return X, z[n : n + s], val, dval

        f_lo, df_lo = f(lo, X_lo)
        return first_zero(at, f_lo, lo, hi, _XTOL * h, df_lo)
