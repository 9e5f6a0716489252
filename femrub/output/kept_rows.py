"""What a record keeps of its checked rows: every array (:class:`AllRows`) or, for a run held
only to be compared with another, what the comparison reads (:class:`LeanRows`).

A :class:`~femrub.output.recorder.Recorder` steps and checks a run chunk by chunk in buffers
of one chunk's rows (their row 0 is the chunk's first row, the previous chunk's last); it
hands each checked row once to its store, ``take(rec, i0, last)`` (rows up to ``last``,
the buffers' row 0 being row ``i0``), and the store makes the
:class:`~femrub.output.results.Results`:

* :class:`AllRows`: every per-step array of every row (a run's history);
* :class:`LeanRows`: what :meth:`~femrub.output.results.Results.lean` keeps (times, impulses,
  signals; the checkpoint states are the recorder's) at rows ``0, k, 2k, …`` with the
  impulses summed over each ``k`` steps, ``h`` becoming ``k h``: the run seen on the steps
  of ``k h`` (:func:`femrub.analysis.step_check.coarsen`), rows of an incomplete last group
  dropped. Gaps, friction rows and the energy balance are never stored; what the verdict
  reads of them is measured as the rows pass, into ``Results.checks``: the largest balance
  residuals and the scales :meth:`~femrub.output.results.Results.energy_error` and
  :meth:`~femrub.output.results.Results.heat_error` divide them by, and the Coulomb check
  (:func:`~femrub.contact.friction.coulomb_check`). Maxima and sums over rows do not depend
  on how the rows are cut, so these are the values the whole arrays would give. A run only
  compared (``RunOptions.compared``, ``LeanRows(coulomb=False)`` and no energy meter)
  measures none of them: its ``Results.checks`` is empty.

What a store reads of the buffers besides times, signals and impulses (``reads_gaps``,
``reads_slips``) tells the recorder which rows to compute: a lean record never reads the
gaps, and reads the slip velocities only for its Coulomb check.
"""

from __future__ import annotations

import numpy as np

from ..contact.friction import coulomb_check_rows, merge_coulomb_checks
from .balance import BALANCE_TERMS, balance_maxima, energy_error_of, heat_error_of
from .results import Results, signal_units

__all__ = ["AllRows", "LeanRows"]


def _signals(rec, obs) -> dict[str, np.ndarray]:
    """The columns of ``obs`` (rows of the recorder's observations) by signal name (views)."""
    out, col = {}, 0
    for name, size in zip(rec.names, rec.sizes):
        out[name] = obs[:, col : col + size]
        col += size
    return out


def _info(rec) -> dict:
    info = {"label": rec.label, "stability_limit": rec.h_lim, "n_dofs": rec.model.n_dofs}
    units = signal_units(rec.model)
    return {**info, "signal_units": units} if units else info


def _put(rows: np.ndarray, at: slice, values: np.ndarray) -> None:
    """``rows[at] = values`` unless ``values`` are all zero: the record's arrays start as
    untouched zeros (pages the system maps only when written), and most per-contact arrays
    of a rub (impulses, friction forces, contact states) are zero most of the time."""
    if values.any():
        rows[at] = values


class AllRows:
    """Every per-step array of every row, ``n_steps + 1`` rows allocated at once (as zeros,
    written only where a chunk's rows are not: :func:`_put`); the tangential impulses and
    slip velocities in global axes (``friction_force``, ``slip_velocity``:
    ``(rows, n_c, 3)``), turned chunk by chunk as the rows arrive (the local rows are not
    kept beside them)."""

    reads_gaps = reads_slips = True
    #: the recorder's buffers kept in global axes, by the name they take in the results
    _GLOBAL = {"imp_t": "friction_force", "slip": "slip_velocity"}
    #: buffers not kept as they are: those turned, and the blade's heat per contact and
    #: step (the energy meter sums it)
    _UNKEPT = (*_GLOBAL, "heat")

    def __init__(self, rec):
        n1, self.taken = rec.n + 1, -1
        c = rec.model.contact
        self._turns = rec.tangents and c.frames is not None
        kept = {k: a for k, a in rec.buffers().items() if k not in self._UNKEPT}
        self.rows = {k: np.zeros((n1, *a.shape[1:]), a.dtype) for k, a in kept.items()}
        nc = rec.model.n_contacts
        for name in self._GLOBAL.values():  # zeros without tangents (untouched: no memory)
            self.rows[name] = np.zeros((n1, nc, 3))
        self.extra: dict[str, np.ndarray] = {}

    def take(self, rec, i0: int, last: int) -> None:
        """Copy rows ``taken + 1 .. last`` from the recorder's buffers (tangential rows turned
        to global axes, friction impulses over ``h`` as forces)."""
        first = self.taken + 1
        if last < first:
            return
        a, b = slice(first, last + 1), slice(first - i0, last + 1 - i0)
        for k, v in rec.buffers().items():
            if k not in self._UNKEPT:
                _put(self.rows[k], a, v[b])
        if self._turns:
            c = rec.model.contact
            if rec.imp_t[b].any():
                self.rows["friction_force"][a] = c.to_global(rec.imp_t[b] / rec.h)
            if rec.slip[b].any():
                self.rows["slip_velocity"][a] = c.to_global(rec.slip[b])
        for k, v in rec.extra.items():
            _put(self.extra.setdefault(k, np.zeros((rec.n + 1, *v.shape[1:]), v.dtype)), a, v[b])
        self.taken = last

    def results(self, rec, m: int, **kw) -> Results:
        """The first ``m`` rows as :class:`Results` (``kw``: status, states, …)."""
        r = self.rows

        def reached(a):  # the rows reached; no copy of a complete run's arrays (not reused)
            return a[:m] if m == a.shape[0] else a[:m].copy()

        c = rec.model.contact
        if not rec.has_friction:  # frictionless stepper: open or (frictionless) sliding
            r["cstate"][:m] = np.where(r["imp"][:m] > 0.0, 2, 0)
        energy = {k[7:]: reached(v) for k, v in r.items() if k.startswith("energy_")}
        return Results(
            scheme=rec.scheme,
            h=rec.h,
            t=reached(r["t"]),
            signals=_signals(rec, reached(r["obs"])),
            gap=reached(r["gap"]),
            impulse=reached(r["imp"]),
            energy=energy,
            steps=m - 1,
            friction_force=reached(r["friction_force"]),
            slip_velocity=reached(r["slip_velocity"]),
            contact_state=reached(r["cstate"]),
            friction_limit=None if c is None else c.friction.copy(),
            info=_info(rec),
            extra={k: reached(v) for k, v in self.extra.items()},
            **kw,
        )


