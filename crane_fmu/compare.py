"""``crane-fmu compare``: every controller FMU on the scoreboard's scenarios, in parallel on Dask.

Cases run through the sweep runner (journal, resume, progress bar). Each case
is a system as data; its FMUs travel to the workers once, by content hash. A
case's id is the hash of everything that makes its row (the FMUs' bytes, the
connections, the parameters, the step, the stop time, :data:`ROW_FORMAT`), so
the journal reuses a row only for the very same run.

From a script, call :func:`compare` under ``if __name__ == "__main__":``: the
local Dask cluster starts its workers as fresh Python processes, which import
the script again (the ``spawn`` start method), as ``multiprocessing`` does.
"""

import hashlib
import json
import sys
import time
from pathlib import Path

from crane_fmu import components, systems
from crane_fmu.analysis import scoreboard
from crane_fmu.analysis.scoreboard import SCENARIOS, Contender
from crane_fmu.sweep.batch import JOURNAL, Progress, read_journal, run_batch
from crane_fmu.sweep.runner import write_table

SIGNALS = ("time", "x", "theta1", "theta2", "u", "x1", "y1", "x2", "y2", "l1_now")  # crane_signals() names
SIGNAL_EVERY = 0.02  # s: the signals kept for plots and animations
ROW_FORMAT = 4  # the version of what a row holds: a journal of another format is not reused
ANIMATE = ("S1", "S2", "S7")  # the scenarios whose nominal runs keep their signals


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
    from crane_fmu.cosim.system import read_fmu

    builtin = [c.model_identifier for c in components.registered("controller")]
    items = list(chosen) + ([] if only and chosen else builtin)
    result = {}
    for item in items:
        if str(item).endswith(".fmu"):
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
                                 "file)")
            variables = {v.name: v.causality for v in component.variables}
            name, source, user = item, item, False
        if name in result:
            if result[name].source == source:
                continue
            raise ValueError(f"two controllers are named {name}: {result[name].source} and {source}; rename the "
                             "FMU file" + ("" if only else " or give --only"))
        inputs = [n for n, c in variables.items() if c == "input"]
        parameters = [n for n, c in variables.items() if c == "parameter"]
        scoreboard.check_interface(name, inputs, [n for n, c in variables.items() if c == "output"], parameters)
        result[name] = Contender(name, source, inputs, parameters, user)
    return [result[name] for name in sorted(result)]


def plan(chosen, fmu_dir, scenarios=tuple(SCENARIOS), quick=False):
    """``(cases, blobs, refused)``: the cases to run, the FMU bytes by hash, and rows of cases that cannot run.

    A case's id covers the metric module's version (:data:`crane_fmu.analysis.metrics.VERSION`): rows a journal
    holds from another version are run again, never mixed into the board.
    """
    from crane_fmu.analysis.metrics import VERSION

    cases, blobs, refused, digests = [], {}, [], {}
    for contender in chosen:
        for sid in scenarios:
            try:
                runs = scoreboard.systems_for(contender, sid, quick)
            except ValueError as exc:
                refused.append({"controller": contender.name, "scenario": sid, "case": "all", "status": "failed",
                                "error": str(exc)})
                continue
            for label, system, step, stop_time, x_d, residual_from in runs:
                system = systems.at_step(system, fmu_dir, step)
                fmus, connections = systems.resolve(system, fmu_dir)
                hashes = {}
                for name, path in fmus.items():
                    if path not in digests:  # each FMU file read once
                        data = Path(path).read_bytes()
                        digests[path] = hashlib.sha256(data).hexdigest()[:20]
                        blobs[digests[path]] = data
                    hashes[name] = digests[path]
                case = {"controller": contender.name, "scenario": sid, "case": label, "fmus": hashes,
                        "connections": [list(c) for c in connections], "parameters": system.parameters,
                        "step": step, "stop_time": stop_time, "x_d": x_d, "residual_from": residual_from,
                        "bounds": {**scoreboard.DRIVE, **scoreboard.RAIL}, "format": ROW_FORMAT,
                        "metrics_version": VERSION, "keep_signals": sid in ANIMATE and len(runs) == 1}
                case["case_id"] = hashlib.sha256(json.dumps(case, sort_keys=True).encode()).hexdigest()[:16]
                try:
                    systems.check_parameters(system, fmu_dir)
                except ValueError as exc:
                    refused.append({**_identity(case), "status": "invalid", "error": str(exc)})
                    continue
                cases.append(case)
    return cases, blobs, refused


def _identity(case):
    return {k: case[k] for k in ("case_id", "controller", "scenario", "case", "metrics_version")}


