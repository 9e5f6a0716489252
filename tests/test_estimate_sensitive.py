"""The reduction error estimate of a sensitive (chaotic) response.

Synthetic runs: the reference's round-off twin departs exponentially, as Rotor 37's does.
A run with the same statistics but a different trajectory is judged by its statistics after
the predictability horizon (small estimate); a run whose mean contact force is 20 % off is
not excused by the chaos; without a twin the pointwise difference decides.
"""

from types import SimpleNamespace

import numpy as np
import scipy.sparse as sp

from femrub.reduction.estimate import estimate, statistics

T = np.linspace(0.0, 1.0, 2001)
WINDOW = 0.05
FOM = SimpleNamespace(
    blocks=SimpleNamespace(M=sp.identity(2)), layout=SimpleNamespace(u=slice(0, 2), n_t=0)
)


def _run(phase_drift, force_scale=1.0):
    """Two contacts pressed by a forcing whose phase drifts by ``phase_drift(t)``."""
    ph = 40 * T + phase_drift
    force = force_scale * 1e3 * np.c_[1 + np.sin(ph), 1 + np.cos(ph)]
    sig = 1e-4 * np.c_[np.sin(ph), np.cos(ph)]
    res = SimpleNamespace(
        t=T,
        impulse=force * (T[1] - T[0]),
        force=force,
        signals={"contact_displacement": sig},
        state_times=T[::400],
        status="ok",
    )
    return (res, np.c_[sig[::400], np.zeros((6, 0))])


def _est(run, ref, twin=None):
    return estimate(((4, 0), *run), ((8, 0), *ref), FOM, window=WINDOW, twin=twin, tolerance=0.05)


ref = _run(0.0)
twin = _run(1e-12 * np.exp(30 * T))  # round-off growing e^30: decorrelated after t = 0.9
chaotic = _run(1e-4 * np.exp(30 * T))  # a model difference amplified the same way


def test_pointwise_estimate_sees_the_decorrelation():
    assert _est(chaotic, ref)["estimate"] > 0.3


def test_sensitive_response_judged_by_statistics_after_the_horizon():
    err = _est(chaotic, ref, twin=twin)
    assert err["sensitivity"] > 0.005
    assert 0.0 < err["predictability_horizon"] < 1.0
    assert err["estimate"] < 0.05, err
    assert "sensitive response" in err["method"]


def test_chaos_does_not_excuse_a_wrong_mean_force():
    wrong = _run(1e-4 * np.exp(30 * T), force_scale=1.2)
    err = _est(wrong, ref, twin=twin)
    assert err["statistics_after_horizon"]["mean_force"] > 0.15
    assert err["estimate"] > 0.15


def test_statistics_per_contact():
    s = statistics(ref[0])
    np.testing.assert_allclose(s["rms_contact_displacement"], 1e-4 / np.sqrt(2), rtol=0.02)
    assert s["max_force"].shape == (2,) and np.all(s["max_force"] <= 2e3 + 1e-9)


def test_a_difference_the_dynamics_amplify_is_judged_by_statistics_from_where_it_grows():
    """A twin whose round-off first shows a decaying transient sets a late horizon; a close
    model whose small difference the dynamics amplify from the start leaves the reference
    long before it. Its amplified difference is the chaos's, not the reduction's: judged by
    its statistics from where it has grown tenfold, as a coarser model's would be."""
    late_twin = _run(1e-8 * np.exp(-50 * T) + 1e-12 * np.exp(30 * T))
    close = _run(1e-5 * np.exp(30 * T))
    err = _est(close, ref, twin=late_twin)
    assert err["predictability_horizon"] < 0.2  # where close's difference has grown tenfold
    assert err["estimate"] < 0.05, err
    wrong = _run(1e-5 * np.exp(30 * T), force_scale=1.2)
    assert _est(wrong, ref, twin=late_twin)["estimate"] > 0.15  # statistics still decide
