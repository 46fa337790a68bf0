"""``crane-fmu compare``: every controller FMU on the scoreboard's scenarios, in parallel: in a local process pool, or
on Dask (the cluster at ``scheduler``, or a local one when ``--dashboard`` asks to watch it; the same bits).

Cases run through the sweep runner (journal, resume, progress bar). Each case
is a system as data; its FMUs travel to the workers once, by content hash. A
case's id is the hash of everything that makes its row (the FMUs' bytes, the
connections, the parameters, the step, the stop time, the master, the metrics'
version, :data:`ROW_FORMAT`), so the journal reuses a row only for the very
same run. A journal that holds another run of one of the board's cases (other
FMUs, other metrics) is not resumed: it is kept aside and the board starts
again, saying why. Every row records its provenance (:func:`provenance`), and
``OUT/board.json`` what the board was made of, so that :func:`check` can run a
sample of its cases again and confirm their figures bit for bit.

From a script, call :func:`compare` under ``if __name__ == "__main__":``: the
local workers, forked from a fork server (Linux, macOS) or started as fresh
Python processes (Windows), import the script again, as ``multiprocessing`` does.
"""

import functools
import hashlib
import importlib.metadata
import json
import os
import platform
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

import fmpy
import numpy as np
import scipy

from crane_fmu import batch, components, laws, native_batch, systems
from crane_fmu.analysis import board_page, board_tables, metrics, score_plots
from crane_fmu.analysis import scenarios as scenario_registry
from crane_fmu.analysis.board_drawing import BoardDrawer, first_scenarios
from crane_fmu.analysis.floor import stored_scenario_floors
from crane_fmu.analysis.scenarios import Contender
from crane_fmu.batch import JOURNAL, Progress, read_journal, run_batch, worker_context, worker_pool
from crane_fmu.cosim import ArrayRecorder, Connection, FmiError, simulate
from crane_fmu.cosim.suggest import did_you_mean
from crane_fmu.cosim.system import read_fmu, unfed_inputs
from crane_fmu.sweep.runner import local_fmus, write_table

SIGNAL_EVERY = 0.02  # s: the signals kept for plots and animations
ROW_FORMAT = 4  # the version of what a row holds: a journal of another format is not reused
ANIMATE = ("S1", "S2", "S7", "S11", "S12", "S13", "S14")  # the scenarios whose nominal runs keep their signals


def _rename(first, second):
    """What to rename of two controllers of one name: a law function, a law file's component, an FMU file (a
    built-in controller keeps its name)."""
    def kind(source):
        if laws.is_law(source):
            return "function" if laws.is_plain(source) else "component"
        return "FMU file" if str(source).endswith(".fmu") else None

    kinds = [kind(first), kind(second)]
    if kinds == ["function"] * 2:
        return "rename one of the functions"
    if kinds == ["component"] * 2:
        return "give one of the components another model identifier"
    advice = {"function": "rename the function", "component": "give the component another model identifier",
              "FMU file": "rename the FMU file"}
    return " or ".join(dict.fromkeys(advice[k] for k in kinds if k))


def contenders(chosen=(), fmu_dir="build/fmus", only=False):
    """The controllers to score, by name, each checked against every scenario's needs before anything runs.

    Parameters
    ----------
    chosen : iterable of str
        Registered controllers by model identifier, or controller FMU files (the user's).
    only : bool
        Score only ``chosen``; by default every registered controller is scored beside them.

    Raises
    ------
    ValueError
        One line: an unknown name, an FMU that cannot be read, two controllers of one name, or what a
        controller misses of the interface (and which scenarios need it).
    """
    builtin = [c.model_identifier for c in components.registered("controller")]
    items = list(chosen) + ([] if only and chosen else builtin)
    result = {}
    for item in items:
        if laws.is_law(item):  # a law file: run in the workers' processes, no FMU built
            law = laws.component(item)
            variables = {v.name: v.causality for v in law.variables}
            source = str(laws.law_file(item).resolve()) + str(item)[len(str(laws.law_file(item))):]
            name, user = law.model_identifier, True
        elif str(item).endswith(".fmu"):
            try:
                md = read_fmu(item)
            except (OSError, ValueError) as exc:
                raise ValueError(f"--controller {item}: cannot be read as an FMU ({exc})") from None
            variables = {v.name: v.causality for v in md.modelVariables}
            name, source, user = Path(item).stem, str(Path(item).resolve()), True
        else:
            component = components.find(item)
            if component is None or component.role != "controller":
                raise ValueError(f"no controller {item!r}; controllers: {', '.join(builtin)} (or a controller .fmu "
                                 "file, or a law file FILE.py[:NAME])" + did_you_mean(item, builtin))
            variables = {v.name: v.causality for v in component.variables}
            name, source, user = item, item, False
        if name in result:
            if result[name].source == source:
                continue
            raise ValueError(f"two controllers are named {name}: {result[name].source} and {source}; "
                             f"{_rename(result[name].source, source)}" + ("" if only else " or give --only"))
        inputs = [n for n, c in variables.items() if c == "input"]
        parameters = [n for n, c in variables.items() if c == "parameter"]
        outputs = [n for n, c in variables.items() if c == "output"]
        scenario_registry.check_interface(name, inputs, outputs, parameters)
        result[name] = Contender(name, source, inputs, parameters, user, outputs)
    return [result[name] for name in sorted(result)]


