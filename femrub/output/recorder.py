"""Recording a run: the stepper's states, checked chunk by chunk, collected into ``Results``.

For the rows ``k = 0 .. n`` of a run of ``n`` steps of size ``h`` the recorder keeps::

    t_k,   s_k = O X_k (observations),   g_k = g0(t_k) + Gᵀ X_k,   P_k (impulse of step k)

and, with friction, the tangential impulses, the blade's heat and the contact state of each
step (the stepper's ``extra``), the slip velocity ``w_t = Gvtᵀ X_k − v_c`` and the energy
balance of :class:`~femrub.output.energy.EnergyMeter`. States are buffered in chunks and
post-processed with row-wise products. A chunk is checked before anything leaves it: a
non-finite state or energy created from nothing ends the run with status
``"unstable"``, a physical stop limit ``max |s| > bound`` (or ``|P / h| > bound`` for
``"contact_force"``) with ``"diverged-physically"``. Only checked states reach the sinks
(the ``on_state`` callback, e.g. a VTK series, the ``on_rows`` callback, e.g. a history
file appended chunk by chunk, and the stored states); whatever stops a run (a check,
Ctrl-C, SIGTERM, an exception), the rows recorded so far are returned and streamed.
Per-step arrays of any trailing shape live in :meth:`Recorder.per_step` (one place: the
streamed chunks and the final :class:`Results` are cut from it). The per-step buffers hold
one chunk (row 0: the previous chunk's last row); the checked rows are kept by
:mod:`femrub.output.kept_rows` (every row, or a lean record of a run only compared).
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
import scipy.sparse as sp
from tqdm.auto import tqdm

from ..blas import one_blas_thread
from ..fem.linalg import compact
from ..model.first_order import FirstOrderModel
from ..steppers.record import WORK_KEYS, State, StepRefused
from .energy import EnergyMeter
from .kept_rows import AllRows, LeanRows
from .limits import limit_hit as _limit_hit
from .limits import limit_index as _limit_index
from .results import Results

__all__ = ["CHUNK_STEPS", "CHUNK_VALUES", "Recorder", "State", "StepRefused"]

CHUNK_STEPS = 512  # steps post-processed together (row products; a blow-up reported soon)
CHUNK_VALUES = 2_000_000  # most state values buffered per chunk (16 MB of float64)


class _Stop(Exception):
    """A check ended the run at ``row`` (the last row kept)."""

    def __init__(self, status, message, row):
        super().__init__(message)
        self.status, self.message, self.row = status, message, int(row)


class Recorder:
    """Collects ``n_steps`` steps of a stepper into :class:`Results` (see module docstring).

    Parameters
    ----------
    model : the model run.
    h : time step (s).
    n_steps : number of steps to record after the initial state.
    scheme : name of the stepper (reported in ``Results`` and messages).
    stability_limit : largest stable step of the scheme (s); above it the status is
        ``"unstable"`` from the start.
    energy : keep the energy balance (needs ``model.energy``).
    limits : physical stop criteria ``{signal name or "contact_force": max |value|}``.
    store_every : keep the full state every that many steps (0: never).
    on_state : callback ``f(State)`` fed each checked state (each ``on_state.stride``-th).
    on_rows : callback ``f(arrays)`` fed each checked block of rows as :meth:`per_step`
        gives them (row 0 with the first block).
    lean : 0 keeps every per-step array; ``k >= 1`` only what a comparison of runs reads,
        every ``k``-th row, impulses summed per ``k`` steps (:mod:`~femrub.output.kept_rows`).
    compared : a lean run only compared (``lean >= 1``): no energy meter (``energy`` is
        ignored), no Coulomb check, no gaps or slip velocities computed
        (:class:`~femrub.analysis.options.RunOptions`).
    label : name of the run (progress bar and ``Results.info``).
    blowup_check : stop on energy created from nothing (a scheme may turn it off when the
        meter's quadratures, not the scheme, would open its balance).
    """

    def __init__(  # noqa: PLR0913 (a run's options as the recorder needs them)
        self,
        model: FirstOrderModel,
        h: float,
        n_steps: int,
        *,
        scheme: str,
        stability_limit: float,
        energy: bool = True,
        limits: dict[str, float] | None = None,
        store_every: int = 0,
        on_state: Callable | None = None,
        on_rows: Callable | None = None,
        label: str | None = None,
        blowup_check: bool = True,
        lean: int = 0,
        compared: bool = False,
        snapshots: tuple = (),
        take_snapshot: Callable | None = None,
    ):
        if compared and not lean:
            raise ValueError("a recorder of a run only compared keeps a lean record: lean >= 1")
        self.model, self.h, self.n, self.scheme = model, h, n_steps, scheme
        self.h_lim, self.label = stability_limit, label
        self.store_every, self.on_state, self.on_rows = store_every, on_state, on_rows
        self._streamed = -1
        self._delivered = 0
        #: further per-step buffers ``(chunk + 1, ...)`` filled by a stepper (kept and streamed)
        self.extra: dict[str, np.ndarray] = {}
        self.blowup_check = blowup_check
        N, nc = model.n_dofs, model.n_contacts
        self.chunk = int(max(1, min(CHUNK_STEPS, CHUNK_VALUES // max(N, 1))))
        n = self.chunk  # the buffers' rows: one chunk after its row 0
        self.names = list(model.observations)
        self.sizes = [model.observations[k].shape[0] for k in self.names]
        obs = [model.observations[k] for k in self.names]
        self._O = compact(sp.vstack(obs)) if obs else None
        self.obs = np.zeros((n + 1, sum(self.sizes)))
        self.t, self.gap, self.imp = np.zeros(n + 1), np.zeros((n + 1, nc)), np.zeros((n + 1, nc))
        c = model.contact
        self.tangents = c is not None and c.Gvt is not None
        nf = nc if self.tangents else 0
        self.imp_t, self.slip = np.zeros((n + 1, nf, 2)), np.zeros((n + 1, nf, 2))
        self.heat = np.zeros((n + 1, nc))
        self.cstate = np.zeros((n + 1, nc), dtype=np.int8)
        self.has_friction = False
        metered = energy and not compared and model.energy is not None
        self.meter = EnergyMeter(model, n + 1) if metered else None
        self.limits = dict(limits or {})
        self._lim_idx = _limit_index(self.limits, self.names, self.sizes)
        self._stored: list[np.ndarray] = []
        self._stored_rows: list[np.ndarray] = []
        self._stored_t: list[np.ndarray] = []
        self.status, self.message = "ok", ""
        if h > stability_limit:
            self.status = "unstable"
            self.message = (
                f"h = {h:.3g} s exceeds the stability limit {stability_limit:.3g} s of {scheme}"
            )
        self._work, self._work_cols = None, {}  # the steps' own integrals (_work_row)
        self._i = self._j = self._i0 = self._end = (
            0  # steps done, chunk row, chunk start, last kept
        )
        self.buf = np.empty((self.chunk + 1, N))
        self.kept = AllRows(self) if not lean else LeanRows(self, lean, coulomb=not compared)
        self._slips = self.tangents and self.kept.reads_slips
        #: the steps after which ``take_snapshot(step)`` is kept (blocks end there)
        self._snap_at = sorted({int(k) for k in snapshots if 0 <= k <= n_steps})
        self._take_snapshot, self.snapshots = take_snapshot, []

    def buffers(self) -> dict[str, np.ndarray]:
        """The per-step buffers, by name (``energy_*``: the meter's), one chunk's rows."""
        out = {"t": self.t, "obs": self.obs, "gap": self.gap, "imp": self.imp}
        out.update(imp_t=self.imp_t, slip=self.slip, heat=self.heat, cstate=self.cstate)
        if self.meter is not None:
            out.update({f"energy_{k}": v for k, v in self.meter.data.items()})
        return out

    # -- the run ---------------------------------------------------------------------------
    def record(
        self, start: State, advance: Callable, *, progress: bool = False, block=None
    ) -> Results:
        """Record ``start`` and ``n_steps`` calls of ``advance() ->``
        :class:`~femrub.steppers.record.StepRecord`.

        ``block`` (optional, :meth:`Stepper.block_writer
        <femrub.steppers.base.Stepper.block_writer>`) replaces ``advance`` by whole blocks of
        steps written into the recorder's rows; its ``error`` ends the run as ``advance``
        raising it would. A record's ``friction`` fills the friction rows, its ``works`` the
        energy meter's own integrals of the step (:data:`~femrub.steppers.record.WORK_KEYS`).
        """
        cpu0 = time.process_time()
        bar = tqdm(
            total=self.n,
            disable=not progress,
            unit="step",
            desc=self.label or self.scheme,
            leave=False,
        )
        take = self._take_block if block is not None else self._take_step
        # one BLAS thread: per-step products are small, threads only add latency (a busy
        # 2-core machine showed 0.4-17 ms for a 20000-long dot product with two threads);
        # a blow-up overflows before the next check, and non-finite states are reported
        with one_blas_thread, np.errstate(over="ignore", invalid="ignore"):
            try:
                self._start(start)
                self._snapshot()
                while self._i < self.n:
                    take(block or advance)
                    self._snapshot()
                    if self._j == self.chunk or self._i == self.n:
                        self._close_chunk(bar)
            except _Stop as stop:
                self._end = self._stopped(stop, self._i0, self._j)
            except KeyboardInterrupt:
                self._interrupted()
            except Exception as exc:  # keep what was computed
                self.status, self.message = "failed", f"{type(exc).__name__}: {exc}"
                self._stream(self._i0, self._end)
            finally:
                bar.close()
            self._flush_sink()
        return self._results(self._end, time.process_time() - cpu0)

    def _halt(self, status: str, message: str) -> _Stop:
        """Check the buffered rows, then the stop at the last of them."""
        self._end = self._flush(self._i0, self._j)
        return _Stop(status, message, self._end)

    def _snapshot(self) -> None:
        """Keep the snapshot of the step just done when one is asked for there."""
        if self._snap_at and self._snap_at[0] == self._i:
            self.snapshots.append(self._take_snapshot(self._snap_at.pop(0)))

    def _take_block(self, block: Callable) -> None:
        """A block of steps in one call of the stepper's block writer, into the rows (it ends
        at the next snapshot's step)."""
        j = self._j
        m = min(self.chunk - j, self.n - self._i)
        if self._snap_at:
            m = min(m, self._snap_at[0] - self._i)
        r = slice(j + 1, j + 1 + m)
        done, friction, err = block(
            m, self.buf[r], self.t[r], self.imp[r], self.imp_t[r], self.heat[r], self.cstate[r]
        )
        self.has_friction |= friction
        self._i, self._j = self._i + done, j + done
        if err is not None:
            raise self._halt("unstable", f"{type(err).__name__}: {err}")

    def _take_step(self, advance: Callable) -> None:
        """One step of the stepper, its record into the next row."""
        self._i += 1
        try:
            rec = advance()
        except (FloatingPointError, ArithmeticError) as exc:
            raise self._halt("unstable", f"{type(exc).__name__}: {exc}") from None
        except StepRefused as exc:
            raise self._halt("failed", f"{self.scheme}: {exc}") from None
        self._j += 1
        j = self._j
        self.buf[j], self.t[j] = rec.X, rec.t
        if self.model.n_contacts:
            self.imp[j] = rec.impulse
        if rec.works:
            self._work_row(j, rec.works)
        if rec.friction is not None:
            self._friction_rows(j, rec.friction)

    def _close_chunk(self, bar) -> None:
        """Check the chunk's rows, hand them on, start the next chunk."""
        self._end = self._flush(self._i0, self._j)
        self._deliver(self._i0, self._end)
        self._stream(self._i0, self._end)
        bar.update(self._j)
        self._next_chunk(self._j)
        self._i0, self._j = self._i, 0

    def _interrupted(self) -> None:
        """Ctrl-C or SIGTERM: keep the checked rows before the last buffered step (it may be
        incomplete)."""
        self.status = "interrupted"
        self.message = "interrupted by the user; results kept up to here"
        i0, j = self._i0, self._j
        try:
            self._end = self._flush(i0, j - 1) if j > 1 else i0
            self._deliver(i0, self._end)
        except _Stop as stop:
            self._end = self._stopped(stop, i0, j - 1)
        except KeyboardInterrupt:  # a second signal: keep the checked rows
            self._end = i0
        self._stream(i0, self._end)

    def _flush_sink(self) -> None:
        """``on_state.flush()`` if it holds states back (batched VTK frames), also after an
        interruption or a failure; its error fails the run."""
        try:
            getattr(self.on_state, "flush", lambda: None)()
        except Exception as exc:
            if self.status != "failed":
                self.status, self.message = "failed", f"output: {type(exc).__name__}: {exc}"

    def _next_chunk(self, j: int) -> None:
        """Row ``j`` becomes the buffers' row 0; rows a step may not write are zeroed."""
        for a in (self.buf, *self.buffers().values(), *self.extra.values()):
            a[0] = a[j]
        for a in (self.imp_t, self.heat, self.cstate, self._work, *self.extra.values()):
            if a is not None:
                a[1:] = 0

    def _work_row(self, i: int, works) -> None:
        """The step's own energy-balance integrals (``{name in WORK_KEYS: J}``) in row ``i``."""
        if self._work is None:
            self._work = np.zeros((self.chunk + 1, len(WORK_KEYS)))
        for key, value in works.items():
            col = WORK_KEYS.index(key)
            self._work[i, col] = value
            self._work_cols[key] = col

    def _friction_rows(self, i: int, friction) -> None:
        """Frictional quantities (:class:`~femrub.steppers.record.Friction`) in row ``i``."""
        self.has_friction = True
        if self.tangents:
            self.imp_t[i] = friction.impulse
        self.heat[i] = friction.heat
        self.cstate[i] = friction.state

    def _start(self, s: State) -> None:
        """Row 0: the initial state."""
        self.t[0], self.buf[0] = s.t, s.X
        if self.model.n_contacts:
            self.gap[0], self.imp[0] = s.gap, s.impulse
            if self.tangents:
                self.slip[0] = self.model.contact.slip_velocity(s.X)
        if self._O is not None:
            self.obs[0] = self._O @ s.X
        if self.meter is not None:
            self.meter.start(s.X)
        self.kept.take(self, 0, 0)
        if self.on_state is not None:
            self.on_state(s)
        if self.store_every:
            self._stored.append(s.X[None, :].copy())
            self._stored_rows.append(np.array([0]))
            self._stored_t.append(np.array([s.t]))

    def _stopped(self, stop: _Stop, i0: int, j: int) -> int:
        """Status and message of a check that ended the run; feed the sinks; last row kept."""
        self.status = stop.status
        unstable = stop.status == "unstable"
        self.message = f"{self.scheme}: {stop.message}" if unstable else stop.message
        self._deliver(i0, min(stop.row, i0 + j))
        self._stream(i0, stop.row)
        return stop.row

    def _stream(self, i0: int, last: int) -> None:
        """Feed ``on_rows`` the rows after the last streamed one, up to ``last`` (≥ ``i0``)."""
        if self.on_rows is None or last <= self._streamed:
            return
        rows = slice(self._streamed + 1 - i0, last + 1 - i0)
        self._streamed = last
        self.on_rows({k: v.copy() for k, v in self.per_step(rows).items()})  # buffers reused

    # -- one chunk ------------------------------------------------------------------------
    def _flush(self, i0: int, m: int) -> int:
        """Post-process and check rows ``i0 + 1 .. i0 + m`` (rows ``1 .. m`` of the buffers,
        whose row 0 is row ``i0``); last valid row."""
        t, h, c = self.t, self.h, self.model.contact
        X = self.buf[: m + 1]
        ok = np.all(np.isfinite(X[1:]), axis=1)
        last = i0 + m if ok.all() else i0 + int(np.argmin(ok))
        if last < i0 + m:
            m, X = last - i0, X[: last - i0 + 1]
        b = slice(1, m + 1)  # the rows in the buffers
        O = self._O
        if O is not None:
            self.obs[b] = X[1:] @ O.T if isinstance(O, np.ndarray) else (O @ X[1:].T).T
        if c is not None and self._gaps_read():
            self.gap[b] = c.gap(t[b], X[1:])
        if self._slips:
            self.slip[b] = c.slip_velocity(X[1:])
        if self.meter is not None and m:
            friction = (self.imp_t[b], self.heat[b]) if self.has_friction else None
            with np.errstate(all="ignore"):
                work = {k: self._work[b, col] for k, col in self._work_cols.items()} or None
                self.meter.update(0, X, self.imp[b], t[: m + 1], h, work, friction)
            bad = self.meter.blown_up(b) if self.blowup_check else None
            if bad is not None:
                raise _Stop(
                    "unstable", f"energy created from nothing at t = {t[bad]:.6g} s", i0 + bad
                )
        if not ok.all():
            raise _Stop("unstable", f"non-finite state at t = {t[last + 1 - i0]:.6g} s", last)
        hit = _limit_hit(self.limits, self._lim_idx, self.obs[b], self.imp[b] / h)
        if hit is not None:
            k, what = hit
            raise _Stop("diverged-physically", f"{what} at t = {t[1 + k]:.6g} s", i0 + 1 + k)
        if self.store_every:
            r = np.arange(i0 + 1, i0 + m + 1)
            r = r[r % self.store_every == 0]
            self._stored.append(self.buf[r - i0].copy())
            self._stored_rows.append(r)
            self._stored_t.append(t[r - i0].copy())
        return i0 + m

    def _gaps_read(self) -> bool:
        """Whether the gaps of the rows are read: kept, or fed to a sink."""
        return self.kept.reads_gaps or self.on_state is not None or self.on_rows is not None

    def _deliver(self, i0: int, last: int) -> None:
        """Hand the checked rows ``i0 + 1 .. last`` of the buffers to what keeps them, then
        feed them to ``on_state``."""
        self.kept.take(self, i0, last)
        first = max(i0, self._delivered)  # a sink interrupted once is not fed a row twice
        if self.on_state is None or last <= first:
            return
        c, self._delivered = self.model.contact, last
        r = np.arange(first + 1, last + 1)
        stride = getattr(self.on_state, "stride", 1)  # a sink that keeps every stride-th
        r = r[r % stride == 0]
        b = r - i0
        X = self.buf[b]
        gdot = np.zeros((X.shape[0], 0)) if c is None else c.gap_velocity(self.t[b], X)
        P, g = self.imp[b], self.gap[b]  # copies: a sink may hold states (buffers reused)
        Pt = self.imp_t[b] if self.tangents else None
        for k, ri in enumerate(r):
            fi = None if Pt is None else Pt[k]
            self.on_state(State(ri, self.t[b[k]], X[k], P[k], g[k], gdot[k], fi))

    # -- the collected results -------------------------------------------------------------
    def per_step(self, rows: slice) -> dict[str, np.ndarray]:
        """Every per-step array for ``rows``, by name, in the order of the history columns."""
        out = {"t": self.t[rows]}
        col = 0
        for name, size in zip(self.names, self.sizes):
            out[name] = self.obs[rows, col : col + size]
            col += size
        if self.model.n_contacts:
            out["gap"] = self.gap[rows]
            out["contact_force"] = self.imp[rows] / self.h
            out["contact_impulse"] = self.imp[rows]
        out.update({k: v[rows] for k, v in self.extra.items()})
        if self.meter is not None:
            out.update({k: v[rows] for k, v in self.meter.data.items()})
        return out

    def _results(self, i_end: int, cpu_seconds: float) -> Results:
        m = i_end + 1
        states = times = None
        if self._stored:
            rows = np.concatenate(self._stored_rows)
            keep = rows <= i_end
            if keep.any():
                states = np.concatenate(self._stored)[keep]
                times = np.concatenate(self._stored_t)[keep]
        res = self.kept.results(
            self,
            m,
            status=self.status,
            message=self.message,
            cpu_seconds=cpu_seconds,
            states=states,
            state_times=times,
        )
        res.snapshots = [s for s in self.snapshots if s.step <= i_end]
        return res
