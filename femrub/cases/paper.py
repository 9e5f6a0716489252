"""Reproduction of the paper's figures (Thorin et al., GT2018-75959) on the 1D bar.

``reproduce(out_dir)`` runs every case once (runs shared between figures are cached), writes
one PNG and one CSV per figure, each run's history (CSV), and ``summary.json`` with a row
per (figure, run). The frictional heat coefficient of Figs. 2 and 4–7 is not printed in the
paper; :data:`ALPHA_DEFAULT` documents the choice. The paper's runaway (α = 7 m/s, Fig. 3)
is stopped by the physical criterion :data:`LIMITS` and reported as
``"diverged-physically"``. Each run is judged like any other
(:func:`femrub.output.verdict.assess`: balance tolerances, contact episodes merged over a
quarter of the forcing period for the resolution warning).

The output folder is claimed (:func:`femrub.output.folder.claim`, kind ``paper``); its
``summary.json`` has a top-level ``status``: ``running``, ``ok`` (every figure written) or
``interrupted`` (Ctrl-C or SIGTERM: the rows of the finished runs are kept, and
``KeyboardInterrupt`` is raised again so that the command exits non-zero).
"""

from __future__ import annotations

import csv
import math
import platform
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from .. import __version__
from ..analysis.runner import MAX_STEPS
from ..analysis.steppers import make_stepper
from ..contact.activation import DEFAULT_RULE
from ..output.csv_rows import decimate_columns
from ..output.folder import claim
from ..output.interrupts import interruptible
from ..output.jsonfile import write_json
from ..output.plots import energy_panel, savefig, tip_panels
from ..output.results import UNITS
from .bar import PAPER, bar_model

__all__ = ["Run", "FIGURES", "ALPHA_DEFAULT", "LIMITS", "MODELS", "run_case", "reproduce"]

#: α (m/s) of the figures whose α the paper does not print (Figs. 2, 4, 5, 6, 7).
ALPHA_DEFAULT = 3.0
#: Physical stop criteria: tip temperature rise (K) beyond which titanium would melt, and a
#: tip displacement of a tenth of the bar's length (m).
LIMITS = {"tip_temperature": 1500.0, "tip_displacement": 0.1 * PAPER.length}
T_END = 0.4
#: Time between two rows of the CSV files (s): runs with smaller steps are written one row
#: per ``CSV_DT`` (impulses summed, forces averaged in between), with 9 significant digits
#: as the figure CSVs; every step is in the .npz, to the last bit.
CSV_DT = 1e-4
#: Time between two rows of a run's ``.npz`` history (s): every step of the runs with
#: ``h >= NPZ_DT``; the h = 1e-6 s reference run one row per ``NPZ_DT``, impulses summed
#: (:meth:`~femrub.output.results.Results.decimated`), which keeps the output under 30 MB.
NPZ_DT = 1e-5


@dataclass(frozen=True)
class Run:
    """One simulation of the paper case."""

    label: str
    scheme: str = "theta"
    h: float = 1e-4
    alpha: float = ALPHA_DEFAULT
    coupled: bool = True
    model: str = "full"
    activation: str = DEFAULT_RULE
    basis: str = "petrov-galerkin"  # left basis of the reduced models (ignored for "full")

    def key(self) -> tuple:
        basis = None if self.model == "full" else self.basis
        return (self.scheme, self.h, self.alpha, self.coupled, self.model, self.activation, basis)


def _full(alpha: float, coupled: bool, basis: str | None = None):
    return bar_model(PAPER, alpha=alpha, coupling="paper" if coupled else "none")


def _reduced(name: str) -> Callable:
    def build(alpha: float, coupled: bool, basis: str = "petrov-galerkin"):
        from .paper_models import paper_reduced_model

        return paper_reduced_model(name, alpha, coupled, projection=basis)

    return build


#: Model builders by name: ``f(alpha, coupled, basis) -> FirstOrderModel``.
MODELS: dict[str, Callable] = {"full": _full, "RM1": _reduced("RM1"), "RM2": _reduced("RM2")}

_S = {
    "solid": {"lw": 1.2},
    "dashed": {"ls": "--", "lw": 1.2},
    "dotted": {"ls": ":", "lw": 1.5},
    "dashdot": {"ls": "-.", "lw": 1.2},
}

