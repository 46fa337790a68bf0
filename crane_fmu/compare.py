"""``crane-fmu compare``: every controller FMU on the scoreboard's scenarios, in parallel on Dask.

Cases run through the sweep runner (journal, resume, progress bar). Each case
is a system as data; its FMUs travel to the workers once, by content hash.
"""

import hashlib
import json
import time
from pathlib import Path

from crane_fmu import components, systems
from crane_fmu.analysis import scoreboard
from crane_fmu.analysis.scoreboard import SCENARIOS, Contender
from crane_fmu.sweep.batch import JOURNAL, Progress, read_journal, run_batch
from crane_fmu.sweep.runner import write_table

SIGNALS = ("time", "plant.x", "plant.theta1", "plant.theta2", "controller.u", "plant.x1", "plant.y1", "plant.x2",
           "plant.y2", "plant.l1_now")
SIGNAL_EVERY = 0.02  # s: the signals kept for plots and animations


def contenders(chosen=(), fmu_dir="build/fmus"):
    """The controllers to score: registered ones by model identifier, or FMU files (default: every registered one)."""
    from crane_fmu.cosim.system import read_fmu

    result = []
    for item in chosen or [c.model_identifier for c in components.all("controller")]:
        if str(item).endswith(".fmu"):
            md = read_fmu(item)
            variables = {v.name: v.causality for v in md.modelVariables}
            name = Path(item).stem
            source = str(Path(item).resolve())
        else:
            component = components.find(item)
            if component is None or component.role != "controller":
                known = ", ".join(c.model_identifier for c in components.all("controller"))
                raise ValueError(f"no controller {item!r}; controllers: {known} (or a controller .fmu file)")
            variables = {v.name: v.causality for v in component.variables}
            name, source = item, item
        inputs = [n for n, c in variables.items() if c == "input"]
        scoreboard.check_interface(name, inputs, [n for n, c in variables.items() if c == "output"])
        result.append(Contender(name, source, inputs, [n for n, c in variables.items() if c == "parameter"]))
    return result


def plan(chosen, fmu_dir, scenarios=tuple(SCENARIOS), quick=False):
    """``(cases, blobs, refused)``: the cases to run, the FMU bytes by hash, and rows of cases that cannot run."""
    cases, blobs, refused, digests = [], {}, [], {}
    for contender in chosen:
        for sid in scenarios:
            try:
                runs = scoreboard.systems_for(contender, sid, quick)
            except ValueError as exc:
                refused.append({"controller": contender.name, "scenario": sid, "case": "all", "status": "failed",
                                "error": str(exc)})
                continue
            for label, system, step, stop_time, x_d in runs:
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
                        "step": step, "stop_time": stop_time, "x_d": x_d,
                        "keep_signals": label in ("nominal", "l1 2 m -> 1 m")}
                case["case_id"] = hashlib.sha256(json.dumps(case, sort_keys=True).encode()).hexdigest()[:16]
                try:
                    systems.check_parameters(system, fmu_dir)
                except ValueError as exc:
                    refused.append({**_identity(case), "status": "invalid", "error": str(exc)})
                    continue
                cases.append(case)
    return cases, blobs, refused


def _identity(case):
    return {k: case[k] for k in ("case_id", "controller", "scenario", "case")}


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
        move_end = 0.0
        if "planner" in case["fmus"]:
            from crane_fmu.model import planner

            move_end = planner.setup({**planner.COMPONENT.defaults(), **case["parameters"]["planner"]}).end
        t = columns["time"]
        row.update(metrics.move_metrics(t, columns["plant.x"], columns["plant.dx"], columns["plant.theta1"],
                                        columns["plant.theta2"], columns["controller.u"], case["x_d"], move_end))
        row["outcome"] = metrics.classify(t, columns["plant.theta1"], columns["plant.theta2"], row["status"] == "ok")
        if case["keep_signals"]:
            every = max(1, round(SIGNAL_EVERY / case["step"]))
            row["signals"] = {k: columns[k][::every].tolist() for k in SIGNALS if k in columns}
    row["duration_s"] = time.perf_counter() - start
    return row


def compare(out_dir, chosen=(), fmu_dir="build/fmus", workers=None, scheduler=None, quick=False, progress=True,
            animate=("S2",), log=print):
    """Score every contender; write scoreboard.md, scores.parquet, plots and animations to ``out_dir``."""
    from crane_fmu.analysis import score_plots

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    chosen = contenders(chosen, fmu_dir)
    cases, blobs, refused = plan(chosen, fmu_dir, quick=quick)
    done = read_journal(out_dir)
    pending = [c for c in cases if c["case_id"] not in done]
    bar = Progress(len(cases), len(cases) - len(pending)) if progress else None
    start = time.perf_counter()
    ran = run_batch(run_score_case, pending, blobs, on="dask", workers=workers, scheduler=scheduler,
                    journal=out_dir / JOURNAL, progress=bar)
    done.update({r["case_id"]: r for r in ran})
    rows = [done[c["case_id"]] for c in cases] + refused
    write_table([{k: v for k, v in r.items() if k != "signals"} for r in rows], out_dir / "scores.parquet")
    (out_dir / "scoreboard.md").write_text(scoreboard.render(rows, chosen))
    paths = score_plots.plot_all(rows, out_dir)
    for sid in animate:
        paths += score_plots.animate_all(rows, sid, out_dir / "animations")
    log(f"{len(cases)} cases: {len(ran)} run now, {len(cases) - len(pending)} already done, "
        f"{sum(r['status'] != 'ok' for r in rows)} not ok, in {time.perf_counter() - start:.1f} s; "
        f"wrote {out_dir / 'scoreboard.md'}, {out_dir / 'scores.parquet'} and {len(paths)} plots and animations")
    return rows
