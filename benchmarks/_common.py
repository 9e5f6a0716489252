"""Shared code of the speed and accuracy benchmarks (SI units throughout).

* the two test problems: the paper's bar (``paper_model``) and a free elastic bar impacting
  a rigid obstacle (``impact_model``, exact d'Alembert solution ``impact_exact``);
* the error measures of ``docs/performance/speed-and-accuracy.md`` (``Measures``, ``compare``);
* CPU timing, peak memory, Markdown tables and JSON output.
"""

from __future__ import annotations

import json
import math
import os
import platform
import resource
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import femrub as fr
from femrub.cases.analytic import bar_impact

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
OUT = DOCS / "performance"

# free bar impacting a rigid obstacle (examples/bar_impact.py; Doyen, Ern & Piperno 2011)
E, RHO, AREA, LENGTH, V0, GAP = 110e9, 4500.0, 1e-6, 0.3, 0.1, 1e-5
WAVE_SPEED = math.sqrt(E / RHO)
EXACT = bar_impact(LENGTH, E, RHO, AREA, V0, GAP)
IMPACT_T_END = 1.5 * (EXACT.contact_start + EXACT.contact_duration)
#: load period of the paper case (s): one contact phase per period
PERIOD = 2.0 * math.pi / fr.PAPER.force_frequency
ALPHA = 3.0


def paper_model(alpha: float = ALPHA, coupled: bool = True, **changes) -> fr.FirstOrderModel:
    """The paper's 20-node bar (60 dofs), coupled through ``β K^uu`` unless ``coupled=False``."""
    return fr.bar_model(alpha=alpha, coupling="paper" if coupled else "none", **changes)


def impact_model(n_elements: int, **changes) -> fr.FirstOrderModel:
    """Free bar of ``n_elements`` elements moving at ``V0`` towards an obstacle ``GAP`` away."""
    from femrub.cases.bar import impact_bar_model

    return impact_bar_model(
        n_elements, velocity=V0, gap=GAP, young=E, density=RHO, area=AREA, length=LENGTH, **changes
    )


def impact_exact_displacement(t: np.ndarray) -> np.ndarray:
    """Exact tip displacement (m): free flight, held at the obstacle for 2L/c, rebound at −v0."""
    t1 = EXACT.contact_start
    t2 = t1 + EXACT.contact_duration
    return np.where(t < t1, V0 * t, np.where(t < t2, GAP, GAP - V0 * (t - t2)))


@dataclass
class Measures:
    """What the error measures compare: tip displacement history, end temperature, phases."""

    t: np.ndarray
    u: np.ndarray
    T_end: float
    phases: np.ndarray
    t1: float

    @classmethod
    def of(cls, res, period: float | None, t_end: float) -> Measures:
        """Measures of a run up to ``t_end``; ``period`` splits the impulses into phases."""
        n = int(np.searchsorted(res.t, t_end * (1 + 1e-9), side="right"))
        t, imp = res.t[:n], res.impulse[:n].sum(axis=1)
        T = res.signals.get("tip_temperature")
        return cls(
            t=t,
            u=res.signal("tip_displacement")[:n],
            T_end=float(T[n - 1, 0]) if T is not None else math.nan,
            phases=phase_impulses(t, imp, period, t_end),
            t1=first_contact(t, imp),
        )


