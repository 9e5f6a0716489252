"""Where the time-step error of a coated rub comes from: first revolution against the later ones.

Builds ``SCENE`` (default ``rotor37-thermal``, through the model cache, VTK off) and steps
its model over ``--revolutions`` at ``h / f`` for each ``--factors`` ``f`` and each wear-map
resolution ``--n-angle`` (the scene's coating on a grid of that many angular cells; 0: the
scene's). Per run: the total normal impulse, split into the first revolution (the blade
cuts fresh coating) and the later ones (it re-contacts the surface it carved itself), the
impulse of the steps held at the coating's yield bound, the number of contact episodes and
the share of them that start in the first tenth of a cell after a cell centre (1/10 if the
map's centres played no part), the hottest contact, the deepest wear, the worn volume. Each
row after the first of a resolution gives the observed order ``log2(d_prev / d)`` of the
differences between consecutive steps.

Stores the rows under ``--name`` with where they were measured in
``docs/performance/abradable_order.json`` and renders them between the
``abradable_order_<name>`` markers of ``docs/abradable.md``: every row (``--layout full``) or
one row per map, the steps side by side (``--layout ladder``). ``--no-write``: print only;
``--render-only``: render the page from the JSON without running anything.

Run: ``flock /tmp/femrub-heavy.lock python benchmarks/abradable_order.py --name NAME
[--scene rotor37-thermal] [--factors 1,2,4] [--revolutions 10] [--n-angle 0,1440]
[--set KEY=VALUE ...] [--layout full|ladder] [--no-write]``.
"""

from __future__ import annotations

import math
import os
import time
from pathlib import Path

import numpy as np
from _common import (
    cli_scene,
    command_line,
    ladder_arguments,
    machine,
    read_json,
    render_sections,
    stamp,
    write_json,
)

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "abradable.md"
JSON = ROOT / "docs" / "performance" / "abradable_order.json"


def with_map(model, n_angle: int):
    """The model with its coating on a map of ``n_angle`` angular cells (same coating)."""
    from femrub.contact.abradable import Abradable, CasingGrid

    c = model.contact
    w, g = c.wear, c.wear.grid
    grid = CasingGrid(
        g.angles,
        g.axial,
        g.radius,
        g.omega,
        n_angle=n_angle,
        n_axial=g.n_axial,
        footprint=g.footprint,
    )
    c.wear = Abradable(w.thickness, w.yield_force, grid)
    return model


def measure(res, wear, h: float, revolution: float) -> dict:
    """Impulse split, episodes and their phase in the map's cells for one run."""
    P = res.impulse[1:]
    t = res.t[1:]
    on = P > 0.0
    held = P >= (1.0 - 1e-9) * h * wear.yield_force
    starts = np.argwhere(on & ~np.vstack([np.zeros((1, P.shape[1]), bool), on[:-1]]))
    x = np.array([wear.grid.position(t[j])[c] for j, c in starts])
    first = t < revolution * (1.0 + 1e-12)
    temps = res.signals.get("contact_temperature")
    return {
        "impulse": float(P.sum()),
        "first": float(P[first].sum()),
        "later": float(P[~first].sum()),
        "held": float(P[held].sum()),
        "episodes": int(len(starts)),
        "after_centre": float(np.mean((x - np.floor(x)) < 0.1)) if starts.size else math.nan,
        "t_max": float(np.max(temps)) if temps is not None else math.nan,
        "wear": wear.max_depth,
        "volume": wear.worn_volume,
    }


def study(scene, factors, revolutions: float, n_angles, log=print) -> list[dict]:
    from femrub.analysis import make_stepper
    from femrub.app.cache import ModelCache
    from femrub.app.scheme import scheme_options
    from femrub.app.simulation import build

    model = build(scene, log=log, cache=ModelCache()).model
    wear0 = model.contact.wear
    if wear0 is None:
        raise SystemExit("the scene has no abradable coating (contact.abradable)")
    revolution = 2 * math.pi / abs(wear0.grid.omega)
    s, opts = scene["scheme"], scheme_options(scene)
    rows = []
    for na in n_angles:
        with_map(model, na or wear0.n_angle)
        wear = model.contact.wear
        for f in factors:
            st = make_stepper(s["name"], model, s["h"] / f, **opts)
            load0, c0 = os.getloadavg()[0], time.process_time()
            res = st.run(revolutions * revolution)
            row = {"n_angle": wear.n_angle, "f": f, "h": s["h"] / f, "status": res.status}
            row["cpu"] = time.process_time() - c0
            row.update(measure(res, st.model.contact.wear, s["h"] / f, revolution))
            row["steps_per_cell"] = revolution / (s["h"] / f * wear.n_angle)
            row["balances"] = (res.energy_error(), res.heat_error())
            row["load"] = (load0, os.getloadavg()[0])
            rows.append(row)
            log(_line(row))
    return rows


def _line(r: dict) -> str:
    return (
        f"n_angle {r['n_angle']} h/{r['f']}: {r['status']}, impulse {r['impulse']:.4g} N s "
        f"(first revolution {r['first']:.4g}, later {r['later']:.4g}, held {r['held']:.4g}), "
        f"{r['episodes']} episodes ({100 * r['after_centre']:.0f} % after a centre), T_max "
        f"{r['t_max']:.1f} K, wear {1e3 * r['wear']:.4g} mm, {r['cpu']:.1f} s CPU"
    )