MASTER = "gauss-seidel"  # the master algorithm of every case
MANIFEST = "board.json"


def versions():
    """The versions that make a figure: this project, Python, fmpy, numpy, scipy."""
    return dict(_versions())


@functools.cache
def _versions():  # read once per process: importlib.metadata takes about 4 ms a case
    return {"crane-antisway-cosim": importlib.metadata.version("crane-antisway-cosim"),
            "python": platform.python_version(), "fmpy": fmpy.__version__, "numpy": np.__version__,
            "scipy": scipy.__version__}


def plan(chosen, fmu_dir, scenarios=None, cases=scenario_registry.CASES, shapes=None):
    """``(cases, blobs, refused)``: the cases to run, the FMU bytes by hash, and rows of cases that cannot run
    (not applicable to a contender: status ``n/a``; refused by a parameter rule: ``invalid``).

    A case's id covers the metric module's version (:data:`crane_fmu.analysis.metrics.VERSION`) and its scenario's
    own measures' (:func:`~crane_fmu.analysis.scenarios.measures_version`): rows a journal holds from another
    version are never mixed into the board. ``shapes``, a dict when given, gets what :func:`unfed` reads of the runs
    of each contender's scenarios, so that it need not make them again.
    """
    planned, blobs, refused, digests, checked = [], {}, [], {}, {}
    for contender in chosen:
        for sid in scenario_registry.scenarios() if scenarios is None else scenarios:
            why = scenario_registry.applicable(contender, sid)
            if why:
                refused.append({"controller": contender.name, "scenario": sid, "case": "all", "status": "n/a",
                                "error": why})
                continue
            runs = scenario_registry.systems_for(contender, sid, cases)
            for label, system, step, stop_time, x_d, residual_from in runs:
                fmus, connections = systems.resolve(system, fmu_dir)
                if shapes is not None:
                    _shape(shapes.setdefault((contender.name, sid), {}), fmus, connections, system.parameters)
                system = systems.prepare(system, step, stop_time, check=False)
                hashes = {}
                suffixes = {}  # a law file's source is its file's digest, then its suffix and name (.py:NAME)
                for name, path in fmus.items():
                    if path not in digests:  # each FMU file read once
                        data = Path(laws.law_file(path) if laws.is_law(path) else path).read_bytes()
                        digests[path] = hashlib.sha256(data).hexdigest()
                        blobs[digests[path][:20]] = data
                    hashes[name] = digests[path]
                    if laws.is_law(path):
                        suffixes[name] = str(path)[len(str(laws.law_file(path).with_suffix(""))):]
                case = {"controller": contender.name, "scenario": sid, "case": label,
                        "fmus": {name: digest[:20] + suffixes.get(name, "") for name, digest in hashes.items()},
                        "sha256": {name: hashes[name] for name in sorted(hashes)},
                        "files": {name: Path(fmus[name]).name for name in sorted(fmus)},
                        "connections": [list(c) for c in connections], "parameters": system.parameters,
                        "step": step, "stop_time": stop_time, "master": MASTER, "x_d": x_d,
                        "residual_from": residual_from, "bounds": scenario_registry.get(sid).bounds,
                        "format": ROW_FORMAT, "metrics_version": metrics.VERSION,
                        "measures_version": scenario_registry.measures_version(sid),
                        "keep_signals": sid in ANIMATE and len(runs) == 1}
                case["case_id"] = hashlib.sha256(json.dumps(case, sort_keys=True).encode()).hexdigest()[:16]
                try:
                    systems.check_parameters(system, checked)  # each component's values once per board
                except ValueError as exc:
                    refused.append({**_identity(case), "status": "invalid", "error": str(exc)})
                    continue
                planned.append(case)
    return planned, blobs, refused


