"""The controllers against their targets, through the FMUs: ``crane-fmu targets``.

Conditions: the Section V plant (nonlinear model), |u| <= 2 m/s2 and |v| <= 1 m/s
in every controller and the planner, a 1 ms communication step unless stated.
Every figure is measured by co-simulating the built FMUs with the master; the
targets are printed next to the measurements and never asserted.
"""

import math
import os
from collections import namedtuple

from crane_fmu import systems
from crane_fmu.cosim import ArrayRecorder, FmiError, run
from crane_fmu.sweep.batch import run_batch

from . import metrics, scoreboard

Run = namedtuple("Run", "group label system parameters step stop_time")
REGULATORS = ("lqr", "energy", "paper")
SHAPERS = ("zv", "zvd", "ei", "none")
ROA_ANGLES = tuple(range(5, 65, 5))
MISMATCH, DISTANCE = scoreboard.MISMATCH, scoreboard.DISTANCE  # the scoreboard's S3 grid and S2 move


def plan(quick=False):
    # regulation runs 40 s: the energy law's swing decays too slowly to classify in 10 s
    runs = [Run("regulation", name, name, {}, 1e-3, 40.0) for name in REGULATORS]
    runs += [Run("transport", shaper, "transport", {"planner": {"shaper": shaper, "x_d": DISTANCE}}, 1e-3, 10.0)
             for shaper in SHAPERS]
    runs.append(Run("hoist", "hoist-transport", "hoist-transport", {}, 1e-3, 12.0))
    for shaper in ("zv",) if quick else ("zv", "zvd"):
        runs += [Run(f"robust_{shaper}", str(plant), "transport", {"plant": plant, "planner": {"shaper": shaper}},
                     1e-3, 10.0) for plant in (MISMATCH[::13] if quick else MISMATCH)]
    for name in ("lqr", "energy"):
        runs += [Run(f"roa_{name}", str(angle), name, {"plant": {"theta1_0": math.radians(angle)}}, 1e-3, 30.0)
                 for angle in (ROA_ANGLES[::4] if quick else ROA_ANGLES)]
    for h in (1e-2, 5e-2):
        runs += [Run(f"step_{h:g}", name, name, {}, h, 40.0) for name in REGULATORS]
        runs.append(Run(f"step_{h:g}", "transport", "transport", {}, h, 10.0))
    return runs


def measure(r, fmu_dir):
    """Co-simulate one run; return its move metrics and outcome."""
    system = systems.at_step(systems.get(r.system), fmu_dir, r.step).with_parameters(r.parameters)
    recorder, error = ArrayRecorder(), None
    try:
        run(system, fmu_dir, recorder=recorder, stop_time=r.stop_time, step=r.step)
    except FmiError as exc:
        error = str(exc)
    x_d = system.parameters.get("planner", {}).get("x_d", system.parameters.get("controller", {}).get("x_d", 0.0))
    plant = dict(system.parameters.get("plant", {}))
    if "hoist" in system.parameters:
        plant["l1"] = system.parameters["hoist"]["x_d"]  # the cable as the run ends
    plan = system.parameters.get("planner", {}) if "planner" in system.instances else None
    s = metrics.crane_signals(recorder.columns(), ("dx",))
    result = metrics.move_metrics(s["time"], s["x"], s["dx"], s["theta1"], s["theta2"], s["u"], x_d,
                                  scoreboard.residual_from(r.stop_time, plan, plant))
    result.update(outcome=metrics.classify(s["time"], s["theta1"], s["theta2"], error is None), error=error,
                  end_s=float(s["time"][-1]))
    return r, result


def _measure_nth(numbered, fmu_dir):
    """``(n, measure(run))`` of ``numbered = (n, run)``: results that finish in any order keep the plan's."""
    n, r = numbered
    return n, measure(r, fmu_dir)


def _fmt(value, digits=2, unit=" s"):
    return "never" if value is None else f"{value:.{digits}f}{unit}"