FIGURES: dict[str, dict] = {
    "fig2": {
        "title": f"Fig. 2: thermal coupling, coupled vs uncoupled (α = {ALPHA_DEFAULT} m/s)",
        "runs": [(Run("coupled"), _S["solid"]), (Run("uncoupled", coupled=False), _S["dashed"])],
    },
    "fig3": {
        "title": "Fig. 3: influence of α in the heat flux α λ",
        "log_panels": ("tip_temperature",),
        "panels": ("tip_displacement", "tip_temperature", "phase_impulse"),
        "runs": [
            (Run("α = 1 m/s", alpha=1.0), _S["solid"]),
            (Run("α = 3 m/s", alpha=3.0), _S["solid"]),
            (Run("α = 7 m/s", alpha=7.0), _S["solid"]),
        ],
    },
    "fig4": {
        "title": f"Fig. 4: complete vs reduced models, two left bases (α = {ALPHA_DEFAULT} m/s)",
        "panels": ("tip_temperature", "phase_impulse", "contact_force"),
        "runs": [
            (Run("complete model (60 dofs)"), _S["solid"]),
            *(
                (Run(label, model=name, basis=basis), style)
                for basis in ("petrov-galerkin", "adjoint")
                for name, label, style in (
                    ("RM1", "RM1 (n_uv = 3, n_θ = 12; 18 dofs)", _S["dashed"]),
                    ("RM2", "RM2 (n_uv = 2, n_θ = 5; 10 dofs)", _S["dotted"]),
                )
            ),
        ],
        # one column per left basis, each with the complete model (run 0)
        "columns": [
            ("default: Petrov–Galerkin left basis", (0, 1, 2)),
            ("adjoint left basis (closest to the paper)", (0, 3, 4)),
        ],
    },
    "fig5": {
        "title": "Fig. 5: Carpenter's scheme vs the θ-method",
        "panels": ("tip_displacement", "tip_temperature", "phase_impulse", "contact_force"),
        "runs": [
            (Run("Carpenter, h = 1e-5 s", scheme="carpenter", h=1e-5), _S["dashed"]),
            (Run("θ-method, h = 1e-5 s", h=1e-5), _S["solid"]),
            (Run("θ-method, h = 1e-6 s", h=1e-6), _S["dotted"]),
        ],
    },
    "fig6": {
        "title": "Fig. 6: close-up of the first contact phase",
        "tlim": (3.5e-3, 6.5e-3),
        "time_unit": "ms",
        "panels": ("tip_displacement", "contact_force"),
        "runs": [
            (Run("Carpenter, h = 1e-5 s", scheme="carpenter", h=1e-5), _S["dashed"]),
            (Run("θ-method, h = 1e-5 s", h=1e-5), _S["solid"]),
            (Run("θ-method, h = 1e-6 s", h=1e-6), _S["dotted"]),
            (Run("θ-method, h = 1e-4 s", h=1e-4), _S["dashdot"]),
        ],
    },
    "fig7": {
        "title": "Fig. 7: influence of the time step (θ-method)",
        "panels": ("tip_displacement", "tip_temperature", "phase_impulse", "contact_force"),
        "runs": [
            (Run("h = 1e-5 s", h=1e-5), _S["solid"]),
            (Run("h = 1e-4 s", h=1e-4), _S["dotted"]),
            (Run("h = 5e-4 s", h=5e-4), _S["dashed"]),
        ],
    },
    "stability": {
        "title": "Carpenter above its stability limit",
        "runs": [(Run("Carpenter, h = 3e-5 s", scheme="carpenter", h=3e-5), _S["solid"])],
        "plot": False,
    },
}


def run_case(run: Run, t_end: float = T_END, *, progress: bool = False):
    """Build the model of ``run`` and integrate it to ``t_end``; return ``(results, model)``."""
    if run.model not in MODELS:
        raise ValueError(f"unknown model {run.model!r}; available: {', '.join(MODELS)}")
    model = MODELS[run.model](run.alpha, run.coupled, run.basis)
    opts = {"activation": run.activation} if run.scheme == "theta" else {}
    stepper = make_stepper(run.scheme, model, run.h, **opts)
    t0 = time.perf_counter()
    period = 2.0 * math.pi / PAPER.force_frequency
    res = stepper.run(
        t_end, progress=progress, limits=LIMITS, label=run.label, merge_time=0.25 * period
    )
    res.info["wall_seconds"] = time.perf_counter() - t0
    return res, model


