"""Per-step cost of a reduced frictional θ-method run, and its floor (target: ≤ 50 µs).

Builds ``SCENE`` (default ``rotor37``; through the model cache, so a second call loads the
reduced model in seconds), then steps it ``--revolutions`` revolutions without output
(``run(energy=False)`` and the default ``run()`` with the energy balance), in this process:

* CPU per step (``time.process_time``), and split between the steps where no contact takes
  an impulse and those where some do (wall time of each ``advance``, median);
* the floor: the dense ``T X`` product of the step and one ``numpy.linalg.solve`` of the
  Delassus block of the contacts active together (the small contact solve), each timed alone;
* a VTK series at stride 50 over the same run, as ``femrub run`` writes it (background
  writer thread) and in the stepping thread: CPU and wall per step against the run without
  output (medians of runs taken in turn);
* what compiling the contact kernels costs (fresh process, empty numba cache) and what
  loading them from the cache costs (both happen when a stepper is built).

Writes a table between ``<!-- step_cost:begin -->`` and ``<!-- step_cost:end -->`` in
``docs/performance/rotor37-costs.md`` with the machine's load (``os.getloadavg``).

Run: ``python benchmarks/step_cost.py [--scene rotor37] [--revolutions 5] [--no-vtk] [--no-write]``
(Rotor 37 needs ``../shared/data``; wrap the first, uncached call in
``flock /tmp/femrub-heavy.lock`` on a shared machine).
"""

from __future__ import annotations

import argparse
import math
import os
import re
import sys
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def _per_step(
    model, scheme: dict, opts: dict, t_end: float, energy: bool, blocks=True, on_state=None
) -> dict:
    """CPU (all threads) and wall time per step of ``run()`` alone (``blocks``: the
    compiled blocks of steps, else step by step; ``on_state``: an output callback, e.g. a
    VTK series, whose frames are all on disk when ``run`` returns)."""
    from femrub.analysis import make_stepper

    st = make_stepper(scheme["name"], model, scheme["h"], **opts)
    st.block_steps = blocks
    c0, w0 = time.process_time(), time.perf_counter()
    res = st.run(t_end, energy=energy, on_state=on_state)
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    return {
        "steps": res.steps,
        "us": 1e6 * cpu / res.steps,
        "wall_us": 1e6 * wall / res.steps,
        "status": res.status,
        "energy_error": float(np.max(np.abs(res.energy["energy_error"])))
        if "energy_error" in res.energy
        else None,
    }


def _bare_blocks(model, scheme: dict, opts: dict, t_end: float) -> dict:
    """CPU per step of the compiled blocks alone (chunks of 512 steps into preallocated
    rows, no recorder): the kernel's cost with the casing terms and signals of each block."""
    from femrub.analysis import make_stepper
    from femrub.output.recorder import CHUNK_STEPS
    from femrub.steppers.theta_blocks import advance_block

    st = make_stepper(scheme["name"], model, scheme["h"], **opts)
    if not getattr(st, "_block_kind", None):
        return {}
    n, N, nc = st.steps_to(t_end), model.n_dofs, model.n_contacts
    m = CHUNK_STEPS
    X, t, P = np.empty((m, N)), np.empty(m), np.empty((m, nc))
    Pt, heat, state = np.empty((m, nc, 2)), np.empty((m, nc)), np.empty((m, nc), np.int8)
    done = 0
    with threadpool_limits(limits=1, user_api="blas"):
        c0 = time.process_time()
        while done < n:
            k = min(m, n - done)
            advance_block(st, k, X[:k], t[:k], P[:k], Pt[:k], heat[:k], state[:k])
            done += k
        cpu = time.process_time() - c0
    return {"bare_us": 1e6 * cpu / n}


def _vtk(sim, scheme: dict, opts: dict, stride: int, t_end: float, repeats: int = 5) -> dict:
    """VTK series at ``stride`` as ``femrub run`` writes it (``VTKSeries`` with its
    defaults: the background writer), and with the frames written in the stepping thread:
    CPU (all threads) and wall per step against the same run without output, each the
    median of ``repeats`` runs taken in turn (the run includes writing every frame: the
    recorder flushes the series before ``run`` returns)."""
    import tempfile

    from femrub.output.vtk import VTKSeries

    if sim.fields is None or sim.model.to_full is None:
        return {}
    out, runs = {"vtk_stride": stride}, {}
    for _ in range(repeats):
        runs.setdefault("plain", []).append(_per_step(sim.model, scheme, opts, t_end, False))
        for key, background in (("vtk", True), ("vtk_inline", False)):
            with tempfile.TemporaryDirectory() as d:
                c0, w0 = time.process_time(), time.perf_counter()
                series = VTKSeries(
                    d, sim.model, sim.fields, h=scheme["h"], stride=stride, background=background
                )
                setup = (time.process_time() - c0, time.perf_counter() - w0)
                row = _per_step(sim.model, scheme, opts, t_end, False, on_state=series)
                series.close()
                files = list(Path(d).glob("*.vtu"))
                row |= {
                    "main_us": 1e6 * series.seconds / row["steps"],
                    "setup": setup,
                    "writer_us": 1e6 * series._writer_cpu / row["steps"],
                }
                runs.setdefault(key, []).append(row)
                out["vtk_frames"] = len(series.frames)
                out["vtk_mb"] = sum(f.stat().st_size for f in files) / len(files) / 1e6
    med = lambda key, q: float(np.median([r[q] for r in runs[key]]))  # noqa: E731
    out["vtk_plain_us"], out["vtk_plain_wall_us"] = med("plain", "us"), med("plain", "wall_us")
    for key in ("vtk", "vtk_inline"):
        out[f"{key}_us"], out[f"{key}_wall_us"] = med(key, "us"), med(key, "wall_us")
        out[f"{key}_main_us"], out[f"{key}_writer_us"] = med(key, "main_us"), med(key, "writer_us")
    out["vtk_repeats"] = repeats
    out["vtk_setup_s"] = float(np.median([r["setup"][1] for r in runs["vtk"]]))
    n = runs["plain"][0]["steps"]
    out["vtk_frame_ms"] = (
        1e3 * (out["vtk_inline_us"] - out["vtk_plain_us"]) * n / 1e6 / (out["vtk_frames"])
    )
    return out


