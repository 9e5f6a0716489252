"""A contact on a swept casing gap can be pickled (sent to a worker, stored)."""

import numpy as np


def test_a_swept_casing_gap_pickles():
    import pickle

    from femrub.contact.casing import Lobed, swept_gap

    gap, rate = swept_gap(Lobed(2e-5, 5e-5, 3), np.linspace(0, 1, 4), 1500.0, 1e-6)
    t = np.array([0.0, 1e-4, 3e-4])
    for f in (gap, rate):
        g = pickle.loads(pickle.dumps(f))
        np.testing.assert_array_equal(g(1e-4), f(1e-4))
        np.testing.assert_array_equal(g.over_times(t), np.array([f(x) for x in t]))
