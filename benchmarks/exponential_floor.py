"""Cost floor of the exponential stepper (``floor`` study of ``benchmarks/exponential.py``).

Where an exponential run's CPU goes, per error: its fixed cost (constructor; per held set the
sub-step flows, probe rows and work integrals), its steps without event, the recorder and the
event steps, each the best of 5.
"""

from __future__ import annotations

import math
import time

import numpy as np

import femrub as fr

try:
    from . import _common as C
except ImportError:  # run as a script
    import _common as C


def _best(f, n=5) -> float:
    """Least CPU time (s) of ``n`` calls of ``f``."""
    out = math.inf
    for _ in range(n):
        c0 = time.process_time()
        f()
        out = min(out, time.process_time() - c0)
    return out


def _timed_run(model, h, T) -> tuple[float, float, int, float]:
    """One run with each step timed: ``(CPU s, median CPU s of a step without event, steps
    without event, CPU s of all steps)`` (the median leaves out the steps that build a held
    set's flows; the run less all steps is the recorder's and the energy meter's share)."""
    st = fr.ExponentialMoreau(model, h)
    step, locate, found, quiet, total = st._step, st._event, [0], [], [0.0]

    def counted(*args):
        ev = locate(*args)
        found[0] += ev is not None
        return ev

    def timed():
        n0, c0 = found[0], time.process_time()
        out = step()
        dt = time.process_time() - c0
        total[0] += dt
        if found[0] == n0:
            quiet.append(dt)
        return out

    st._event, st._step = counted, timed
    c0 = time.process_time()
    st.run(T)
    median = float(np.median(quiet)) if quiet else 0.0
    return time.process_time() - c0, median, len(quiet), total[0]


def _floor(name, model, h, T, log, key) -> dict:
    """Where an exponential run's CPU goes: its fixed cost (constructor; per held set met, the
    sub-step flows, probe rows and work integrals of its exact flows), its steps without
    event (median step × their number) and the rest (events), the events it located (best
    of 5 each); ``key``: the error the row is compared at (its target: a third of the best
    other method's cheapest run within 1 %)."""
    st = fr.ExponentialMoreau(model, h)
    events, locate = [], st._event

    def counted(*args):
        ev = locate(*args)
        events.append(ev is not None)
        return ev

    st._event = counted
    steps = st.steps_to(T)
    st.run(T)
    flows, work, q = st._flows, st._integrals, st.probes
    unit = h / q
    sets = sorted({S for S, _ in flows._levels})

    def rebuild(cache, key):
        def f():
            cache.pop(key, None)
            return key

        return f

    levels = probe = integrals = 0.0
    for S in sets:
        levels += _best(lambda S=S: (rebuild(flows._levels, (S, unit))(), flows.levels(S, unit)))
        probe += _best(
            lambda S=S: (rebuild(flows._probe, S)(), flows.probe(S, model.contact.GT, q))
        )
        integrals += _best(
            lambda S=S: (
                rebuild(work._levels, (S, unit))(),
                rebuild(work._full, (S, unit))(),
                work.step(S, np.zeros(flows.generator_z(S).shape[0]), q, unit),
            )
        )
    timed = min((_timed_run(model, h, T) for _ in range(5)), key=lambda r: r[0])
    row = {
        "case": name,
        "key": key,
        "h": h,
        "steps": steps,
        "events": int(sum(events)),
        "held_sets": len(sets),
        "run": _best(lambda: fr.ExponentialMoreau(model, h).run(T)),
        "run_no_energy": _best(lambda: fr.ExponentialMoreau(model, h).run(T, energy=False)),
        "constructor": _best(lambda: fr.ExponentialMoreau(model, h)),
        "flows": levels,
        "probe_rows": probe,
        "work_integrals": integrals,
        "quiet_step": timed[1],
        "quiet_steps": timed[2],
        "recording": timed[0] - timed[3],
    }
    row["fixed"] = row["constructor"] + levels + probe + integrals
    row["quiet"] = row["quiet_step"] * row["quiet_steps"]
    row["events_rest"] = row["run"] - row["fixed"] - row["quiet"] - row["recording"]
    log(
        f"floor {name} h={h:g}: "
        + ", ".join(f"{k} {v:.3g}" for k, v in row.items() if k != "case" and k != "key")
    )
    return row


def floor(cfg, log) -> list[dict]:
    """The exponential stepper's cost floor at its coarsest step (the tip temperature's
    1 %) and at its cheapest step within 1 % ``u_L2`` (paper case; blade)."""
    model, T = C.paper_model(), cfg["t_wp"]
    rows = [_floor("paper", model, cfg["exp_h"][0], T, log, "T_end")]
    rows.append(_floor("paper", model, cfg["floor_u_h"], T, log, "u_L2"))
    if cfg["blade_t"]:
        from femrub.app.simulation import Simulation
        from femrub.scene import load_scene

        scene = load_scene("twisted-naca", {"outputs.vtk_stride": 0})
        model = frictionless(Simulation.from_scene(scene).model, scene)
        rows.append(_floor("blade", model, cfg["blade_exp_h"][0], cfg["blade_t"], log, "T_end"))
    return rows


def frictionless(model, scene):
    """``model`` with its Coulomb friction replaced by the α heat law of the same heat at full
    slip, ``α = η μ Ω r_tip`` (the exponential stepper has no friction)."""
    from dataclasses import replace

    c, g = model.contact, scene["geometry"]
    r_tip = g["hub_radius"] + g["span"]
    alpha = c.heat_partition * c.friction * abs(scene["loads"]["rotation_speed"]) * r_tip
    return model.with_(contact=replace(c, friction=0.0, heat_law="alpha", heat_coefficient=alpha))
