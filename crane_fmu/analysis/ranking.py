"""How the board ranks controllers in a scenario, and the statistics of its paired scenarios.

Each contender's cases of a scenario become one line (:func:`summarise`): the worst case of every figure
(:data:`FIGURES`), the targets met, and its rank by :data:`RULES`; on the paired design the statistics of
its cases (:func:`board_statistics`, :mod:`crane_fmu.analysis.statistics`).
"""

import math

from .scenarios import met, paired, scenarios

RULES = ("a controller's rank is 1 + the number of controllers better than it in the scenario. A is better than B when "
         "B failed in a case and A did not; else when A meets more targets (in every case); else, on the paired design "
         "(" + ", ".join(paired()) + "), when the two-sided Wilcoxon signed-rank test of their paired ranking figures "
         "gives p < 0.05 with A's figures lower (cases with equal figures left out); "
         "elsewhere when A's ranking figure (its worst case) is lower, *never* after every finite value, or, equal, "
         "when A leaves less swing over the last quarter of the run (a law that keeps swinging below one that "
         "converges slowly). Controllers of one rank tie and the board says so; they are listed by name")


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
FORMAT = {metric: (digits, unit) for _, metric, digits, unit in FIGURES}


def not_applicable(rows, scenario):
    """``{controller: why}`` of the contenders the scenario does not apply to."""
    return {r["controller"]: r["error"] for r in rows if r["scenario"] == scenario and r["status"] == "n/a"}


def _pairs(line_a, line_b):
    """The paired ranking figures of two lines over the cases both ran, by case label."""
    common = sorted(set(line_a["values"]) & set(line_b["values"]))
    return [line_a["values"][c] for c in common], [line_b["values"][c] for c in common]


def _better(a, b, scenario, verdicts):
    """Whether line ``a`` is better than line ``b`` by :data:`RULES`."""
    key_a, key_b = (a["failed"] > 0, -sum(a["targets"])), (b["failed"] > 0, -sum(b["targets"]))
    if key_a != key_b:
        return key_a < key_b
    if scenario in paired() and not a["failed"] and not b["failed"]:
        pair = (a["controller"], b["controller"])
        if pair not in verdicts:
            from crane_fmu.analysis import statistics

            verdicts[pair] = statistics.wilcoxon(*_pairs(a, b))[1]
        return verdicts[pair] < 0
    metric = scenarios()[scenario].rank_by
    return _figure_key(a, metric) < _figure_key(b, metric)


def summarise(rows, scenario):
    """One line per contender for a scenario: the worst case of each metric, the targets met, the ranking figure
    of every case (``values``), its ``rank`` by :data:`RULES` and whether it ties (``tie``); by rank, then name.

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
        for metric in WORST:
            values = [r.get(metric) for r in cases]
            worst[metric] = None if any(v is None for v in values) else max(values)
        held = [r.get("bounds_held") for r in cases]
        broken = sorted({b for r in cases for b in (r.get("bounds_broken") or "").split(", ") if b})
        targets = [all(met(r, t) for r in cases) for t in s.targets]
        lines.append({"controller": name, "cases": len(cases), "failed": len(failed),
                      "error": min(r["error"] or "" for r in failed) if failed else None, **worst,
                      "bounds_held": None if None in held else all(held), "bounds_broken": ", ".join(broken),
                      "targets": targets, "values": {r["case"]: r.get(s.rank_by) for r in cases}})
    verdicts = {}
    for line in lines:
        line["rank"] = 1 + sum(_better(other, line, scenario, verdicts) for other in lines if other is not line)
    for line in lines:
        line["tie"] = any(other["rank"] == line["rank"] for other in lines if other is not line)
    return sorted(lines, key=lambda line: (line["rank"], line["controller"]))


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
