"""The board as Markdown: the summary table, a table per scenario with its targets, the paired statistics."""

import math

from .ranking import FIGURES, FORMAT, RULES, board_statistics, not_applicable, summarise
from .scenarios import CASES, OTHER_PLANT, notes, scenarios
from .scenarios import plants as scenario_plants


def figure_text(value, digits=2, unit="", against=()):
    """A figure with ``digits`` decimals, or more where fewer would print it as one of the limits ``against`` it
    is not (4.004 s against a 4.0 s target prints 4.004 s, not 4.00 s)."""
    if value is None or value == math.inf:
        return "never" if unit == " s" else "-"  # a time not reached; a figure of a run that ended early
    while digits < 12 and any(value != limit and f"{value:.{digits}f}" == f"{limit:.{digits}f}" for limit in against):
        digits += 1
    return f"{value:.{digits}f}{unit}"


_cell = figure_text


def _limits(sid, metric):
    """The limits of the scenario's targets on ``metric``."""
    return tuple(t.limit for t in scenarios()[sid].targets if t.metric == metric)


def table_row(cells):
    """A Markdown table row; a ``|`` in a cell (``|u|``) escaped as ``\\|``, so it stays in its cell."""
    return "| " + " | ".join(str(c).replace("|", "\\|") for c in cells) + " |"


def _interval(low, high, digits):
    return f"[{_cell(low, digits)}, {_cell(high, digits)}]".replace("-, ", "never, ").replace(", -]", ", never]")


def _bounds(line):
    if line["bounds_held"] is None:
        return "-"
    return "held" if line["bounds_held"] else f"**broken**: {line['bounds_broken']}"


def _name(name, users):
    return f"`{name}`" + (" (yours)" if name in users else "")


def _scenario_label(sid, cases=CASES, quick=False):
    """``S3 (64 cases): S2 on plants ...``; on a quick board every scenario says so: ``S1 (QUICK: 1 case): ...``."""
    s = scenarios()[sid]
    n = s.scope(cases)["cases"]
    if not s.paired and not quick:
        return f"{sid}: {s.title}"
    return f"{sid} ({'QUICK: ' if quick else ''}{n} case{'s' if n > 1 else ''}): {s.title}"


def run_length(rows, sid):
    """``10 s`` (``10 s, 12 s``): how long the scenario's cases run, from its rows; ``-`` where no row says."""
    times = sorted({r["stop_time"] for r in rows if r["scenario"] == sid and r.get("stop_time") is not None})
    return ", ".join(f"{t:g} s" for t in times) or "-"


def _ranked_by(sid):
    s = scenarios()[sid]
    return f"{s.rank_by}, median, paired Wilcoxon" if s.paired else s.rank_by


def floor_ratio(value, floor):
    """`` (1.32x floor)``: a time as a multiple of the scenario's floor (:mod:`.floor`), or nothing."""
    return "" if floor is None or value is None else f" ({value / floor.seconds:.2f}x floor)"


def _summary_cells(rows, users, stats, floors):
    """``[(scenario, cells)]``: per scenario with a row, its controllers by rank (each cell one controller's rank,
    figure, targets and tie), then those it does not apply to; a controller of another crane (S11's planar ones) is
    left out, the scenario's section of the board names it."""
    lines = []
    for sid, s in scenarios().items():
        ranked = summarise(rows, sid)
        absent = {name: why for name, why in not_applicable(rows, sid).items() if not why.startswith(OTHER_PLANT)}
        if not ranked and not absent:
            continue
        digits, unit = FORMAT.get(s.rank_by, (2, " s"))
        digits = max(digits, 3) if unit == " deg" else digits
        cells = []
        for line in ranked:
            if line["failed"]:
                figure = "failed"
            elif sid in stats:
                d = stats[sid]["describe"][line["controller"]][s.rank_by]
                figure = (f"median {_cell(d.median, digits, unit, _limits(sid, s.rank_by))} "
                          f"{_interval(d.median_low, d.median_high, digits)}")
            else:
                figure = (_cell(line[s.rank_by], digits, unit, _limits(sid, s.rank_by))
                          + floor_ratio(line[s.rank_by], floors.get(sid)))
            verdict = "all targets met" if all(line["targets"]) and not line["failed"] else (
                f"{sum(line['targets'])} of {len(line['targets'])} targets met")
            cells.append(f"{line['rank']}. {_name(line['controller'], users)}: {figure}, {verdict}"
                         + (", tie" if line["tie"] else "") + _p_above(line))
        cells += [f"{_name(name, users)}: {why}" for name, why in sorted(absent.items())]
        lines.append((sid, cells))
    return lines