class LeanRows:
    """Times and signals every ``every``-th row, impulses summed per ``every`` steps, and the
    verdict's measures of every row (module docstring; ``coulomb=False``: no Coulomb check,
    the balance measured only when the recorder has an energy meter)."""

    reads_gaps = False

    def __init__(self, rec, every: int, coulomb: bool = True):
        self.k, self.taken, self.groups = int(every), -1, 0
        if self.k < 1:
            raise ValueError(f"a lean record keeps every k-th row, k >= 1; got {every!r}")
        n1, nc = rec.n // self.k + 1, rec.model.n_contacts
        self.t, self.obs = np.zeros(n1), np.zeros((n1, rec.obs.shape[1]))
        self.imp, self._open = np.zeros((n1, nc)), np.zeros((0, nc))
        self.maxima = dict.fromkeys(BALANCE_TERMS, -np.inf) if rec.meter is not None else None
        # Coulomb check parts with the recorded contact states and, while the stepper has
        # written no friction rows, with a frictionless stepper's (AllRows.results)
        c = rec.model.contact
        self._coulomb = None if c is None or not nc or not coulomb else ([], [])
        self.reads_slips = self._coulomb is not None

    def take(self, rec, i0: int, last: int) -> None:
        """Keep and measure rows ``taken + 1 .. last`` of the recorder's buffers."""
        first = self.taken + 1
        if last < first:
            return
        b, k = slice(first - i0, last + 1 - i0), self.k
        rows = np.arange(first, last + 1)
        at = rows % k == 0
        self.t[rows[at] // k], self.obs[rows[at] // k] = rec.t[b][at], rec.obs[b][at]
        P = rec.imp[b]
        if first == 0:  # the initial impulse, as is
            self.imp[0], P = P[0], P[1:]
        P = np.concatenate([self._open, P])  # the group left open by the previous rows first
        g, j = len(P) // k, self.groups
        self.imp[j + 1 : j + 1 + g] = P[: g * k].reshape(g, k, P.shape[1]).sum(axis=1)
        self.groups, self._open = j + g, P[g * k :].copy()
        self._measure(rec, b)
        self.taken = last

    def _measure(self, rec, b: slice) -> None:
        """Running maxima of the balance (``Results.energy_error``'s terms) and Coulomb
        check parts of the buffers' rows ``b``."""
        if self.maxima is not None:
            mx = balance_maxima(rec.meter.data, b)
            self.maxima = {k: max(v, mx[k]) for k, v in self.maxima.items()}
        if self._coulomb is None:
            return
        c, h, imp = rec.model.contact, rec.h, rec.imp[b]
        ff = sv = np.zeros((imp.shape[0], imp.shape[1], 3))
        if rec.tangents and c.frames is not None:
            ff, sv = c.to_global(rec.imp_t[b] / h), c.to_global(rec.slip[b])
        mu, recorded, frictionless = np.asarray(c.friction, dtype=float), *self._coulomb
        recorded.append(coulomb_check_rows(imp / h, ff, sv, rec.cstate[b], mu))
        if not rec.has_friction:
            state = np.where(imp > 0.0, 2, 0)
            frictionless.append(coulomb_check_rows(imp / h, ff, sv, state, mu))

    def checks(self, rec, m: int) -> dict:
        """``Results.checks``: the balance residuals relative to their scales (as
        ``energy_error()`` and ``heat_error()`` of the whole arrays) and the Coulomb check."""
        out = {}
        mx = self.maxima
        if mx is not None:
            nan = m < 2
            out["energy_error"] = float("nan") if nan else energy_error_of(mx)
            out["heat_error"] = float("nan") if nan else heat_error_of(mx)
        if self._coulomb is not None and m:
            parts = self._coulomb[0 if rec.has_friction else 1]
            out["coulomb"] = merge_coulomb_checks(parts)
        return out

    def results(self, rec, m: int, **kw) -> Results:
        """The kept rows of the first ``m`` rows reached as :class:`Results` (``kw``: status,
        states, …): ``h`` is ``k h``, ``steps`` the steps of ``h`` stepped."""
        n = (m - 1) // self.k if m else -1  # complete groups of the rows reached

        def kept(a):
            return a[: n + 1] if n + 1 == a.shape[0] else a[: n + 1].copy()

        c = rec.model.contact
        return Results(
            scheme=rec.scheme,
            h=rec.h * self.k,
            t=kept(self.t),
            signals=_signals(rec, kept(self.obs)),
            gap=np.zeros((n + 1, 0)),
            impulse=kept(self.imp),
            steps=max(m - 1, 0),
            info={**_info(rec), "lean": self.k},
            friction_limit=None if c is None else c.friction.copy(),
            checks=self.checks(rec, m),
            **kw,
        )