def unfed(chosen, fmu_dir, scenarios=None, shapes=None):
    """One line per input that nothing feeds in a contender's scenarios (:func:`crane_fmu.cosim.system.unfed_inputs`,
    from the first case of each: every case of a scenario has the same connections), naming the scenarios.
    ``shapes``: those :func:`plan` gathered of the same board (the runs of every case, each of its shapes once),
    else the runs are made here (a design of one case for the paired scenarios)."""
    found = {}
    for contender in chosen:
        for sid in scenario_registry.scenarios() if scenarios is None else scenarios:
            if scenario_registry.applicable(contender, sid):
                continue
            if shapes is None:
                runs = {}
                for run in scenario_registry.systems_for(contender, sid, 1):
                    _shape(runs, *systems.resolve(run.system, fmu_dir), run.system.parameters)
            else:
                runs = shapes.get((contender.name, sid), {})
            for fmus, connections, parameters in runs.values():
                for line in unfed_inputs(fmus, connections, parameters):
                    found.setdefault(f"{contender.name}: {line}", []).append(sid)
    return [f"{line} (in {', '.join(dict.fromkeys(sids))})" for line, sids in found.items()]


def _shape(shapes, fmus, connections, parameters):
    """Keep a run's FMUs, connections and parameters in ``shapes`` under what :func:`unfed_inputs` reads of them (the
    FMUs, the connections and the parameters' names): the runs of a scenario's cases differ only in values."""
    key = json.dumps([sorted(map(str, fmus.items())), [list(c) for c in connections],
                      sorted((i, sorted(v)) for i, v in parameters.items())])
    shapes.setdefault(key, (fmus, connections, parameters))


def provenance(case):
    """What a case's figures were made of, for its row: the sha256 of every FMU, the seeds, the master, the
    step, the stop time (and, added when it runs, the versions and the date)."""
    seeds = {f"{instance}.seed": values["seed"] for instance, values in sorted(case["parameters"].items())
             if "seed" in values}
    plant = case["parameters"].get("plant", {})
    return {"fmus_sha256": json.dumps({case["files"][n]: case["sha256"][n] for n in case["sha256"]},
                                      sort_keys=True),
            "seeds": json.dumps(seeds, sort_keys=True), "master": case["master"], "step": case["step"],
            "stop_time": case["stop_time"],
            **{f"plant_{k}": plant.get(k) for k in ("l1", "l2", "m1", "m2")}}


def _identity(case):
    return {k: case[k] for k in ("case_id", "controller", "scenario", "case", "metrics_version")}


def run_score_case(case, blobs):
    """Co-simulate one case on a worker; return its row: identity, provenance, status, error, metrics (and
    signals)."""
    start = time.perf_counter()
    fmus = local_fmus({name: (digest, blobs[digest.partition(".")[0]]) for name, digest in case["fmus"].items()})
    recorder, error = ArrayRecorder(), None
    try:
        simulate(fmus, [Connection(*c) for c in case["connections"]], case["stop_time"], case["step"],
                 case["master"], parameters=case["parameters"], recorder=recorder)
    except FmiError as exc:
        error = exc
    row = score_row(case, recorder.columns() if recorder.names else None, error)
    row["duration_s"] = time.perf_counter() - start
    return row


def score_row(case, columns, error, measure=metrics):
    """A case's row (without ``duration_s``) from its recorded ``columns`` (``{name: array}`` or None) and the
    :class:`FmiError` that stopped it (None: none did); ``measure``: the metrics module, or its twin of the same
    figures (``crane_fmu.analysis.fast_metrics``)."""
    row = {**_identity(case), "status": "ok" if error is None else "failed",
           "error": None if error is None else str(error), **provenance(case),
           "versions": json.dumps(versions(), sort_keys=True), "date": _now()}
    if columns and len(columns["time"]) > 1:
        row.update(case_metrics(columns, case, row["status"] == "ok", measure))
        if case["keep_signals"]:
            row["signals"] = kept_signals(columns, max(1, round(SIGNAL_EVERY / case["step"])))
    return row


