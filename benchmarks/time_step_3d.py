"""Time-step convergence of a scene's model: the same model at h, h/2, h/4, ....

Builds ``SCENE`` (default ``rotor37-thermal``, through the model cache) as ``femrub run``
does, then steps the model that runs (reduced or full) at ``h / f`` for each ``--factors``
``f`` (and each ``--gamma-thermal`` variant of the θ-method's heat rows), each run coarsened
to the steps of ``h`` (:func:`femrub.analysis.step_check.coarsen`). Consecutive runs are compared
with the measures of ``scheme.step_check`` (:func:`femrub.reduction.estimate.estimate`:
contact impulse per lobe passage, contact temperature history, fields at 5 checkpoints),
so each row's ``difference`` is what the check would see at that step and twice it is the
check's estimate. Also: hottest contact, total impulse, deepest wear, balances, CPU.

Writes the table between ``<!-- time_step_3d:begin -->`` and ``<!-- time_step_3d:end -->``
of ``docs/rotor37.md`` (``--no-write``: print it), with the load.

Run: ``flock /tmp/femrub-heavy.lock python benchmarks/time_step_3d.py [--scene rotor37-thermal]
[--factors 1,2,4] [--gamma-thermal 1.0] [--set KEY=VALUE ...] [--no-write]`` (Rotor 37 needs
``../shared/data``; the first build takes minutes and ~6 GB).
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
from _common import cli_scene, ladder_arguments, write_between

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "rotor37.md"


def ladder(scene, factors, gammas, log=print) -> list[dict]:
    """One row per (γ_θ, f): the run at ``h/f`` against the run at the previous factor."""
    from femrub.analysis import make_stepper
    from femrub.analysis.reduction_check import lobe_passage
    from femrub.analysis.step_check import CHECKPOINTS, coarsen, full_states
    from femrub.app.cache import ModelCache
    from femrub.app.scheme import scheme_options
    from femrub.app.simulation import build
    from femrub.reduction.estimate import DECISIVE, estimate

    sim = build(scene, log=log, cache=ModelCache())
    model, full = sim.model, sim.full
    fields = full_states(model, full)
    s = scene["scheme"]
    h, t_end, window = s["h"], s["t_end"], lobe_passage(scene)
    rows = []
    for gt in gammas:
        opts = dict(scheme_options(scene))
        if gt is not None:
            opts["gamma_thermal"] = gt
        prev = None
        for f in factors:
            st = make_stepper(s["name"], model, h / f, **opts)
            every = max(1, st.steps_to(t_end) // (CHECKPOINTS * f))
            load0, c0 = os.getloadavg()[0], time.process_time()
            res = st.run(t_end, store_every=f * every, limits=sim.limits)
            cpu = time.process_time() - c0
            wear = st.model.contact.wear if st.model.contact is not None else None
            row = {
                "gamma_thermal": opts.get("gamma_thermal"),
                "f": f,
                "h": h / f,
                "steps": res.steps,
                "status": res.status,
                "cpu_us": 1e6 * cpu / max(res.steps, 1),
                "energy": res.energy_error(),
                "heat": res.heat_error(),
                "t_max": _largest(res, "contact_temperature"),
                "impulse": float(res.impulse.sum()),
                "wear": wear.max_depth if wear is not None else float("nan"),
                "load": (load0, os.getloadavg()[0]),
            }
            cur = (coarsen(res, f), fields(res.states))
            del res
            if prev is not None:
                err = estimate(((), *prev), ((), *cur), full, window=window)
                row["vs"] = factors[factors.index(f) - 1]
                row["measures"] = {k: err[k] for k in DECISIVE + ("temperature",) if k in err}
                row["difference"] = err["estimate"]
            prev = cur
            rows.append(row)
            log(_line(row))
    return rows


def _largest(res, key: str) -> float:
    """Largest magnitude of a signal (``tip_temperature`` when the model has no contact
    temperatures)."""
    key = key if key in res.signals else "tip_temperature"
    return float(np.abs(res.signals[key]).max()) if key in res.signals else float("nan")


def _line(r: dict) -> str:
    d = r.get("difference")
    return (
        f"γθ {r['gamma_thermal']} h/{r['f']}: {r['steps']} steps, {r['cpu_us']:.0f} µs/step, "
        f"{r['status']}, T_max {r['t_max']:.1f} K, impulse {r['impulse']:.4g} N s, wear "
        f"{1e3 * r['wear']:.3g} mm" + ("" if d is None else f", difference {100 * d:.2f} %")
    )


HEADER = (
    "| γ_θ | step | steps | µs/step (CPU) | status | hottest contact (K) | total impulse (N s) "
    "| deepest wear (mm) | vs | contact impulse | contact temperature | displacement | "
    "temperature field | difference (largest) | check's estimate (2×) | load |\n"
    "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
)


def table(rows) -> str:
    out = [HEADER]
    for r in rows:
        m = r.get("measures", {})
        pct = lambda k, m=m: f"{100 * m[k]:.2f} %" if k in m else "—"  # noqa: E731
        disp = max((m[k] for k in ("displacement", "displacement_end") if k in m), default=None)
        d = r.get("difference")
        out.append(
            f"| {r['gamma_thermal']} | h/{r['f']} ({r['h']:.4g} s) | {r['steps']} | "
            f"{r['cpu_us']:.0f} | {r['status']} | {r['t_max']:.1f} | {r['impulse']:.4g} | "
            f"{1e3 * r['wear']:.3g} | {'h/' + str(r['vs']) if 'vs' in r else '—'} | "
            f"{pct('contact_force')} | {pct('contact_temperature')} | "
            f"{'—' if disp is None else f'{100 * disp:.2f} %'} | {pct('temperature')} | "
            f"{'—' if d is None else f'{100 * d:.2f} %'} | "
            f"{'—' if d is None else f'{200 * d:.2f} %'} | {r['load'][0]:.1f}–{r['load'][1]:.1f} |"
        )
    return "\n".join(out)


def main(argv=None) -> int:
    ap = ladder_arguments(__doc__)
    ap.add_argument("--gamma-thermal", default="", help="comma-separated γ_θ variants")
    a = ap.parse_args(argv)
    scene = cli_scene(a.scene, a.set)
    if scene is None:
        return 0
    factors = [int(x) for x in a.factors.split(",")]
    gammas = [float(x) for x in a.gamma_thermal.split(",")] if a.gamma_thermal else [None]
    rows = ladder(scene, factors, gammas)
    settings = ", ".join(f"`{s.replace('=', ' = ', 1)}`" for s in a.set) or "as built in"
    text = (
        f"`python benchmarks/time_step_3d.py --scene {a.scene} --factors {a.factors}"
        + "".join(f" --set {s}" for s in a.set)
        + (f" --gamma-thermal {a.gamma_thermal}" if a.gamma_thermal else "")
        + f"` (scene {settings}; {time.strftime('%Y-%m-%d')}):\n\n"
        + table(rows)
    )
    print(text)
    if not a.no_write:
        write_between(DOC, "time_step_3d", text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
