"""How the board ranks controllers in a scenario, and the statistics of its paired scenarios.

Each contender's cases of a scenario become one line (:func:`summarise`): the worst case of every figure
(:data:`FIGURES`), the targets met, and its rank by :data:`RULES`; on the paired design the statistics of
its cases (:func:`board_statistics`, :mod:`crane_fmu.analysis.statistics`).
"""

import math

import numpy as np

from .scenarios import met, paired, scenarios

RULES = ("controllers are listed best first, and a controller's rank is 1 + the number listed above it, except "
         "that one the board cannot tell from the one just above shares that one's rank (ranks like 1, 2, 2, 4; of "
         "two that met the same targets, the one with the better figure is never ranked lower). The order: a "
         "controller that failed in a case after every one that did not; then more targets met (in every case) "
         "first; then on the paired design (" + ", ".join(paired()) + ") the lower median of the ranking figure "
         "over the cases first, and one shares the rank above when the two-sided Wilcoxon signed-rank test of the "
         "two's paired figures (cases with equal figures left out) does not give p < 0.05 in favour of the one "
         "above (the p-value to the one above is shown; every pair's is in the scenario's statistics); elsewhere "
         "the lower ranking figure (the worst case) first, *never* after every finite value, or, equal, the one "
         "that leaves less swing over the last quarter of the run (a law that keeps swinging below one that "
         "converges slowly), and only equal figures share a rank. Equal figures are listed by name")


def _figure_key(line, metric):
    value, swing = line[metric], line["end_swing_deg"]
    return (value is None, 0.0 if value is None else value, math.inf if swing is None else swing)


def rank_key(line, metric):
    """A line's place in a sort (see :data:`RULES`): failed, targets met, worst figure, never, swing left, name."""
    return (line["failed"] > 0, -sum(line["targets"])) + _figure_key(line, metric) + (line["controller"],)


# The figures of a board row: (column header, metric, digits, unit); lower is better, a row shows the worst case.
FIGURES = (("0.5 deg from", "settling_0.5deg_s", 2, " s"), ("0.1 deg from", "settling_0.1deg_s", 2, " s"),
           ("arrival", "arrival_s", 2, " s"), ("residual", "residual_deg", 3, " deg"),
           ("peak swing", "peak_swing_deg", 2, " deg"), ("RMS swing", "rms_swing_deg", 3, " deg"),
           ("ISE of swing", "ise_swing_deg2s", 2, " deg2 s"), ("overshoot", "overshoot_m", 3, " m"),
           ("final error", "final_error_m", 4, " m"), ("peak abs u", "peak_abs_u", 1, " m/s2"),
           ("peak abs v", "peak_abs_v", 2, " m/s"), ("effort", "effort", 1, " m2/s3"),
           ("u total variation", "u_total_variation", 1, " m/s2"))
WORST = tuple(metric for _, metric, _, _ in FIGURES) + ("position_1cm_s", "end_swing_deg")
# ... and the scenarios' own figures (Scenario.measures), shown where a scenario ranks by them or sets a target
FORMAT = {**{metric: (digits, unit) for _, metric, digits, unit in FIGURES}, "path_deviation_m": (3, " m"),
          "arrival_eq_s": (2, " s"), "residual_eq_deg": (3, " deg"), "load_error_m": (4, " m")}


def not_applicable(rows, scenario):
    """``{controller: why}`` of the contenders the scenario does not apply to."""
    return {r["controller"]: r["error"] for r in rows if r["scenario"] == scenario and r["status"] == "n/a"}


def _pairs(line_a, line_b):
    """The paired ranking figures of two lines over the cases both ran, by case label."""
    common = sorted(set(line_a["values"]) & set(line_b["values"]))
    return [line_a["values"][c] for c in common], [line_b["values"][c] for c in common]


def _median(line):
    """The median (numpy's ``inverted_cdf``: a figure some case had) of a line's ranking figure over its cases."""
    values = [math.inf if v is None else v for _, v in sorted(line["values"].items())]
    return float(np.quantile(values, 0.5, method="inverted_cdf")) if values else math.inf


