"""Shared fixtures: everything expensive is made once per test run and shared by every test and every worker.

The suite runs on pytest-xdist workers (``-n auto`` in pyproject.toml). A session fixture runs once per
*worker*, so the expensive ones below go through :func:`made_once`: the first worker that needs the thing
makes it under a file lock in a folder all workers share, the others wait for it and reuse it.

For test writers (keep new tests fast):

- ``fmu_dir``: the FMI 2.0 FMUs of every component, as ``crane-fmu build --bench`` leaves them; beside it
  (``fmu_dir.parent``) ``fmi3/``, ``native/`` (``native/fmi3/``), ``systems/`` and ``containers/``. Built
  once per run. Read it, never write into it: build what your test changes into ``tmp_path``, and never
  build every FMU inside a test. ``build_record`` is what that ``crane-fmu build`` printed.
- ``crane_fmus`` / ``connections``: the ``paper`` system's FMUs and connections.
- ``native``: ``{2: build/native, 3: build/native/fmi3}``, every ported component's FMU checked to be native; the
  test skips, naming the missing C compiler, where there are none (and fails in CI, see required_checks.py). Take
  it, never ``native_dir(fmu_dir)`` and a skip of your own. ``host``: ``fmu_src/host/host.c`` for Linux.
- ``fmu_kinds``: ``{kind: {FMI version: folder}}`` for tests that hold every kind of FMU (Python, native;
  the one-FMU systems are native FMUs) to the same rule (the FMI state table, the fuzzers); a new kind
  of FMU is one entry in ``fmu_kinds.FMU_KINDS``.
- ``plant_dir``: the FMI 2.0 folder of each kind in turn (a test taking it runs once per kind).
- ``wine_env``: the environment of the run's one Wine prefix and server (made once, deleted when the run ends);
  the test skips without Wine and mingw-w64 (and fails in CI, see required_checks.py). ``windows_host``:
  ``fmu_src/host/host.c`` compiled for Windows once per run (copy it beside the DLLs it loads).
- ``dask_scheduler``: a local Dask cluster kept for the run; give it as ``scheduler=`` to compare, sweeps and
  ``run_batch`` unless the test is about starting a cluster (``workers=2`` starts one at every call).
- ``builtin_quick_board``: a quick board of the built-in controllers ``BOARD_CONTROLLERS`` (Python FMUs) at
  ``BOARD_CASES`` cases of the paired design, made once per run; its journal lets a test score one more
  controller on a board of that size without running the built-ins' cases again.
- ``made_once(tmp_path_factory, name, make)`` (``from once import made_once``): your own thing made once per
  run for every worker.
- A helper that more than one test module uses lives in ``helpers.py`` (or the support modules it lists), never in
  a ``test_*.py``: no test module imports another, and no test module defines a fixture named ``native``
  (test_suite_layout.py checks both).
- ``CRANE_TEST_CACHE=<folder>`` (environment): the build is kept there under a hash of everything it is made
  from (the sources, the Python, pythonfmu, the C compilers) and reused by later runs while that is unchanged;
  for the edit-and-check loop only (CI and a fresh clone build afresh).
- Mark a test ``@pytest.mark.quick`` when it takes well under a second and needs no ``fmu_dir``: the
  quick subset (``python -m pytest -m quick``) must stay under a minute and touch every package.
"""

import os
import shutil
import subprocess
import sys
import threading
import zipfile
from pathlib import Path

import pytest
import pythonfmu  # noqa: F401 (see below)
import pythonfmu3  # noqa: F401
from fmu_kinds import FMU_KINDS
from helpers import BOARD_CASES, BOARD_CONTROLLERS
from native_fmus import remove_extracted
from once import made_in, made_once

from crane_fmu import systems

pytest_plugins = ["required_checks"]  # CI=true: a skipped test fails the run

# pythonfmu and pythonfmu3 are imported above, the installed ones, before any Python FMU runs in a test process: an
# FMU run in a process that has not imported them imports its bundled copy under the same name, and a build later
# in that process gets no binaries (build_fmus.build_fmu refuses it). An xdist worker may run FMUs before it builds.

# Bytecode is written even where the environment asks not to (PYTHONDONTWRITEBYTECODE, which some CI images set):
# otherwise every process of the run (the xdist workers, each `crane-fmu` command, each Dask worker) compiles the
# project's modules from source again, about 30 CPU-seconds of a run on 2 cores. Set here, before the workers start.
os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
sys.dont_write_bytecode = False

