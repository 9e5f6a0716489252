"""Model reduction of first-order thermoelastic models (paper Sec. 2).

``ThermoelasticCraigBampton(model, max_n_uv, max_n_theta, projection=...)`` builds the bases
once and ``reduce(n_uv, n_theta)`` returns a :class:`~femrub.model.first_order.FirstOrderModel`
of any smaller sizes that the steppers run as they run the full model; ``reconstruct()`` maps
reduced states back to the full state.
"""

from .craig_bampton import PROJECTIONS, ThermoelasticCraigBampton, craig_bampton_thermal
from .interior import InteriorSolver

__all__ = [
    "InteriorSolver",
    "PROJECTIONS",
    "ThermoelasticCraigBampton",
    "craig_bampton_thermal",
]
