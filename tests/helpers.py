"""The helpers that more than one test module uses (no test module imports another: a shared helper lives here).

Beside this module: ``native_fmus.py`` (open, run and compare the native FMUs), ``third_party_hosts.py`` (fmusim,
fmuCheck, OMSimulator), ``derivation.py`` (the sympy derivation of the plant's equations), ``once.py`` (made once
per run) and ``fmu_kinds.py``; the fixtures are in ``conftest.py``.
"""

import glob
import json
import math
import os
import random
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description
from native_fmus import compiler

from crane_fmu import components, systems
from crane_fmu.build_scripts.folders import fmi3_dir
from crane_fmu.build_scripts.one_fmu import one_fmu_name, plan
from crane_fmu.build_scripts.wrapper import fmi_headers
from crane_fmu.cli import main
from crane_fmu.cosim import read_result
from crane_fmu.model import mpc, plant, plant3d, plant3d_continuous, qp
from crane_fmu.model.component import Step
from crane_fmu.model.plant_continuous import FREE, Mode

# The free swing's largest theta2 [deg]: Section V's plant released at theta1 = 10 deg, 20 s on a 1 ms grid. The
# independent answer (DOP853 on the sympy equations, tests/derivation.py) is 15.59762 (test_fmus.py
# test_the_free_swings_peak_is_the_independent_answer); every host of the native and Python FMUs must give it.
FREE_SWING_MAX_THETA2_DEG = 15.5976

# ---- the quick board of the built-in controllers (conftest.py's builtin_quick_board) -------------------------------

BOARD_CASES = 2  # of the paired design on builtin_quick_board: every scenario, the fewest cases (16 cases, as
# `compare --quick` runs, cost 3.6 times as many runs)
# The controllers of builtin_quick_board: every built-in one but the MPC, whose Python runs were half the board's
# time. test_native_mpc.py holds the native MPC to the Python one bit for bit on the board's kinds of run
# (regulation, the move, a plant it does not know, hoisting, the hard hit); test_compare.py's full board runs it
# natively on every scenario.
BOARD_CONTROLLERS = tuple(c.model_identifier for c in components.registered("controller")
                          if c.model_identifier != "MpcController")

def kind_folder(request, fmu_dir, kind, version):
    """The folder of the FMI ``version`` FMUs of ``kind``: ``python`` (``fmu_dir``'s), else ``native`` or ``one-fmu``
    (conftest.py's ``native``, which skips where no C compiler made them)."""
    if kind == "python":
        return fmu_dir if version == 2 else fmi3_dir(fmu_dir)
    return request.getfixturevalue("native")[version]


# ---- C hosts of the Python FMUs, and the CPythons they find (test_c_host, test_c_fuzz, ...) ------------------------

# The five CPythons of this machine kind: pyenv's 3.10-3.13 and Debian's own 3.11 (libpython in /usr/lib).
PYTHONS = {f"3.{minor}": f"{os.path.expanduser('~')}/.pyenv/versions/3.{minor}.*/bin/python3.{minor}"
           for minor in (10, 11, 12, 13)}
PYTHONS["debian-3.11"] = "/usr/bin/python3.11"


def installed_python(name):
    """The executable of :data:`PYTHONS` ``[name]``; the test skips, naming it, where it is not installed."""
    found = sorted(glob.glob(PYTHONS[name]))
    if not found:
        pytest.skip(f"CPython {name} is not installed here ({PYTHONS[name]})")
    return found[-1]


def compile_hosts(source, folder):
    """``{2: program, 3: program}``: C ``source`` compiled for each FMI version against the official headers."""
    (folder / "host.c").write_text(source)
    built = {}
    for version in (2, 3):
        built[version] = folder / f"host{version}"
        subprocess.run([compiler(), f"-DFMI={version}", "-I", str(fmi_headers()), str(folder / "host.c"), "-o",
                        str(built[version]), "-ldl", "-lm"], check=True)
    return built


def unpack_fmu(fmu, folder):
    """Extract an FMU: ``(model description, its Linux library, instantiation token, resource location)``."""
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    md = read_model_description(str(fmu))
    token = md.guid if md.fmiVersion == "2.0" else md.instantiationToken
    platform = "linux64" if md.fmiVersion == "2.0" else "x86_64-linux"
    library = folder / "binaries" / platform / f"{md.coSimulation.modelIdentifier}.so"
    resources = (folder / "resources").as_uri() if md.fmiVersion == "2.0" else str(folder / "resources") + "/"
    return md, str(library), token, resources


# ---- libcosim (test_system_files, test_registry, test_one_fmu) ------------------------------------------------------

LIBCOSIM = Path(__file__).parent / "libcosim_run.py"