CLEAN_ENV = {"PATH": "/usr/bin:/bin"}  # what `env -i PATH=/usr/bin:/bin` leaves: no venv, no pyenv, no Python
MINGW = "x86_64-w64-mingw32-gcc"
ROOT = Path(__file__).resolve().parent.parent


# the fixtures that need the run's build (or Wine): a quick test may use none of them
BUILT = {"fmu_dir", "build_record", "crane_fmus", "connections", "native", "fmu_kinds", "plant_dir",
         "builtin_quick_board", "wine_env", "windows_host"}


def pytest_collection_modifyitems(config, items):
    """The quick subset stays quick: a test marked quick that needs the build is a mistake, said at collection.

    The order of the modules (each stays whole, in its order; pyproject.toml's ``--no-loadscope-reorder`` keeps
    pytest-xdist to it, handing out one module at a time): those that need no build first, while the build is
    made (:func:`pytest_collection_finish`); then the longest first (``LONGEST``), so that no worker is left
    alone with a long one at the end.
    """
    for item in items:
        needs = BUILT & set(item.fixturenames)
        if item.get_closest_marker("quick") and needs:
            raise pytest.UsageError(f"{item.nodeid} is marked quick but needs the build ({', '.join(sorted(needs))})")
    waits = {item.module for item in items if BUILT & set(item.fixturenames)}
    rank = {name: i for i, name in enumerate(LONGEST)}
    items.sort(key=lambda item: (item.module in waits, rank.get(item.module.__name__, len(rank))))  # stable


# the modules that take longest (seconds of a whole run on 2 cores: python -m pytest --durations=0, summed by module)
LONGEST = ("test_docs", "test_compare", "test_native_components", "test_one_fmu", "test_native_board",
           "test_third_party_hosts", "test_mpc", "test_cli", "test_c_host", "test_robustness", "test_native",
           "test_serve", "test_wiring", "test_sweep", "test_controllers", "test_fmu_environments",
           "test_model_structure", "test_incremental_build", "test_native_lqr", "test_native_mpc")


def _build_inputs():
    """A hash of everything the build is made from: the project's sources, this Python, the build's tools."""
    import hashlib
    from importlib.metadata import version

    import crane_fmu

    digest = hashlib.sha256()
    for top in (Path(crane_fmu.__file__).parent, ROOT / "fmu_src", ROOT / "build_scripts"):
        for path in sorted(top.rglob("*")):
            if path.is_file() and "__pycache__" not in path.parts:
                digest.update(str(path.relative_to(top.parent)).encode() + b"\0" + path.read_bytes())
    tools = [sys.version, *(version(p) for p in ("pythonfmu", "pythonfmu3", "fmpy"))]
    for compiler in (os.environ.get("CC", "cc"), MINGW):
        found = shutil.which(compiler)
        tools.append(subprocess.run([found, "--version"], capture_output=True, text=True).stdout if found else "-")
    digest.update(repr(tools).encode())
    return digest.hexdigest()[:16]


def _build(folder):
    """``crane-fmu build --bench --out folder/fmus`` in a process of its own, its printed lines kept in
    ``folder/build.out``."""
    done = subprocess.run([sys.executable, "-m", "crane_fmu", "build", "--bench", "--out", str(folder / "fmus")],
                          capture_output=True, text=True)
    (folder / "build.out").write_text(f"{done.returncode}\n{done.stdout}")
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    (folder / "build.manifest").write_text(_manifest(folder))


NOT_BUILT = ("build.manifest", ".crane-build.lock")  # in the build's folder, not made by the build


def _manifest(folder):
    """Every file of the build with its size and time of change: the run's end checks that no test wrote there
    (a build run again there, which makes nothing, takes the build's lock: the lock file is not part of it)."""
    return "".join(f"{p.relative_to(folder)} {p.stat().st_size} {p.stat().st_mtime_ns}\n"
                   for p in sorted(folder.rglob("*")) if p.is_file() and p.name not in NOT_BUILT)


def _the_build(tmp_path_factory):
    """The run's build folder, made by the first to ask (see ``fmu_dir``)."""
    cache = os.environ.get("CRANE_TEST_CACHE")
    if cache:
        Path(cache).mkdir(parents=True, exist_ok=True)
        return made_in(Path(cache), f"build-{_build_inputs()}", _build)
    return made_once(tmp_path_factory, "build", _build)


