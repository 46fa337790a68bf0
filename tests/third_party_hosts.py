"""Helpers for the tests that run our files in FMI hosts nobody here wrote (``../shared/tools``).

Reference-FMUs' ``fmusim``, the FMU Compliance Checker ``fmuCheck.linux64`` and OMSimulator are in the
folder ``shared/tools`` beside the repository (``CRANE_FMU_TOOLS`` names another) for the developers and
CI; a user's clone has none of them, so a test that needs one skips there, naming it (in CI, where
``CI=true``, that skip fails the run: tests/required_checks.py).
"""

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

TOOLS = Path(os.environ.get("CRANE_FMU_TOOLS") or Path(__file__).resolve().parents[2] / "shared" / "tools")
FMUSIM, FMUCHECK, OMSIMULATOR = "fmusim", "fmuCheck.linux64", "omsimulator/bin/OMSimulator"
CLEAN_ENV = {"PATH": "/usr/bin:/bin"}  # what `env -i PATH=/usr/bin:/bin` leaves: no venv, no pyenv
SAME = 1e-9  # relative to the signal's largest magnitude (at least 1): rounding, not behaviour


def tool(name):
    """The path of a tool in :data:`TOOLS`; the test skips, naming it, where it is absent."""
    path = TOOLS / name
    if not path.is_file():
        pytest.skip(f"{Path(name).name} not found at {path}: it comes with the CI machines' ../shared/tools "
                    "(CRANE_FMU_TOOLS names another folder)")
    return path


def run_tool(command, cwd, env=None, timeout=600):
    """Run a host; ``(exit code, its output and errors)``."""
    done = subprocess.run([str(c) for c in command], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=timeout)
    return done.returncode, done.stdout + done.stderr


def fmusim(fmu, stop_time, step, out):
    """``fmusim --interface-type cs`` under ``env -i PATH=/usr/bin:/bin``: ``{column: array}`` of its CSV."""
    code, log = run_tool([tool(FMUSIM), "--interface-type", "cs", "--stop-time", repr(stop_time),
                          "--output-interval", repr(step), "--output-file", out, fmu], out.parent, CLEAN_ENV)
    assert code == 0 and "[Error]" not in log, f"fmusim on {fmu.name}: exit {code}\n{log[-2000:]}"
    table = np.genfromtxt(out, delimiter=",", names=True, deletechars="", dtype=float)
    return {name: table[name] for name in table.dtype.names}


def fmusim_me(fmu, start, stop_time, step, out, tolerance, inputs=None):
    """``fmusim --interface-type me --solver cvode`` with start values ``{name: value}`` (and ``--input-file
    inputs``), under ``env -i``: ``{column: array}`` of its CSV."""
    command = [tool(FMUSIM), "--interface-type", "me", "--solver", "cvode", "--tolerance", repr(tolerance),
               "--stop-time", repr(stop_time), "--output-interval", repr(step), "--output-file", out]
    command += ["--input-file", inputs] if inputs else []
    for name, value in start.items():
        command += ["--start-value", name, repr(value)]
    code, log = run_tool([*command, fmu], out.parent, CLEAN_ENV)
    assert code == 0 and "[Error]" not in log, log[-2000:]
    table = np.genfromtxt(out, delimiter=",", names=True, deletechars="", dtype=float)
    return {name: table[name] for name in table.dtype.names}


def omsimulator_log_problems(log):
    """The warning and error lines of an OMSimulator log, less the two about its own missing schema files."""
    return [line for line in log.splitlines() if line.startswith(("warning:", "error:"))
            and "could not load the" not in line]


def read_oms_mat(path, step):
    """``{variable: array}`` of an OMSimulator result (.mat, OpenModelica's format, full precision) on the grid
    ``k * step``: OMSimulator writes a communication point twice, and a run that ends with a remainder step a
    point within rounding of the last; the last row at each grid point is kept (after the exchange)."""
    import scipy.io

    m = scipy.io.loadmat(str(path), chars_as_strings=False)
    names = ["".join(column).rstrip("\x00 ") for column in m["name"].T]
    k = np.rint(m["data_2"][0] / step).astype(int)
    last = np.append(k[1:] != k[:-1], True)
    values = {}
    for j, name in enumerate(names):
        matrix, index = int(m["dataInfo"][0, j]), int(m["dataInfo"][1, j])
        row = m[f"data_{matrix or 2}"][abs(index) - 1] * np.sign(index)
        values[name] = np.full(last.sum(), row[0]) if matrix == 1 else row[last]
    values["k"] = k[last]
    return values


def worst_difference(theirs, ours, pairs):
    """The largest ``|theirs - ours| / max(1, max |ours|)`` over ``pairs`` of (their column, our column)."""
    return max(float(np.max(np.abs(theirs[a] - ours[b])) / max(1.0, float(np.max(np.abs(ours[b])))))
               for a, b in pairs)


def held_inputs(path, time, columns):
    """Write an fmusim input file of inputs held over each step (``columns``: ``{input: array}`` on ``time``): a row
    at the start, two rows at each time an input jumps (the value before it, then after: fmusim's event) and one at
    the end; fmusim interpolates between rows, which here hold the same values."""
    names = list(columns)
    values = np.column_stack([columns[n] for n in names])
    rows = [(time[0], *values[0])]
    for k in np.flatnonzero(np.any(values[1:] != values[:-1], axis=1)) + 1:
        rows += [(time[k], *values[k - 1]), (time[k], *values[k])]
    rows.append((time[-1], *values[-1]))
    path.write_text("time," + ",".join(names) + "\n" + "".join(",".join(repr(float(v)) for v in row) + "\n"
                                                               for row in rows))
    return path