def case_metrics(columns, case, completed, measure=metrics):
    """The figures of a board's case from its recorded columns: :func:`~crane_fmu.analysis.metrics.move_metrics`
    of the plant's signals (read by its roles) to the case's target, and the outcome (``measure``: the metrics
    module, or its twin of the same figures)."""
    s = measure.crane_signals(columns)
    swing = list(s["swing"].values())
    figures = measure.move_metrics(s["time"], s["position"], s["velocity"], swing, s["demand"], case["x_d"],
                                   case["residual_from"], bounds=case["bounds"])
    figures["outcome"] = measure.classify(s["time"], swing, completed)
    figures.update(scenario_registry.measured(case, columns))  # a scenario's own (S13's corridor)
    return figures


def kept_signals(columns, every):
    """The signals a board keeps of a nominal run for its pictures and animations, every ``every``-th sample:
    ``time``, the plant's axis positions, swing angles, hook, load and cable, and the demands, by name."""
    s = metrics.crane_signals(columns)
    crane = s["crane"]
    names = (*(a.position for a in crane.axes), *crane.swing, *crane.hook, *crane.load, *filter(None, [crane.cable]))
    kept = {"time": s["time"], **metrics.plant_outputs(columns, s["instance"], names),
            **dict(zip(crane.demands, s["demand"]))}
    return {k: v[::every].tolist() for k, v in kept.items()}


def _now():
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


def stale(done, cases):
    """Why a journal (``done``: its rows by case id) cannot be resumed into the board of ``cases``: it holds
    another run of one of the board's cases (other FMUs, other metrics, other settings); None when it can."""
    planned = {(c["controller"], c["scenario"], c["case"]): c for c in cases}
    for row in done.values():
        case = planned.get((row["controller"], row["scenario"], row["case"]))
        if case is None or case["case_id"] == row["case_id"]:
            continue
        where = f"{row['controller']}, {row['scenario']}, {row['case']}"
        if "fmus_sha256" not in row:
            return f"it was written by an earlier version of the board, without provenance ({where})"
        recorded = json.loads(row["fmus_sha256"])
        now = json.loads(provenance(case)["fmus_sha256"])
        changed = [f"{f}: sha256 {recorded.get(f, 'none')[:12]}..., now {now[f][:12]}..." for f in now
                   if recorded.get(f) != now[f]]
        if changed:
            return f"it was made with other FMUs ({'; '.join(changed)}; in {where})"
        if row.get("metrics_version") != case["metrics_version"]:
            return (f"its figures were measured by another version of the metrics ({row.get('metrics_version')}; "
                    f"crane_fmu/analysis/metrics.py is now {case['metrics_version']})")
        return (f"it holds another run of the same case ({where}: other parameters, connections, master, format or "
                "its scenario's own measures)")
    return None


def _same_columns(rows):
    """Parquet's column types come from the first rows: give every row every key (None where it has none)."""
    keys = list(dict.fromkeys(k for r in rows for k in r if k != "signals"))
    return [{k: r.get(k) for k in keys} for r in rows]


