"""Contact events inside a step of the exponential stepper, located on its exact flows.

The exact gaps ``g = g0(t) + Gᵀ X`` and the multipliers ``λ_S`` of held contacts are checked on
a grid of ``probes`` points per step (probe rows: one product per step,
:meth:`~femrub.steppers.flows.FlowFamily.probe`); at the first sign change of a gap below
``min(g(a), 0)`` (a closing) or of a multiplier (a release) the time is found on the exact
flow by :func:`~femrub.steppers.flows.first_zero` (cubic Hermite start, safeguarded Newton),
each evaluation composed of cached sub-step flows from the latest state computed before it
(:meth:`~femrub.steppers.flows.FlowFamily.advance_z`). Event times are exact to ``1e-10 h``.
"""

from __future__ import annotations

import math

import numpy as np

from .flows import first_zero, shift

__all__ = ["EventLocation"]

_XTOL = 1e-10  # relative tolerance (of h) on an event time


class EventLocation:
    """Event location of :class:`~femrub.steppers.exponential.ExponentialMoreau` (mixin: it
    reads the stepper's model, ``h``, ``t``, ``probes``, flows and load polynomial helpers)."""

    # -- events --------------------------------------------------------------------------------
    def _event(self, S, Xa, a, Xe, b):
        """Earliest closing or release in ``(a, h]``: ``(τ, kind, i, X(τ), P_S(a..τ))``.

        The exact gaps and held multipliers are checked on a grid of spacing ``h / probes``
        (probe rows on a full step, the cached flow marched on a part step); the first sign
        change is then located on the exact flow (cached sub-step flows over ``h / probes × 2^e``).
        """
        c, h, t, flows, q = self.model.contact, self.h, self.t, self._flows, self.probes
        n_s, d = len(S), h / self.probes
        if a == 0.0 and self._quiet(S, Xa, Xe, b):
            return None

        def values(tau, X):
            g = c.gap(t + tau, X)
            return np.concatenate([g, flows.multiplier(S, X, self._u(b, tau / h))]) if S else g

        # grid: a, the next multiples of d, h; rows of gaps and multipliers on it (blocks)
        grid, rows, states = [[a]], [values(a, Xa)[None]], {0: (Xa, np.zeros(n_s))}
        i1 = math.floor(a / d * (1.0 + 1e-12)) + 1  # first grid index after a
        if i1 < q:
            g1 = i1 * d
            if a > 0.0:  # part step: to the grid with cached sub-step flows
                X1, P1 = flows.advance(S, Xa, a, g1, b, d)
                grid.append([g1])
                rows.append(values(g1, X1)[None])
                states[1] = (X1, P1)
            else:
                X1 = Xa
            start = g1 if a > 0.0 else 0.0  # the grid start the probe rows run from
            if q - i1 > 1 or a == 0.0:
                Rx, Rb = flows.probe(S, c.GT, q)
                nj = q - 1 - (i1 if a > 0.0 else 0)  # probe points before h
                r = Rx.shape[0] // (q - 1)
                sig0 = start / h  # the load polynomial re-expanded at the grid start
                b1 = b if sig0 == 0.0 else self._Dinv @ shift(b, sig0, 1.0)
                V = Rx[: nj * r] @ X1
                if Rb.shape[1]:
                    V += Rb[: nj * r] @ b1.ravel()
                V = V.reshape(nj, r)
                taus = start + d * np.arange(1, nj + 1)
                V[:, : c.n] += c.gap_at(t + taus) if callable(c.gap0) else c.gap0
                grid.append(taus)
                rows.append(V)
        grid.append([h])
        rows.append(values(h, Xe)[None])
        grid, V = np.concatenate(grid), np.concatenate(rows)
        gv, lv = V[:, : c.n], V[:, c.n :]
        # closing: the gap falls below min(g(a), 0) after having been above it
        f_cl = gv - np.minimum(gv[0], 0.0)
        closing = (f_cl[1:] < 0.0).any(axis=0)
        if S:
            closing[list(S)] = False
        elif not closing.any():  # the common case: free flight, nothing closes
            return None
        cand = []  # (bracket j, kind, contact, f(τ, X) -> (value, d/dτ))
        lam, c_n = (flows.generator(S)[2], self.model.n_dofs) if S else (None, 0)
        for i in np.flatnonzero(closing):
            ref = min(gv[0, i], 0.0)

            def f(tau, X, i=i, ref=ref):
                rate = c.rate_at(t + tau)[i] if callable(c.gap_rate) else 0.0
                dX = flows.rate(S, X, self._u(b, tau / h))
                return c.gap(t + tau, X)[i] - ref, rate + c.GT[i] @ dX

            cand.append((1 + int(np.argmax(f_cl[1:, i] < 0.0)), "closing", int(i), f))
        for k in np.flatnonzero(np.any(lv < 0.0, axis=0)):
            j = int(np.argmax(lv[:, k] < 0.0))
            if j == 0:  # pulled away already: release now
                return a, "release", S[k], Xa, np.zeros(n_s)

            def f(tau, X, k=k):
                u, du = self._u(b, tau / h), self._du(b, tau / h)
                lx, lu = lam[k, :c_n], lam[k, c_n:]
                val = lx @ X + (lu @ u if lu.size else 0.0)
                return val, lx @ flows.rate(S, X, u) + (lu @ du if lu.size else 0.0)

            cand.append((j, "release", S[k], f))
        if not cand:
            return None
        j = min(x[0] for x in cand)
        lo = grid[j - 1]
        if j - 1 not in states:  # march the cached flows to the bracket
            k = max(states)
            Xk, Pk = states[k]
            Xj, Pj = flows.advance(S, Xk, grid[k], grid[j - 1], b, d)
            states[j - 1] = (Xj, Pk + Pj)
        X0, P0 = states[j - 1]
        best = None
        for jj, kind, i, f in cand:
            if jj != j:
                continue
            found = self._root(S, f, lo, grid[j], X0, b)
            if found is not None and (best is None or found[0] < best[0]):
                best = (*found, kind, i)
        if best is None:
            return None
        tau, X, Pl, kind, i = best
        return tau, kind, i, X, P0 + Pl

    def _quiet(self, S, Xa, Xe, b) -> bool:
        """A whole step without event: no free gap falls below ``min(g(0), 0)`` and no held
        multiplier is negative on the probe grid and at the step's ends (the common case,
        checked with one product of the probe rows and one of the end rows)."""
        c, t, h, q, flows = self.model.contact, self.t, self.h, self.probes, self._flows
        Ex, Eu = flows.end_rows(S, c.GT)
        ends = np.vstack([Xa, Xe]) @ Ex.T  # [gaps; multipliers] at 0 and h, gap0 aside
        if Eu is not None:
            ends += np.vstack([b[0], b.sum(axis=0)]) @ Eu.T
        if q > 1:
            Rx, Rb = flows.probe(S, c.GT, q)
            V = Rx @ Xa
            if Rb.shape[1]:
                V += Rb @ b.ravel()
            V = np.vstack([ends[:1], V.reshape(q - 1, -1), ends[1:]])
        else:
            V = ends
        gv = V[:, : c.n]
        if callable(c.gap0):
            gv += c.gap_at(t + (h / q) * np.arange(q + 1))
        else:
            gv += c.gap0
        ref = np.minimum(gv[0], 0.0)
        if S:
            ref[list(S)] = -np.inf
        return not ((gv[1:] < ref).any() or (V[:, c.n :] < 0.0).any())

    def _root(self, S, f, lo, hi, X_lo, b):
        """First zero of ``f`` in ``(lo, hi]`` on the exact flow from ``(lo, X_lo)``
        (:func:`~femrub.steppers.flows.first_zero`): ``(τ, X(τ), P_S(lo..τ))`` or ``None``.
        Each evaluation starts from the latest state already computed before it (the open
        side of the bracket), so Newton's shrinking corrections compose few sub-step flows."""
        h, flows, d = self.h, self._flows, self.h / self.probes
        n, s = self.model.n_dofs, len(S)
        known = [(lo, np.concatenate([X_lo, np.zeros(s), flows.chain(b, lo / h)]))]

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