def _order_key(line, scenario):
    """A line's place in the list (see :data:`RULES`), before the name."""
    key = (line["failed"] > 0, -sum(line["targets"]))
    if scenario in paired() and not line["failed"]:
        return key + (_median(line), line["end_swing_deg"] is None, line["end_swing_deg"] or 0.0)
    return key + _figure_key(line, scenarios()[scenario].rank_by)


def _separated(above, below, scenario):
    """``(separated, p)``: whether the board tells ``below`` from the line just ``above`` it (see :data:`RULES`),
    and on the paired design the Wilcoxon p-value of the two (None elsewhere)."""
    if _order_key(above, scenario)[:2] != _order_key(below, scenario)[:2]:
        return True, None
    if scenario in paired() and not above["failed"] and not below["failed"]:
        from crane_fmu.analysis import statistics

        p, better = statistics.wilcoxon(*_pairs(above, below))
        return better < 0, p
    return _order_key(above, scenario) != _order_key(below, scenario), None


def summarise(rows, scenario):
    """One line per contender for a scenario: the worst case of each metric, the targets met, the ranking figure
    of every case (``values``), its ``rank`` by :data:`RULES`, whether it ties (``tie``) and, on the paired design,
    the Wilcoxon p-value to the line above (``p_above``; None elsewhere); in the order of :data:`RULES`.

    Contenders the scenario does not apply to have no line (:func:`not_applicable`).
    """
    s = scenarios()[scenario]
    by = {}
    for r in rows:
        if r["scenario"] == scenario and r["status"] != "n/a":
            by.setdefault(r["controller"], []).append(r)
    lines = []
    for name, cases in by.items():
        failed = [r for r in cases if r["status"] != "ok"]
        worst = {}
        own = tuple(dict.fromkeys(m for m in (s.rank_by, *(t.metric for t in s.targets)) if m not in WORST))
        for metric in WORST + own:  # the scenario's own figures too (S13's path_deviation_m)
            values = [r.get(metric) for r in cases]
            worst[metric] = None if any(v is None for v in values) else max(values)
        held = [r.get("bounds_held") for r in cases]
        broken = sorted({b for r in cases for b in (r.get("bounds_broken") or "").split(", ") if b})
        targets = [all(met(r, t) for r in cases) for t in s.targets]
        lines.append({"controller": name, "cases": len(cases), "failed": len(failed),
                      "error": min(r["error"] or "" for r in failed) if failed else None, **worst,
                      "bounds_held": None if None in held else all(held), "bounds_broken": ", ".join(broken),
                      "targets": targets, "values": {r["case"]: r.get(s.rank_by) for r in cases}})
    lines.sort(key=lambda line: _order_key(line, scenario) + (line["controller"],))
    for i, line in enumerate(lines):
        separated, line["p_above"] = _separated(lines[i - 1], line, scenario) if i else (True, None)
        line["rank"] = i + 1 if separated else lines[i - 1]["rank"]
    for line in lines:
        line["tie"] = any(other["rank"] == line["rank"] for other in lines if other is not line)
    return lines


def board_statistics(rows, chosen=None):
    """The statistics of the paired scenarios (or of ``chosen``): ``{scenario: {"describe": {controller: {metric:
    Description}}, "pairs": [(a, b, Paired)]}}`` over the cases of each (:mod:`crane_fmu.analysis.statistics`)."""
    from crane_fmu.analysis import statistics

    result = {}
    for sid in paired() if chosen is None else chosen:
        lines = summarise(rows, sid)
        if not lines:
            continue
        metrics = [metric for _, metric, _, _ in FIGURES]
        s = scenarios()[sid]  # and its own figures it ranks by or sets a target on (S10's residual_eq_deg)
        metrics += [m for m in dict.fromkeys((s.rank_by, *(t.metric for t in s.targets))) if m not in metrics]
        describe = {}
        for line in lines:
            cases = sorted((r for r in rows if r["scenario"] == sid and r["controller"] == line["controller"]),
                           key=lambda r: r["case"])
            found = statistics.describe_all([[r.get(m) for r in cases] for m in metrics])
            describe[line["controller"]] = dict(zip(metrics, found))
        pairs = [(a["controller"], b["controller"], statistics.compare_paired(*_pairs(a, b)))
                 for i, a in enumerate(lines) for b in lines[i + 1:]]
        result[sid] = {"describe": describe, "pairs": pairs}
    return result