def every_target(rows, users=()):
    """Per crane whose every scenario is on the board, a line naming the controllers that meet every target of every
    scenario in every case (issue 51 asks for one on the planar crane), or, none doing so, those that meet the most
    scenarios' and what they miss."""
    out = []
    for plant in scenario_plants():
        ids = [sid for sid, s in scenarios().items() if s.plant == plant]
        if not all(any(r["scenario"] == sid for r in rows) for sid in ids):
            continue
        missed = {}  # controller: the scenarios where it misses a target in some case
        for sid in ids:
            for line in summarise(rows, sid):
                missed.setdefault(line["controller"], [])
                if line["failed"] or not all(line["targets"]):
                    missed[line["controller"]].append(sid)
        if not missed:
            continue
        span = f"{ids[0]}-{ids[-1]}"
        fewest = min(len(m) for m in missed.values())
        best = sorted(name for name, m in missed.items() if len(m) == fewest)
        names = ", ".join(_name(name, users) for name in best)
        if fewest == 0:
            out.append(f"Every target of {span} in every case: met by {names}.")
        else:
            misses = "; ".join(f"{_name(name, users)} misses {', '.join(missed[name])}" for name in best)
            out.append(f"Every target of {span} in every case: met by no controller; the closest ({len(ids) - fewest} "
                       f"of {len(ids)} scenarios): {misses}.")
    return out


def render_summary(rows, users=(), quick=False, cases=CASES, stats=None, floors=None):
    """One table: per scenario the controllers by rank, with their ranking figure (the worst case, and its ratio to
    the scenario's floor where ``floors`` gives one; on the paired design the median with its 95 % interval), the
    targets they met and ties; then those it does not apply to."""
    stats = board_statistics(rows) if stats is None else stats
    lines = _summary_cells(rows, users, stats, floors or {})
    width = max(len(cells) for _, cells in lines)
    out = [table_row(["scenario", "runs", "ranked by", "controllers by rank"] + [""] * (width - 1)),
           "|---|---|---|" + "---|" * width]
    for sid, cells in lines:
        out.append(table_row([_scenario_label(sid, cases, quick), run_length(rows, sid), _ranked_by(sid)] + cells
                             + [""] * (width - len(cells))))
    return "\n".join(out)


def render_terminal(rows, users=(), quick=False, cases=CASES, stats=None, floors=None):
    """The summary table for a terminal: per scenario a line (what it is, how long it runs, what ranks), then its
    controllers by rank, one a line."""
    stats = board_statistics(rows) if stats is None else stats
    out = []
    for sid, cells in _summary_cells(rows, users, stats, floors or {}):
        out.append(f"{_scenario_label(sid, cases, quick)} ({run_length(rows, sid)}; ranked by {_ranked_by(sid)})")
        out += [f"  {cell.replace('`', '')}" for cell in cells]
    return "\n".join(out + [text.replace("`", "") for text in every_target(rows, users)])


def _p_above(line):
    """`` (p = 0.031 to the one above)``: on the paired design, the Wilcoxon p-value to the line above."""
    return "" if line.get("p_above") is None else f" (p = {line['p_above']:.2g} to the one above)"


def _statistics_section(sid, stats, users):
    """Markdown of a paired scenario's statistics: each figure's median and 90th percentile per contender with
    their intervals, and each pair's paired difference of the ranking figure with the test."""
    describe, pairs = stats["describe"], stats["pairs"]
    names = list(describe)
    out = ["Over the cases: median [95 % interval]; 90th percentile [95 % interval] (bootstrap):", "",
           table_row(["figure"] + [_name(n, users) for n in names]), "|---|" + "---|" * len(names)]
    known = {metric for _, metric, _, _ in FIGURES}
    own = [(metric, metric, *FORMAT[metric]) for metric in next(iter(describe.values()), {}) if metric not in known]
    for header, metric, digits, unit in (*FIGURES, *own):  # the scenario's own figures last (S10's residual_eq_deg)
        cells = []
        for n in names:
            d = describe[n][metric]
            cells.append(f"{_cell(d.median, digits)} {_interval(d.median_low, d.median_high, digits)}; "
                         f"{_cell(d.p90, digits)} {_interval(d.p90_low, d.p90_high, digits)}")
        out.append(table_row([f"{header} [{unit.strip()}]"] + cells))
    metric = scenarios()[sid].rank_by
    digits, unit = FORMAT[metric]
    digits = max(digits, 3)
    out += ["", f"Pairs, on {metric} case by case (A - B):", "",
            "| A | B | median difference [95 % interval] | Wilcoxon p | verdict |", "|---|---|---|---|---|"]
    for a, b, paired in pairs:
        verdict = "tie" if paired.better == 0 else f"{_name(a if paired.better < 0 else b, users)} lower"
        out.append(table_row([_name(a, users), _name(b, users), f"{_cell(paired.difference, digits, unit)} "
                              f"{_interval(paired.low, paired.high, digits)}", f"{paired.p:.3g}", verdict]))
    return out + [""]