def _split(model, scheme: dict, opts: dict, t_end: float) -> dict:
    """Median wall time of a step without / with an impulse (the per-step path,
    ``advance``), and the contacts active."""
    from femrub.analysis import make_stepper

    st = make_stepper(scheme["name"], model, scheme["h"], **opts)
    n = st.steps_to(t_end)
    dt, act = np.zeros(n), np.zeros(n, dtype=int)
    with threadpool_limits(limits=1, user_api="blas"):
        for i in range(n):
            t0 = time.perf_counter()
            out = st.advance()
            dt[i] = time.perf_counter() - t0
            act[i] = np.count_nonzero(out.impulse > 0.0)
    on = act > 0
    T = getattr(st, "_T", None)
    floor = {}
    with threadpool_limits(limits=1, user_api="blas"):
        if T is not None:
            X, k = np.ones(T.shape[0]), 20000
            t0 = time.perf_counter()
            for _ in range(k):
                T @ X
            floor["matvec_us"] = 1e6 * (time.perf_counter() - t0) / k
        m = int(np.percentile(act[on], 90)) if on.any() else 1
        W = getattr(st, "_W3", None)
        if W is not None and m:
            Wa = W[: 3 * m, : 3 * m] + 0.0
            b, k = np.ones(3 * m), 5000
            t0 = time.perf_counter()
            for _ in range(k):
                np.linalg.solve(Wa, b)
            floor["solve_us"], floor["solve_size"] = 1e6 * (time.perf_counter() - t0) / k, 3 * m
    return {
        "quiet_us": 1e6 * float(np.median(dt[~on])) if (~on).any() else None,
        "contact_us": 1e6 * float(np.median(dt[on])) if on.any() else None,
        "contact_share": float(on.mean()),
        "active_mean": float(act[on].mean()) if on.any() else 0.0,
        **floor,
    }


