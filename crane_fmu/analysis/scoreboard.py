"""The controller scoreboard: the scenarios, the metrics, the targets, and how controllers are ranked.

The one place that documents the **controller interface** a scored FMU (FMI 2.0
or 3.0 co-simulation) must have:

- inputs ``x`` [m], ``dx`` [m/s], ``theta1`` [rad], ``dtheta1`` [rad/s],
  ``theta2`` [rad], ``dtheta2`` [rad/s]: the measured crane state;
- output ``u`` [m/s2]: the demanded trolley acceleration;
- for the transport scenarios, either a parameter ``x_d`` [m] (the target
  position) or the reference inputs ``x_ref`` [m], ``dx_ref`` [m/s],
  ``ddx_ref`` [m/s2] (and optionally ``theta1_ref``, ``dtheta1_ref``,
  ``theta2_ref``, ``dtheta2_ref``) of a ``TrajectoryPlanner``;
- optionally: an input ``l1_now`` [m] (the measured main cable length, when
  the plant hoists), parameters ``m1``, ``m2``, ``l1``, ``l2``, ``g`` (its model
  of the crane: set to the nominal plant), ``h`` [s] (the communication step).

The crane is the Section V plant with a trolley drive limited to 2 m/s2 and
1 m/s; every metric is computed from the plant's true state.
"""

from collections import namedtuple

MEASURED = ("x", "dx", "theta1", "dtheta1", "theta2", "dtheta2")
REFERENCE = ("x_ref", "dx_ref", "ddx_ref", "theta1_ref", "dtheta1_ref", "theta2_ref", "dtheta2_ref")
DRIVE = {"u_max": 2.0, "v_max": 1.0}
DISTANCE = 2.0
MISMATCH = [{"l1": l1, "l2": l2, "m2": m2}
            for l1 in (0.9, 1.0, 1.1) for l2 in (0.4, 0.5, 0.6) for m2 in (3.5, 7.0, 10.5)]
STEPS = (1e-3, 1e-2, 5e-2)

Target = namedtuple("Target", "metric limit text")
Scenario = namedtuple("Scenario", "id title rank_by targets")
Scenario.__doc__ = "A scenario: its id, what it is, the metric it ranks by (lower is better) and its targets."

# Every target, in one place: a case meets a target when its metric is not None and <= the limit.
SCENARIOS = {
    "S1": Scenario("S1", "Section V regulation from theta1 = 10 deg", "settling_0.1deg_s",
                   (Target("settling_0.5deg_s", 3.0, "both angles within 0.5 deg by 3.0 s"),
                    Target("settling_0.1deg_s", 4.0, "within 0.1 deg by 4.0 s"),
                    Target("position_1cm_s", 4.0, "trolley within 1 cm of x_d by 4.0 s"))),
    "S2": Scenario("S2", f"{DISTANCE:g} m transport from rest", "arrival_s",
                   (Target("arrival_s", 3.8, "within 5 mm and 0.5 deg from 3.8 s"),
                    Target("residual_deg", 0.1, "residual swing after the move <= 0.1 deg"))),
    "S3": Scenario("S3", "S2 on 27 plants: l1 +-10 %, l2 +-20 %, m2 +-50 % unknown to the controller",
                   "residual_deg",
                   (Target("residual_deg", 1.0, "worst residual swing <= 1 deg"),
                    Target("arrival_s", 6.0, "every plant arrives by 6 s"))),
    "S4": Scenario("S4", "S2 with a gust: a 10 N half-sine push on the payload at 1.5-2.0 s", "arrival_s",
                   (Target("arrival_s", 6.0, "within 5 mm and 0.5 deg from 6.0 s"),
                    Target("residual_deg", 0.1, "residual swing <= 0.1 deg"))),
    "S5": Scenario("S5", "S2 measured with noise (seed 1) one communication step late", "arrival_s",
                   (Target("arrival_s", 5.0, "within 5 mm and 0.5 deg from 5.0 s"),
                    Target("residual_deg", 0.2, "residual swing <= 0.2 deg"))),
    "S6": Scenario("S6", "S1 at communication steps of 1, 10 and 50 ms", "settling_0.5deg_s",
                   (Target("settling_0.5deg_s", 5.0, "within 0.5 deg by 5 s at every step"),)),
    "S7": Scenario("S7", f"{DISTANCE:g} m transport while hoisting from l1 = 2 m to 1 m", "arrival_s",
                   (Target("arrival_s", 8.0, "within 5 mm and 0.5 deg from 8.0 s"),
                    Target("residual_deg", 0.1, "residual swing <= 0.1 deg"))),
}

Contender = namedtuple("Contender", "name source inputs parameters")
Contender.__doc__ = "A controller to score: its name, its FMU (a model identifier or an .fmu path), its interface."