def libcosim_run(kind, path, steps=1000, instance="plant", names=("x", "theta1", "theta2")):
    """libcosim's trajectories of ``names`` (the planar plant's x, theta1, theta2) for a system file, from a
    subprocess."""
    pytest.importorskip("libcosimpy")
    proc = subprocess.run([sys.executable, str(LIBCOSIM), kind, str(path), str(steps), instance, ",".join(names)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def assert_libcosim_matches(theirs, ours, instance="plant", bound=1e-12):
    for name in ("x", "theta1", "theta2"):
        times, values = np.array(theirs[name][0]), np.array(theirs[name][1])
        assert len(times) > 900
        index = np.rint(times / 1e-3).astype(int)
        assert np.abs(values - ours[f"{instance}.{name}"][index]).max() < bound


# ---- a system as one native FMU (test_one_fmu, test_native_mpc) -----------------------------------------------------

OBSERVED = ("x", "theta1", "theta2", "u")  # the planar systems' observed(name)


def observed(name):
    """The one-FMU outputs of system ``name`` a host prints, by its plant's roles: ``(states, demands)``, each
    axis's position and the swing angles, then the demands (the planar plant's x, theta1, theta2; u)."""
    crane = systems.plant_of(systems.get(name)).crane
    return (*(a.position for a in crane.axes), *crane.swing), crane.demands
# the host's command and the binary folders (Linux, Windows) of each FMI version
HOST_COMMAND = {2: "outputs", 3: "outputs3"}
BINARIES = {2: ("linux64", "win64"), 3: ("x86_64-linux", "x86_64-windows")}


def one_fmu(native, name, version=2):
    """The one-FMU of the system ``name`` in the ``native`` fixture's folders."""
    return native[version] / f"{one_fmu_name(name)}.fmu"


_RUNS = {}


def master_run(native, name, settings=(), stop_time=None, tmp=None):
    """``crane-fmu simulate --system NAME --fmu-dir build/native --set ...``: its columns (cached)."""
    key = (name, tuple(settings), stop_time)
    if key not in _RUNS:
        out = tmp / f"{len(_RUNS)}.csv"
        args = ["simulate", "--system", name, "--fmu-dir", str(native[2]), "--out", str(out)]
        args += [f"--set={item}" for item in settings] + (["--stop-time", str(stop_time)] if stop_time else [])
        assert main(args) == 0
        _RUNS[key] = read_result(out)
    return _RUNS[key]


def one_fmu_outputs(name):
    """``{one-FMU output: master column}``."""
    links = plan(systems.get(name)).links
    md_outputs = [v for v in plan(systems.get(name)).variables if v.causality == "output"]
    return {v.name: "{}.{}".format(*links[v.name][0]) for v in md_outputs}


def unpack_one_fmu(native, name, folder, version=2):
    """The one-FMU unpacked into folder: its guid (FMI 3.0: instantiationToken) and the value references of observed()
    (FMI 3.0's are FMI 2.0's plus one: vr 0 is time)."""
    fmu = one_fmu(native, name, version)
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    return md.guid, [str(vr[v]) for v in sum(observed(name), ())]


def host_rows(command, *args, **kwargs):
    """The rows a host printed (comma-separated numbers), or an assertion with its errors."""
    done = subprocess.run([*map(str, command), *map(str, args)], capture_output=True, text=True, timeout=300, **kwargs)
    assert done.returncode == 0, done.stderr[-2000:]
    return np.array([[float(x) for x in line.split(",")] for line in done.stdout.replace("\r", "").splitlines()])


def observed_columns(columns, name):
    """Our master's columns of the one-FMU's :func:`observed` outputs, after its time: the host's rows."""
    outputs = one_fmu_outputs(name)
    return np.column_stack([columns["time"]] + [columns[outputs[v]] for v in sum(observed(name), ())])


# ---- the MPC and its QP solver (test_mpc, test_native_mpc) ----------------------------------------------------------

def random_qp(rng):
    """A random strictly convex QP with bounds, general rows and a few equalities, and a feasible point."""
    n, m = int(rng.integers(1, 30)), int(rng.integers(0, 40))
    a = rng.normal(size=(n, n))
    h = a @ a.T + 0.1 * np.eye(n)
    general = rng.normal(size=(m, n))
    feasible = rng.normal(size=n)
    at = np.concatenate([feasible, general @ feasible])
    lower, upper = at - rng.uniform(0, 1, n + m), at + rng.uniform(0, 1, n + m)
    lower[rng.random(n + m) < 0.2] = -np.inf
    upper[rng.random(n + m) < 0.2] = np.inf
    equal = np.r_[np.zeros(n, bool), rng.random(m) < 0.1]
    lower[equal] = upper[equal] = at[equal]
    rows = [(k, [1.0]) for k in range(n)] + [(0, list(row)) for row in general]
    return qp.prepare(h.tolist(), rows), (rng.normal(size=n) * 3).tolist(), lower.tolist(), upper.tolist(), \
        feasible.tolist()


def mpc_loop(plant_values, controller_values, stop_time, h=1e-3, with_state=False):
    """The plant and the MpcController called directly, as the master calls the FMUs; the run's arrays, its
    messages (and with ``with_state`` the controller's last state)."""
    pc = plant.configure({**plant.COMPONENT.defaults(), "u_max": 2.0, "v_max": 1.0, **plant_values})
    cc = mpc.configure({**mpc.COMPONENT.defaults(), "h": h, **controller_values})
    ps, cs = pc.state0, mpc.initial_state(cc)
    rows, messages = [], []
    for k in range(round(stop_time / h) + 1):
        out = plant.COMPONENT.output(pc, ps, (0.0,) * 4)
        inputs = tuple(out[:6]) + (out[11], 0.0, 0.0)  # l1_now; F2_hat, F1_hat unconnected
        u = mpc.COMPONENT.output(cc, cs, inputs)[0]
        rows.append(tuple(out[:6]) + (u, out[-1]))
        ps = plant.update(pc, ps, (u, 0.0, 0.0, 0.0), k * h, h)
        cs = mpc.update(cc, cs, inputs, k * h, h)
        if isinstance(cs, Step):
            messages += cs.messages
            cs = cs.state
    return (np.array(rows), messages, cs) if with_state else (np.array(rows), messages)


# ---- the plant's Model Exchange interface (test_plant_continuous, test_native_continuous) ---------------------------

def continuous_plant_cases(n=30, seed=3):
    """Random parameters (damping, a drive lag, finite limits), states, inputs and modes."""
    rng = random.Random(seed)
    for k in range(n):
        values = {"m1": rng.uniform(0.5, 10), "m2": rng.uniform(0.1, 10), "l1": rng.uniform(0.3, 3),
                  "l2": rng.uniform(0.1, 2), "g": rng.uniform(1, 20), "c1": rng.uniform(0, 5), "c2": rng.uniform(0, 5),
                  "tau": rng.choice((0.0, rng.uniform(0.05, 1))), "u_max": rng.choice((math.inf, 3.0))}
        config = plant.COMPONENT.check(values)
        state = (rng.uniform(-2, 2), rng.uniform(-1, 1), *(rng.uniform(-1.5, 1.5) for _ in range(4)),
                 rng.uniform(0.3, 3), rng.uniform(-1, 1), rng.uniform(-2, 2))
        inputs = (rng.uniform(-5, 5), rng.uniform(-2, 2), rng.uniform(-50, 50), rng.uniform(-50, 50))
        mode = FREE if k % 3 == 0 else Mode(rng.choice((-1, 0, 1)), rng.choice((-1, 0, 1)), rng.choice((-1, 0, 1)))
        yield config, state, inputs, mode


def spatial_plant_cases(n=20, seed=3):
    """Random parameters (damping, drive lags, finite limits), states, inputs and modes of the CranePlant3D's Model
    Exchange plant (its Python and its C tests)."""
    rng = random.Random(seed)
    for k in range(n):
        values = {"m1": rng.uniform(0.5, 10), "m2": rng.uniform(0.1, 10), "l1": rng.uniform(0.3, 3),
                  "l2": rng.uniform(0.1, 2), "g": rng.uniform(1, 20), "c1": rng.uniform(0, 5), "c2": rng.uniform(0, 5),
                  "tau_x": rng.choice((0.0, rng.uniform(0.05, 1))), "tau_y": rng.choice((0.0, rng.uniform(0.05, 1))),
                  "ux_max": rng.choice((math.inf, 3.0)), "uy_max": rng.choice((math.inf, 3.0))}
        config = plant3d.COMPONENT.check(values)
        state = tuple(rng.uniform(-1.2, 1.2) for _ in range(12)) + (rng.uniform(0.3, 3), rng.uniform(-1, 1),
                                                                   rng.uniform(-2, 2), rng.uniform(-2, 2))
        inputs = (rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-2, 2),
                  *(rng.uniform(-50, 50) for _ in range(4)))
        mode = plant3d_continuous.FREE
        if k % 3:
            mode = plant3d_continuous.Mode(*(rng.choice((-1, 0, 1)) for _ in range(4)))
        yield config, state, inputs, mode


def chunk_waiting_once(item, folder):
    """A chunked task: each case's row, with the process that made it; the first run of the chunk holding case 0
    waits after that row (for its worker, a Dask worker or a pool process, to be killed)."""
    _, cases = item
    first = not (Path(folder) / f"ran-{cases[0]}").exists()
    (Path(folder) / f"ran-{cases[0]}").touch()
    for case in cases:
        yield {"case_id": f"{case:016x}", "status": "ok", "pid": os.getpid()}
        if first and case == 0:
            time.sleep(120)