def _compile_cost() -> dict:
    """Seconds to compile the contact kernels in a fresh process with an empty numba cache,
    then to load them from that cache in a second fresh process."""
    import subprocess
    import tempfile

    code = (
        "import time; t = time.perf_counter()\n"
        "from femrub.contact.activation import compile_kernels\n"
        "t1 = time.perf_counter(); compile_kernels(); print(time.perf_counter() - t1)"
    )
    out = {}
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache, "PYTHONPATH": str(ROOT)}
        for key in ("compile_s", "cached_s"):
            run = subprocess.run(
                [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
            )
            out[key] = float(run.stdout.split()[-1])
    return out


def measure(scene_name: str, revolutions: float, vtk: bool = True) -> dict:
    from femrub.app.cache import ModelCache
    from femrub.app.scheme import scheme_options
    from femrub.app.simulation import build
    from femrub.scene import load_scene

    scene = load_scene(scene_name)
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    sim = build(scene, log=lambda s: None, cache=ModelCache())
    build_s = time.perf_counter() - t0
    omega = scene["loads"]["rotation_speed"]
    t_end = revolutions * 2 * math.pi / omega if omega else scene["scheme"]["t_end"]
    opts = scheme_options(scene)
    m = sim.model
    row = {
        "scene": scene_name,
        "n_dofs": m.n_dofs,
        "contacts": m.contact.n,
        "t_end": t_end,
        "build_s": build_s,
        "no_energy": _per_step(m, scene["scheme"], opts, t_end, False),
        "energy": _per_step(m, scene["scheme"], opts, t_end, True),
        "steps_path": _per_step(m, scene["scheme"], opts, t_end, False, blocks=False),
        **_bare_blocks(m, scene["scheme"], opts, t_end),
        **_split(m, scene["scheme"], opts, t_end),
    }
    if vtk:
        row.update(_vtk(sim, scene["scheme"], opts, 50, t_end))
    row["load"] = [load0, os.getloadavg()[0]]
    row.update(_compile_cost())
    return row


def table(row: dict) -> str:
    f = lambda x: "—" if x is None else f"{x:.1f}"  # noqa: E731
    floor = f(row.get("matvec_us", 0.0) + row.get("solve_us", 0.0))
    return (
        f"`{row['scene']}` reduced ({row['n_dofs']} coordinates, {row['contacts']} frictional "
        f"contacts), θ-method, {row['no_energy']['steps']} steps, one process; load "
        f"{row['load'][0]:.2f}–{row['load'][1]:.2f} (1-minute average).\n\n"
        "| quantity | µs per step |\n|---|---|\n"
        f"| CPU per step, no output, `run(energy=False)` (compiled blocks of steps) | "
        f"{f(row['no_energy']['us'])} |\n"
        f"| CPU per step, energy balance on (default `run()`) | {f(row['energy']['us'])} |\n"
        f"| CPU per step, the compiled blocks alone (no recorder) | {f(row.get('bare_us'))} |\n"
        f"| CPU per step, `run(energy=False)` step by step (`block_steps = False`) | "
        f"{f(row['steps_path']['us'])} |\n"
        f"| per-step path: step without impulse (median wall, "
        f"{100 * (1 - row['contact_share']):.0f} % of the steps) | {f(row['quiet_us'])} |\n"
        f"| per-step path: step with impulses (median wall, {100 * row['contact_share']:.0f} % "
        f"of the steps, {row['active_mean']:.1f} contacts active on average) | "
        f"{f(row['contact_us'])} |\n"
        f"| floor: dense `T X` ({row['n_dofs']}²) | {f(row.get('matvec_us'))} |\n"
        f"| floor: `numpy.linalg.solve` of the {row.get('solve_size', 0)}×"
        f"{row.get('solve_size', 0)} Delassus block | {f(row.get('solve_us'))} |\n"
        f"| floor: sum | {floor} |\n"
        + (_vtk_table(row) if "vtk_us" in row else "")
        + f"\nContact kernels (numba, `femrub.contact.coulomb`): first compilation "
        f"{row.get('compile_s', float('nan')):.1f} s in a fresh process with an empty cache, "
        f"{row.get('cached_s', float('nan')):.2f} s to load them from the on-disk cache; done "
        "when the stepper is built, never inside the steps above. Blocks: chunks of the "
        "recorder's rows advanced in one compiled call (`femrub.steppers.theta_blocks`).\n"
    )


def _vtk_table(row: dict) -> str:
    f = lambda x: f"{x:.1f}"  # noqa: E731
    p = row["vtk_plain_us"]
    pw = row["vtk_plain_wall_us"]
    pct = lambda x, ref: f"{100 * (x / ref - 1):+.0f} %"  # noqa: E731
    return (
        f"\nVTK at stride {row['vtk_stride']} over the same run ({row['vtk_frames']} frames "
        f"of {row['vtk_mb']:.2f} MB, float32 fields, raw binary), every frame on disk when "
        f"`run` returns; medians of {row['vtk_repeats']} runs of each kind taken in turn; "
        f"without output: CPU {f(p)} µs, wall {f(pw)} µs per step. The series is built "
        f"once before the run ({row['vtk_setup_s']:.2f} s wall, not in the table).\n\n"
        "| VTK writer | CPU per step (all threads) | wall per step | stepping thread in "
        "the series | writer thread | one frame (CPU) |\n|---|---|---|---|---|---|\n"
        f"| background thread (default, `femrub run`) | {f(row['vtk_us'])} "
        f"({pct(row['vtk_us'], p)}) | {f(row['vtk_wall_us'])} ({pct(row['vtk_wall_us'], pw)})"
        f" | {f(row['vtk_main_us'])} | {f(row['vtk_writer_us'])} | |\n"
        f"| in the stepping thread | {f(row['vtk_inline_us'])} "
        f"({pct(row['vtk_inline_us'], p)}) | {f(row['vtk_inline_wall_us'])} "
        f"({pct(row['vtk_inline_wall_us'], pw)}) | {f(row['vtk_inline_main_us'])} | | "
        f"{row['vtk_frame_ms']:.2f} ms |\n"
    )


def write(text: str, path: Path = ROOT / "docs" / "performance" / "rotor37-costs.md") -> None:
    doc = path.read_text()
    block = f"<!-- step_cost:begin -->\n{text}<!-- step_cost:end -->"
    pat = re.compile(r"<!-- step_cost:begin -->.*?<!-- step_cost:end -->", re.S)
    if pat.search(doc):
        doc = pat.sub(lambda _: block, doc)
    else:
        doc += "\n" + block + "\n"
    path.write_text(doc)


def main(argv=None) -> int:
    from femrub.scene import SceneError

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="rotor37")
    ap.add_argument("--revolutions", type=float, default=5.0)
    ap.add_argument("--no-vtk", action="store_true", help="skip the VTK rows")
    ap.add_argument("--no-write", action="store_true", help="print, do not edit the docs")
    args = ap.parse_args(argv)
    try:
        row = measure(args.scene, args.revolutions, not args.no_vtk)
    except (FileNotFoundError, SceneError) as exc:
        print(f"skipped: {exc}")
        return 0
    text = table(row)
    print(row)
    print(text)
    if not args.no_write:
        write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