def check_interface(name, inputs, outputs):
    """Raise ValueError (one line) naming what a controller FMU misses of the interface."""
    missing = [n for n in MEASURED if n not in inputs] + (["output u"] if "u" not in outputs else [])
    if missing:
        raise ValueError(f"{name} is not a crane controller: it misses {', '.join(missing)} (the interface: inputs "
                         f"{', '.join(MEASURED)}; output u)")


def systems_for(contender, scenario, quick=False):
    """``[(case label, System, step, stop time, x_d)]`` of one scenario for a contender.

    Raises
    ------
    ValueError
        When the contender cannot be given the scenario's target.
    """
    from crane_fmu.cosim import Connection, System

    c = contender
    tracking = all(n in c.inputs for n in REFERENCE[:3])

    def regulation(step):
        return System(f"{c.name}-regulation", {"plant": "CranePlant", "controller": c.source},
                      parameters={"plant": dict(DRIVE)}, stop_time=10.0, step=step)

    def transport(plant=None, extra=None, connections=(), l1=None, hoist=False):
        instances = {"plant": "CranePlant", "controller": c.source}
        parameters = {"plant": {**DRIVE, "theta1_0": 0.0, **(plant or {})}, "controller": {}}
        if l1 is not None and "l1" in c.parameters:
            parameters["controller"]["l1"] = l1
        if tracking:
            instances["planner"] = "TrajectoryPlanner"
            parameters["planner"] = {"x_d": DISTANCE, "shaper": "zvd" if hoist else "zv"}
            if hoist:
                parameters["planner"]["l1"] = 1.5
                connections = connections + tuple(Connection("planner", n, "controller", n) for n in REFERENCE
                                                   if n in c.inputs)
        elif "x_d" in c.parameters:
            parameters["controller"]["x_d"] = DISTANCE
        else:
            raise ValueError(f"{c.name} has neither x_ref, dx_ref, ddx_ref inputs nor an x_d parameter: "
                             "it cannot be given a target position")
        for name, (kind, values) in (extra or {}).items():
            instances[name] = kind
            parameters[name] = values
        return System(f"{c.name}-transport", instances, connections, parameters=parameters,
                      stop_time=12.0 if hoist else 10.0)

    if scenario == "S1":
        return [("nominal", regulation(1e-3), 1e-3, 10.0, 0.0)]
    if scenario == "S6":
        return [(f"h={h * 1e3:g}ms", regulation(h), h, 10.0, 0.0) for h in STEPS]
    if scenario == "S2":
        return [("nominal", transport(), 1e-3, 10.0, DISTANCE)]
    if scenario == "S3":
        grid = MISMATCH[::13] if quick else MISMATCH
        return [(", ".join(f"{k}={v:g}" for k, v in p.items()), transport(p), 1e-3, 10.0, DISTANCE) for p in grid]
    if scenario == "S4":
        gust = {"gust": ("Gust", {"F2_peak": 10.0, "start": 1.5, "duration": 0.5})}
        return [("F2 10 N at 1.5 s", transport(extra=gust), 1e-3, 10.0, DISTANCE)]
    if scenario == "S5":
        sensor = {"sensor": ("Sensor", {"seed": 1.0, "delay": 1.0})}
        wiring = tuple(Connection("sensor", n + "_m", "controller", n) for n in MEASURED)
        return [("seed 1, one step late", transport(extra=sensor, connections=wiring), 1e-3, 10.0, DISTANCE)]
    if scenario == "S7":
        hoist = {"hoist": ("TrajectoryPlanner", {"x0": 2.0, "x_d": 1.0, "shaper": "none", "u_max": 0.5,
                                                  "v_max": 0.5})}
        plant = {"l1": 2.0, "l1_min": 1.0, "l1_max": 2.0}
        system = transport(plant, hoist, (Connection("hoist", "ddx_ref", "plant", "hoist"),), l1=2.0, hoist=True)
        if "l1_low" in c.parameters:
            system = system.with_parameters({"controller": {"l1_low": 1.0, "l1_high": 2.0}})
        return [("l1 2 m -> 1 m", system, 1e-3, 12.0, DISTANCE)]
    raise ValueError(f"no scenario {scenario!r}; scenarios: {', '.join(SCENARIOS)}")


def met(row, target):
    value = row.get(target.metric)
    return row.get("status") == "ok" and value is not None and value <= target.limit


