"""The native (C) Wind FMU against its specification, crane_fmu/model/wind.py.

Built by the session's ``fmu_dir`` fixture into ``build/native`` beside the Python FMUs. On Linux (glibc's libm in
both, the same operations in the same order, noise.h's noise of the same seed) the native outputs are the Python
ones bit for bit. The Windows DLL under Wine: test_native_components.py's C host (HOST_CASES).
"""

import math
import random
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest
import scipy.signal
from fmpy import read_model_description
from fmpy.validation import validate_fmu
from native_fmus import (
    close,
    compare_to_python,
    compiler,
    messages,
    open_native,
    outputs_beside_python,
    python_folder,
    steps_after_restore,
)

from crane_fmu import components
from crane_fmu.analysis.scenarios import Contender, systems_for
from crane_fmu.build_scripts.native import FOLDERS, source_path, variables_header
from crane_fmu.cosim import run

WIND = components.get("Wind")
LINUX = sys.platform.startswith("linux")  # glibc's libm in both models: the same bits
INF, NAN = float("inf"), float("nan")


@pytest.mark.parametrize("version", [2, 3])
def test_native_model_description_has_the_python_fmus_variables(fmu_dir, native, version):
    """Names, value references, causalities, start values, units, descriptions; fmpy's validation is clean."""
    def variables(path):
        return [(v.name, v.valueReference, v.causality, v.variability, v.initial, v.start, v.unit, v.description)
                for v in read_model_description(str(path)).modelVariables]

    assert variables(native[version] / "Wind.fmu") == variables(python_folder(fmu_dir, version) / "Wind.fmu")
    assert validate_fmu(str(native[version] / "Wind.fmu")) == []


@pytest.mark.parametrize("own_math", [False, True], ids=["libm", "portable"])
def test_the_model_file_compiles_without_warnings_under_strict_flags(tmp_path, own_math):
    """ISO C99, -Wall -Wextra -Werror (less unused parameters), with the C library's math and the portable one."""
    flags = ["-c", "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Wno-unused-parameter", "-Werror",
             *(["-DCRANE_OWN_MATH"] if own_math else [])]
    (tmp_path / "Wind_variables.h").write_text(variables_header(WIND))
    subprocess.run([compiler(), *flags, f"-I{tmp_path}", *(f"-I{folder}" for folder in FOLDERS),
                    str(source_path("wind.c")), "-o", str(tmp_path / "m.o")], check=True)


def _parameters(rng, i):
    return {"U_mean": rng.choice([rng.uniform(-15, 15), 10.0]), "sigma": rng.choice([0.0, rng.uniform(0, 4)]),
            "L": rng.uniform(1, 300), "rho": rng.uniform(1, 1.3), "Cd": rng.uniform(0.5, 2),
            "A1": rng.uniform(0, 0.1), "A2": rng.uniform(0, 0.5), "l1": rng.uniform(0.2, 5),
            "l2": rng.uniform(0.1, 3), "seed": float(rng.choice([0, 1, 2 ** 32 - 1, rng.randrange(2 ** 32)]))}


@pytest.mark.parametrize("version", [2, 3])
def test_outputs_equal_the_python_model_over_random_steps(native, version):
    """8 parameter sets (no turbulence too, a wind against the move, the extreme seeds) x 50 steps of random length
    and inputs: the drag, the wind and the noise sequence of the seed are the Python model's."""
    rng = random.Random(2038)
    n_inputs = len(WIND.names("input"))
    ours, theirs = outputs_beside_python(native[version] / "Wind.fmu", version, WIND,
                                         (_parameters(rng, i) for i in range(8)), 50,
                                         lambda rng: [rng.uniform(-2, 2) for _ in range(n_inputs)], rng, 0.5)
    compare_to_python(ours, theirs)
    speeds = np.array(theirs)[:, 2].reshape(8, 50)
    assert sum(len(set(row)) > 40 for row in speeds) >= 4  # turbulent sets: the wind moves at every step


REFUSED = [{"U_mean": NAN}, {"l1": INF}, {"l2": -INF}, {"sigma": -1.0}, {"rho": NAN}, {"Cd": -1e-3}, {"A1": INF},
           {"A2": -1.0}, {"L": 0.0}, {"L": INF}, {"U_mean": 0.0}, {"U_mean": -0.0, "sigma": 1e-300}, {"seed": 1.5},
           {"seed": -1.0}, {"seed": 2.0 ** 32}, {"seed": NAN}, {"sigma": -1.0, "L": 0.0}]


@pytest.mark.parametrize("settings", REFUSED, ids=lambda c: ",".join(f"{k}={v!r}" for k, v in c.items()))
def test_every_parameter_refusal_has_the_python_fmus_rule_and_message(fmu_dir, native, settings):
    ours = messages(native[2] / "Wind.fmu", settings)
    theirs = messages(fmu_dir / "Wind.fmu", settings)
    assert ours == theirs
    assert ours[0][-2] == "exit: 3" and ours[1][-1].startswith("fmi2ExitInitializationMode: ")


def test_no_turbulence_needs_no_mean_wind(fmu_dir, native):
    """U_mean = 0 with sigma = 0 passes (still air: no time constant needed), in both FMUs alike."""
    settings = {"U_mean": 0.0, "sigma": 0.0}
    ours = messages(native[2] / "Wind.fmu", settings, steps=[(0.0, 0.1)], read_at_end=["F1", "F2", "wind"])
    assert ours == messages(fmu_dir / "Wind.fmu", settings, steps=[(0.0, 0.1)], read_at_end=["F1", "F2", "wind"])
    assert ours[0] == ["end"]


