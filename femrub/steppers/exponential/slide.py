"""Slip directions of the exponential stepper's sliding held contacts (Coulomb friction).

A held contact sliding with friction ``μ`` takes the force ``λ_t = −μ λ ŝ`` along a unit
direction ``ŝ`` of its tangent plane that is constant over a flight, so that its force column
``H = Hm − μ Hmt ŝ + Ht α_h`` is constant and the held flow linear and exact
(:mod:`~.friction`). Coulomb's law wants ``ŝ`` along the slip ``w_t = Gvtᵀ X − v_c``,
which turns with the structure's own tangential velocity. The direction is therefore chosen per
step by a fixed point: the step is flown with a direction, the slip ``w_t`` at the end of each
held flight in it (after any impulse at the step end) gives the next direction, and the step is
repeated from its start until the two agree; the recorded friction impulse of the step is then
along the end slip. Each pass is exact for its direction (flows, impulses, works and heats), so
the energy and heat balances close to round-off whatever the pass count.

Directions are quantised: the angle of ``ŝ`` from the casing's direction ``−v_c / |v_c|`` (in
the tangent plane) is a multiple of :data:`DIRECTION_STEP`, and a pass is accepted when the
end slip's angle is within ``0.75 DIRECTION_STEP`` of it, so ``1 + cos`` between the step's
friction impulse and its end slip stays below ``(0.75 DIRECTION_STEP)² / 2`` (steps with an
impulse inside them excepted: the impulse is along the slip at its own time). The flows,
check rows and work integrals of a held set depend on its contacts' directions; those of the
directions met are kept (the oldest dropped first beyond :data:`STASH_BYTES` in all), so a
slide swinging about the casing's direction reuses them instead of building new exponentials
every step. The first pass of a step keeps the directions of the step before (their flows are
at hand); on a reduced blade the slip direction jitters by several quanta from step to step
(the modes an impact excites), so extrapolating it does not save the second pass.
"""

from __future__ import annotations

import math
from collections import OrderedDict

import numpy as np

from .flows import held_set

__all__ = ["DIRECTION_STEP", "MAX_DIRECTION_ITERATIONS", "STASH_BYTES", "SlideDirections"]

#: angle quantum of a held slide's direction (rad)
DIRECTION_STEP = 5e-5
#: most passes of a step on the directions of its held slides
MAX_DIRECTION_ITERATIONS = 6
#: memory kept for the flows of directions not in use (bytes)
STASH_BYTES = 2e8


def _nbytes(value) -> int:
    """Bytes of the arrays in a cache entry (arrays, tuples/lists of them, objects)."""
    if isinstance(value, np.ndarray):
        return value.nbytes
    if isinstance(value, dict):
        return sum(_nbytes(v) for v in value.values())
    if isinstance(value, (tuple, list)):
        return sum(_nbytes(v) for v in value)
    return sum(_nbytes(v) for v in getattr(value, "__dict__", {}).values())