def contact_phases(res, merge: float) -> list[tuple[float, float]]:
    """Contact phases, merging contacts separated by less than ``merge`` seconds.

    Within one load cycle the tip may impact, lift off for a few steps and impact again
    (paper Fig. 6 shows two impulses); such bursts count as one contact phase.
    """
    phases = res.contact_phases()
    out: list[list[float]] = []
    for a, b in phases:
        if out and a - out[-1][1] <= merge:
            out[-1][1] = b
        else:
            out.append([a, b])
    return [(a, b) for a, b in out]


def summarise(figure: str, run: Run, res, model) -> dict:
    """The ``summary.json`` row of one run."""
    period = 2.0 * math.pi / PAPER.force_frequency
    temp = res.signals.get("tip_temperature")
    gap = res.gap[:, 0] if res.gap.size else np.zeros(1)
    fct = res.first_contact_time()
    return {
        "figure": figure,
        "label": run.label,
        "scheme": run.scheme,
        "activation": run.activation if run.scheme == "theta" else None,
        "model": run.model,
        "basis": None if run.model == "full" else run.basis,
        "h": run.h,
        "alpha": run.alpha,
        "coupled": run.coupled,
        "n_dofs": model.n_dofs,
        "t_end": float(res.t[-1]),
        "first_contact_time": fct,
        "contact_phases": len(contact_phases(res, merge=0.25 * period)),
        "impacts": len(res.contact_phases()),
        "max_contact_force": float(res.force.max()) if res.force.size else 0.0,
        "tip_temperature_end": float(temp[-1, 0]) if temp is not None else 0.0,
        "max_penetration": float(max(0.0, -gap.min())),
        "energy_error": res.energy_error(),
        "impact_dissipation": float(res.energy["impact_dissipation"][-1]) if res.energy else None,
        "steps": res.steps,
        "cpu_seconds": res.cpu_seconds,
        "wall_seconds": res.info.get("wall_seconds"),
        "cpu_per_step_us": 1e6 * res.cpu_seconds / max(res.steps, 1),
        "stability_limit": res.info.get("stability_limit"),
        "status": res.status,
        "message": res.message,
        "warnings": list(res.warnings),
    }


def _stride(res, dt: float = CSV_DT) -> int:
    """Steps per row of a run's CSV (``dt`` = :data:`CSV_DT`) or ``.npz`` (:data:`NPZ_DT`):
    one row per ``dt``, every step when the step is larger."""
    return max(1, round(dt / res.h)) if res.h else 1


def _figure_csv(path: Path, runs, tlim=None) -> None:
    """One CSV per figure: time and the three signals of every run, one row per
    :data:`CSV_DT` (:meth:`~femrub.output.results.Results.save_csv`), or every step inside
    the window ``tlim`` of a close-up."""
    cols, names = [], []
    for label, res, _ in runs:
        temp = res.signals.get("tip_temperature")
        table = {
            "t": res.t,
            "tip_displacement": res.signal("tip_displacement"),
            "tip_temperature": temp[:, 0] if temp is not None else np.zeros_like(res.t),
            "contact_force": res.force.sum(axis=1),
            "contact_impulse": res.impulse.sum(axis=1),
        }
        if tlim is not None:
            keep = (res.t >= tlim[0]) & (res.t <= tlim[1])
            table = {k: v[keep] for k, v in table.items()}
        else:
            table = decimate_columns(table, _stride(res))
        for name in ("t", "tip_displacement", "tip_temperature", "contact_force"):
            cols.append(table[name])
            names.append(f"{label} | {name} [{UNITS[name]}]")
    n = max(len(c) for c in cols)
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(names)
        for i in range(n):
            w.writerow([f"{c[i]:.9g}" if i < len(c) else "" for c in cols])


def reproduce(
    out_dir,
    *,
    figures=None,
    t_end: float = T_END,
    progress: bool = True,
    log: Callable[[str], None] = print,
    overwrite: bool = False,
) -> list[dict]:
    """Run the paper's cases, write PNGs, CSVs and ``summary.json`` into ``out_dir``.

    The summary is rewritten after every run, so an interrupted reproduction keeps the rows
    of the runs it finished (and raises ``KeyboardInterrupt``). A finished reproduction in
    ``out_dir`` is not replaced unless ``overwrite``.
    """
    out = Path(out_dir)
    names = list(figures or FIGURES)
    unknown = [f for f in names if f not in FIGURES]
    if unknown:
        raise ValueError(f"unknown figure(s) {unknown}; available: {', '.join(FIGURES)}")
    t_end = float(t_end)
    if not (math.isfinite(t_end) and t_end > 0):
        raise ValueError(f"--t-end {t_end!r}: give a finite end time > 0 (s)")
    h_min = min(run.h for f in names for run, _ in FIGURES[f]["runs"])
    if t_end / h_min > MAX_STEPS:
        raise ValueError(
            f"--t-end {t_end:g} s gives {t_end / h_min:.3g} steps at h = {h_min:g} s; at most "
            f"{MAX_STEPS:.0e} allowed (lower --t-end or choose --figures)"
        )
    with claim(out, "paper", overwrite=overwrite), interruptible():
        return _reproduce(out, names, t_end, progress, log)


