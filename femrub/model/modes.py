"""The damped modes of a first-order model, contacts open: what damping each mode gets.

A scene's ``physics.damping_ratio`` ζ is Rayleigh damping ``C = a M + b K`` with ratio ζ at
two modes only (``physics.damping_modes``); every other mode of frequency ω gets
``ζ(ω) = a / (2 ω) + b ω / 2``, less between the two modes and more above them. What the
run's model does is read here from the model itself: the eigenvalues ``λ`` of
``λ A v = B v`` (Eq. 4's first-order form, no contact force) come as pairs
``λ = ω (−ζ ± i √(1 − ζ²))`` for the vibration modes, with the natural frequency
``ω = |λ|`` (rad/s) and the damping ratio ``ζ = −Re λ / |λ|``; real ``λ`` are the thermal
(diffusive) modes. The modes of a reduced model are those of the run, thermoelastic
coupling included.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

__all__ = ["MAX_DOFS", "damped_modes"]

#: largest model (state coordinates) whose modes are computed (a dense eigen-solve)
MAX_DOFS = 2000


def _dense(a) -> np.ndarray:
    return a.toarray() if sp.issparse(a) else np.asarray(a, dtype=float)


def damped_modes(model, max_dofs: int = MAX_DOFS) -> dict | None:
    """The vibration modes of ``model`` (contacts open), lowest first, or ``None`` above
    ``max_dofs`` state coordinates.

    Returns
    -------
    dict
        ``frequency_hz`` (natural frequencies ``|λ| / 2π``, Hz), ``ratio`` (damping ratios
        ``−Re λ / |λ|``, dimensionless), and ``rayleigh`` ``(a, b)`` (1/s, s) when the model's
        damping is Rayleigh damping set from a modal ratio (``None`` otherwise).
    """
    if model.n_dofs > max_dofs:
        return None
    lam = sla.eig(_dense(model.B), _dense(model.A), right=False)
    lam = lam[np.isfinite(lam)]
    vib = lam[lam.imag > 1e-9 * np.maximum(np.abs(lam), 1.0)]
    omega = np.abs(vib)
    order = np.argsort(omega)
    omega, vib = omega[order], vib[order]
    rayleigh = model.info.get("rayleigh") or model.info.get("full_info", {}).get("rayleigh")
    return {
        "frequency_hz": (omega / (2.0 * np.pi)).tolist(),
        "ratio": (-vib.real / omega).tolist(),
        "rayleigh": None if rayleigh is None else [float(x) for x in rayleigh],
    }