def summarise(rows, scenario):
    """One line per contender for a scenario: the worst case of each metric, targets met, rank order."""
    s = SCENARIOS[scenario]
    by = {}
    for r in rows:
        if r["scenario"] == scenario:
            by.setdefault(r["controller"], []).append(r)
    lines = []
    for name, cases in by.items():
        failed = [r for r in cases if r["status"] != "ok"]
        worst = {}
        for metric in ("settling_0.5deg_s", "settling_0.1deg_s", "position_1cm_s", "arrival_s", "residual_deg",
                       "overshoot_m", "final_error_m", "peak_abs_u", "peak_abs_v", "effort"):
            values = [r.get(metric) for r in cases]
            worst[metric] = None if any(v is None for v in values) else max(values)
        targets = [all(met(r, t) for r in cases) for t in s.targets]
        lines.append({"controller": name, "cases": len(cases), "failed": len(failed),
                      "error": failed[0]["error"] if failed else None, **worst, "targets": targets})
    key = s.rank_by
    lines.sort(key=lambda line: (line["failed"] > 0, line[key] is None, line[key] if line[key] is not None else 0))
    return lines


def _cell(value, digits=2, unit=""):
    if value is None:
        return "never"
    return f"{value:.{digits}f}{unit}"


def render_summary(rows):
    """One table: per scenario the controllers ranked, with their ranking figure and whether they met every target."""
    units = {"residual_deg": " deg"}
    lines = []
    for sid, s in SCENARIOS.items():
        ranked = summarise(rows, sid)
        if not ranked:
            continue
        cells = []
        for line in ranked:
            value = line[s.rank_by]
            figure = "failed" if line["failed"] else _cell(value, 3 if s.rank_by == "residual_deg" else 2,
                                                           units.get(s.rank_by, " s"))
            verdict = "all targets met" if all(line["targets"]) and not line["failed"] else (
                f"{sum(line['targets'])} of {len(line['targets'])} targets met")
            cells.append(f"`{line['controller']}`: {figure}, {verdict}")
        lines.append((sid, s, cells))
    width = max(len(cells) for _, _, cells in lines)
    out = ["| scenario | ranked by | " + " | ".join(f"{i + 1}." for i in range(width)) + " |",
           "|---|---|" + "---|" * width]
    for sid, s, cells in lines:
        out.append(f"| {sid}: {s.title} | {s.rank_by} | " + " | ".join(cells + [""] * (width - len(cells))) + " |")
    return "\n".join(out)


def render(rows, contenders):
    """scoreboard.md: per scenario a table ranked by its metric, with each target met or missed."""
    out = ["# Controller scoreboard", "",
           "Every controller on the same crane (Section V plant, trolley drive limited to 2 m/s2 and 1 m/s), through "
           "the same master, on the same scenarios (`crane_fmu/analysis/scoreboard.py` defines them and their "
           "targets). Times are from the start of the run; *never* means not within the run. A row's figure is the "
           "worst over the scenario's cases.", "",
           "Controllers: " + ", ".join(f"`{c.name}`" for c in contenders), "", render_summary(rows), ""]
    for sid, s in SCENARIOS.items():
        lines = summarise(rows, sid)
        if not lines:
            continue
        out += [f"## {sid}: {s.title}", "", "Targets: " + "; ".join(t.text for t in s.targets) + ".", ""]
        out.append("| rank | controller | 0.5 deg from | 0.1 deg from | arrival | residual | overshoot | final error "
                   "| peak abs u | peak abs v | effort | targets |")
        out.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
        for rank, line in enumerate(lines, 1):
            verdict = ", ".join(("met" if ok else "**missed**") for ok in line["targets"])
            if line["failed"]:
                verdict = f"**failed** in {line['failed']} of {line['cases']}: {line['error']}"[:300]
            out.append(f"| {rank} | `{line['controller']}` | {_cell(line['settling_0.5deg_s'], 2, ' s')} | "
                       f"{_cell(line['settling_0.1deg_s'], 2, ' s')} | {_cell(line['arrival_s'], 2, ' s')} | "
                       f"{_cell(line['residual_deg'], 3, ' deg')} | {_cell(line['overshoot_m'], 3, ' m')} | "
                       f"{_cell(line['final_error_m'], 4, ' m')} | {_cell(line['peak_abs_u'], 1, ' m/s2')} | "
                       f"{_cell(line['peak_abs_v'], 2, ' m/s')} | {_cell(line['effort'], 1)} | "
                       f"{verdict.replace('|', '/')} |")
        out.append("")
    out += ["Metrics: settling times are from when both angles stay within the band; arrival is from when the "
            "trolley also stays within 5 mm of the target; the residual swing is the largest angle after the "
            "arrival and the end of the planned move; overshoot is how far the trolley went past the target; "
            "effort is the integral of u^2 [m2/s3]; peak |u| is what the controller demanded (the drive gives at "
            "most 2 m/s2).", ""]
    return "\n".join(out)