class SlideDirections:
    """Directions of held slides (mixin of :class:`~.friction.FrictionalContact`;
    see module docstring): the per-step fixed point and the flows kept per direction."""

    _target = None  # during a step's pass: contact -> state at the end of its held flight

    def _slide_setup(self) -> None:
        """Start every held slide along the casing's direction; no direction kept yet."""
        n = self.model.contact.n
        self._key = [None] * n  # per contact: its angle's multiple of DIRECTION_STEP (or None)
        self._stash: OrderedDict = OrderedDict()  # direction signature -> {cache: {key: entry}}
        self._stash_size: dict = {}
        self._fixed: set = set()
        self._target = None
        self._dir0 = self._dir.copy()  # the casing's direction: angle 0
        self._apply(self._dir.copy(), ())

    def _caches(self) -> list[dict]:
        """The caches that depend on the directions of held slides."""
        out = [self._fused, self._probe_rows, *self._flows.caches()]
        for integ in (self._integrals, self._rest):
            if integ is not None:
                out += integ.caches()
        return out

    def _signature(self, S) -> tuple:
        return tuple((int(i), self._key[i]) for i in S if self._sliding[i])

    def _apply(self, D, changed) -> None:
        """Slide along ``D`` (n_c, 2): the slip rows, works, heats and held columns that depend
        on it, in place (the flows and integrals hold these arrays)."""
        c, n = self.model.contact, self.model.contact.n
        self._dir[:] = D
        R, off, _ = self._slip
        R[:] = np.einsum("ik,ikn->in", D, c.GvtT.reshape(n, 2, -1))
        off[:] = -np.einsum("ik,ik->i", D, c.casing_velocity)  # σ0 = −ŝ · v_c
        self._T[:] = -self._mu[:, None] * R
        if self._power:
            self._alpha_h[:] = self._eta * self._mu * off
            self._rest_rows[:] = (self._eta * self._mu)[:, None] * R
        if self._alpha_h is not None:
            tang = -np.einsum("nik,ik->ni", self._Zmt.reshape(-1, n, 2), D) * self._mu
            cols = self._Zm + tang + self._Zt * self._alpha_h
            if self._AinvH is None:
                self._AinvH = cols
            else:
                self._AinvH[:] = cols

    def _set_angles(self, keys: dict) -> None:
        """Slide the contacts of ``keys`` (contact -> multiple of :data:`DIRECTION_STEP`) along
        those angles; stash the flows of their old directions, restore those of the new."""
        changed = {int(i) for i, k in keys.items() if self._key[i] != k}
        if not changed:
            return
        caches = self._caches()
        for idx, cache in enumerate(caches):  # out: entries of held sets with a changed contact
            for key in list(cache):
                S = held_set(key)
                if changed.intersection(S):
                    sig = self._signature(S)
                    self._stash.setdefault(sig, {}).setdefault(idx, {})[key] = cache.pop(key)
        D = self._dir.copy()
        for i in changed:
            self._key[i] = keys[i]
            phi, (a, b) = keys[i] * DIRECTION_STEP, self._dir0[i]
            D[i] = (a * math.cos(phi) - b * math.sin(phi), b * math.cos(phi) + a * math.sin(phi))
        self._apply(D, changed)
        for sig in [s for s in self._stash if changed.intersection(i for i, _ in s)]:
            if all(self._key[i] == k for i, k in sig):  # in: entries of the new directions
                for idx, entries in self._stash.pop(sig).items():
                    caches[idx].update(entries)
                self._stash_size.pop(sig, None)
        for sig in [s for s in self._stash if s not in self._stash_size]:
            self._stash_size[sig] = _nbytes(self._stash[sig])  # newly stashed: most recent
            self._stash.move_to_end(sig)
        while self._stash and sum(self._stash_size.values()) > STASH_BYTES:  # oldest out
            sig, _ = self._stash.popitem(last=False)
            self._stash_size.pop(sig, None)

    def _slip_angles(self, contacts, X) -> dict:
        """Angles of the slip ``w_t`` at ``X`` of the sliding ``contacts`` from the casing's
        direction (where the slip is not 0)."""
        w, d = self.model.contact.slip_velocity(X), self._dir0
        return {
            int(i): math.atan2(d[i, 0] * w[i, 1] - d[i, 1] * w[i, 0], d[i] @ w[i])
            for i in contacts
            if self._sliding[i] and (w[i, 0] or w[i, 1])
        }

    def _start_slides(self, contacts, X) -> None:
        """New held slides of ``contacts`` (at an impulse): along their slip at ``X``, unless
        the step's fixed point sets their direction."""
        new = [i for i in contacts if i not in self._fixed]
        ang = self._slip_angles(new, X)
        self._set_angles({i: round(a / DIRECTION_STEP) for i, a in ang.items()})

    def _slide_passes(self):
        """One step with held slides: :meth:`_one_step` repeated from its start until each
        held slide's direction is its slip's at the end of its held flight in the step (see
        module docstring; at most :data:`MAX_DIRECTION_ITERATIONS` passes)."""
        start = (self._S, self._warm3, self._loads.sk)
        self._fixed = {int(i) for i in start[0]}
        for it in range(MAX_DIRECTION_ITERATIONS):
            self._target = {}  # contact -> state at the end of its held flight
            out = self._one_step()
            for i in self._S:  # held at the step end: its slip after any impulse there
                self._target[int(i)] = out[0]
            ang = {}
            for i, X in self._target.items():
                ang.update(self._slip_angles([i], X))
            off = [
                abs((a - self._key[i] * DIRECTION_STEP + math.pi) % (2 * math.pi) - math.pi)
                for i, a in ang.items()
                if i in self._slid and self._key[i] is not None
            ]
            if max(off, default=0.0) <= 0.75 * DIRECTION_STEP or it == MAX_DIRECTION_ITERATIONS - 1:
                break
            self._S, self._warm3, self._loads.sk = start
            self._fixed = set(ang)
            self._set_angles({i: round(a / DIRECTION_STEP) for i, a in ang.items()})
        new = {i: round(a / DIRECTION_STEP) for i, a in ang.items() if i not in self._slid}
        self._set_angles(new)  # slides started at the step end: along their slip
        self._target = None
        return out
