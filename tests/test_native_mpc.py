"""The native (C) MpcController and its QP solver against their specification.

The Python models (crane_fmu/model/mpc.py and qp.py) are the specification: on Linux (glibc's libm in both, the
same operations in the same order) the native numbers are the Python ones bit for bit. The FMUs are built by the
session's ``fmu_dir`` fixture into ``build/native``; the solver alone is qp.c compiled here and called through
ctypes. The systems ``mpc`` and ``mpc-transport`` as one native FMU each (``CraneMpc``, ``CraneMpcTransport``) are
held to our master over the native component FMUs in test_one_fmu.py (fmpy, the C host without Python, the Windows
DLLs under Wine); here the native component to the Python one through our master.
"""

import ctypes
import math
import shutil
import subprocess
from dataclasses import replace

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu
from helpers import (
    BINARIES,
    HOST_COMMAND,
    host_rows,
    master_run,
    mpc_loop,
    observed_columns,
    one_fmu,
    random_qp,
    unpack_one_fmu,
)
from native_fmus import (
    close,
    compare_to_python,
    compiler,
    messages,
    open_native,
    python_folder,
    python_run_equal_to_native,
    steps_after_restore,
)

from crane_fmu import components, systems
from crane_fmu.build_scripts.native import FOLDERS, source_path, variables_header
from crane_fmu.build_scripts.one_fmu import one_fmu_name
from crane_fmu.model import mpc, qp

MPC = components.get("MpcController")
INF, NAN = float("inf"), float("nan")
MISMATCH = {"l1": 1.1, "l2": 0.4, "m2": 3.5}  # a plant the controller's model (l1 2 m, l2 0.5 m, m2 5 kg) is not


# ---- one source: the Python FMU's variables; strict C --------------------------------------------------------------

@pytest.mark.parametrize("version", [2, 3])
def test_native_model_description_has_the_python_fmus_variables(fmu_dir, native, version):
    """Names, value references, causalities, start values, units, descriptions; fmpy's validation is clean."""
    def variables(path):
        return [(v.name, v.valueReference, v.causality, v.variability, v.initial, v.start, v.unit, v.description)
                for v in read_model_description(str(path)).modelVariables]

    path = native[version] / "MpcController.fmu"
    assert variables(path) == variables(python_folder(fmu_dir, version) / "MpcController.fmu")
    assert validate_fmu(str(path)) == []


@pytest.mark.parametrize("own_math", [False, True], ids=["libm", "portable"])
def test_the_model_files_compile_without_warnings_under_strict_flags(tmp_path, own_math):
    """ISO C99, -Wall -Wextra -Werror (less unused parameters), with the C library's math and the portable one: the
    MPC of one axis (mpc_axis.c) and the two components over it (mpc.c, mpc3d.c)."""
    flags = ["-c", "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Wno-unused-parameter", "-Werror"]
    flags += ["-DCRANE_OWN_MATH"] if own_math else []
    (tmp_path / "MpcController_variables.h").write_text(variables_header(MPC))
    (tmp_path / "MpcController3D_variables.h").write_text(variables_header(components.get("MpcController3D")))
    for name in ("mpc.c", "mpc_axis.c", "mpc3d.c", "qp.c"):
        subprocess.run([compiler(), *flags, f"-I{tmp_path}", *(f"-I{folder}" for folder in FOLDERS),
                        str(source_path(name)), "-o", str(tmp_path / "m.o")], check=True)


# ---- the solver: qp.c against qp.py --------------------------------------------------------------------------------

class _Prepared(ctypes.Structure):
    _fields_ = [("n", ctypes.c_int), ("m", ctypes.c_int), ("first", ctypes.POINTER(ctypes.c_int)),
                ("length", ctypes.POINTER(ctypes.c_int)), ("offset", ctypes.POINTER(ctypes.c_int)),
                ("values", ctypes.POINTER(ctypes.c_double)), ("hinv", ctypes.POINTER(ctypes.c_double)),
                ("g", ctypes.POINTER(ctypes.c_double)), ("norms", ctypes.POINTER(ctypes.c_double)),
                ("chain_end", ctypes.POINTER(ctypes.c_int))]


class _Solution(ctypes.Structure):
    _fields_ = [("x", ctypes.POINTER(ctypes.c_double)), ("active", ctypes.POINTER(ctypes.c_int)),
                ("sides", ctypes.POINTER(ctypes.c_int)), ("n_active", ctypes.c_int), ("iterations", ctypes.c_int),
                ("optimal", ctypes.c_int)]


