"""What a run changes in a contact's history outside ``X``, kept and put back.

An abradable coating's wear map and the casing's heat are state a run carries beside its
state vector (:attr:`Contact.carried_state <femrub.contact.gap.Contact.carried_state>`);
:class:`RunState` copies the attributes a run changes (``_STATE``) into a snapshot and puts
a snapshot back, so that a stepper restarted from a run's
:class:`~femrub.output.results.Snapshot` continues it.
"""

from __future__ import annotations

import copy

__all__ = ["RunState"]


class RunState:
    """:meth:`snapshot` and :meth:`restore` of the attributes named in ``_STATE``."""

    #: the attributes a run changes
    _STATE: tuple[str, ...] = ()

    def snapshot(self) -> dict:
        """The state a run changes, as it is now, copied."""
        return copy.deepcopy({k: getattr(self, k) for k in self._STATE})

    def restore(self, snapshot: dict) -> None:
        """Take the state :meth:`snapshot` gave (a copy of it: the snapshot serves again)."""
        for k, v in copy.deepcopy(snapshot).items():
            setattr(self, k, v)