def render(rows, contenders, quick=False, cases=CASES, provenance=None, stats=None, floors=None):
    """scoreboard.md: per scenario a table ranked by :data:`RULES`, with each target met or missed and its source;
    on the paired design the statistics (``stats``: :func:`board_statistics`, computed when not given); the
    provenance of the figures.

    ``floors``: ``{scenario: floor.Floor}``, the least time the crane needs there, shown with its method and as
    each ranking figure's ratio to it.
    """
    from crane_fmu.analysis import metrics, statistics

    users = {c.name for c in contenders if c.user}
    stats = board_statistics(rows) if stats is None else stats
    floors = floors or {}
    title = "# Controller scoreboard" + (" (QUICK: fewer cases of the paired design, not the full board)"
                                         if quick else "")
    plants = {scenarios()[r["scenario"]].plant for r in rows}
    about = [notes(plant, cases) for plant in scenario_plants() if plant in plants]
    out = [title, "", render_summary(rows, users, quick, cases, stats, floors), "",
           *(line for text in every_target(rows, users) for line in (text, "")),
           "Controllers: " + ", ".join(_name(c.name, users) for c in sorted(contenders, key=lambda c: c.name)), ""]
    if floors:
        method = next(iter(floors.values())).method
        out += [f"The floor of a scenario is the least time the crane needs for its task: {method}.", ""]
    out += ["## How the board is made", "",
            "Every controller on the same crane (" + "; ".join(n["crane"] for n in about) + "), through the same "
            "master, on the same scenarios (registered with their targets: `crane_fmu/analysis/scenarios.py`). "
            "Times are from the start of the run; *never* means not within the run. A row's figure is the worst over "
            "the scenario's cases.", ""]
    for n in about:
        out += n["design"]
    out += [f"Ranking: {RULES}.", "",
            f"Statistics: medians and 90th percentiles are figures some case had (the smallest with at least half, "
            f"nine tenths, of the cases at or below it); their 95 % intervals are percentile bootstraps "
            f"(scipy.stats.bootstrap, {statistics.RESAMPLES} resamples, seed {statistics.SEED}); {statistics.RULE} "
            "(scipy.stats.wilcoxon; each pair on its own, at 5 %).", "",
            "Figures print with the digits of their column, and more where fewer would show a figure as its target "
            "(4.004 s against a 4.0 s target prints 4.004 s).", ""]
    for sid, s in scenarios().items():
        lines, absent = summarise(rows, sid), not_applicable(rows, sid)
        if not lines and not absent:
            continue
        out += [f"## {_scenario_label(sid, cases, quick)}", "", "Targets:", ""]
        out += [f"- {t.text} ({t.source})" for t in s.targets] + [""]
        if run_length(rows, sid) != "-":
            out += [f"Each case runs {run_length(rows, sid)} of simulated time{s.duration_note}.", ""]
        if sid in floors:
            out += [f"Floor: {floors[sid].seconds:.2f} s ({floors[sid].task})", ""]
        if lines:
            out.append("| rank | controller | " + " | ".join(header for header, _, _, _ in FIGURES)
                       + " | bounds | targets |")
            out.append("|---|---|" + "---|" * (len(FIGURES) + 2))
        for line in lines:
            verdict = ", ".join(("met" if ok else "**missed**") for ok in line["targets"])
            if line["failed"]:
                verdict = f"**failed** in {line['failed']} of {line['cases']}: {line['error']}"[:300]
            out.append(table_row([f"{line['rank']}{' (tie)' if line['tie'] else ''}", _name(line["controller"], users)]
                                 + [_cell(line[metric], digits, unit, _limits(sid, metric))
                                    for _, metric, digits, unit in FIGURES] + [_bounds(line), verdict]))
        out.append("")
        out += [f"- {_name(name, users)}: {why}" for name, why in sorted(absent.items())] + ([""] if absent else [])
        if sid in stats:
            out += _statistics_section(sid, stats[sid], users)
    out += [f"Metrics (`crane_fmu/analysis/metrics.py`, version {metrics.VERSION}): settling times are from when both "
            "angles stay within the band; arrival is from when the trolley also stays within 5 mm of the target; the "
            "residual swing is the largest angle (either) in a window the scenario fixes, as measured: for a move "
            "from the planned move's end plus one period of the plant's slow swing mode, for regulation the last "
            "quarter of the run; peak, RMS and ISE of the swing are over the whole run (RMS and ISE of theta1 and "
            "theta2 together); overshoot is how far the trolley went past the target; effort is the integral of "
            "u^2; peak |u| is what the controller demanded (the drive gives at most 2 m/s2); the total variation "
            "of u is the sum of |u_k - u_(k-1)| over the communication steps (how much the command chatters); "
            "bounds: " + "; ".join(n["bounds"] for n in about) + ", at every step (checked, not enforced).", ""]
    if provenance:
        out += ["## Provenance", ""] + [f"- {key}: {value}" for key, value in provenance.items()] + [""]
    return "\n".join(out)
