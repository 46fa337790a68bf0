"""The native FMUs where they will run: a C host with no Python, Windows x64 under Wine, long-lived hosts.

``fmu_src/host/host.c`` (a host with no model of its own: it reads and sets the value references it is
given) is compiled for Linux and, with mingw-w64, for Windows. It runs Section V without Python: the
native plant with the native BacksteppingController FMU (``pair``), exchanged by value references at
each step as our master does; likewise the ``lqr`` system with the native LqrController. On Linux they
give our master's run of the Python FMUs. Tests that need mingw-w64 or Wine skip where they are
missing; ``.ci/run`` installs both.
"""

import glob
import os
import shutil
import subprocess
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description
from helpers import FREE_SWING_MAX_THETA2_DEG
from native_fmus import compiler

from crane_fmu import systems
from crane_fmu.build_scripts.native import HOST
from crane_fmu.build_scripts.wrapper import fmi_headers
from crane_fmu.cosim import run
from crane_fmu.model.tables import STATE

CLEAN_ENV = {"PATH": "/usr/bin:/bin"}  # what `env -i PATH=/usr/bin:/bin` leaves: no venv, no pyenv



@pytest.fixture(scope="module")
def plant(native, tmp_path_factory):
    """The unpacked native FMI 2.0 FMU: ``(folder, guid)``; the host's value references checked against it."""
    fmu = native[2] / "CranePlant.fmu"
    folder = tmp_path_factory.mktemp("plant")
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    assert [vr[s] for s in STATE] == list(range(vr["x"], vr["x"] + 6))  # what the host reads from X
    return folder, md.guid, vr


@pytest.fixture(scope="module")
def controller(native, tmp_path_factory):
    """The unpacked native BacksteppingController (FMI 2.0): ``(folder, guid, x, u)``; its measured states checked."""
    fmu = native[2] / "BacksteppingController.fmu"
    folder = tmp_path_factory.mktemp("controller")
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    assert [vr[s] for s in STATE] == list(range(vr["x"], vr["x"] + 6))  # what the host's pair expects
    return folder, md.guid, vr["x"], vr["u"]


@pytest.fixture(scope="module")
def lqr(native, tmp_path_factory):
    """The unpacked native LqrController (FMI 2.0): ``(folder, guid)``; its x and u for ``host pair ... CX CU``."""
    fmu = native[2] / "LqrController.fmu"
    folder = tmp_path_factory.mktemp("lqr")
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    assert [vr[s] for s in STATE] == list(range(vr["x"], vr["x"] + 6))  # what host.c's pair expects
    return folder, md.guid, vr["x"], vr["u"]


@pytest.fixture(scope="module")
def lqr_run(fmu_dir):
    """Our master's run of the ``lqr`` system on the Python FMUs: ``[t, 6 states, u]`` rows, 20 s at 1 ms."""
    columns = run(systems.get("lqr"), fmu_dir).columns()
    return np.column_stack([columns["time"]] + [columns[f"plant.{s}"] for s in STATE] + [columns["controller.u"]])


def _rows(text):
    return np.array([[float(x) for x in line.split(",")] for line in text.replace("\r", "").splitlines()])


def _loop(plant, controller):
    """The host's ``pair`` arguments after STEPS and H: the plant's x and u, the controller's x and u."""
    return plant[2]["x"], plant[2]["u"], controller[2], controller[3]


def _host(host, *args, env=None, cwd=None, wine=None, timeout=300):
    command = [*wine, str(host)] if wine else [str(host)]
    done = subprocess.run([*command, *map(str, args)], capture_output=True, text=True, env=env, cwd=cwd,
                          timeout=timeout)
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout


@pytest.fixture(scope="module")
def section5(fmu_dir, native):
    """Our master's Section V run of the Python plant and controller FMUs: ``[t, 6 states, u]`` rows, 20 s at 1 ms
    (only where the native FMUs it is compared with were built)."""
    columns = run(systems.get("paper"), fmu_dir).columns()
    return np.column_stack([columns["time"]] + [columns[f"plant.{s}"] for s in STATE] + [columns["controller.u"]])


