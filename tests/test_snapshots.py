"""A run's snapshots (``RunOptions.snapshots``): a stepper restarted from one continues the run.

The snapshot holds the state and the history the contact carries outside it (the abradable
coating's wear map): a restart from it must give the run's own rows and leave the coating
the run left, in the compiled blocks and on the per-step path; asking for snapshots must not
change the run.
"""

import numpy as np
import pytest
from test_rub_blocks import SCENE, blade  # noqa: F401  (the coated, heated blade fixture)

from femrub.analysis import make_stepper


def _stepper(blade, blocks=True):  # noqa: F811
    model, scheme, opts = blade
    st = make_stepper(scheme["name"], model, scheme["h"], **opts)
    st.block_steps = blocks
    return st, scheme["t_end"]


def _close(a, b, rel):
    scale = max(float(np.abs(b).max()), 1e-300)
    np.testing.assert_allclose(a, b, rtol=0, atol=rel * scale)


def test_snapshots_leave_the_run_unchanged(blade):  # noqa: F811
    st, t_end = _stepper(blade)
    plain = st.run(t_end)
    st, _ = _stepper(blade)
    kept = st.run(t_end, snapshots=(0, 77, 150, 10**9))
    assert [s.step for s in kept.snapshots] == [0, 77, 150]
    np.testing.assert_array_equal(kept.impulse, plain.impulse)
    np.testing.assert_array_equal(
        kept.signals["contact_temperature"], plain.signals["contact_temperature"]
    )
    s = kept.snapshots[1]
    assert s.t == pytest.approx(kept.t[77], abs=1e-15) and len(s.history) == 1
    assert s.history[0]["depth"].shape == st.model.contact.wear.depth.shape


@pytest.mark.parametrize("blocks", [True, False])
def test_a_restart_from_a_snapshot_continues_the_run(blade, blocks):  # noqa: F811
    st, t_end = _stepper(blade, blocks)
    res = st.run(t_end, snapshots=(120,))
    wear = st.model.contact.wear
    assert wear.max_depth > 1e-6  # the run cut the coating, before and after the snapshot
    (snap,) = res.snapshots
    depth_at_snapshot = snap.history[0]["depth"]
    assert 0 < np.abs(depth_at_snapshot).max() < wear.max_depth

    again, _ = _stepper(blade, blocks)
    again.restart(snap.X, snap.t, snap.history)
    tail = again.run(t_end)
    assert tail.steps == res.steps - 120
    _close(tail.impulse[1:], res.impulse[121:], 1e-9)
    _close(tail.signals["contact_temperature"], res.signals["contact_temperature"][120:], 1e-9)
    w = again.model.contact.wear
    _close(w.depth, wear.depth, 1e-9)
    _close(w.incursion, wear.incursion, 1e-9)
    assert len(w.history) == len(wear.history)
    # the snapshot serves again: restored from a copy, untouched by the restarted run
    np.testing.assert_array_equal(snap.history[0]["depth"], depth_at_snapshot)


def test_a_contact_with_a_history_needs_it_to_restart(blade):  # noqa: F811
    st, t_end = _stepper(blade)
    res = st.run(t_end, snapshots=(50,))
    with pytest.raises(ValueError, match="history"):
        st.restart(res.snapshots[0].X, res.snapshots[0].t)