def compare(out_dir, chosen=(), fmu_dir="build/fmus", workers=None, scheduler=None, quick=False, progress=True,
            animate=("S2",), only=False, log=print, scenarios=None, cases=None, strict=False, warn=None):
    """Score the contenders; write scoreboard.md, scores.parquet, board.json, plots and animations to ``out_dir``.

    Parameters
    ----------
    chosen, only
        The controllers (see :func:`contenders`): by default every built-in one, and the user's FMUs beside them.
    quick : bool
        A quick board (:data:`~crane_fmu.analysis.scenarios.QUICK_CASES` cases of the paired design), written to
        ``out_dir/quick`` with its own journal, so that it never replaces a full board and is never mistaken for one.
    animate : iterable of str
        The scenarios (of :data:`ANIMATE`) whose nominal runs are animated; an animation is drawn again only when
        its run changed.
    scenarios : iterable of str, optional
        The scenarios to run (default: every one).
    cases : int, optional
        Cases of the paired design (default :data:`~crane_fmu.analysis.scenarios.CASES`, quick
        :data:`~crane_fmu.analysis.scenarios.QUICK_CASES`).
    strict : bool
        Refuse (ValueError) a board where an input of a contender's scenario is fed by nothing (:func:`unfed`);
        else each is a warning, given to ``warn`` (default: a line on stderr).

    Returns
    -------
    list of dict
        The rows of the board: one per contender, scenario and case.

    Raises
    ------
    ValueError
        One line: a mistake in the arguments, or a controller that no chosen scenario applies to.
    """
    start = time.perf_counter()
    if sys._getframe(1).f_globals.get("__name__") == "__mp_main__":  # called by a script a worker imports
        raise RuntimeError("compare() was called while a worker process imported your script again: call it "
                           "under `if __name__ == \"__main__\":`")
    unknown = [s for s in animate if s not in ANIMATE]
    if unknown:
        raise ValueError(f"animate {', '.join(unknown)}: no animation there; the animated scenarios are "
                         f"{', '.join(ANIMATE)}")
    known = scenario_registry.scenarios()
    scenarios = list(known) if scenarios is None else list(dict.fromkeys(scenarios))
    wrong = [s for s in scenarios if s not in known]
    if wrong or not scenarios:
        raise ValueError(f"--scenario {','.join(wrong)}: no such scenario; the scenarios are {', '.join(known)}"
                         + (did_you_mean(wrong[0], known) if wrong else ""))
    cases = (scenario_registry.QUICK_CASES if quick else scenario_registry.CASES) if cases is None else cases
    if isinstance(cases, bool) or not isinstance(cases, int) or cases < 1:
        raise ValueError(f"--cases must be a whole number >= 1, got {cases!r}")
    out_dir = Path(out_dir) / "quick" if quick else Path(out_dir)
    # The cases run in a local process pool, or on Dask: the cluster at ``scheduler``, or a local one where --dashboard
    # asks to watch it. The fork server of the drawing pool and the workers imports their modules (about 2 s) now,
    # while this process plans the board: the drawing's too, once for both drawing processes.
    on = "dask" if scheduler or batch.DASHBOARD is not None else "processes"
    worker_context(["crane_fmu.analysis.board_preload"], dask=on == "dask")
    named = {str(c) for c in chosen}
    chosen = contenders(chosen, fmu_dir, only)
    # a built-in controller nobody named is left out where no chosen scenario applies to it (S10: the 3-D ones)
    chosen = [c for c in chosen if c.user or c.name in named
              or None in {scenario_registry.applicable(c, sid) for sid in scenarios}]
    for contender in chosen:
        reasons = {scenario_registry.applicable(contender, sid) for sid in scenarios}
        if None not in reasons:
            runs = [s for s in known if not scenario_registry.applicable(contender, s)]
            raise ValueError(f"{contender.name}: no scenario of {', '.join(scenarios)} applies to it: "
                             f"{reasons.pop()}; it can run {', '.join(runs)}")
    shapes = {}
    planned, blobs, refused = plan(chosen, fmu_dir, scenarios, cases, shapes)
    lines = unfed(chosen, fmu_dir, scenarios, shapes)
    if strict and lines:
        raise ValueError(f"--strict: {'; '.join(lines)}")
    for line in lines:
        (warn or (lambda text: print(f"crane-fmu: warning: {text}", file=sys.stderr)))(line)
    out_dir.mkdir(parents=True, exist_ok=True)  # only now: a refused board leaves no folder behind
    done = read_journal(out_dir)
    why = stale(done, planned)
    if why:
        kept = out_dir / f"{JOURNAL}.{_now().replace(':', '-')}.old"
        (out_dir / JOURNAL).replace(kept)
        log(f"{out_dir / JOURNAL} is not resumed: {why}; kept as {kept.name}, the board starts again")
        done = {}
    pending = [c for c in planned if c["case_id"] not in done]
    failed_before = sum(done[c["case_id"]]["status"] != "ok" for c in planned if c["case_id"] in done)
    bar = Progress(len(planned), len(planned) - len(pending), failed=failed_before) if progress else None
    users = {c.name for c in chosen if c.user}

    def finished(row):  # a row as the board keeps it
        scope = scenario_registry.get(row["scenario"]).scope(cases)
        row.update(quick=quick, **{f"scenario_{k}": v for k, v in scope.items()})
        return row

    # The statistics and the pictures in two other processes (and this one), each scenario's begun as soon as its
    # rows are in, while the cases of the others run (the scenarios drawn longest run first).
    with _drawing(workers) as pool:
        floors = pool.submit(stored_scenario_floors)
        drawer = BoardDrawer(pool, [(c["case_id"], c["scenario"]) for c in planned]
                             + [(None, r["scenario"]) for r in refused], out_dir, users, animate)
        for row in [done[c["case_id"]] for c in planned if c["case_id"] in done] + refused:
            drawer.add(finished(row))
        first = {sid: i for i, sid in enumerate(dict.fromkeys(first_scenarios(animate)))}
        pending.sort(key=lambda c: first.get(c["scenario"], len(first)))  # a stable sort: the board's order within
        ran = run_batch(native_batch.score_chunk, _items(pending, blobs), blobs, on=on, workers=workers,
                        scheduler=scheduler, journal=out_dir / JOURNAL, progress=bar, chunked=True,
                        on_row=lambda row: drawer.add(finished(row)), lost=lambda case, why: score_row(case, None, why))
        done.update({r["case_id"]: r for r in ran})
        rows = [done[c["case_id"]] for c in planned] + refused
        write_table(_same_columns(rows), out_dir / "scores.parquet")
        manifest = {"contenders": [{"name": c.name, "source": c.source, "user": c.user} for c in chosen],
                    "scenarios": scenarios, "cases": cases, "quick": quick, "fmu_dir": str(Path(fmu_dir).resolve()),
                    "fmus": dict(sorted({f: d for c in planned for f, d in json.loads(provenance(c)["fmus_sha256"])
                                         .items()}.items())),
                    "versions": versions(), "master": MASTER, "metrics_version": metrics.VERSION, "design_seed":
                    _design_seeds(planned), "date": _now()}
        _write(out_dir / MANIFEST, json.dumps(manifest, indent=1))
        board_md = out_dir / "scoreboard.md"
        stats = drawer.statistics()
        summary = pool.submit(score_plots.plot_board_summary, rows, out_dir, users, stats)
        floors = floors.result()
        _write(board_md, board_tables.render(rows, chosen, quick, cases, _provenance_lines(manifest), stats, floors))
        new = drawer.animations_drawn()
        paths, drawn = drawer.pictures_drawn() + [summary.result()] + new, len(new)
    removed = score_plots.prune(rows, out_dir, animate)  # an earlier board's pictures, never shown as this one's
    page = board_page.write_page(out_dir)
    log(board_tables.render_terminal(rows, {c.name for c in chosen if c.user}, quick, cases, stats, floors))
    not_ok = sum(r["status"] not in ("ok", "n/a") for r in rows)
    log(f"{len(planned)} cases: {len(ran)} run now, {len(planned) - len(pending)} already done, {not_ok} not ok, "
        f"in {time.perf_counter() - start:.1f} s; wrote {board_md}{' (a QUICK board)' if quick else ''}, {page}, "
        f"{out_dir / 'scores.parquet'}, {len(paths) - drawn} plots and {drawn} animations drawn now"
        + (f"; removed {len(removed)} pictures of an earlier board" if removed else ""))
    return rows


