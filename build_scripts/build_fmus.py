"""Build the FMUs with pythonfmu and post-process their modelDescription.xml.

On Linux the FMU's binary is our own FMI wrapper (``fmu_src/fmi2_wrapper.c``,
compiled here against this Python's libpython) instead of pythonfmu's: it
reports the reason of every error to the host's logger and loads in non-Python
hosts. Where it cannot be compiled, pythonfmu's binary stays (with a warning).

Each FMU bundles the runtime core (``crane_fmu/model`` plus the slave support
module) in its resources under a private package name that carries a hash of
its sources, ``crane_core_<hash>``. pythonfmu FMUs run inside the host's Python
interpreter and share ``sys.modules`` with it, so a bundle named ``crane_fmu``
would silently use whatever ``crane_fmu`` the host imported first (another
version, or the unrelated PyPI project of that name).
"""

import hashlib
import os
import shutil
import sys
import tempfile
import zipfile
from collections import namedtuple
from pathlib import Path

import crane_fmu.model
import fmu_src
from build_scripts.model_description import postprocess, postprocess3
from build_scripts.wrapper import WrapperUnavailable, compile_binaries
from crane_fmu.model import tables

MODEL_DIR = Path(crane_fmu.model.__file__).parent
SLAVE_DIR = Path(fmu_src.__file__).parent
# bundled with the core, by FMI version: each version's FMUs import all of theirs, so a host
# that loaded one FMU has the whole package in sys.modules even after that FMU's folder is gone
SUPPORT = {2: [SLAVE_DIR / "slave_support.py", SLAVE_DIR / "crane_logic.py"],
           3: [SLAVE_DIR / "slave_support3.py", SLAVE_DIR / "crane_logic.py"]}

Spec = namedtuple("Spec", "name script table feedthrough saves_state")
CRANE_FMUS = (
    Spec("CranePlant", "crane_plant.py", tables.PLANT, False, True),
    Spec("BacksteppingController", "backstepping_controller.py", tables.CONTROLLER, True, True),
)
FMI3_FMUS = (  # the same pair as FMI 3.0 co-simulation FMUs (pythonfmu3)
    Spec("CranePlant", "crane_plant3.py", tables.PLANT, False, True),
    Spec("BacksteppingController", "backstepping_controller3.py", tables.CONTROLLER, True, True),
)
BENCH_FMUS = (
    Spec("TrivialPlant", "trivial_plant.py", tables.TRIVIAL_PLANT, False, False),
    Spec("TrivialController", "trivial_controller.py", tables.TRIVIAL_CONTROLLER, True, False),
)


def core_name(fmi_version=2):
    """``crane_core<version>_<hash>``: the bundled core's package name, unique per source and FMI version."""
    digest = hashlib.sha256()
    for path in sorted(MODEL_DIR.glob("*.py")) + SUPPORT[fmi_version]:
        digest.update(path.name.encode() + b"\0" + path.read_bytes())
    return f"crane_core{fmi_version}_" + digest.hexdigest()[:12]


def _stage(spec, stage_dir, core, fmi_version=2):
    """Copy the slave and the core to ``stage_dir`` with imports renamed to the core."""
    package = stage_dir / core
    package.mkdir()
    for path in MODEL_DIR.glob("*.py"):
        shutil.copy2(path, package / path.name)
    for path in SUPPORT[fmi_version]:
        (package / path.name).write_text(_bundled(path.read_text(), core, path.name))
    script = stage_dir / spec.script
    script.write_text(_bundled((SLAVE_DIR / spec.script).read_text(), core, spec.script))
    return script, package


def _bundled(source, core, name):
    """``source`` with this project's imports renamed to the bundled core package."""
    source = source.replace("from fmu_src import", f"from {core} import")
    source = source.replace("fmu_src.", f"{core}.").replace("crane_fmu.model", core)
    if "crane_fmu" in source or "fmu_src" in source:
        raise RuntimeError(f"{name} imports a module that is not bundled")
    return source


