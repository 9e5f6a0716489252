"""A free elastic bar hits a rigid obstacle: femrub against the exact d'Alembert solution.

Reference: Doyen, Ern & Piperno, SIAM J. Sci. Comput. 33 (2011) 223-249. The bar (titanium,
0.3 m, 1 mm²) moves at 0.1 m/s towards an obstacle 10 µm away; the exact contact lasts 2L/c
with a constant force ρ c A v0, and the bar leaves at -v0. The exponential stepper flies
exactly between impacts: its answer does not depend on the Courant number, the θ-method's
does. Run: ``python examples/bar_impact.py``. Results are module-level names (``exact``,
``rows``, ``courant_rows``) that the tests import.
"""

import numpy as np

import femrub as fr
from femrub.cases.analytic import bar_impact
from femrub.cases.bar import impact_bar_model

E, RHO, AREA, LENGTH, V0, GAP = 110e9, 4500.0, 1e-6, 0.3, 0.1, 1e-5
exact = bar_impact(LENGTH, E, RHO, AREA, V0, GAP)


def simulate(n_elements: int, scheme: str = "theta", courant: float = 0.5) -> dict:
    """Run one discretisation; return contact start/duration, impulse, rebound velocity."""
    model = impact_bar_model(
        n_elements, velocity=V0, gap=GAP, young=E, density=RHO, area=AREA, length=LENGTH
    )
    c = np.sqrt(E / RHO)
    h = courant * (LENGTH / n_elements) / c
    t_end = 1.5 * (exact.contact_start + exact.contact_duration)
    res = fr.make_stepper(scheme, model, h).run(t_end, store_every=1)
    momentum = res.states @ (model.energy.Qk @ np.ones(model.n_dofs))
    phases = res.contact_phases()
    return {
        "n_elements": n_elements,
        "scheme": scheme,
        "courant": courant,
        "h": h,
        "contact_start": phases[0][0],
        "contact_duration": phases[-1][1] - phases[0][0],
        "impulse": float(res.impulse.sum()),
        "mean_force": float(res.impulse.sum()) / (phases[-1][1] - phases[0][0]),
        "rebound_velocity": float(momentum[-1] / (RHO * AREA * LENGTH)),
        "energy_error": res.energy_error(),
    }


rows = [simulate(n, s) for n in (50, 200) for s in ("theta", "carpenter")]
courant_rows = [simulate(100, s, nu) for s in ("exponential", "theta") for nu in (0.5, 8.0)]

if __name__ == "__main__":
    print(f"exact: {exact}")
    for r in rows + courant_rows:
        print({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