# ---- Linux: no Python at all -----------------------------------------------------------------------------------

def test_the_linux_binary_needs_no_libpython(plant):
    library = plant[0] / "binaries" / "linux64" / "CranePlant.so"
    needed = subprocess.run(["readelf", "-d", str(library)], capture_output=True, text=True, check=True).stdout
    assert "NEEDED" in needed and "python" not in needed.lower()
    undefined = subprocess.run(["nm", "-D", "--undefined-only", str(library)], capture_output=True, text=True,
                               check=True).stdout
    assert not [line for line in undefined.splitlines() if " Py" in line or " _Py" in line]


def test_c_host_without_python_runs_the_free_swing(host, plant):
    """``env -i PATH=/usr/bin:/bin``, no libpython loaded in the process; max theta2 15.5976 deg as the Python FMU."""
    folder, guid, vr = plant
    library = folder / "binaries" / "linux64" / "CranePlant.so"
    assert _host(host, "maps", library, guid, env=CLEAN_ENV) == ""  # no library naming python in the process
    rows = _rows(_host(host, "run", library, guid, 20_000, 1e-3, vr["x"], env=CLEAN_ENV))
    assert rows.shape == (20_001, 7)
    assert np.degrees(rows[:, 5].max()) == pytest.approx(FREE_SWING_MAX_THETA2_DEG, abs=5e-5)


def _libpythons():
    """Every libpython the dynamic linker knows (ldconfig -p), in the usual folders and under pyenv."""
    cache = subprocess.run(["ldconfig", "-p"], capture_output=True, text=True).stdout
    paths = [line.split(" => ")[-1] for line in cache.splitlines() if "libpython" in line]
    for pattern in ("/usr/lib/*/libpython3*.so*", "/usr/lib/libpython3*.so*", "/usr/local/lib/libpython3*.so*",
                    os.path.expanduser("~/.pyenv/versions/*/lib/libpython3*.so*")):
        paths += glob.glob(pattern)
    return sorted({os.path.realpath(p) for p in paths if os.path.exists(p)})


def test_c_host_runs_with_every_libpython_hidden(host, plant, tmp_path):
    """Each libpython on this machine is covered by /dev/null in a private mount namespace (unshare, as root)."""
    hidden = _libpythons()
    if not hidden or shutil.which("unshare") is None or os.geteuid() != 0:
        pytest.skip("needs root, unshare and a libpython to hide")
    folder, guid, vr = plant
    library = folder / "binaries" / "linux64" / "CranePlant.so"
    script = "".join(f"mount --bind /dev/null '{path}' && [ ! -s '{path}' ] && " for path in hidden)  # now empty
    script += f"exec '{host}' run '{library}' '{guid}' 20000 0.001 {vr['x']}"
    done = subprocess.run(["unshare", "--mount", "--propagation", "private", "sh", "-c", script],
                          capture_output=True, text=True, env=CLEAN_ENV, timeout=300)
    if done.returncode != 0 and "unshare" in done.stderr:
        pytest.skip(f"no mount namespace here: {done.stderr.strip()[:200]}")
    assert done.returncode == 0, done.stderr[-2000:]
    rows = _rows(done.stdout)
    assert np.degrees(rows[:, 5].max()) == pytest.approx(FREE_SWING_MAX_THETA2_DEG, abs=5e-5)


def test_c_host_runs_section5_on_the_native_plant_and_controller_fmus(host, plant, controller, section5):
    """The two native FMUs exchanged by value references in the C host, no Python: the Python pair's run, 1e-9."""
    rows = _rows(_host(host, "pair", plant[0] / "binaries" / "linux64" / "CranePlant.so", plant[1],
                       controller[0] / "binaries" / "linux64" / "BacksteppingController.so", controller[1], 20_000,
                       1e-3, *_loop(plant, controller), env=CLEAN_ENV))
    assert rows.shape == section5.shape
    assert np.max(np.abs(rows - section5)) <= 1e-9  # in practice 0