def build_fmu(spec, out_dir, binaries=None, fmi3=False):
    """Build one FMU into ``out_dir`` and return its path.

    ``binaries`` are the compiled ``(loader, wrapper)`` to use as the Linux
    binary (None keeps pythonfmu's); ``fmi3`` builds an FMI 3.0 FMU with pythonfmu3
    (with pythonfmu3's binary). The FMU is written under a temporary name and
    renamed, so an existing FMU is never left half-written.
    """
    # the build needs pythonfmu (or pythonfmu3), the runtime does not
    from pythonfmu import FmuBuilder
    from pythonfmu3 import FmuBuilder as FmuBuilder3

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="crane_build_") as tmp:
        tmp = Path(tmp)
        stage = tmp / "stage"
        stage.mkdir()
        version = 3 if fmi3 else 2
        core = core_name(version)
        script, package = _stage(spec, stage, core, version)
        saved_path = list(sys.path)
        try:
            # The FMUs need a Python runtime, not an external tool that runs the model.
            if fmi3:
                raw = FmuBuilder3.build_FMU(script, dest=tmp / "raw", project_files=[package],
                                            needsExecutionTool=False, canHandleVariableCommunicationStepSize=True,
                                            canGetAndSetFMUState=spec.saves_state,
                                            canSerializeFMUState=spec.saves_state)
            else:
                raw = FmuBuilder.build_FMU(script, dest=tmp / "raw", project_files=[package],
                                           needsExecutionTool=False, canGetAndSetFMUstate=spec.saves_state,
                                           canSerializeFMUstate=spec.saves_state)
        finally:
            # pythonfmu imports the staged slave and core and leaves them (and
            # the stage folder) in this process; forget them before the next build.
            sys.path[:] = saved_path
            for name in [m for m in sys.modules if m == script.stem or m.split(".")[0] == core]:
                del sys.modules[name]
        final = out_dir / f"{spec.name}.fmu"
        partial = out_dir / f".{spec.name}.fmu.partial"
        with zipfile.ZipFile(raw) as src, zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as dst:
            for item in src.infolist():
                data = src.read(item)
                if item.filename == "modelDescription.xml":
                    process = postprocess3 if fmi3 else postprocess
                    data = process(data, spec.table, tables.DISPLAY_UNITS, spec.feedthrough)
                elif item.filename == f"binaries/linux64/{spec.name}.so" and binaries is not None and not fmi3:
                    data = Path(binaries[0]).read_bytes()
                    dst.write(binaries[1], "binaries/linux64/PythonWrapper.so")
                dst.writestr(item.filename, data)
            dst.writestr("resources/slaveclass.txt", spec.name)  # read by the wrapper
        os.replace(partial, final)
    return final


def build_all(out_dir="build/fmus", specs=CRANE_FMUS, log=print):
    """Build every FMU of ``specs`` into ``out_dir``; return their paths.

    With the crane pair, also write the system for other tools (the SSP package
    ``CraneSystem.ssp`` in the parent of ``out_dir`` and ``OspSystemStructure.xml``
    beside the FMUs) and the FMI 3.0 pair into :func:`fmi3_dir`.
    """
    with tempfile.TemporaryDirectory(prefix="crane_wrapper_") as tmp:
        try:
            binaries = compile_binaries(tmp)
        except WrapperUnavailable as exc:
            log(f"warning: {exc}; the FMUs keep pythonfmu's binary, which loads only in Python hosts "
                "and reports no error messages")
            binaries = None
        paths = [build_fmu(spec, out_dir, binaries) for spec in specs]
    if all(spec in specs for spec in CRANE_FMUS):
        from build_scripts.system_files import write_osp, write_ssp

        paths += [write_ssp(out_dir, Path(out_dir).parent / "CraneSystem.ssp"), write_osp(out_dir)]
        paths += [build_fmu(spec, fmi3_dir(out_dir), fmi3=True) for spec in FMI3_FMUS]
    return paths


def fmi3_dir(out_dir):
    """Where the FMI 3.0 pair goes: ``build/fmi3`` next to ``build/fmus``."""
    return Path(out_dir).parent / "fmi3"


if __name__ == "__main__":
    for path in build_all():
        print(path)
