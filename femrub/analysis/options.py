"""How a run is recorded and judged: :class:`RunOptions`, one frozen object."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, fields, replace

__all__ = ["RunOptions"]


@dataclass(frozen=True)
class RunOptions:
    """The options of :func:`~femrub.analysis.runner.run` (``stepper.run(t_end, options)``).

    Attributes
    ----------
    progress : show a progress bar.
    limits : physical stop criteria ``{signal name: max |value|}``; the key
        ``"contact_force"`` limits the contact force (N). They replace the model's default
        limits of their signals (:mod:`femrub.output.limits`; ``inf``: no limit on that
        signal). Reaching one ends the run with status ``"diverged-physically"``.
    default_limits : also stop on the model's default physical limits (a temperature rise of
        1500 K, a displacement of 0.1 times ``model.length_scale``); ``False``: only
        ``limits``.
    energy : keep the energy balance (needs ``model.energy``); it also detects numerical
        blow-up (energy created from nothing).
    store_every : keep the full state every that many steps (0: never).
    on_state : callback ``f(state)`` after each checked step (e.g. streaming VTK output).
    on_rows : callback ``f(arrays)`` per checked block of rows (e.g. a streamed history).
    label : name of the run (progress bar and ``Results.info``).
    tolerances, merge_time : see :func:`femrub.output.verdict.assess` (balance tolerances;
        contact impulses closer than ``merge_time`` s form one episode of the resolution
        check, ``None``: no check).
    lean : 0: results with every per-step array. ``k >= 1``: a run held only to be compared
        with another: only times, impulses, signals and the stored states, at every ``k``-th
        step with the impulses summed over each ``k`` steps (``h`` of the results ``k h``);
        the verdict reads its measures of the rest taken as the steps were recorded
        (:mod:`femrub.output.kept_rows`, ``Results.checks``).
    snapshots : steps of the run after which its whole state is kept
        (``Results.snapshots``: the time, ``X`` and the history the contact carries outside
        ``X``): a stepper restarted from one continues the run.
    compared : a lean run held only to be compared with another (needs ``lean >= 1``): the
        recorder evaluates neither the energy and heat balance (nor the stepper's own works
        of each step) nor the Coulomb check, nor the gaps and slip velocities; the stop
        checks that end a run (non-finite state, stop limits) stay, so the rows kept are the
        same. Its status says how it ended: the balance and Coulomb rules are not applied
        (``Results.checks`` is empty) and, without the balance, a numerical blow-up ends it
        at its first non-finite state or stop limit rather than at the energy it created.
    """

    progress: bool = False
    limits: Mapping[str, float] | None = None
    default_limits: bool = True
    energy: bool = True
    store_every: int = 0
    on_state: Callable | None = None
    on_rows: Callable | None = None
    label: str | None = None
    tolerances: Mapping | None = None
    merge_time: float | None = None
    lean: int = 0
    compared: bool = False
    snapshots: tuple = ()

    def __post_init__(self):
        if self.compared and self.lean < 1:
            raise ValueError(
                f"RunOptions.compared = True needs lean >= 1 (a run only compared is a lean "
                f"record); got lean = {self.lean!r}: pass lean=1 too"
            )

    @classmethod
    def of(cls, options: RunOptions | None = None, **changes) -> RunOptions:
        """``options`` (default: the defaults) with ``changes``; an unknown name is refused."""
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(changes) - known)
        if unknown:
            raise TypeError(
                f"unknown run option(s) {', '.join(unknown)}; use {', '.join(sorted(known))}"
            )
        return replace(options or cls(), **changes)