def test_c_host_runs_the_lqr_system_on_the_native_plant_and_lqr_fmus(host, plant, lqr, lqr_run):
    """The LQR designed inside its FMU, no Python in the process: the Python FMUs' run through our master, 1e-9."""
    rows = _rows(_host(host, "pair", plant[0] / "binaries" / "linux64" / "CranePlant.so", plant[1],
                       lqr[0] / "binaries" / "linux64" / "LqrController.so", lqr[1], 20_000, 1e-3, *_loop(plant, lqr),
                       env=CLEAN_ENV))
    assert rows.shape == lqr_run.shape
    assert np.max(np.abs(rows - lqr_run)) <= 1e-9  # in practice 0


# ---- long-lived hosts -----------------------------------------------------------------------------------------

def test_ten_thousand_instances_in_one_process_leave_memory_flat(host, plant):
    """10,000 instantiate/initialise/10 steps/free cycles: resident memory after 2,000 and after 10,000 cycles.

    From 2,000 on: the host's first line of output (at 1,000) allocates stdout's buffer, a one-off step.
    """
    folder, guid, vr = plant
    out = _host(host, "cycles", folder / "binaries" / "linux64" / "CranePlant.so", guid, 10_000, vr["x"])
    rss = dict(tuple(map(int, line.split(","))) for line in out.splitlines())
    assert len(rss) == 10
    # an instance is about 0.5 kB: a leak of one per cycle would add 4 MB over 8,000 cycles
    assert rss[10_000] - rss[2_000] <= 64


def test_a_run_after_a_failed_run_in_the_same_process_is_a_fresh_run(host, plant):
    folder, guid, vr = plant
    library = folder / "binaries" / "linux64" / "CranePlant.so"
    after = _rows(_host(host, "after-failure", library, guid, 1000, 1e-3, vr["x"], f"{vr['l1']}=-1"))
    fresh = _rows(_host(host, "run", library, guid, 1000, 1e-3, vr["x"]))
    assert np.array_equal(after[-1], fresh[-1])


def test_two_instances_in_two_threads_give_the_results_of_one(host, plant):
    folder, guid, vr = plant
    assert _host(host, "threads", folder / "binaries" / "linux64" / "CranePlant.so", guid, 20_000, 1e-3,
                 vr["x"]) == "same\n"


# ---- Windows x64 under Wine -------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def wine(plant, controller, lqr, windows_host, wine_env, tmp_path_factory):
    """``(wine command, folder with host.exe and the DLLs of the plant, controller and LQR, environment)``."""
    folder = tmp_path_factory.mktemp("windows")
    shutil.copy(windows_host, folder)
    shutil.copy(plant[0] / "binaries" / "win64" / "CranePlant.dll", folder)
    shutil.copy(controller[0] / "binaries" / "win64" / "BacksteppingController.dll", folder)
    shutil.copy(lqr[0] / "binaries" / "win64" / "LqrController.dll", folder)
    return ["wine"], folder, wine_env


def test_the_windows_dll_needs_only_system_dlls(plant):
    if shutil.which("x86_64-w64-mingw32-objdump") is None:
        pytest.skip("needs mingw-w64's objdump")
    dump = subprocess.run(["x86_64-w64-mingw32-objdump", "-p", str(plant[0] / "binaries" / "win64" / "CranePlant.dll")],
                          capture_output=True, text=True, check=True).stdout
    dlls = {line.split()[-1].lower() for line in dump.splitlines() if "DLL Name:" in line}
    assert dlls <= {"kernel32.dll", "msvcrt.dll"}, dlls


