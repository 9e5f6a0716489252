"""Common machinery of the time steppers: ``step()``, ``iterate()`` and ``run()``.

A stepper works on any :class:`~femrub.model.FirstOrderModel`. Subclasses implement
``_step()`` (advance one step, return the new state and the contact impulses); the public
``step()`` validates and records, ``iterate()`` yields states, ``run()`` collects a
:class:`~femrub.results.Results` with the energy balance, a progress bar, physical stop
criteria and protection against numerical blow-up. Whatever stops a run (instability, a
stop criterion, Ctrl-C, an exception), ``run()`` returns what was computed so far.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from tqdm.auto import tqdm

from ..energy import EnergyMeter
from ..model import FirstOrderModel
from ..results import Results

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
        return c.gap_at(t) + c.G.T @ X, c.Gv.T @ X

    @property
    def state(self) -> State:
        gap, gdot = self._contact_state(self.t, self.X)
        return State(self.k, self.t, self.X, self.impulse, gap, gdot)

    def step(self) -> State:
        """Advance one step of size ``h`` and return the new :class:`State`."""
        X, impulse = self._step()
        self.k += 1
        self.t = self.t0 + self.k * self.h
        self.X, self.impulse = X, impulse
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
        """Integrate to ``t_end`` and collect :class:`~femrub.results.Results`.

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
        names = list(model.observations)
        O = [model.observations[k] for k in names]
        sizes = [o.shape[0] for o in O]
        obs = np.zeros((n + 1, sum(sizes)))
        nc = model.n_contacts
        gap, imp = np.zeros((n + 1, nc)), np.zeros((n + 1, nc))
        t = np.zeros(n + 1)
        meter = EnergyMeter(model, n + 1) if (energy and model.energy is not None) else None
        states, stimes = [], []
        limits = dict(limits or {})
        lim_idx = _limit_index(limits, names, sizes)
        status, message = "ok", ""
        h_lim = self.stability_limit()
        if h > h_lim:
            status = "unstable"
            message = f"h = {h:.3g} s exceeds the stability limit {h_lim:.3g} s of {self.name}"

        def record(i, st):
            t[i] = st.t
            obs[i] = np.concatenate([np.asarray(o @ st.X).ravel() for o in O]) if O else []
            if nc:
                gap[i], imp[i] = st.gap, st.impulse
            if store_every and i % store_every == 0:
                states.append(st.X.copy())
                stimes.append(st.t)

        start = time.process_time()
        i = 0
        bar = tqdm(total=n, disable=not progress, unit="step", desc=label or self.name, leave=False)
        try:
            st = self.state
            record(0, st)
            if meter is not None:
                meter.start(st.X)
            for i in range(1, n + 1):
                Xk, tk = self.X, self.t
                st = self.step()
                if not np.all(np.isfinite(st.X)):
                    raise NumericalInstability(f"non-finite state at t = {st.t:.6g} s")
                record(i, st)
                if meter is not None:
                    c = model.contact
                    gm = c.Gv.T @ (0.5 * (Xk + st.X)) if nc else np.zeros(0)
                    alpha = c.alpha_at(st.t) if nc else np.zeros(0)
                    meter.update(i, Xk, st.X, st.impulse, tk, st.t, h, alpha, gm)
                    if meter.blown_up():
                        raise NumericalInstability(
                            f"energy created from nothing at t = {st.t:.6g} s (blow-up)"
                        )
                if on_state is not None:
                    on_state(st)
                hit = _limit_hit(limits, lim_idx, obs[i], imp[i] / h)
                if hit:
                    status, message = "diverged-physically", hit + f" at t = {st.t:.6g} s"
                    break
                if i % 256 == 0:
                    bar.update(256)
            i_end = i
        except NumericalInstability as exc:
            status, message, i_end = "unstable", f"{self.name}: {exc}", i - 1
        except KeyboardInterrupt:
            status, message, i_end = "interrupted", "interrupted by the user", i - 1
        except Exception as exc:  # keep what was computed
            status, message, i_end = "failed", f"{type(exc).__name__}: {exc}", i - 1
        finally:
            bar.close()
        m = max(i_end, 0) + 1
        signals, col = {}, 0
        for name, size in zip(names, sizes):
            signals[name] = obs[:m, col : col + size].copy()
            col += size
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
            states=np.array(states) if states else None,
            state_times=np.array(stimes) if stimes else None,
            info={"label": label, "stability_limit": h_lim, "n_dofs": model.n_dofs},
        )


def _limit_index(limits, names, sizes):
    idx, col = {}, 0
    for name, size in zip(names, sizes):
        idx[name] = slice(col, col + size)
        col += size
    for key in limits:
        if key != "contact_force" and key not in idx:
            raise ValueError(f"stop limit on unknown signal {key!r}; use one of {names}")
    return idx


def _limit_hit(limits, idx, row, force):
    for key, bound in limits.items():
        vals = force if key == "contact_force" else row[idx[key]]
        if vals.size and np.max(np.abs(vals)) > bound:
            return f"{key} exceeded {bound:g}"
    return ""