def _doubles(values):
    return (ctypes.c_double * max(1, len(values)))(*values)


def _ints(values):
    return (ctypes.c_int * max(1, len(values)))(*values)


@pytest.fixture(scope="module")
def c_qp(tmp_path_factory):
    """``solve(prepared, f, lower, upper, start, hint, cap)``: qp.c's prepare and solve of a qp.py problem, as
    ``((hinv, g), qp.Solution)``."""
    library = tmp_path_factory.mktemp("qp") / "qp.so"
    subprocess.run([compiler(), "-shared", "-fPIC", "-O2", "-Wall", "-Werror", "-ffp-contract=off",
                    str(source_path("qp.c")), "-o", str(library), "-lm"], check=True)
    lib = ctypes.CDLL(str(library))

    def solve(prepared, f, lower, upper, start, hint=(), cap=100):
        n, m = prepared.n, len(prepared.rows)
        values, offsets = [], []
        for _, row in prepared.rows:
            offsets.append(len(values))
            values += row
        keep = (_ints([first for first, _ in prepared.rows]), _ints([len(row) for _, row in prepared.rows]),
                _ints(offsets), _doubles(values))
        hinv, g = _doubles([0.0] * n * n), _doubles([0.0] * m * n)
        p = _Prepared(n, m, *keep, hinv, g, _doubles([0.0] * m), _ints([0] * m))
        assert lib.qp_prepare(ctypes.byref(p), _doubles([v for row in prepared.h for v in row]),
                              _doubles([0.0] * 2 * n * n)) == 0
        x, active, sides = _doubles([0.0] * n), _ints([0] * m), _ints([0] * m)
        out = _Solution(x, active, sides, 0, 0, 0)
        lib.qp_solve(ctypes.byref(p), _doubles(f), _doubles(lower), _doubles(upper), _doubles(start),
                     _ints([row for row, _ in hint]), _ints([side for _, side in hint]), len(hint), cap,
                     _doubles([0.0] * (3 * n + 7 * m + m * (m + 1) // 2)), _ints([0] * 3 * m), ctypes.byref(out))
        rows = [list(hinv[i * n:(i + 1) * n]) for i in range(n)], [list(g[i * n:(i + 1) * n]) for i in range(m)]
        solution = qp.Solution(list(x[:n]), list(zip(active[:out.n_active], sides[:out.n_active])), out.iterations,
                               bool(out.optimal))
        return rows, solution

    return solve


def _same(ours, theirs):
    """qp.c's prepared matrices and solution are qp.py's: bit for bit on Linux, to 1e-12 (relative) elsewhere."""
    (hinv, g), solution = ours
    prepared, expected = theirs
    assert (solution.active, solution.iterations, solution.optimal) == \
        (expected.active, expected.iterations, expected.optimal)
    compare_to_python([solution.x, *hinv, *g], [expected.x, *prepared.hinv, *prepared.g])


def test_the_c_solver_gives_the_python_solvers_bits_on_random_convex_qps(c_qp):
    """40 random strictly convex QPs (bounds, general rows, equalities), solved cold to optimality, cold to a cap
    of 3 iterations, and warm from the optimum's active set moved to a nearby feasible point."""
    rng = np.random.default_rng(36)
    capped = warm = 0
    for _ in range(40):
        prepared, f, lower, upper, start = random_qp(rng)
        full = qp.solve(prepared, f, lower, upper, start)
        _same(c_qp(prepared, f, lower, upper, start), (prepared, full))
        early = qp.solve(prepared, f, lower, upper, start, max_iterations=3)
        _same(c_qp(prepared, f, lower, upper, start, cap=3), (prepared, early))
        capped += not early.optimal
        hinted = qp.solve(prepared, f, lower, upper, full.x, full.active)
        _same(c_qp(prepared, f, lower, upper, full.x, full.active), (prepared, hinted))
        warm += hinted.iterations < full.iterations
    assert capped >= 10 and warm >= 10  # the cap and the warm start are exercised


def test_the_c_solver_gives_the_python_solvers_bits_on_the_cranes_qps(c_qp, monkeypatch):
    """Every QP of the first 0.6 s of the 2 m move on a plant unknown to the model (the plan's bisections with
    their resampled warm starts, the identified model's plan) and from a 40 deg swing (the limits bind: the
    tracking QPs with their shifted warm starts)."""
    recorded, solve = [], qp.solve

    def recording(prepared, f, lower, upper, start, hint=(), max_iterations=100):
        solution = solve(prepared, f, lower, upper, start, hint, max_iterations)
        recorded.append(((prepared, f, lower, upper, start, list(hint), max_iterations), solution))
        return solution

    monkeypatch.setattr(qp, "solve", recording)
    mpc_loop({"theta1_0": 0.0, **MISMATCH}, {"x_d": 2.0}, 0.6)
    mpc_loop({"theta1_0": math.radians(40.0)}, {}, 0.6)
    tracking = MPC.check({}).steps
    hinted = [args[0].n == tracking for args, _ in recorded if args[5]]
    assert True in hinted and False in hinted  # warm starts: a tracking QP's shifted one, a plan's resampled one
    for args, solution in recorded:
        _same(c_qp(*args), (args[0], solution))


# ---- the controller through our master: Python FMUs against native ones -------------------------------------------

RUNS = {  # system, plant parameters over the system's, stop time: the limits bind, the move, identification
    "regulation": ("mpc", {}, 1.5),
    "transport": ("mpc-transport", {}, 3.5),  # handed over to its LQR at rest from 2.85 s
    "unknown plant": ("mpc-transport", MISMATCH, 1.0),
    "hard hit": ("mpc", {"theta1_0": math.radians(60.0)}, 1.0),  # no plan from the large swing: the QP alone
    # issue 51: the large swing taken down, the move planned below PLAN_BELOW (5.1 s) and planned again
    "hard hit, its plan": ("mpc", {"theta1_0": math.radians(60.0)}, 6.0),
}


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("case", RUNS)
def test_the_native_mpc_equals_the_python_mpc_through_our_master(fmu_dir, native, case, version):
    """Every column of the run within 1e-9 (bit for bit on Linux); the MPC acts at its limit."""
    name, plant, stop_time = RUNS[case]
    system = systems.get(name)
    system = replace(system, parameters={**system.parameters, "plant": {**system.parameters["plant"], **plant}},
                     stop_time=stop_time)
    theirs = python_run_equal_to_native(system, fmu_dir, native, version)
    assert np.max(np.abs(theirs["controller.u"])) > 1.9  # at the drive's limit


@pytest.mark.parametrize("version", [2, 3])
def test_while_hoisting_the_native_mpc_equals_the_python_mpc_through_our_master(fmu_dir, native, version):
    """The board's S7 (the cable hoisted from 2 m to 1 m as the trolley moves, the MPC designing again for the
    cable's length it is told) over its first 4 s, in which the hoist ends: every column bit for bit on Linux. With
    the runs above, it stands for the MPC's rows of the board, which test_native_board.py runs without the MPC."""
    from crane_fmu.analysis import planar_scenarios as planar
    from crane_fmu.analysis import scenarios
    from crane_fmu.compare import contenders

    system = replace(scenarios.systems_for(contenders(["MpcController"], fmu_dir, only=True)[0], "S7")[0].system,
                     stop_time=4.0)
    assert system.instances["hoist"] == "TrajectoryPlanner"
    theirs = python_run_equal_to_native(system, fmu_dir, native, version)
    assert theirs["plant.l1_now"][-1] == pytest.approx(planar.HOIST["to"], abs=1e-3)  # hoisted within the run


def test_the_transport_run_hands_over_to_the_lqr_at_rest():
    """What the ``transport`` run above covers: the move over, at rest on the target, the MPC hands over to its LQR
    (the safety envelope), whose input it gives every step from then on."""
    _, _, state = mpc_loop({"theta1_0": 0.0}, {"x_d": 2.0}, 3.5, with_state=True)
    assert state[mpc.HEADER.handed] == 1.0 and state[mpc.HEADER.replans] == 0.0


def test_on_the_unknown_plant_the_mpc_identifies_it_and_plans_again():
    """What the ``unknown plant`` run above covers: within its first second the model is identified (the lengths
    within 1 %) and the move planned again from there."""
    _, _, state = mpc_loop({"theta1_0": 0.0, **MISMATCH}, {"x_d": 2.0}, 1.0, with_state=True)
    assert state[mpc.HEADER.l1] == pytest.approx(MISMATCH["l1"], rel=0.01)
    assert state[mpc.HEADER.l2] == pytest.approx(MISMATCH["l2"], rel=0.01)
    assert 0 < state[mpc.HEADER.plan_start] < 20  # planned again at an interval of the first second


@pytest.mark.parametrize("true", [MISMATCH, {"l1": 0.9, "l2": 0.6, "m2": 10.5}], ids=str)
def test_the_native_mpc_identifies_a_known_crane_within_1_percent(native, true):
    """The native MPC FMU on the native plant FMU (a crane it is not told: l1, l2, m2), called as a host calls
    them, 1 s of a 2 m move: its identified model, read from its serialised FMU state (the state's header as
    mpc.HEADER names it, found by its step count), is the true crane: both lengths and the payload's share
    m2 / (m1 + m2) within 1 % (the MPC keeps its configured m1 + m2 = 10 kg). No Python model is run."""
    plant, pvr, pset, pget = open_native(native[2] / "CranePlant.fmu", 2, {"theta1_0": 0.0, "u_max": 2.0,
                                                                          "v_max": 1.0, **true})
    control, cvr, cset, cget = open_native(native[2] / "MpcController.fmu", 2, {"x_d": 2.0})
    plant.exitInitializationMode()
    control.exitInitializationMode()
    names = [n for n in MPC.names("input") if n in pvr]  # the plant's outputs by name (F2_hat, F1_hat: none)
    measured = [pvr[n] for n in names]
    inputs = [cvr[n] for n in names]
    steps = 1000
    for k in range(steps):
        cset(inputs, pget(measured))
        pset([pvr["u"]], cget([cvr["u"]]))
        control.doStep(k * 1e-3, 1e-3)
        plant.doStep(k * 1e-3, 1e-3)
    saved = control.getFMUstate()
    data = bytes(control.serializeFMUstate(saved))
    control.freeFMUstate(saved)
    close(control)
    close(plant)
    doubles = np.frombuffer(data[16:16 + (len(data) - 16) // 8 * 8], dtype=np.float64)  # after "CRF1", mode, time
    at = np.flatnonzero(doubles == float(steps))
    assert len(at) == 1, at  # the header's step count, once
    header = doubles[at[0]:at[0] + len(mpc.HEADER)]
    share = header[mpc.HEADER.m2] / 10.0
    assert (header[mpc.HEADER.l1], header[mpc.HEADER.l2], share) == pytest.approx(
        (true["l1"], true["l2"], true["m2"] / (3.0 + true["m2"])), rel=0.01)


# ---- messages, rules, FMU states -----------------------------------------------------------------------------------

def test_at_its_cap_the_native_mpc_warns_once_as_the_python_fmu_does(fmu_dir, native):
    """One QP iteration allowed, from a 40 deg swing: three solves, each stopped at the cap, one warning, the same
    words; no step fails."""
    steps = [(0.0, 1e-3, {"theta1": math.radians(40.0)})] + [(k * 1e-3, 1e-3) for k in range(1, 120)]
    ours = messages(native[2] / "MpcController.fmu", {"max_iterations": 1.0}, steps, read_at_end=["iterations"])
    theirs = messages(fmu_dir / "MpcController.fmu", {"max_iterations": 1.0}, steps, read_at_end=["iterations"])
    assert ours == theirs
    assert ours[0][-1] == "end" and len(ours[1]) == 1 and "iteration cap (1) at t = 0.0 s" in ours[1][0]


REFUSED = [{"m2": -1.0}, {"q_theta1": NAN}, {"r": 0.0}, {"interval": INF}, {"horizon": -1.0}, {"replan_x": NAN},
           {"margin": 1.0}, {"max_iterations": 2.5}, {"max_iterations": 0.0}, {"max_iterations": INF},
           {"identify": INF}, {"x_d": NAN},
           {"u_max": 0.0}, {"v_max": INF}, {"horizon": 20.0}, {"interval": 0.004, "horizon": 0.4},
           {"l1_low": -1.0, "l1_high": 2.0}, {"l1_low": 1.0, "l1_high": 0.5}, {"offset_free": 3.0},
           {"offset_free": 0.5}, {"offset_free": 1.0, "m2": 0.0}]


@pytest.mark.parametrize("settings", REFUSED, ids=lambda c: ",".join(f"{k}={v!r}" for k, v in c.items()))
def test_every_parameter_refusal_has_the_python_fmus_rule_and_message(fmu_dir, native, settings):
    ours = messages(native[2] / "MpcController.fmu", settings)
    theirs = messages(fmu_dir / "MpcController.fmu", settings)
    assert ours == theirs
    assert ours[0][-2] == "exit: 3" and ours[1][-1].startswith("fmi2ExitInitializationMode: ")


@pytest.mark.parametrize("version", [2, 3])
def test_a_restored_fmu_state_repeats_the_steps_after_it(native, version):
    """Saved mid-move (a plan and a last solution in the state), restored, restored from its serialised copy."""
    fmu, vr, set_, get = open_native(native[version] / "MpcController.fmu", version, {"x_d": 1.0})
    fmu.exitInitializationMode()
    inputs, outputs = [vr[n] for n in MPC.names("input")], [vr[n] for n in MPC.names("output")]

    def steps(k0, n):
        rows = []
        for k in range(k0, k0 + n):
            set_(inputs, [0.3 * math.sin(k * 0.01 + i) for i in range(len(inputs) - 3)] + [0.0] * 3)  # l1_now, forces 0
            fmu.doStep(k * 1e-3, 1e-3)
            rows.append(get(outputs))
        return rows

    steps(0, 120)
    first, again, third = steps_after_restore(fmu, version, steps, 120, 160)
    close(fmu)
    assert first == again == third
    assert len({r[0] for r in first}) >= 3  # u, held over 50 steps, is solved again three times


# ---- Windows: the DLL under Wine ------------------------------------------------------------------------------------

@pytest.mark.parametrize("version", [2, 3])
def test_under_wine_the_windows_dll_plans_again_as_the_linux_one(native, windows_host, wine_env, tmp_path, version):
    """CraneMpcTransport pushed by a 2 N force on the hook that its model does not know: its plan made again (the
    deviation's rule) until the safety envelope hands over to the LQR (1.4 s), in the Windows DLL under Wine
    (portable sin and cos), give the Linux run of our master over the native FMUs: the states within 1e-9; u
    within 1e-9 relative while the MPC plans, within sum(|K|) 1e-9 once it has handed over to its LQR (u = -K s
    carries the states' 1e-9 agreement, each state's difference times its gain: |du| <= sum(|K|) max|ds|)."""
    name, stop_time = "mpc-transport", 4.0
    guid, vrs = unpack_one_fmu(native, name, tmp_path, version)
    fmu = one_fmu(native, name, version)
    dll = tmp_path / "binaries" / BINARIES[version][1] / f"{one_fmu_name(name)}.dll"
    if not dll.exists():
        pytest.skip("the one-FMU has no Windows binary (mingw-w64 missing at build time)")
    shutil.copy(windows_host, tmp_path)
    shutil.copy(dll, tmp_path)
    force = next(v.valueReference for v in read_model_description(str(fmu)).modelVariables if v.name == "F1")
    step = systems.get(name).step
    windows = host_rows(["wine", tmp_path / "host.exe", HOST_COMMAND[version]], dll.name, guid, round(stop_time / step),
                   step, f"{force}=2.0", *vrs, env=wine_env, cwd=tmp_path)
    linux = master_run(native, name, ["plant.F1=2.0"], stop_time, tmp=tmp_path)
    expected = observed_columns(linux, name)
    assert windows.shape == expected.shape
    assert np.max(np.abs(windows[:, :4] - expected[:, :4])) <= 1e-9
    gains = mpc.COMPONENT.check({**systems.get(name).parameters["controller"], "h": step}).lqr.gains
    handed = _handover_step(name, stop_time, step, 2.0)
    assert 0 < handed < len(expected)  # the LQR's in the run's end
    relative = np.abs(windows[:, 4] - expected[:, 4]) / np.maximum(np.abs(expected[:, 4]), 1.0)
    assert np.max(relative[:handed]) <= 1e-9
    assert np.max(np.abs(windows[handed:, 4] - expected[handed:, 4])) <= sum(map(abs, gains)) * 1e-9
    assert len(set(linux["controller.plan_end"][:handed])) > 1  # planned again, then handed over (the envelope)


def _handover_step(name, stop_time, step, force):
    """The first row of the system's run (the Python models called as our master calls them), the hook pushed by
    ``force`` [N], whose u is the LQR's: the MPC's state after the solve that handed over."""
    from crane_fmu.model import plant
    from crane_fmu.model.component import Step

    parameters = systems.get(name).parameters
    pc = plant.configure({**plant.COMPONENT.defaults(), **parameters["plant"]})
    cc = mpc.configure({**mpc.COMPONENT.defaults(), "h": step, **parameters["controller"]})
    ps, cs = pc.state0, mpc.initial_state(cc)
    for k in range(round(stop_time / step) + 1):
        out = plant.COMPONENT.output(pc, ps, (0.0, 0.0, force, 0.0))
        inputs = tuple(out[:6]) + (out[11], 0.0, 0.0)
        u = mpc.COMPONENT.output(cc, cs, inputs)[0]
        cs = mpc.update(cc, cs, inputs, k * step, step)
        cs = cs.state if isinstance(cs, Step) else cs
        if cs[mpc.HEADER.handed]:
            return k
        ps = plant.update(pc, ps, (u, 0.0, force, 0.0), k * step, step)
    return None


# ---- the estimated forces (offset-free, issue 51 item 3) ------------------------------------------------------------

@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("offset_free", [0.0, 1.0, 2.0], ids=["off", "load", "trolley"])
def test_told_the_forces_the_native_mpc_gives_the_python_mpcs_bits(native, offset_free, version):
    """The native MpcController FMU and the Python model, fed the same inputs step by step (a host's loop): the
    Python plant pushed by 2 N on the payload and 0.5 N on the hook, driven by the Python MPC, its state and
    F2_hat, F1_hat (the true forces after 0.3 s, a step as an estimate's) given to both. Each step's outputs bit
    for bit on Linux: the QP's error about the forces' rest, the handover to the LQR (which the pushed move makes,
    the safety envelope) and the LQR's target told the forces."""
    from crane_fmu.model import plant as plant_model

    values = {"x_d": 1.0, "offset_free": offset_free}
    fmu, vr, set_, get = open_native(native[version] / "MpcController.fmu", version, values)
    fmu.exitInitializationMode()
    names, outputs = MPC.names("input"), [vr[n] for n in MPC.names("output")]
    pc = plant_model.configure({**plant_model.COMPONENT.defaults(), "u_max": 2.0, "v_max": 1.0, "theta1_0": 0.0})
    cc = MPC.check({**values, "h": 1e-3})
    ps, cs, ours, theirs, handed = pc.state0, mpc.initial_state(cc), [], [], None
    pushes = (0.0, 0.0, 0.5, 2.0)  # u, F_hoist, F1 (hook), F2 (payload)
    for k in range(5000):  # the forces leave the data unexplained: cautious plans, their plans for a deviation run
        # out, the held one tracked to its end: handed over at 3.9 s (off), 2.9 s (load), 2.8 s (trolley)
        out = plant_model.COMPONENT.output(pc, ps, pushes)
        forces = (2.0, 0.5) if k >= 300 else (0.0, 0.0)
        inputs = tuple(out[:6]) + (0.0,) + forces
        assert tuple(names[-3:]) == ("l1_now", "F2_hat", "F1_hat")
        set_([vr[n] for n in names], list(inputs))
        ours.append(get(outputs))
        theirs.append(MPC.output(cc, cs, inputs))
        fmu.doStep(k * 1e-3, 1e-3)
        cs = mpc.update(cc, cs, inputs, k * 1e-3, 1e-3)
        cs = getattr(cs, "state", cs)
        if handed is None and cs[mpc.HEADER.handed]:
            handed = k
        ps = plant_model.update(pc, ps, (theirs[-1][0], 0.0, 0.5, 2.0), k * 1e-3, 1e-3)
    close(fmu)
    compare_to_python(ours, theirs)
    assert handed is not None and 300 < handed < 4900  # the QP told the forces, then the LQR told them


def _s9_case_residual(native, controller, law=None, case="#54", scenario="S9"):
    """The residual swing [deg] of one of S9's cases (only x and theta1 measured, a StateEstimator of the configured
    crane in front of the controller, the plant another; or another ``scenario``'s) run on the native FMUs, the
    controller's FMU or ``law``."""
    return _s9_case_run(native, controller, law, case, scenario)[0]


def _s9_case_run(native, controller, law=None, case="#54", scenario="S9", figure="residual_deg"):
    """``(residual [deg], the run's columns)`` of :func:`_s9_case_residual` (or of another ``scenario``'s case, or
    another of :func:`.metrics.move_metrics`' ``figure``)."""
    from crane_fmu.analysis import metrics, scenarios
    from crane_fmu.compare import contenders
    from crane_fmu.cosim import ArrayRecorder, simulate

    run = next(r for r in scenarios.systems_for(contenders([controller], native[2], only=True)[0], scenario)
               if r.label == case or r.label.startswith(case + " "))
    fmus, connections = systems.resolve(run.system, native[2])
    if law:
        fmus["controller"] = law
    recorder = ArrayRecorder()
    simulate(fmus, connections, run.stop_time, run.step, "gauss-seidel",
             parameters=systems.prepare(run.system, run.step, run.stop_time, check=False).parameters,
             recorder=recorder)
    columns = recorder.columns()
    s = metrics.crane_signals(columns)
    return metrics.move_metrics(s["time"], s["position"], s["velocity"], list(s["swing"].values()), s["demand"],
                                run.x_d, run.residual_from)[figure], columns


def _python_mpc_law(tmp_path):
    """The Python MPC of this process as a law (``FILE.py:COMPONENT``) for :func:`_s9_case_run`."""
    law = tmp_path / "mpc_law.py"
    law.write_text("from crane_fmu.model.mpc import COMPONENT  # noqa: F401\n")
    return f"{law}:COMPONENT"


def _native_and_python_bit_for_bit(native, tmp_path, case, scenario="S9", figure="residual_deg"):
    """``(figure, Python law)`` of one case of the native MPC, after checking that the Python MPC (the law) gives the
    same figure and the native MPC's input bit for bit (on Linux)."""
    value, ours = _s9_case_run(native, "MpcController", case=case, scenario=scenario, figure=figure)
    law = _python_mpc_law(tmp_path)
    python_value, theirs = _s9_case_run(native, "MpcController", law, case=case, scenario=scenario, figure=figure)
    assert python_value == value
    compare_to_python(ours["controller.u"], theirs["controller.u"])
    return value, law


@pytest.mark.parametrize("form", ["native", "python"])
def test_behind_an_estimator_of_another_crane_the_mpc_leaves_no_more_swing_than_the_lqr(native, tmp_path, form,
                                                                                        monkeypatch):
    """S9's case #54 (plant l1 = 0.905 m, l2 = 0.548 m, m1 = 3.56 kg, m2 = 3.79 kg; the estimator and the MPC told
    the configured crane): the MPC's shortest move left the payload swinging 2.04 deg against the LQR's 0.82 deg
    (the board before the cautious plan). The estimate's misfit turns the MPC cautious within 0.3 s: its residual is
    within the envelope's 0.05 deg of the LQR's (issue 51, item 2). ``python``: the Python MPC in this process, and
    without the cautious plan (CAUTIOUS_STRETCH 1) the case fails the envelope: the rule is what acts."""
    from crane_fmu.analysis.envelope import RESIDUAL_MARGIN

    law = _python_mpc_law(tmp_path) if form == "python" else None
    lqr = _s9_case_residual(native, "LqrController")
    assert _s9_case_residual(native, "MpcController", law) <= lqr + RESIDUAL_MARGIN
    if form == "python":
        monkeypatch.setattr(mpc, "CAUTIOUS_STRETCH", 1.0)
        assert _s9_case_residual(native, "MpcController", law) > lqr + RESIDUAL_MARGIN


@pytest.mark.parametrize("form", ["native", "python"])
def test_behind_an_estimator_the_cautious_plan_leaves_no_fast_swing_on_another_crane(native, tmp_path, form,
                                                                                      monkeypatch):
    """S9's case #48 (plant l1 = 0.944 m, l2 = 0.565 m, m1 = 3.45 kg, m2 = 4.03 kg; the estimator and the MPC told
    the configured crane): the cautious plan of the configured crane alone left 0.596 deg (the MPC's worst of S9
    before), the fast swing mode the estimator cannot see. Robust to the cranes at the corners of mpc.SPREAD
    (mpc.robust_ends), its residual is within S9's 0.1 deg target. ``python``: the Python MPC in this process gives
    the native MPC's input bit for bit (on Linux) through the whole run, the cautious plan's robust QPs included; and
    without the corners (no ROBUST_WEIGHTS) the case misses the target: the robust plan is what acts."""
    from crane_fmu.analysis.scenarios import STOPPED_DEG

    if form == "native":
        assert _s9_case_residual(native, "MpcController", case="#48") <= STOPPED_DEG
    else:
        residual, law = _native_and_python_bit_for_bit(native, tmp_path, "#48")
        assert residual <= STOPPED_DEG
        monkeypatch.setattr(mpc, "ROBUST_WEIGHTS", ())
        assert _s9_case_residual(native, "MpcController", law, case="#48") > STOPPED_DEG


@pytest.mark.parametrize("form", ["native", "python"])
def test_told_its_state_is_an_estimators_the_mpc_turns_cautious_in_time_for_the_fast_swing(native, tmp_path, form,
                                                                                          monkeypatch):
    """S9's case #61 (plant l1 = 1.095 m, l2 = 0.530 m, m1 = 3.57 kg, m2 = 5.16 kg; the estimator and the MPC told
    the configured crane): the estimate's misfit passed mpc.UNEXPLAINED only at 0.2 s, and the shortest move's 50 ms
    more left 0.146 deg of residual swing (the MPC's worst of S9, against the 0.1 deg target). Told its state is a
    StateEstimator's (estimated = 1, set by S8's and S9's systems), the MPC turns cautious once the data give no model
    (mpc.MISFIT), at 0.15 s: within the target. ``python``: the Python MPC gives the native MPC's input bit for bit (on
    Linux), and judging its data as without an estimator (estimated 0) it misses the target: the rule is what acts."""
    from crane_fmu.analysis.scenarios import STOPPED_DEG

    if form == "native":
        assert _s9_case_residual(native, "MpcController", case="#61") <= STOPPED_DEG
    else:
        residual, law = _native_and_python_bit_for_bit(native, tmp_path, "#61")
        assert residual <= STOPPED_DEG
        identify = mpc.identify
        monkeypatch.setattr(mpc, "identify", lambda c, *rest: identify(c._replace(estimated=0.0), *rest))
        assert _s9_case_residual(native, "MpcController", law, case="#61") > STOPPED_DEG


@pytest.mark.parametrize("case", ["#24", "#54"])
def test_in_the_wind_the_mpc_whose_plans_for_a_deviation_run_out_leaves_no_more_swing_than_the_lqr(native, tmp_path,
                                                                                                  case):
    """S10's cases #24 and #54 (turbulent wind, plants unknown to the controller; found on the board before S10 ran
    the controllers offset-free, and since held there as the board runs them): the wind makes the MPC plan again
    for a deviation until its plans run out (mpc.MOST_REPLANS), mid-move at 1.95 s and 1.1 s. Handed over to its
    LQR there, at speed, the MPC left 1.341 and 0.657 deg of residual swing against the LQR's 1.288 and 0.584 deg
    (0.074 and 0.053 deg more: beyond the envelope's 0.05 deg). Tracking the held plan to its end first, it is
    within the envelope (issue 51, item 2); the Python MPC gives the native MPC's input bit for bit (on Linux)."""
    from crane_fmu.analysis.envelope import RESIDUAL_MARGIN

    lqr = _s9_case_residual(native, "LqrController", case=case, scenario="S10")
    residual, _ = _native_and_python_bit_for_bit(native, tmp_path, case, scenario="S10")
    assert residual <= lqr + RESIDUAL_MARGIN


@pytest.mark.parametrize("case", ["#04", "#43"])
def test_on_a_crane_that_swings_more_the_mpcs_later_plans_stay_within_its_first_plans_swing(native, tmp_path, case,
                                                                                            monkeypatch):
    """S3's cases #04 (l2 = 0.433 m) and #43 (l1 = 1.071 m, l2 = 0.494 m), plants unknown to the MPC: the shortest
    move planned again with the identified crane at 0.3 s swung to 17.85 and 17.98 deg, past the envelope's bound
    (the MPC's own S2 peak plus 2 deg, 17.85 deg; issue 51, item 2). A plan after the first swings at most
    mpc.PEAK_ALLOWANCE more than the first (a longer move): within the bound, the Python MPC bit for bit with the
    native one (on Linux); without the allowance (infinite) the Python MPC's peak is past the bound again."""
    from crane_fmu.analysis.envelope import PEAK_MARGIN

    nominal, _ = _s9_case_run(native, "MpcController", case="nominal", scenario="S2", figure="peak_swing_deg")
    peak, law = _native_and_python_bit_for_bit(native, tmp_path, case, scenario="S3", figure="peak_swing_deg")
    assert peak <= nominal + PEAK_MARGIN
    monkeypatch.setattr(mpc, "PEAK_ALLOWANCE", math.inf)
    assert _s9_case_run(native, "MpcController", law, case=case, scenario="S3",
                        figure="peak_swing_deg")[0] > nominal + PEAK_MARGIN