def _order(rows, i: int, key: str) -> str:
    """``log2(d_prev / d)`` of the differences of ``key`` between consecutive steps."""
    if i < 2 or rows[i - 2]["n_angle"] != rows[i]["n_angle"]:
        return "—"
    d0 = abs(rows[i - 1][key] - rows[i - 2][key])
    d1 = abs(rows[i][key] - rows[i - 1][key])
    return f"{math.log2(d0 / d1):.2f}" if d0 > 0 and d1 > 0 else "—"


def _diff(rows, i: int, key: str) -> str:
    if i < 1 or rows[i - 1]["n_angle"] != rows[i]["n_angle"]:
        return "—"
    return f"{100 * (rows[i - 1][key] / rows[i][key] - 1):+.1f} %"


def table(rows) -> str:
    out = [
        "| cells | step | status | total impulse (N s) | vs previous step | order | first "
        "revolution | vs previous | order | later revolutions | vs previous | order | held at "
        "the yield | episodes | started in the first tenth after a centre | hottest contact "
        "(K) | vs previous | deepest wear (mm) | worn volume (mm³) | energy / heat balance | "
        "CPU (s) | load |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for i, r in enumerate(rows):
        out.append(
            f"| {r['n_angle']} | h/{r['f']} ({r['h']:.4g} s) | {r['status']} | "
            f"{r['impulse']:.4g} | {_diff(rows, i, 'impulse')} | {_order(rows, i, 'impulse')} "
            f"| {r['first']:.4g} | {_diff(rows, i, 'first')} | {_order(rows, i, 'first')} | "
            f"{r['later']:.4g} | {_diff(rows, i, 'later')} | {_order(rows, i, 'later')} | "
            f"{r['held']:.4g} | {r['episodes']} | {100 * r['after_centre']:.0f} % | "
            f"{r['t_max']:.1f} | {_diff(rows, i, 't_max')} | {1e3 * r['wear']:.4g} | "
            f"{1e9 * r['volume']:.4g} | {r['balances'][0]:.1e} / {r['balances'][1]:.1e} | "
            f"{r['cpu']:.1f} | {r['load'][0]:.1f}–{r['load'][1]:.1f} |"
        )
    return "\n".join(out)


def _by_map(rows) -> list[list[dict]]:
    """The rows grouped by map resolution, each group in the order of its steps."""
    cells = list(dict.fromkeys(r["n_angle"] for r in rows))
    return [[r for r in rows if r["n_angle"] == n] for n in cells]


def _series(group, key: str, scale: float = 1.0, digits: int = 3) -> str:
    return ", ".join(f"{scale * r[key]:.{digits}g}" for r in group)


def ladder(rows) -> str:
    """One row per map: impulses of the first and later revolutions and the hottest contact
    at every step, the hottest contact extrapolated to h → 0 at first order
    (``T(h_n) − (T(h_{n−1}) − T(h_n))`` on the two finest steps), the finest step's episodes."""
    steps = ", ".join(f"h/{r['f']}" for r in _by_map(rows)[0])
    out = [
        f"| cells | steps per cell at h | first revolution: {steps} (N s) | later revolutions: "
        f"{steps} (N s) | hottest contact: {steps} (K) | hottest contact extrapolated in h (K) | "
        "episodes at the finest step | deepest wear (mm) | largest energy / heat balance |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for g in _by_map(rows):
        fine = g[-1]
        extrapolated = 2 * fine["t_max"] - g[-2]["t_max"] if len(g) > 1 else math.nan
        balance = max(r["balances"][0] for r in g), max(r["balances"][1] for r in g)
        out.append(
            f"| {g[0]['n_angle']} | {g[0]['steps_per_cell']:.3g} | {_series(g, 'first')} | "
            f"{_series(g, 'later')} | {_series(g, 't_max', digits=4)} | {extrapolated:.4g} | "
            f"{fine['episodes']} | {_series(g, 'wear', 1e3, 4)} | {balance[0]:.1e} / "
            f"{balance[1]:.1e} |"
        )
    return "\n".join(out)


LAYOUTS = {"full": table, "ladder": ladder}


def render(data: dict) -> dict[str, str]:
    """``marker name -> text`` of every stored ladder: its stamp, then its table."""
    return {
        f"abradable_order_{name}": stamp(e["command"], e["machine"])
        + f" h = {e['h']:.4g} s.\n\n"
        + LAYOUTS[e["layout"]](e["rows"])
        for name, e in data.items()
    }


def main(argv=None) -> int:
    ap = ladder_arguments(__doc__)
    ap.add_argument("--name", default="order", help="where the ladder goes in the JSON and page")
    ap.add_argument("--revolutions", type=float, default=10.0)
    ap.add_argument("--n-angle", default="0", help="comma-separated map resolutions (0: scene)")
    ap.add_argument("--layout", choices=sorted(LAYOUTS), default="full")
    ap.add_argument("--render-only", action="store_true")
    a = ap.parse_args(argv)
    data = read_json(JSON) if JSON.exists() else {}
    if a.render_only:
        render_sections(DOC, render(data))
        return 0
    scene = cli_scene(a.scene, a.set)
    if scene is None:
        return 0
    where = machine()
    factors = [int(x) for x in a.factors.split(",")]
    rows = study(scene, factors, a.revolutions, [int(x) for x in a.n_angle.split(",")])
    command = command_line("abradable_order.py", argv)
    entry = {"command": command, "machine": where, "layout": a.layout, "rows": rows}
    entry["h"] = scene["scheme"]["h"]
    print(LAYOUTS[a.layout](rows))
    if not a.no_write:
        data[a.name] = entry
        write_json(JSON, data)
        render_sections(DOC, render(read_json(JSON)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