def report(results, out=print):
    """Print every figure with its target."""
    by = {}
    for r, m in results:
        by.setdefault(r.group, {})[r.label] = m
    out("Regulation from theta1(0) = 10 deg, h = 1 ms, 40 s (targets: 0.5 deg by <= 3.0 s, 0.1 deg by <= 4.0 s, "
        "trolley within 1 cm by 4 s; ambition 2.5 s and 3.5 s)")
    for name, m in by["regulation"].items():
        out(f"  {name:<8} 0.5 deg from {_fmt(m['settling_0.5deg_s'])}, 0.1 deg from {_fmt(m['settling_0.1deg_s'])}, "
            f"trolley within 1 cm from {_fmt(m['position_1cm_s'])}, peak |u| {m['peak_abs_u']:.2f} m/s2, "
            f"peak |v| {m['peak_abs_v']:.2f} m/s, {m['outcome']}")
    out(f"Transport of {DISTANCE:g} m from rest, |v| <= 1 m/s (targets: within 5 mm and 0.5 deg from <= "
        f"{scoreboard.ZV_MOVE_S:.1f} s (the ZV-shaped time-optimal move, scoreboard S2), "
        "residual swing (from one slow period after the planned move) <= 0.1 deg)")
    for shaper, m in by["transport"].items():
        out(f"  {shaper:<8} arrival {_fmt(m['arrival_s'])}, residual {_fmt(m['residual_deg'], 3, ' deg')}, "
            f"overshoot {m['overshoot_m'] * 1e3:.1f} mm, peak |u| {m['peak_abs_u']:.2f} m/s2, "
            f"peak |v| {m['peak_abs_v']:.2f} m/s")
    for name, m in by.get("hoist", {}).items():
        out(f"Transport of {DISTANCE:g} m while hoisting from l1 = 2 m to 1 m ({name}, ZVD planned for 1.5 m, LQR "
            f"scheduled on l1): arrival {_fmt(m['arrival_s'])}, residual {_fmt(m['residual_deg'], 3, ' deg')}, "
            f"peak |u| {m['peak_abs_u']:.2f} m/s2")
    for group in [g for g in by if g.startswith("robust_")]:
        cases = by[group]
        worst = max(cases.items(), key=lambda kv: kv[1]["residual_deg"] if kv[1]["residual_deg"] is not None
                    else math.inf)
        slowest = max(cases.items(), key=lambda kv: kv[1]["arrival_s"] if kv[1]["arrival_s"] is not None else math.inf)
        out(f"Robustness, {group[7:]} shaper: {len(cases)} plants with l1 +-10 %, l2 +-20 %, m2 +-50 % unknown to "
            f"planner and controller (target: residual <= {scoreboard.STOPPED_DEG:g} deg, scoreboard S3)")
        out(f"  worst residual {_fmt(worst[1]['residual_deg'], 3, ' deg')} at {worst[0]}; "
            f"latest arrival {_fmt(slowest[1]['arrival_s'])} at {slowest[0]}")
    for group in [g for g in by if g.startswith("roa_")]:
        angles = sorted((int(a), m["outcome"]) for a, m in by[group].items())
        contiguous = 0
        for angle, outcome in angles:
            if outcome not in metrics.CONVERGING:
                break
            contiguous = angle
        out(f"Region of attraction, {group[4:]} (30 s runs): converges or is decaying from every theta1(0) up to "
            f"{contiguous} deg "
            f"(target for the nonlinear law: >= 45 deg); " + ", ".join(f"{a}: {o}" for a, o in angles))
    for group in [g for g in by if g.startswith("step_")]:
        out(f"Communication step h = {float(group[5:]) * 1e3:g} ms:")
        for name, m in by[group].items():
            what = (f"arrival {_fmt(m['arrival_s'])}, residual {_fmt(m['residual_deg'], 3, ' deg')}"
                    if name == "transport" else
                    f"0.5 deg from {_fmt(m['settling_0.5deg_s'])}, 0.1 deg from {_fmt(m['settling_0.1deg_s'])}")
            out(f"  {name:<9} {m['outcome']}{' (' + m['error'] + ')' if m['error'] else ''}: {what}")


def run_targets(fmu_dir, quick=False, workers=None, out=print):
    """Measure every run of :func:`plan` on ``workers`` processes and print the report; return the results."""
    runs = plan(quick)
    workers = workers or os.cpu_count() or 1
    out(f"{len(runs)} co-simulations on {workers} worker(s)")
    finished = run_batch(_measure_nth, list(enumerate(runs)), workers=workers, fmu_dir=fmu_dir)
    results = [result for _, result in sorted(finished, key=lambda pair: pair[0])]  # in the plan's order
    report(results, out)
    return results