def pytest_collection_finish(session):
    """When some test of the run needs the build, the first worker starts it at once, beside its first tests: by
    the time a test asks for it, it is made or being made (its lock makes every other asker wait)."""
    if session.config.option.collectonly or os.environ.get("PYTEST_XDIST_WORKER", "gw0") != "gw0":
        return
    if any(BUILT & set(item.fixturenames) for item in session.items):
        threading.Thread(target=_the_build, args=(session.config._tmp_path_factory,), daemon=True).start()


@pytest.fixture(scope="session")
def fmu_dir(tmp_path_factory):
    """Folder holding the FMUs of every registered component (FMI 3.0 ones in ../fmi3), built once per run."""
    return _the_build(tmp_path_factory) / "fmus"


@pytest.fixture(scope="session")
def build_record(fmu_dir):
    """``(exit code, [printed lines])`` of the run's one ``crane-fmu build --bench``."""
    code, *lines = (fmu_dir.parent / "build.out").read_text().splitlines()
    return int(code), lines


@pytest.fixture(scope="session")
def crane_fmus(fmu_dir):
    """``{instance: FMU path}`` of the built-in ``paper`` system."""
    return systems.get("paper").fmus(fmu_dir)


@pytest.fixture(scope="session")
def connections(fmu_dir):
    """The connections of the built-in ``paper`` system (plant state -> controller, u -> plant)."""
    return systems.get("paper").resolve(fmu_dir)[1]


@pytest.fixture(scope="session")
def native(fmu_dir):
    """``{FMI version: folder}`` of the native FMUs (``build/native``, ``build/native/fmi3``): the C twin of every
    ported component, each checked to hold its C binary (not the Python FMU copied beside it), with the Python FMUs
    of the other components and the one-FMU systems. Skips, naming the missing C compiler, where the build could
    make none (in CI that fails the run: required_checks.py)."""
    from crane_fmu.build_scripts.native import PLATFORMS, NativeUnavailable, compilers, native_dir, ported

    try:
        compilers()
    except NativeUnavailable as exc:
        pytest.skip(f"{exc}: no native FMUs were built")
    folders = {version: native_dir(fmu_dir, version) for version in (2, 3)}
    for version, folder in folders.items():
        for name in ported():
            with zipfile.ZipFile(folder / f"{name}.fmu") as fmu:
                binary = f"binaries/{PLATFORMS[version]['linux']}/{name}.so"
                assert binary in fmu.namelist(), f"{folder / name}.fmu has no {binary}: not a native FMU"
    return folders


@pytest.fixture(scope="session")
def fmu_kinds(fmu_dir):
    """``{kind: {FMI version: folder}}`` of :data:`FMU_KINDS` in the run's build."""
    return {kind: {2: fmu_dir.parent / two, 3: fmu_dir.parent / three} for kind, (two, three) in FMU_KINDS.items()}


@pytest.fixture(params=list(FMU_KINDS))
def plant_dir(request, fmu_kinds):
    """The FMI 2.0 folder of each kind of FMU in turn (the test runs once per kind): physics checks that hold
    every kind of CranePlant to the same independent reference take this instead of ``fmu_dir``."""
    return fmu_kinds[request.param][2]


def _make_wine_prefix(folder):
    """The prefix, and its Wine server started for the whole run with the services every program uses: started by
    a test's first program instead, they would hold its captured output open (the server 2 s after each program)."""
    env = {**CLEAN_ENV, "HOME": str(folder), "WINEPREFIX": str(folder), "WINEDEBUG": "-all"}
    quiet = {"stdin": subprocess.DEVNULL, "stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
    subprocess.run(["wineboot", "--init"], env=env, capture_output=True, timeout=300, check=True)
    subprocess.run(["wineserver", "-w"], env=env, timeout=300)
    subprocess.run(["wineserver", "-p"], env=env, timeout=120, check=True, **quiet)  # persistent: stopped at the end
    subprocess.run(["wine", "cmd", "/c", "exit"], env=env, timeout=300, check=True, **quiet)


@pytest.fixture(scope="session")
def wine_env(tmp_path_factory):
    """The environment (``CLEAN_ENV``, ``WINEPREFIX``, ...) of the run's one Wine prefix, made once for all workers,
    its server running. The run's end stops the server and deletes the prefix (about 700 MB). Skips without
    mingw-w64 or Wine.
    """
    if shutil.which(MINGW) is None or shutil.which("wine") is None:
        pytest.skip("needs mingw-w64 (gcc-mingw-w64-x86-64) and Wine (wine64, wine): .ci/run installs them")
    prefix = made_once(tmp_path_factory, "wineprefix", _make_wine_prefix)
    return {**CLEAN_ENV, "HOME": str(prefix), "WINEPREFIX": str(prefix), "WINEDEBUG": "-all"}


@pytest.fixture(scope="session")
def dask_scheduler():
    """The address of a local Dask cluster (2 worker processes) kept for the whole run by this test process.

    For tests of what runs on Dask (compare, sweeps), not of starting a cluster: pass it as ``scheduler=``
    instead of ``workers=2``, which starts and stops a cluster of its own at every call.
    """
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0",
                      silence_logs=50) as cluster:
        yield cluster.scheduler_address