def test_windows_dlls_under_wine_give_the_linux_section5_run(wine, plant, controller, section5, tmp_path):
    """Section V on the plant and controller DLLs in the Windows host under Wine: the Linux results to 1e-9 at
    every step of the 20 s.

    The Windows build uses the portable sin, cos and exp (mingw-w64's libm is the x87's), the Linux
    one glibc's: they differ in a rare last bit, which the run carries to about 1e-11 in the states
    and 1.2e-9 in u (|u| reaches 810 m/s2: 4e-10 relative). Built from the same math source (the
    FMUs' sources with CRANE_OWN_MATH), Linux gives Windows' bits exactly.
    """
    command, folder, env = wine
    windows = _rows(_host(folder / "host.exe", "pair", "CranePlant.dll", plant[1], "BacksteppingController.dll",
                          controller[1], 20_000, 1e-3, *_loop(plant, controller), env=env, cwd=folder, wine=command))
    assert windows.shape == section5.shape
    assert np.max(np.abs(windows[:, :7] - section5[:, :7])) <= 1e-9
    assert np.max(np.abs(windows[:, 7] - section5[:, 7]) / np.maximum(np.abs(section5[:, 7]), 1.0)) <= 1e-9
    # the same math source on Linux: bit for bit
    own = {}
    for name, unpacked in (("CranePlant", plant[0]), ("BacksteppingController", controller[0])):
        sources = unpacked / "sources"
        own[name] = tmp_path / f"{name}.so"
        subprocess.run([compiler(), "-shared", "-fPIC", "-O2", "-Wall", "-Werror", "-ffp-contract=off",
                        "-DCRANE_OWN_MATH", f"-I{sources}", f"-I{fmi_headers()}",
                        *map(str, sorted(sources.glob("*.c"))), "-o", str(own[name]), "-lm"], check=True)
    linux = _rows(_host(_linux_host(tmp_path), "pair", own["CranePlant"], plant[1], own["BacksteppingController"],
                        controller[1], 20_000, 1e-3, *_loop(plant, controller)))
    assert np.array_equal(linux, windows)


def _linux_host(folder):
    """The host compiled for Linux into ``folder``."""
    out = folder / "host"
    subprocess.run([compiler(), "-O2", "-Wall", "-Werror", "-ffp-contract=off", f"-I{fmi_headers()}", str(HOST), "-o",
                    str(out), "-ldl", "-lpthread"], check=True)
    return out


def test_windows_dlls_of_the_native_plant_and_lqr_under_wine_give_the_lqr_run(wine, plant, lqr, lqr_run):
    """The lqr system in the Windows host: the LQR designed under Wine (portable math in the plant, mingw's
    log2 in the design's scaling), the Python FMUs' run through our master to 1e-9 at every step."""
    command, folder, env = wine
    rows = _rows(_host(folder / "host.exe", "pair", "CranePlant.dll", plant[1], "LqrController.dll", lqr[1], 20_000,
                       1e-3, *_loop(plant, lqr), env=env, cwd=folder, wine=command))
    assert rows.shape == lqr_run.shape
    assert np.max(np.abs(rows - lqr_run)) <= 1e-9


def test_windows_dll_under_wine_free_swing_and_long_lived_host(wine, plant):
    command, folder, env = wine
    x, l1 = plant[2]["x"], plant[2]["l1"]
    rows = _rows(_host(folder / "host.exe", "run", "CranePlant.dll", plant[1], 20_000, 1e-3, x, env=env, cwd=folder,
                       wine=command))
    assert np.degrees(rows[:, 5].max()) == pytest.approx(FREE_SWING_MAX_THETA2_DEG, abs=5e-5)
    after = _rows(_host(folder / "host.exe", "after-failure", "CranePlant.dll", plant[1], 1000, 1e-3, x, f"{l1}=-1",
                        env=env, cwd=folder, wine=command))
    assert np.array_equal(after[-1], rows[1000])
    out = _host(folder / "host.exe", "cycles", "CranePlant.dll", plant[1], 10_000, x, env=env, cwd=folder,
                wine=command)
    assert len(out.splitlines()) == 10  # 10,000 cycles completed (Windows' memory is not read here)