def run_score_case(case, blobs):
    """Co-simulate one case on a worker; return its row: identity, status, error, metrics (and signals)."""
    from crane_fmu.analysis import metrics
    from crane_fmu.cosim import ArrayRecorder, Connection, FmiError, simulate
    from crane_fmu.sweep.runner import local_fmus

    row = {**_identity(case), "status": "ok", "error": None}
    start = time.perf_counter()
    fmus = local_fmus({name: (digest, blobs[digest]) for name, digest in case["fmus"].items()})
    recorder = ArrayRecorder()
    try:
        simulate(fmus, [Connection(*c) for c in case["connections"]], case["stop_time"], case["step"],
                 parameters=case["parameters"], recorder=recorder)
    except FmiError as exc:
        row.update(status="failed", error=str(exc))
    columns = recorder.columns() if recorder.names else None
    if columns and len(columns["time"]) > 1:
        s = metrics.crane_signals(columns, ("dx",) + SIGNALS[5:])
        row.update(metrics.move_metrics(s["time"], s["x"], s["dx"], s["theta1"], s["theta2"], s["u"], case["x_d"],
                                        case["residual_from"], bounds=case["bounds"]))
        row["outcome"] = metrics.classify(s["time"], s["theta1"], s["theta2"], row["status"] == "ok")
        if case["keep_signals"]:
            every = max(1, round(SIGNAL_EVERY / case["step"]))
            row["signals"] = {k: s[k][::every].tolist() for k in SIGNALS if k in s}
    row["duration_s"] = time.perf_counter() - start
    return row


def compare(out_dir, chosen=(), fmu_dir="build/fmus", workers=None, scheduler=None, quick=False, progress=True,
            animate=("S2",), only=False, log=print):
    """Score the contenders; write scoreboard.md, scores.parquet, plots and animations to ``out_dir``.

    Parameters
    ----------
    chosen, only
        The controllers (see :func:`contenders`): by default every built-in one, and the user's FMUs beside them.
    quick : bool
        A quick board (3 of the 27 plants of S3 and S9), written to ``out_dir/quick`` with its own journal, so
        that it never replaces a full board and is never mistaken for one.
    animate : iterable of str
        The scenarios (of :data:`ANIMATE`) whose nominal runs are animated; an animation is drawn again only when
        its run changed.

    Returns
    -------
    list of dict
        The rows of the board: one per contender, scenario and case.
    """
    from crane_fmu.analysis import score_plots
    from crane_fmu.analysis.metrics import VERSION

    start = time.perf_counter()
    if sys._getframe(1).f_globals.get("__name__") == "__mp_main__":  # called by a script a worker imports
        raise RuntimeError("compare() was called while a Dask worker process imported your script again: call it "
                           "under `if __name__ == \"__main__\":`")
    unknown = [s for s in animate if s not in ANIMATE]
    if unknown:
        raise ValueError(f"animate {', '.join(unknown)}: no animation there; the animated scenarios are "
                         f"{', '.join(ANIMATE)}")
    out_dir = Path(out_dir) / "quick" if quick else Path(out_dir)
    chosen = contenders(chosen, fmu_dir, only)
    cases, blobs, refused = plan(chosen, fmu_dir, quick=quick)
    out_dir.mkdir(parents=True, exist_ok=True)  # only now: a refused board leaves no folder behind
    done = read_journal(out_dir)
    other = sum(r.get("metrics_version") != VERSION for r in done.values())
    if other:
        log(f"{out_dir / JOURNAL}: {other} rows were measured by another version of the metrics "
            f"(crane_fmu/analysis/metrics.py is now {VERSION}): not used, their cases run again")
    pending = [c for c in cases if c["case_id"] not in done]
    failed_before = sum(done[c["case_id"]]["status"] != "ok" for c in cases if c["case_id"] in done)
    bar = Progress(len(cases), len(cases) - len(pending), failed=failed_before) if progress else None
    ran = run_batch(run_score_case, pending, blobs, on="dask", workers=workers, scheduler=scheduler,
                    journal=out_dir / JOURNAL, progress=bar)
    done.update({r["case_id"]: r for r in ran})
    rows = [done[c["case_id"]] for c in cases] + refused
    for row in rows:
        row.update(quick=quick, **{f"scenario_{k}": v for k, v in scoreboard.scope(row["scenario"], quick).items()})
    write_table([{k: v for k, v in r.items() if k != "signals"} for r in rows], out_dir / "scores.parquet")
    board = out_dir / "scoreboard.md"
    board.with_name(".scoreboard.md.partial").write_text(scoreboard.render(rows, chosen, quick))
    board.with_name(".scoreboard.md.partial").replace(board)
    paths = score_plots.plot_all(rows, out_dir, {c.name for c in chosen if c.user})
    drawn = 0
    for sid in animate:
        new = score_plots.animate_all(rows, sid, out_dir / "animations")
        paths += new
        drawn += len(new)
    log(f"{len(cases)} cases: {len(ran)} run now, {len(cases) - len(pending)} already done, "
        f"{sum(r['status'] != 'ok' for r in rows)} not ok, in {time.perf_counter() - start:.1f} s; "
        f"wrote {board}{' (a QUICK board)' if quick else ''}, {out_dir / 'scores.parquet'}, "
        f"{len(paths) - drawn} plots and {drawn} animations drawn now")
    return rows