def phase_impulses(t, impulse, period: float | None, t_end: float) -> np.ndarray:
    """Impulse (N s) per contact phase: per load period, or the whole run if no period."""
    if period is None:
        return np.array([impulse.sum()])
    n = max(1, math.ceil(t_end / period - 1e-9))
    # the impulse of row k belongs to the step (t_{k-1}, t_k]
    idx = np.clip(((t - 1e-12) // period).astype(int), 0, n - 1)
    return np.bincount(idx, weights=impulse, minlength=n)


def first_contact(t, impulse, rel: float = 1e-6) -> float:
    """First time (s) whose step carries an impulse above ``rel`` × the largest one."""
    if impulse.size == 0 or impulse.max() <= 0:
        return math.nan
    return float(t[np.argmax(impulse > rel * impulse.max())])


def compare(m: Measures, ref: Measures) -> dict[str, float]:
    """Error measures of ``m`` against ``ref`` (docs/performance/speed-and-accuracy.md).

    ``u_L2``: time-L2 relative error of the tip displacement (piecewise-linear interpolant
    of ``m`` on the reference grid); ``u_max``: largest error / largest reference value;
    ``T_end``: relative error of the tip temperature at the end; ``P_phase``: largest error
    of the impulse of a contact phase / largest reference phase impulse; ``t1``: error of
    the first-contact time (s).
    """
    u = np.interp(ref.t, m.t, m.u)
    du = u - ref.u
    k = min(m.phases.size, ref.phases.size)
    dP = np.abs(m.phases[:k] - ref.phases[:k])
    if m.phases.size != ref.phases.size:
        dP = np.r_[dP, np.abs(m.phases[k:]), np.abs(ref.phases[k:])]
    return {
        "u_L2": float(np.sqrt(_integral(du**2, ref.t) / _integral(ref.u**2, ref.t))),
        "u_max": float(np.max(np.abs(du)) / np.max(np.abs(ref.u))),
        "T_end": abs(m.T_end - ref.T_end) / abs(ref.T_end) if ref.T_end else math.nan,
        "P_phase": float(dP.max() / np.abs(ref.phases).max()),
        "t1": abs(m.t1 - ref.t1),
    }


def _integral(y, t) -> float:
    """Trapezoidal rule."""
    return float(0.5 * np.sum((y[1:] + y[:-1]) * np.diff(t)))


def exact_impact_measures(n: int = 20001) -> Measures:
    """The exact solution of the impact problem as :class:`Measures`."""
    t = np.linspace(0.0, IMPACT_T_END, n)
    return Measures(
        t=t,
        u=impact_exact_displacement(t),
        T_end=math.nan,
        phases=np.array([EXACT.impulse]),
        t1=EXACT.contact_start,
    )


def timed(fn, *args, **kwargs):
    """``(fn(*args, **kwargs), CPU seconds, wall seconds)``."""
    c0, w0 = time.process_time(), time.perf_counter()
    out = fn(*args, **kwargs)
    return out, time.process_time() - c0, time.perf_counter() - w0


def write_between(doc: Path, name: str, text: str, heading: str = "") -> None:
    """Put ``text`` between ``<!-- name:begin -->`` and ``<!-- name:end -->`` in ``doc``
    (the markers appended, under ``heading``, when the document has none yet)."""
    begin, end = f"<!-- {name}:begin -->", f"<!-- {name}:end -->"
    page = doc.read_text()
    if begin not in page:
        page += f"\n{heading}{begin}\n{end}\n"
    i, j = page.index(begin) + len(begin), page.index(end)
    doc.write_text(page[:i] + "\n" + text + "\n" + page[j:])


def peak_rss_mib() -> float:
    """Peak resident memory of this process (MiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _commit() -> str | None:
    """The project's git commit (``None`` outside a git checkout)."""
    import subprocess

    try:
        done = subprocess.run(
            ["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
            capture_output=True,
            text=True,
            timeout=10,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return done.stdout.strip() or None


def machine() -> dict:
    """Where the numbers come from: date, commit, platform, Python, cores, load average."""
    import os

    return {
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "commit": _commit(),
        "python": platform.python_version(),
        "platform": platform.platform(),
        "cores": os.cpu_count(),
        "load_average": [round(x, 2) for x in os.getloadavg()],
        "femrub": fr.__version__,
        "numpy": np.__version__,
        "executable": sys.executable,
    }


def stamp(command: str, machine: dict | None) -> str:
    """Where a table's numbers come from, as an italic sentence: the command that measured
    them, its date, commit, Python, cores and the load average at its start."""
    m = machine or {}
    when = m.get("date") or "date not recorded"
    commit = f"commit {m['commit']}" if m.get("commit") else "commit not recorded"
    return (
        f"*Measured by `{command}` ({when}, {commit}; Python {m.get('python', '?')}, "
        f"{m.get('cores', '?')} cores, load average {m.get('load_average', '?')} at its start).*"
    )


def render_sections(doc: Path, sections: dict[str, str]) -> None:
    """Put each ``sections[name]`` between the ``name`` markers of ``doc`` (write_between)."""
    for name, text in sections.items():
        write_between(doc, name, text)


def command_line(script: str, argv=None) -> str:
    """The command that ran ``benchmarks/<script>``: ``argv``, or this process's arguments."""
    args = sys.argv[1:] if argv is None else list(argv)
    return " ".join([f"python benchmarks/{script}", *args])


def stamped_sections(data: dict, prefix: str) -> dict[str, str]:
    """``marker name -> text`` of stored sections ``{key: {command, machine, text}}``: each
    section's :func:`stamp` (under the text's heading if it has one), then the text its
    benchmark generated."""
    return {f"{prefix}_{key}": _stamped(e) for key, e in data.items()}


def _stamped(entry: dict) -> str:
    """A stored section's text with its stamp under its heading (first, without one)."""
    text = entry["text"].strip()
    heading, body = text.split("\n", 1) if text.startswith("#") else ("", text)
    stamped = stamp(entry["command"], entry["machine"]) + "\n\n" + body.strip()
    return f"{heading}\n\n{stamped}" if heading else stamped


def store_section(store: Path, page: Path, prefix: str, key: str, entry: dict) -> None:
    """Keep ``entry`` (``command``, ``machine``, ``text``) under ``key`` in the JSON ``store``
    and render every stored section into ``page`` (:func:`stamped_sections`)."""
    data = read_json(store) if store.exists() else {}
    data[key] = entry
    write_json(store, data)
    render_sections(page, stamped_sections(read_json(store), prefix))


def fmt(x, digits: int = 3) -> str:
    """Number for a Markdown table: ``—`` for NaN/None, scientific for small or large."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "—"
    if isinstance(x, (int, np.integer)) and not isinstance(x, bool):
        return str(int(x))
    if isinstance(x, str):
        return x
    x = float(x)
    if x == 0.0:
        return "0"
    if 1e-2 <= abs(x) < 1e4:
        return f"{x:.{digits}g}"
    return f"{x:.{max(digits - 1, 1)}e}"


def md_table(rows: list[dict], cols: list[tuple[str, str]]) -> str:
    """Markdown table of ``rows`` with ``cols = [(key, header), ...]``."""
    out = ["| " + " | ".join(h for _, h in cols) + " |", "|" + "---|" * len(cols)]
    for r in rows:
        out.append("| " + " | ".join(fmt(r.get(k)) for k, _ in cols) + " |")
    return "\n".join(out)


def read_json(path: Path):
    """A document :func:`write_json` wrote: its nulls back to the NaNs they were."""

    def nan(x):
        if isinstance(x, dict):
            return {k: nan(v) for k, v in x.items()}
        if isinstance(x, list):
            return [nan(v) for v in x]
        return math.nan if x is None else x

    return nan(json.loads(Path(path).read_text()))


def write_json(path: Path, doc) -> Path:
    """Write ``doc`` as indented JSON (NaN as null)."""

    def clean(x):
        if isinstance(x, dict):
            return {k: clean(v) for k, v in x.items()}
        if isinstance(x, (list, tuple)):
            return [clean(v) for v in x]
        if isinstance(x, (np.floating, float)):
            return float(x) if math.isfinite(x) else None
        if isinstance(x, np.integer):
            return int(x)
        return x

    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(clean(doc), indent=1))
    return path


def _value(text: str):
    """A ``--set`` value: an int, else a float, else the text."""
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def ladder_arguments(doc: str):
    """The parser of a step-ladder benchmark: ``--scene`` (default ``rotor37-thermal``),
    ``--factors``, ``--set KEY=VALUE`` (repeatable), ``--no-write``; add the study's own."""
    import argparse

    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--scene", default="rotor37-thermal")
    ap.add_argument("--factors", default="1,2,4")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--no-write", action="store_true")
    return ap


def cli_scene(name: str, sets: list[str]):
    """The scene ``name`` with the ``--set KEY=VALUE`` changes ``sets`` and VTK off, or
    ``None`` (printing why) when it is a Rotor 37 scene and ``../shared/data`` is absent."""
    from femrub.scene import load_scene

    root = Path(__file__).resolve().parents[1]
    shared = (root.parent / "shared" / "data").is_dir() or os.environ.get("FEMRUB_SHARED_DATA")
    if name.startswith("rotor37") and not shared:
        print("skipped: no ../shared/data (Rotor 37 mesh)")
        return None
    changes = {k: _value(v) for k, v in (s.split("=", 1) for s in sets)}
    return load_scene(name, {"outputs.vtk_stride": 0, **changes})


#: runs ``femrub ARGS`` in this child and reports its own peak resident memory last
_FEMRUB_CHILD = (
    "import resource, sys; from femrub.app.cli import main; code = main(sys.argv[1:]); "
    "sys.stderr.write(f'\\nmaxrss_kib {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss}\\n'); "
    "sys.exit(code)"
)


def femrub_process(*args) -> dict:
    """Wall seconds and peak resident memory (MiB) of ``femrub ARGS`` in its own process
    (exit 0 or 1: a run whose status is not ``ok`` exits 1; anything else raises)."""
    import subprocess

    t0 = time.perf_counter()
    cmd = [sys.executable, "-c", _FEMRUB_CHILD, *args]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if done.returncode not in (0, 1):
        raise RuntimeError(f"femrub {' '.join(args)} failed:\n{done.stderr[-2000:]}")
    peak = float(done.stderr.rsplit("maxrss_kib", 1)[1].split()[0]) / 1024.0
    return {
        "command": "femrub " + " ".join(args),
        "exit": done.returncode,
        "wall_s": wall,
        "peak_mib": peak,
    }


def rotor37_study(argv, description: str, store: Path, page: Path, marker: str, measure, render):
    """The ``main`` of a Rotor 37 study: ``--render-only`` renders the ``marker`` section of
    ``page`` from ``store``; otherwise ``measure()`` (skipped with a message without the
    shared data), its JSON written to ``store`` and its section rendered and printed."""
    import argparse

    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--render-only", action="store_true", help="render the page from the JSON")
    a = ap.parse_args(argv)
    if a.render_only:
        write_between(page, marker, render(read_json(store)))
        return 0
    from femrub.geometry.rotor37 import shared_data_dir

    if not (shared_data_dir() / "rotor37-fe-mesh").is_dir():
        print(f"skipped: no Rotor 37 mesh under {shared_data_dir()} (set FEMRUB_SHARED_DATA)")
        return 0
    doc = measure()
    write_json(store, doc)
    text = render(doc)
    write_between(page, marker, text)
    print(text)
    return 0
