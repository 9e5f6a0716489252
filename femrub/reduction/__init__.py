"""Model reduction of first-order thermoelastic models (paper Sec. 2).

``ThermoelasticCraigBampton(model, n_uv, n_theta, projection=...)`` builds the bases and
``reduce()`` returns a :class:`~femrub.model.first_order.FirstOrderModel` that the steppers run as they
run the full model; ``reconstruct()`` maps reduced states back to the full state.
"""

from .blocks import InteriorSolver, ModelBlocks, contact_boundary, split_blocks
from .craig_bampton import PROJECTIONS, ThermoelasticCraigBampton, craig_bampton_thermal

__all__ = [
    "InteriorSolver",
    "ModelBlocks",
    "PROJECTIONS",
    "ThermoelasticCraigBampton",
    "contact_boundary",
    "craig_bampton_thermal",
    "split_blocks",
]
