"""The numbers of ``docs/paper-reproduction.md``, from ``femrub paper``'s ``summary.json``.

``docs/paper/summary.json`` is what ``femrub paper --out DIR`` writes (``DIR/summary.json``);
``tests/test_cli_paper.py`` fails when a fresh run no longer reproduces it. The page quotes
its numbers as MyST substitutions (``{{ theta_h4.T }}``), so they cannot drift from it.
"""

from __future__ import annotations

import json
from pathlib import Path

#: substitution name -> the fields that select its run in ``summary.json["runs"]``
RUNS = {
    "coupled": {"figure": "fig2", "label": "coupled"},
    "uncoupled": {"figure": "fig2", "label": "uncoupled"},
    "alpha1": {"figure": "fig3", "alpha": 1.0},
    "alpha7": {"figure": "fig3", "alpha": 7.0},
    "rm1": {"figure": "fig4", "model": "RM1", "basis": "petrov-galerkin"},
    "rm2": {"figure": "fig4", "model": "RM2", "basis": "petrov-galerkin"},
    "rm1_adjoint": {"figure": "fig4", "model": "RM1", "basis": "adjoint"},
    "rm2_adjoint": {"figure": "fig4", "model": "RM2", "basis": "adjoint"},
    "carpenter_h5": {"figure": "fig5", "scheme": "carpenter"},
    "theta_h5": {"figure": "fig5", "scheme": "theta", "h": 1e-5},
    "theta_h6": {"figure": "fig5", "scheme": "theta", "h": 1e-6},
    "theta_h4": {"figure": "fig7", "h": 1e-4},
    "theta_5h4": {"figure": "fig7", "h": 5e-4},
}


def select(runs: list[dict], fields: dict) -> dict:
    """The one run whose fields match ``fields``."""
    found = [r for r in runs if all(r.get(k) == v for k, v in fields.items())]
    if len(found) != 1:
        raise ValueError(f"docs/paper/summary.json: {len(found)} runs match {fields}")
    return found[0]


def _formatted(run: dict, complete: dict) -> dict:
    """A run's quoted numbers as the page prints them (SI units, ms for times)."""
    return {
        "T": f"{run['tip_temperature_end']:.2f} K",
        "F": f"{run['max_contact_force']:.1f} N",
        "t1": f"{run['first_contact_time'] * 1e3:.4g} ms",
        "phases": str(run["contact_phases"]),
        "impacts": str(run["impacts"]),
        "dofs": str(run["n_dofs"]),
        "status": run["status"],
        "dT": f"{run['tip_temperature_end'] / complete['tip_temperature_end'] - 1:+.1%}",
        "dF": f"{run['max_contact_force'] / complete['max_contact_force'] - 1:+.1%}",
        "limit": f"{run['stability_limit']:.3g} s" if run.get("stability_limit") else "—",
        "E": f"{run['energy_error']:.1g}",
        "pen": f"{run['max_penetration']:.1g} m",
    }


def substitutions(path: Path) -> dict:
    """``{name: {quantity: text}}`` for every run of ``RUNS``."""
    runs = json.loads(Path(path).read_text())["runs"]
    complete = select(runs, RUNS["coupled"])
    return {name: _formatted(select(runs, fields), complete) for name, fields in RUNS.items()}
