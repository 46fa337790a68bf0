"""Reproduction of the paper's Figures 4, 5, 7 and 8 through the co-simulated FMUs.

Every number comes from running CranePlant.fmu (and BacksteppingController.fmu)
with the project's master; scipy only supplies the continuous-time reference of
the communication-step study and the linear analysis. Nothing is tuned: the
cases are the paper's, and the verdict rules in ``report.py`` are fixed.
"""

import json
import math
import os
from pathlib import Path

import numpy as np

from crane_fmu import DEFAULT_FMU_DIR, systems
from crane_fmu.batch import Progress, run_batch
from crane_fmu.cosim import ArrayRecorder, FmiError, run, write_csv

from . import figures, metrics, paper_summary, report
from .paper_cases import plan


def run_case(case, fmu_dir, csv_dir):
    """Co-simulate one case through the FMUs; write its CSV; return its metrics and coarse signals."""
    system = systems.get(case.system)
    parameters = {"plant": case.plant, "controller": case.controller} if case.form else {"plant": case.plant}
    recorder = ArrayRecorder()
    error = None
    try:
        run(systems.prepare(system, case.step, case.stop_time, [parameters], check=False), fmu_dir, recorder=recorder)
    except FmiError as exc:
        error = str(exc)
    columns = recorder.columns()
    every = max(1, round(case.output_interval / case.step))
    write_csv(Path(csv_dir) / f"{case.name}.csv", columns, every)
    s = metrics.crane_signals(columns)
    signals = {"time": s["time"], "x": s["position"][0], **s["swing"], "u": s["demand"][0]}
    result = {"case": case, "error": error, "completed": error is None}
    if case.form is None:
        result["metrics"] = free_swing_metrics(s["time"], signals["theta1"], signals["theta2"],
                                               case.plant.get("theta1_0", math.pi / 18))
    else:
        result["metrics"] = metrics.closed_loop_metrics(s["time"], signals["x"], s["swing"], signals["u"],
                                                        error is None)
    keep = ["time", "x", "theta1", "theta2"] + (["u"] if case.form else [])
    result["signals"] = {k: signals[k][::every].tolist() for k in keep}
    return result


def free_swing_metrics(t, theta1, theta2, theta1_0):
    """Largest angles, the Figure 4 ratio, and the frequencies present in each angle."""
    return {
        "max_theta1_deg": math.degrees(metrics.peak_abs(theta1)),
        "max_theta2_deg": math.degrees(metrics.peak_abs(theta2)),
        "ratio_max_theta2_to_theta1_0": metrics.peak_abs(theta2) / theta1_0,
        "rms_theta1_deg": math.degrees(metrics.rms(theta1)),
        "freqs_theta1_hz": metrics.dominant_frequencies(t, theta1),
        "freqs_theta2_hz": metrics.dominant_frequencies(t, theta2),
    }


def reproduce(out_dir, fmu_dir=DEFAULT_FMU_DIR, quick=False, workers=None, log=print):
    """Run every case, then write figures, CSVs, ``metrics.json`` and ``REPORT.md`` to ``out_dir``.

    Returns
    -------
    dict
        The metrics written to ``metrics.json``.
    """
    out_dir = Path(out_dir)
    csv_dir = out_dir / "runs"
    csv_dir.mkdir(parents=True, exist_ok=True)
    cases = plan(quick)
    workers = workers or os.cpu_count() or 1
    log(f"running {len(cases)} co-simulations on {workers} worker(s)")
    done = run_batch(run_case, cases, workers=workers, progress=Progress(len(cases), ok=lambda r: r["completed"]),
                     fmu_dir=fmu_dir, csv_dir=csv_dir)
    finished = {r["case"].name: r for r in done}
    results = {case.name: finished[case.name] for case in cases}  # in the plan's order
    summary = paper_summary.summarise(results, quick)
    (out_dir / "metrics.json").write_text(json.dumps(summary, indent=2, default=_jsonable))
    for path in figures.draw_all(results, out_dir):
        log(f"wrote {path}")
    (out_dir / "REPORT.md").write_text(report.render(summary))
    log(f"wrote {out_dir / 'metrics.json'} and {out_dir / 'REPORT.md'}")
    return summary


def _jsonable(value):
    if isinstance(value, complex | np.complexfloating):
        return [value.real, value.imag]
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"cannot write {type(value).__name__} to JSON")