@pytest.mark.parametrize("version", [2, 3])
def test_fmu_state_saved_serialised_and_restored_repeats_the_steps_exactly(native, version):
    """The wind's state is its sample count and turbulence: restored, the same noise follows."""
    fmu, vr, set_, get = open_native(native[version] / "Wind.fmu", version, {"seed": 11.0})
    fmu.exitInitializationMode()
    outputs = [vr[n] for n in WIND.names("output")]

    def steps(k0, n):
        rows = []
        for k in range(k0, k0 + n):
            fmu.doStep(k * 1e-2, 1e-2)
            rows.append(get(outputs))
        return rows

    steps(0, 20)
    first, again, third = steps_after_restore(fmu, version, steps, 20, 30)
    close(fmu)
    assert first == again == third
    assert len({r[-1] for r in first}) == 30  # a new wind at every step


@pytest.mark.parametrize("version", [2, 3])
def test_the_scoreboards_wind_case_on_native_fmus_equals_the_python_fmus(fmu_dir, native, version):
    """S10's first paired case (its plant, its seed), the EnergyController in the loop, 3 s at 1 ms through our
    master: every recorded signal of the native run within 1e-9 of the Python FMUs' run (on Linux: equal)."""
    energy = components.get("EnergyController")
    contender = Contender("EnergyController", "EnergyController", energy.names("input"), energy.names("parameter"))
    system = replace(systems_for(contender, "S10", cases=2)[0].system, stop_time=3.0)
    ours, theirs = run(system, native[version]).columns(), run(system, python_folder(fmu_dir, version)).columns()
    assert list(ours) == list(theirs) and len(theirs["time"]) == 3001
    worst = max(float(np.max(np.abs(ours[k] - theirs[k]))) for k in theirs)
    assert worst <= 1e-9
    if LINUX:
        assert worst == 0.0
    assert np.std(theirs["wind.wind"]) > 0.05 and np.max(np.abs(theirs["wind.F2"])) > 0.1  # turbulent, and pushing


# ---- the native FMU against the Dryden closed forms, no Python model in between ------------------------------------

DRYDEN = {"U_mean": 10.0, "L": 1.0, "sigma": 2.0, "seed": 3.0}  # T = L / U = 0.1 s: many time constants per second
DRYDEN_H, DRYDEN_N = 0.01, 100_000


@pytest.fixture(scope="module")
def native_turbulence(native):
    """The native Wind FMU's turbulence (its wind speed less U_mean) at 100 001 samples, h = 10 ms, bodies at rest."""
    fmu, vr, set_, get = open_native(native[2] / "Wind.fmu", 2, DRYDEN)
    fmu.exitInitializationMode()
    wind = [vr["wind"]]
    speeds = [get(wind)[0]]
    for k in range(DRYDEN_N):
        fmu.doStep(k * DRYDEN_H, DRYDEN_H)
        speeds.append(get(wind)[0])
    close(fmu)
    return np.array(speeds) - DRYDEN["U_mean"]


def test_the_native_winds_variance_and_correlation_are_drydens(native_turbulence):
    """Dryden's turbulence sampled exactly is an AR(1) with a = exp(-h / T) = exp(-0.1): variance sigma^2 (standard
    error of the sample variance sigma^2 sqrt(2 (1 + a^2) / (N (1 - a^2))) = 2 %; 4 allowed), mean 0 within 4
    standard errors sigma sqrt((1 + a) / (N (1 - a))), and the correlation at lag k a^k (k = 1, 5, 20; standard
    error about sqrt((1 + a^2) / (N (1 - a^2))) = 1 %; 0.04 allowed)."""
    w = native_turbulence
    a, n, var = math.exp(-DRYDEN_H * DRYDEN["U_mean"] / DRYDEN["L"]), len(w), DRYDEN["sigma"] ** 2
    assert abs(w.var() - var) <= 4 * var * math.sqrt(2 * (1 + a * a) / (n * (1 - a * a)))
    assert abs(w.mean()) <= 4 * DRYDEN["sigma"] * math.sqrt((1 + a) / (n * (1 - a)))
    for lag in (1, 5, 20):
        assert np.mean(w[lag:] * w[:-lag]) / w.var() == pytest.approx(a ** lag, abs=0.04)


def test_the_native_winds_spectrum_is_drydens(native_turbulence):
    """Welch's estimate (segments of 4096 samples, 48 of them) against 4 sigma^2 T / (1 + (2 pi f T)^2) from 0.05 Hz
    to 10 Hz (a fifth of Nyquist: not folded yet): the log-PSDs correlate >= 0.95 and their mean log ratio is 0
    within 0.1 (each Welch point has a standard error of about 1/sqrt(48); the band averages 400 of them)."""
    f, measured = scipy.signal.welch(native_turbulence, fs=1 / DRYDEN_H, nperseg=4096)
    band = (f >= 0.05) & (f <= 10.0)
    t = DRYDEN["L"] / DRYDEN["U_mean"]
    dryden = 4 * DRYDEN["sigma"] ** 2 * t / (1 + (2 * math.pi * f[band] * t) ** 2)
    assert np.corrcoef(np.log(measured[band]), np.log(dryden))[0, 1] >= 0.95
    assert abs(np.mean(np.log(measured[band] / dryden))) <= 0.1
