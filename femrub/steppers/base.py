"""Common machinery of the time steppers: ``step()``, ``iterate()`` and ``run()``.

A stepper works on any :class:`~femrub.model.first_order.FirstOrderModel`. Subclasses implement
``_step()`` (advance one step, return the new state and the contact impulses); the public
``step()`` validates and records, ``iterate()`` yields states, ``run()`` collects a
:class:`~femrub.output.results.Results` with the energy balance, a progress bar, physical stop
criteria and protection against numerical blow-up. Whatever stops a run (instability, a
stop criterion, Ctrl-C, an exception), ``run()`` returns what was computed so far.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from threadpoolctl import threadpool_limits
from tqdm.auto import tqdm

from ..fem.linalg import compact
from ..model.first_order import FirstOrderModel
from ..output.energy import EnergyMeter
from ..output.results import Results

__all__ = ["State", "Stepper", "NumericalInstability", "check_step"]


class NumericalInstability(RuntimeError):
    """Raised by a stepper whose solution blows up (never returned as NaN)."""


def check_step(h, t_end=None) -> float:
    """Validate the step ``h`` (s) and the end time; return ``float(h)``."""
    try:
        h = float(h)
    except (TypeError, ValueError):
        raise ValueError(f"time step h must be a number, got {h!r}") from None
    if not math.isfinite(h) or h <= 0.0:
        raise ValueError(f"time step h must be finite and > 0 (seconds), got {h!r}")
    if t_end is not None:
        t_end = float(t_end)
        if not math.isfinite(t_end) or t_end < 0.0:
            raise ValueError(f"end time t_end must be finite and >= 0 (seconds), got {t_end!r}")
    return h


@dataclass
class State:
    """The state after step ``k``: time, state vector and contact quantities of the step."""

    k: int
    t: float
    X: np.ndarray
    impulse: np.ndarray
    gap: np.ndarray
    gap_velocity: np.ndarray


class Stepper:
    """Base class; see the module docstring. ``h`` is the time step (s)."""

    name = "stepper"

    def __init__(self, model: FirstOrderModel, h: float, *, t0: float = 0.0):
        if not isinstance(model, FirstOrderModel):
            raise TypeError("a stepper needs a femrub.FirstOrderModel")
        self.model = model
        self.h = check_step(h)
        self.k = 0
        self.t0 = self.t = float(t0)
        self.X = model.x0.copy()
        nc = model.n_contacts
        self.impulse = np.zeros(nc)
        self._setup()

    # -- to be implemented by subclasses ---------------------------------------------------
    def _setup(self) -> None:
        """Factorise constant matrices, precompute operators."""

    def _step(self) -> tuple[np.ndarray, np.ndarray]:
        """Advance from ``(self.t, self.X)`` by ``h``; return ``(X_new, impulse)``."""
        raise NotImplementedError

    def stability_limit(self) -> float:
        """Largest stable step (s); ``inf`` for unconditionally stable schemes."""
        return math.inf

    # -- public API ------------------------------------------------------------------------
    def _contact_state(self, t, X):
        c = self.model.contact
        if c is None:
            return np.zeros(0), np.zeros(0)
        return c.gap(t, X), c.gap_velocity(t, X)

    @property
    def state(self) -> State:
        gap, gdot = self._contact_state(self.t, self.X)
        return State(self.k, self.t, self.X, self.impulse, gap, gdot)

    def _advance(self) -> None:
        X, impulse = self._step()
        self.k += 1
        self.t = self.t0 + self.k * self.h
        self.X, self.impulse = X, impulse

    def step(self) -> State:
        """Advance one step of size ``h`` and return the new :class:`State`."""
        self._advance()
        return self.state

    def iterate(self, t_end: float):
        """Yield the initial state, then the state after every step until ``t_end``."""
        check_step(self.h, t_end)
        n = int(round((t_end - self.t) / self.h))
        yield self.state
        for _ in range(n):
            yield self.step()

    def run(
        self,
        t_end: float,
        *,
        progress: bool = False,
        limits: dict[str, float] | None = None,
        energy: bool = True,
        store_every: int = 0,
        on_state=None,
        label: str | None = None,
    ) -> Results:
        """Integrate to ``t_end`` and collect :class:`~femrub.output.results.Results`.

        Parameters
        ----------
        t_end : end time (s).
        progress : show a progress bar.
        limits : physical stop criteria, ``{signal name: max |value|}``; the key
            ``"contact_force"`` limits the contact force (N). Reaching one ends the run with
            status ``"diverged-physically"``.
        energy : keep the energy balance (needs ``model.energy``); it also detects numerical
            blow-up (energy created from nothing).
        store_every : keep the full state every that many steps (0: never).
        on_state : callback ``f(state)`` after each step (e.g. streaming VTK output).
        """
        check_step(self.h, t_end)
        model, h = self.model, self.h
        n = int(round((t_end - self.t) / h))
        N, nc, c = model.n_dofs, model.n_contacts, model.contact
        names = list(model.observations)
        sizes = [model.observations[k].shape[0] for k in names]
        O = compact(sp.vstack([model.observations[k] for k in names])) if names else None
        obs = np.zeros((n + 1, sum(sizes)))
        gap, imp, t = np.zeros((n + 1, nc)), np.zeros((n + 1, nc)), np.zeros(n + 1)
        alpha = np.zeros((n + 1, nc))
        meter = EnergyMeter(model, n + 1) if (energy and model.energy is not None) else None
        lim_idx = _limit_index(limits or {}, names, sizes)
        states, stimes = [], []
        status, message = "ok", ""
        h_lim = self.stability_limit()
        if h > h_lim:
            status = "unstable"
            message = f"h = {h:.3g} s exceeds the stability limit {h_lim:.3g} s of {self.name}"
        # states are post-processed in chunks; the callback gets the checked ones afterwards
        chunk = int(max(1, min(512, 2_000_000 // max(N, 1))))

        def deliver(i0, last):
            """Call ``on_state`` for the checked rows ``i0 + 1 .. last`` of the buffer."""
            if on_state is None:
                return
            for r in range(i0 + 1, last + 1):
                X = buf[r - i0]
                gdot = c.gap_velocity(t[r], X) if nc else np.zeros(0)
                on_state(State(r, t[r], X, imp[r], gap[r], gdot))

        buf = np.empty((chunk + 1, N))

        def flush(i0, m):
            """Post-process rows i0+1..i0+m from the buffer; return the last valid row."""
            rows = slice(i0 + 1, i0 + 1 + m)
            X = buf[: m + 1]
            ok = np.all(np.isfinite(X[1:]), axis=1)
            last = i0 + m if ok.all() else i0 + int(np.argmin(ok))
            if last < i0 + m:
                m, rows, X = last - i0, slice(i0 + 1, last + 1), X[: last - i0 + 1]
            if O is not None:
                obs[rows] = X[1:] @ O.T if isinstance(O, np.ndarray) else (O @ X[1:].T).T
            if nc:
                gap[rows] = c.gap(t[rows], X[1:])
                alpha[rows] = c.alpha_at(t[rows])
            if meter is not None and m:
                with np.errstate(all="ignore"):
                    meter.update(i0, X, imp[rows], t[i0 : rows.stop], h, alpha[rows])
                bad = meter.blown_up(rows)
                if bad is not None:
                    raise _Stop(
                        "unstable", f"energy created from nothing at t = {t[bad]:.6g} s", bad
                    )
            if last < rows.stop - 1 or not ok.all():
                raise _Stop("unstable", f"non-finite state at t = {t[last + 1]:.6g} s", last)
            hit = _limit_hit(limits or {}, lim_idx, obs[rows], imp[rows] / h)
            if hit is not None:
                j, what = hit
                raise _Stop(
                    "diverged-physically", f"{what} at t = {t[i0 + 1 + j]:.6g} s", i0 + 1 + j
                )
            if store_every:
                for r in range(rows.start, rows.stop):
                    if r % store_every == 0:
                        states.append(buf[r - i0].copy())
                        stimes.append(t[r])
            return rows.stop - 1

        start = time.process_time()
        # one BLAS thread: per-step products are small, threads only add latency (a busy
        # 2-core machine showed 0.4-17 ms for a 20000-long dot product with two threads)
        blas = threadpool_limits(limits=1, user_api="blas")
        blas.__enter__()
        # a blow-up overflows before the next check; non-finite states are caught and reported
        fp = np.errstate(over="ignore", invalid="ignore")
        fp.__enter__()
        bar = tqdm(total=n, disable=not progress, unit="step", desc=label or self.name, leave=False)
        i_end = 0
        try:
            t[0], buf[0] = self.t, self.X
            if nc:
                gap[0], imp[0] = self.state.gap, self.impulse
                alpha[0] = c.alpha_at(self.t)
            if O is not None:
                obs[0] = O @ self.X
            if meter is not None:
                meter.start(self.X)
            if on_state is not None:
                on_state(self.state)
            if store_every:
                states.append(self.X.copy())
                stimes.append(self.t)
            i0, j = 0, 0
            for i in range(1, n + 1):
                try:
                    self._advance()
                except (FloatingPointError, ArithmeticError) as exc:
                    i_end = flush(i0, j)
                    raise _Stop("unstable", f"{type(exc).__name__}: {exc}", i_end) from None
                j += 1
                buf[j], t[i] = self.X, self.t
                if nc:
                    imp[i] = self.impulse
                if j == chunk or i == n:
                    i_end = flush(i0, j)
                    deliver(i0, i_end)
                    bar.update(j)
                    buf[0] = buf[j]
                    i0, j = i, 0
        except _Stop as stop:
            status, i_end = stop.status, stop.row
            deliver(i0, min(i_end, i0 + j))
            message = f"{self.name}: {stop.message}" if stop.status == "unstable" else stop.message
        except KeyboardInterrupt:
            status, message = "interrupted", "interrupted by the user; results kept up to here"
            i_end = flush(i0, j - 1) if j > 1 else i0
        except Exception as exc:  # keep what was computed
            status, message = "failed", f"{type(exc).__name__}: {exc}"
        finally:
            bar.close()
            fp.__exit__(None, None, None)
            blas.__exit__(None, None, None)
        m = i_end + 1
        signals, col = {}, 0
        for name, size in zip(names, sizes):
            signals[name] = obs[:m, col : col + size].copy()
            col += size
        keep = [k for k, tt in enumerate(stimes) if tt <= t[i_end] + 0.5 * h]
        return Results(
            scheme=self.name,
            h=h,
            t=t[:m].copy(),
            signals=signals,
            gap=gap[:m].copy(),
            impulse=imp[:m].copy(),
            energy=meter.arrays(m) if meter is not None else {},
            status=status,
            message=message,
            steps=m - 1,
            cpu_seconds=time.process_time() - start,
            states=np.array([states[k] for k in keep]) if keep else None,
            state_times=np.array([stimes[k] for k in keep]) if keep else None,
            info={"label": label, "stability_limit": h_lim, "n_dofs": model.n_dofs},
        )


class _Stop(Exception):
    def __init__(self, status, message, row):
        super().__init__(message)
        self.status, self.message, self.row = status, message, int(row)


def _limit_index(limits, names, sizes):
    idx, col = {}, 0
    for name, size in zip(names, sizes):
        idx[name] = slice(col, col + size)
        col += size
    for key in limits:
        if key != "contact_force" and key not in idx:
            raise ValueError(f"stop limit on unknown signal {key!r}; use one of {names}")
    return idx


def _limit_hit(limits, idx, rows, force):
    """First ``(row, message)`` where a stop limit is exceeded in a block, or ``None``."""
    first = None
    for key, bound in limits.items():
        vals = force if key == "contact_force" else rows[:, idx[key]]
        if vals.size:
            over = np.any(np.abs(vals) > bound, axis=1)
            if over.any() and (first is None or np.argmax(over) < first[0]):
                first = (int(np.argmax(over)), f"{key} exceeded {bound:g}")
    return first