def _design_seeds(planned):
    """The seed of the paired design of each plant the board's scenarios run on (one: that seed)."""
    plants = {scenario_registry.get(c["scenario"]).plant for c in planned}
    seeds = {scenario_registry.notes(plant)["seed"] for plant in plants}
    return seeds.pop() if len(seeds) == 1 else sorted(seeds)


def _items(cases, blobs):
    """The board's cases as items of the batch path (:func:`crane_fmu.native_batch.items`): chunks of the cases of one
    system whose FMUs are all native, every other case alone."""
    def batched(case):
        if any("." in d for d in case["fmus"].values()):  # a law file (<digest>.py) runs in Python
            return False
        return native_batch.batchable([(d, blobs[d]) for d in case["fmus"].values()], case["master"])

    def system_of(case):
        return json.dumps([case[k] for k in ("fmus", "connections", "master", "step", "stop_time")], sort_keys=True)

    return native_batch.items(cases, batched, system_of)


def _drawing(workers=None):
    """A pool of (at most) two processes for the board's pictures."""
    return worker_pool(max(1, min(2, workers or os.cpu_count() or 1)))


def _write(path, text):
    """Write ``text`` under a temporary name, then rename: a reader never sees half a file."""
    partial = path.with_name(f".{path.name}.partial")
    partial.write_text(text)
    partial.replace(path)