def _reproduce(out: Path, names, t_end, progress, log) -> list[dict]:
    (out / "runs").mkdir(parents=True, exist_ok=True)
    rows: list[dict] = []
    started = time.perf_counter()
    _write_summary(out, rows, started)
    try:
        _figures(out, names, t_end, progress, log, rows, started)
    except KeyboardInterrupt:  # Ctrl-C / SIGTERM: keep the rows of the finished runs
        _write_summary(out, rows, started, "interrupted")
        raise
    _write_summary(out, rows, started, "ok")
    return rows


def _figures(out, names, t_end, progress, log, rows, started) -> None:
    cache: dict[tuple, tuple] = {}
    for fig in names:
        spec = FIGURES[fig]
        drawn, named = [], []
        for run, style in spec["runs"]:
            if run.key() not in cache:
                res, model = run_case(run, t_end, progress=progress)
                if res.status == "interrupted":  # the run caught the signal: stop here too
                    raise KeyboardInterrupt(f"interrupted during {fig} / {run.label}")
                cache[run.key()] = (res, model)
                stem = "_".join(str(k) for k in run.key() if k is not None).replace(" ", "")
                res.save_csv(out / "runs" / f"{stem}.csv", every=_stride(res), digits=9)
                res.decimated(_stride(res, NPZ_DT)).save_npz(out / "runs" / f"{stem}.npz")
                log(
                    f"  {fig}: {run.label:<24} {res.status:<20} {res.steps:>7} steps "
                    f"{res.cpu_seconds:6.2f} s cpu"
                )
            res, model = cache[run.key()]
            rows.append(summarise(fig, run, res, model))
            drawn.append((run.label, res, style))
            named.append(
                (run.label if run.model == "full" else f"{run.label}, {run.basis}", res, style)
            )
            _write_summary(out, rows, started)
        if spec.get("plot", True):
            cols = spec.get("columns")
            f = tip_panels(
                drawn,
                title=spec["title"],
                panels=spec.get("panels", ("tip_displacement", "tip_temperature", "contact_force")),
                tlim=spec.get("tlim"),
                time_unit=spec.get("time_unit", "s"),
                gap=PAPER.gap,
                merge=0.25 * 2.0 * math.pi / PAPER.force_frequency,
                log_panels=spec.get("log_panels", ()),
                columns=cols and [(t, [drawn[i] for i in idx]) for t, idx in cols],
            )
            savefig(f, out / f"{fig}.png")
            _figure_csv(out / f"{fig}.csv", named, spec.get("tlim"))
        if fig == "fig5":  # energy balances of the two schemes at the same step
            for run, _ in spec["runs"][:2]:
                res = cache[run.key()][0]
                title = f"Energy balance: {run.label}"
                savefig(energy_panel(res, title=title), out / f"energy_{run.scheme}.png")


#: SI units of the numeric fields of a summary row
_ROW_UNITS = {
    "h": "s",
    "alpha": "m/s",
    "t_end": "s",
    "first_contact_time": "s",
    "max_contact_force": "N",
    "tip_temperature_end": "K",
    "max_penetration": "m",
    "impact_dissipation": "J",
    "energy_error": "-",
    "cpu_seconds": "s",
    "wall_seconds": "s",
    "cpu_per_step_us": "us",
    "stability_limit": "s (null: unconditionally stable)",
}


def _write_summary(out: Path, rows, started, status: str = "running") -> None:
    doc = {
        "status": status,
        "femrub_version": __version__,
        "python": platform.python_version(),
        "case": asdict(PAPER),
        "alpha_default": ALPHA_DEFAULT,
        "limits": LIMITS,
        "wall_seconds": time.perf_counter() - started,
        "units": _ROW_UNITS,
        "runs": rows,
    }
    write_json(out / "summary.json", doc)
