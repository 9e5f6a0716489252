"""The paper's reduced models RM1 and RM2 of the 1D bar (paper Sec. 4.2, Fig. 4).

Sizes from the paper: the full bar has ``n^uv = 2n − 2 = 38`` and ``n^θ = n − 1 = 19``
(n = 20 nodes, one boundary node: the tip); RM1 keeps ``n^uv = 3``, ``n^θ = 12`` and RM2
``n^uv = 2``, ``n^θ = 5``. ``"full-basis"`` keeps every shape: the reduction is then a change
of variables and reproduces the full model to round-off.
"""

from __future__ import annotations

from ..model.first_order import FirstOrderModel
from ..reduction.craig_bampton import ThermoelasticCraigBampton
from .bar import PAPER, bar_model

__all__ = ["PAPER_SIZES", "DEFAULT_PROJECTION", "paper_reduced_model", "paper_reductor"]

#: (n_uv, n_theta) of the paper's reduced models; ``None`` means every shape.
PAPER_SIZES = {"RM1": (3, 12), "RM2": (2, 5), "full-basis": (None, None)}
#: Left projection of the paper models (see docs/reduction.md for the comparison).
DEFAULT_PROJECTION = "petrov-galerkin"


def paper_reductor(
    name: str, alpha: float, coupled: bool, *, projection: str = DEFAULT_PROJECTION, **changes
) -> ThermoelasticCraigBampton:
    """Reductor of the paper bar (``femrub.cases.bar.bar_model``) for ``name`` in PAPER_SIZES."""
    if name not in PAPER_SIZES:
        raise ValueError(f"unknown reduced model {name!r}; use one of {', '.join(PAPER_SIZES)}")
    full = bar_model(PAPER, alpha=alpha, coupling="paper" if coupled else "none", **changes)
    n_uv, n_theta = PAPER_SIZES[name]
    if full.layout.n_t == 0:
        n_theta = 0
    return ThermoelasticCraigBampton(full, n_uv, n_theta, projection=projection)


def paper_reduced_model(
    name: str, alpha: float, coupled: bool, *, projection: str = DEFAULT_PROJECTION
) -> FirstOrderModel:
    """Reduced paper bar ``"RM1"``, ``"RM2"`` or ``"full-basis"`` (paper Sec. 4.2).

    Parameters
    ----------
    name : ``"RM1"`` (n^uv = 3, n^θ = 12), ``"RM2"`` (2, 5) or ``"full-basis"`` (all shapes).
    alpha : frictional heat coefficient α (m/s) in ``f_tip = α λ``.
    coupled : paper coupling ``K^uθ = β K^uu`` if true, else ``K^uθ = 0``.
    projection : ``"petrov-galerkin"`` (default) or ``"galerkin"``.
    """
    red = paper_reductor(name, alpha, coupled, projection=projection)
    rom = red.reduce()
    return rom.with_(info={**rom.info, "label": name})