def _provenance_lines(manifest):
    return {"FMUs (sha256)": ", ".join(f"{f} {d}" for f, d in manifest["fmus"].items()),
            "seeds": f"the paired design's {manifest['design_seed']}; each case's noise and wind seed in "
                     "scores.parquet (`seeds`); S5's sensor seed 1, S8's 1",
            "versions": ", ".join(f"{k} {v}" for k, v in manifest["versions"].items()),
            "master": f"{manifest['master']}, communication step 1 ms (S6: 1, 10 and 50 ms)",
            "metrics": manifest["metrics_version"], "date": manifest["date"],
            "check": "`crane-fmu compare --check OUT` runs a sample of these cases again and compares every figure"}


# Keys of a row that are not figures of the run: they may differ when the same case runs again.
_NOT_FIGURES = ("duration_s", "date", "versions", "quick", "scenario_plants", "scenario_steps", "scenario_cases",
                "signals")


def check(out_dir, sample=5, workers=None, scheduler=None, log=print, seed=None):
    """Run a random sample of a board's recorded cases again; return the differences from their recorded figures.

    Parameters
    ----------
    out_dir : path
        A board's folder (with board.json and scores.parquet); where it holds none, its quick board
        (``OUT/quick``).
    sample : int
        How many of its cases to run again.

    Returns
    -------
    list of str
        One line per case whose figures differ (empty: every figure was the same, bit for bit).

    Raises
    ------
    ValueError
        One line: no board in ``out_dir``, or FMUs that differ from the board's.
    """
    import pyarrow.parquet as pq

    out_dir = Path(out_dir)
    if not (out_dir / MANIFEST).exists() and (out_dir / "quick" / MANIFEST).exists():
        out_dir = out_dir / "quick"  # where `compare --quick --out OUT` wrote it
        log(f"no full board in {out_dir.parent}: checking the quick board in {out_dir}")
    try:
        manifest = json.loads((out_dir / MANIFEST).read_text())
        recorded = {r["case_id"]: r for r in pq.read_table(out_dir / "scores.parquet").to_pylist() if r["case_id"]}
    except (OSError, ValueError, KeyError) as exc:
        raise ValueError(f"--check {out_dir}: no board there (board.json and scores.parquet of crane-fmu compare): "
                         f"{exc}") from None
    if isinstance(sample, bool) or not isinstance(sample, int) or sample < 1:
        raise ValueError(f"--sample must be a whole number >= 1, got {sample!r}")
    chosen = contenders([c["source"] for c in manifest["contenders"]], manifest["fmu_dir"], only=True)
    planned, blobs, _ = plan(chosen, manifest["fmu_dir"], manifest["scenarios"], manifest["cases"])
    why = stale(recorded, planned)
    if why:
        raise ValueError(f"--check {out_dir}: the board cannot be run again as it was: {why}")
    known = [c for c in planned if c["case_id"] in recorded]
    picked = [known[i] for i in sorted(np.random.default_rng(seed).choice(len(known), min(sample, len(known)),
                                                                          replace=False))]
    log(f"running {len(picked)} of the board's {len(known)} cases again: "
        + "; ".join(f"{c['controller']} {c['scenario']} {c['case']}" for c in picked))
    differences = []
    for row in run_batch(run_score_case, picked, blobs, on="dask", workers=workers, scheduler=scheduler):
        before = recorded[row["case_id"]]
        changed = [f"{k}: {before.get(k)!r} recorded, {row.get(k)!r} now" for k in row
                   if k not in _NOT_FIGURES and before.get(k) != row.get(k)]
        if changed:
            differences.append(f"{row['controller']}, {row['scenario']}, {row['case']}: " + "; ".join(changed))
    return differences