@pytest.fixture(scope="session")
def builtin_quick_board(fmu_dir, dask_scheduler, tmp_path_factory):
    """``(folder, rows)``: ``crane-fmu compare --quick --cases 2 --only`` (``BOARD_CASES``) of ``BOARD_CONTROLLERS`` on
    the Python FMUs, made once per run (the board, its scores and its journal ``cases.jsonl`` in ``folder``;
    ``rows`` as compare returned them). A test that scores another controller beside them may start from a copy of
    that journal: compare then runs only the new controller's cases (the built-ins' are the very same runs)."""
    import pickle

    from crane_fmu.compare import compare

    def make(folder):
        rows = compare(folder, BOARD_CONTROLLERS, fmu_dir, scheduler=dask_scheduler, quick=True, progress=False,
                       animate=(), log=lambda _: None, cases=BOARD_CASES, only=True)
        (folder / "rows.pickle").write_bytes(pickle.dumps(rows))

    folder = made_once(tmp_path_factory, "builtin_quick_board", make)
    return folder / "quick", pickle.loads((folder / "rows.pickle").read_bytes())


def _compile_windows_host(folder):
    from crane_fmu.build_scripts.native import HOST
    from crane_fmu.build_scripts.wrapper import fmi_headers

    subprocess.run([MINGW, "-O2", "-Wall", "-Werror", "-static-libgcc", f"-I{fmi_headers()}", str(HOST), "-o",
                    str(folder / "host.exe")], check=True)


def _compile_linux_host(folder):
    from native_fmus import compiler

    from crane_fmu.build_scripts.native import HOST
    from crane_fmu.build_scripts.wrapper import fmi_headers

    subprocess.run([compiler(), "-O2", "-Wall", "-Werror", "-ffp-contract=off", f"-I{fmi_headers()}", str(HOST), "-o",
                    str(folder / "host"), "-ldl", "-lpthread", "-lm"], check=True)


@pytest.fixture(scope="session")
def host(tmp_path_factory):
    """``host``: ``fmu_src/host/host.c`` for Linux, made once per run; skips without a C compiler."""
    from native_fmus import compiler

    compiler()
    return made_once(tmp_path_factory, "linux_host", _compile_linux_host) / "host"


@pytest.fixture(scope="session")
def windows_host(wine_env, tmp_path_factory):
    """``host.exe``: ``fmu_src/host/host.c`` for Windows x64 (mingw-w64), made once per run."""
    return made_once(tmp_path_factory, "windows_host", _compile_windows_host) / "host.exe"


def pytest_sessionfinish(session):
    """When a process's tests end, the FMUs it extracted go; when the whole run ends (in the controller under xdist,
    after every worker): the run fails if a test wrote into the shared build; the Wine prefix goes."""
    remove_extracted()
    if os.environ.get("PYTEST_XDIST_WORKER") or not hasattr(session.config, "_tmp_path_factory"):
        return
    build = session.config._tmp_path_factory.getbasetemp() / "build"
    if (build / "build.manifest").exists() and _manifest(build) != (build / "build.manifest").read_text():
        changed = set(_manifest(build).splitlines()) ^ set((build / "build.manifest").read_text().splitlines())
        session.config.get_terminal_writer().line(
            "a test wrote into the shared build (fmu_dir and its siblings are read-only for tests): "
            + ", ".join(sorted({line.split()[0] for line in changed})), red=True)
        session.exitstatus = pytest.ExitCode.TESTS_FAILED
    prefix = session.config._tmp_path_factory.getbasetemp() / "wineprefix"
    if prefix.exists():
        env = {**CLEAN_ENV, "HOME": str(prefix), "WINEPREFIX": str(prefix), "WINEDEBUG": "-all"}
        subprocess.run(["wineserver", "-k"], env=env, timeout=120, capture_output=True)
        shutil.rmtree(prefix, ignore_errors=True)
