"""Native FMUs: the components ported to C (``fmu_src/models``), built without any Python inside.

Each is its model file behind the FMI framework every FMU of this project shares (``fmu_src/framework``),
which runs the model named by a generated ``fmu_model.c``.

One FMU per ported component and FMI version, with the Python FMU's model identifier,
variables, value references, units and start values: its modelDescription.xml and the C
header of its variables (``<model>_variables.h``, the analogue of Reference-FMUs' config.h)
are both generated here from the component's variable table, the one the Python FMU is
built from. Each FMU holds

- ``binaries/linux64`` (FMI 3.0: ``x86_64-linux``), compiled with the machine's C compiler;
- ``binaries/win64`` (``x86_64-windows``), cross-compiled with mingw-w64 when
  ``x86_64-w64-mingw32-gcc`` is found (static libgcc: no DLL beyond Windows' own);
- its C sources: an FMI 2.0 source code FMU (``<SourceFiles>``), FMI 3.0 ``sources/`` with
  ``buildDescription.xml``.

Both are compiled with ``-ffp-contract=off`` (no fused multiply-adds: the same operations as
the Python model). The Linux binary uses glibc's libm, as CPython does, so it gives the Python
FMU's numbers; mingw-w64's libm differs, so the Windows binary (and a build from the sources)
uses the portable sin, cos, exp, tanh and log of ``fmu_src/models/portable_math.c``.
"""

import atexit
import hashlib
import os
import re
import shutil
import subprocess
import tempfile
import threading
import uuid
import xml.etree.ElementTree as ET
import zipfile
from concurrent.futures import Future, ThreadPoolExecutor
from functools import partial
from pathlib import Path

import crane_fmu.fmu_src as fmu_src
from crane_fmu import components
from crane_fmu.build_scripts import incremental, model_exchange
from crane_fmu.build_scripts.folders import fmi3_dir, native_dir
from crane_fmu.build_scripts.model_description import _unit_definitions, postprocess, postprocess3
from crane_fmu.build_scripts.wrapper import fmi_headers
from crane_fmu.model import rules
from crane_fmu.model.tables import DISPLAY_UNITS, enumeration_value, xml_double

SOURCES = Path(fmu_src.__file__).parent
FOLDERS = tuple(SOURCES / folder for folder in ("framework", "models", "system"))  # where copy_sources looks
MODELS_DIR = SOURCES / "models"
HOST = SOURCES / "host" / "host.c"  # a C host for tests and benchmarks, in no FMU
DERIVATIVE_BENCH = SOURCES / "host" / "derivative_bench.c"  # the Model Exchange derivatives' cost (bench)
FMI_DERIVATIVE_BENCH = SOURCES / "host" / "fmi_derivative_bench.c"  # the same through the FMU's FMI 2.0 calls
# every native FMU's: the framework's files, the component interface and the portable math; besides them each FMU
# compiles its model files (:func:`model_sources`) and the generated fmu_model.c, which names the model its
# framework runs
COMMON = ("instance.c", "continuous.c", "py_repr.c", "component.c", "portable_math.c")
HEADERS = ("model.h", "instance.h", "continuous.h", "py_repr.h", "component.h", "rules.h", "plant_math.h")
FRAMEWORKS = {2: ("fmi2Functions.c", "fmi2_calls.h"), 3: ("fmi3Functions.c", "fmi3_calls.h")}
PLATFORMS = {2: {"linux": "linux64", "windows": "win64"}, 3: {"linux": "x86_64-linux", "windows": "x86_64-windows"}}
FLAGS = ["-O2", "-Wall", "-Werror", "-ffp-contract=off"]  # every C file's, for both platforms
MINGW = "x86_64-w64-mingw32-gcc"


class NativeUnavailable(RuntimeError):
    """No C compiler for the native FMUs here."""


def compilers():
    """``{"linux": cc, "windows": mingw or None}``; NativeUnavailable without a C compiler for this machine."""
    cc = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")
    if cc is None:
        raise NativeUnavailable("no C compiler found (set CC or install gcc)")
    return {"linux": cc, "windows": shutil.which(MINGW)}


def ported():
    """The model identifiers of the registered components that have a native model (``Component.native``)."""
    return [c.model_identifier for c in components.registered() if c.native]


def model_sources(model_files):
    """``(c_files, headers)``: the model files and what they include of ``fmu_src/models``, transitively: a header
    ``name.h`` there brings its ``name.c`` when there is one (a plant's equations, the LQR design, the QP solver),
    so that an FMU compiles only the models it runs."""
    c_files, headers, todo = list(model_files), [], list(model_files)
    while todo:
        for name in re.findall(r'^#include "([^"]+)"', source_path(todo.pop()).read_text(), re.MULTILINE):
            if name in headers or name in HEADERS or not (MODELS_DIR / name).exists():
                continue  # known, the framework's, or generated (a variables header)
            headers.append(name)
            todo.append(name)
            c_file = name[:-2] + ".c"
            if (MODELS_DIR / c_file).exists() and c_file not in c_files:
                c_files.append(c_file)
                todo.append(c_file)
    return c_files, headers


def _sources(component, fmi_version):
    """The C files of fmu_src the component's FMU is compiled from, and its headers (not the generated ones)."""
    framework, functions = FRAMEWORKS[fmi_version]
    c_files, headers = model_sources([component.native])
    return [*c_files, *COMMON, framework], [*HEADERS, *headers, functions]


def compiled(component, fmi_version):
    """The C files the component's FMU is compiled from: those of fmu_src and the generated fmu_model.c."""
    return [*_sources(component, fmi_version)[0], "fmu_model.c"]


def source_path(name):
    """The path of a C file of ``fmu_src`` (framework, models or system) by its name."""
    return next(folder / name for folder in FOLDERS if (folder / name).exists())


def token(component):
    """The GUID / instantiation token: a hash of the variable table, the rules and every C source."""
    digest = hashlib.sha256(repr((component.variables, component.rules)).encode())
    for name in sorted({name for version in (2, 3) for group in _sources(component, version) for name in group}):
        digest.update(name.encode() + source_path(name).read_bytes())
    return "{" + str(uuid.UUID(digest.hexdigest()[:32])) + "}"


def variables_header(component, guid=None):
    """``<model>_variables.h``: the value references, causalities and start values, from the table, and
    ``parameter_rules()``, the C check of the component's rules (:func:`.rules.c_function`)."""
    rows, enum = [], []
    causality = {"parameter": "PARAMETER", "input": "INPUT", "output": "OUTPUT"}
    strings = [v.name for v in component.variables if v.type in ("String", "Enumeration")]  # kept by name
    items = []
    for vr, v in enumerate(component.variables):
        if v.type not in ("Real", "String", "Enumeration") or (v.type != "Real" and v.causality != "parameter"):
            raise ValueError(f"{component.model_identifier}.{v.name}: the native framework has Reals and String "
                             "and Enumeration parameters only")
        if v.type == "Enumeration":
            names = ", ".join(f'"{i}"' for i in v.items)
            items.append(f"static const char *const ITEMS_{v.name}[] = {{{names}}};")
            rows.append(f'    {{"{v.name}", {causality[v.causality]}, ENUMERATION, 0.0, "{v.start}", ITEMS_{v.name}, '
                        f'{len(v.items)}}},')
        elif v.type == "String":
            text = v.start.encode("unicode_escape").decode("ascii").replace('"', '\\"')
            rows.append(f'    {{"{v.name}", {causality[v.causality]}, STRING, 0.0, "{text}", NULL, 0}},')
        else:
            start = "0.0" if v.start is None else xml_double(v.start)
            start = {"INF": "INFINITY", "-INF": "-INFINITY"}.get(start, start)
            rows.append(f'    {{"{v.name}", {causality[v.causality]}, REAL, {start}, NULL, NULL, 0}},')
        enum.append(f"VR_{v.name} = {vr},")
    enum += [f"STRING_{name} = {i}, /* its place among the Strings */" for i, name in enumerate(strings)]
    outputs = [i for i, v in enumerate(component.variables) if v.causality == "output"]
    if outputs != list(range(outputs[0], len(component.variables))):
        raise ValueError(f"{component.model_identifier}: the native model expects the outputs last in the table")
    name = component.model_identifier
    continuous = model_exchange.header(component) if component.continuous else ""
    checks = rules.c_function(getattr(component, "rules", ()))  # a one-FMU system's own table has none
    return f"""/* Generated by crane-fmu build from the variable table of {name} (crane_fmu/model); do not edit. */
#ifndef VARIABLES_H
#define VARIABLES_H

#include <math.h>
#include <stddef.h>

#include "component.h"

#define MODEL_IDENTIFIER "{name}"
#define INSTANTIATION_TOKEN "{guid or token(component)}"
#define MODEL_TYPE {name}_MODEL /* the ModelType a model file registers */

enum {{
{chr(10).join("    " + line for line in enum)}
    N_VARIABLES = {len(component.variables)},
    FIRST_OUTPUT = {outputs[0]},
    N_OUTPUTS = {len(outputs)},
    N_STRINGS = {len(strings)},
    N_ENUMERATIONS = {len(items)}
}};

{chr(10).join(items)}

static const VariableRow VARIABLE_TABLE[N_VARIABLES] = {{
{chr(10).join(rows)}
}};
{continuous}
#include "rules.h"

{checks}
#endif
"""


def fmu_model(name):
    """``fmu_model.c``: the model the FMU's framework runs, ``<name>_MODEL`` (model.h's FMU_MODEL)."""
    return f"""/* Generated by crane-fmu build; do not edit. The model this FMU runs. */
#include "model.h"

extern const ModelType {name}_MODEL;
const ModelType *const FMU_MODEL = &{name}_MODEL;
"""


def _skeleton2(component, sources, guid):
    """An FMI 2.0 modelDescription.xml without units and structure, for model_description.postprocess()."""
    name = component.model_identifier
    root = ET.Element("fmiModelDescription", fmiVersion="2.0", modelName=name, guid=guid,
                      generationTool="crane-fmu build (native C)", variableNamingConvention="structured",
                      description=component.description, author="crane anti-sway co-simulation toolkit")
    cs = ET.SubElement(root, "CoSimulation", needsExecutionTool="false",
                       canHandleVariableCommunicationStepSize="true", canInterpolateInputs="false",
                       canBeInstantiatedOnlyOncePerProcess="false", canGetAndSetFMUstate="true",
                       canSerializeFMUstate="true", modelIdentifier=name, canNotUseMemoryManagementFunctions="true")
    files = ET.SubElement(cs, "SourceFiles")
    for source in sources:
        ET.SubElement(files, "File", name=source)
    _log_categories(root, "fmi2")
    _default_experiment(root, component)
    variables = ET.SubElement(root, "ModelVariables")
    for vr, v in enumerate(component.variables):
        attrs = {"name": v.name, "valueReference": str(vr), "causality": v.causality, "variability": v.variability}
        if v.causality == "output":
            attrs["initial"] = "calculated"
        sv = ET.SubElement(variables, "ScalarVariable", attrs)
        if v.type == "String":
            ET.SubElement(sv, "String", start=v.start)
        elif v.type == "Enumeration":  # its type declared by model_description.postprocess
            ET.SubElement(sv, "Integer", start=str(enumeration_value(v, v.start)))
        else:
            ET.SubElement(sv, "Real", {} if v.start is None else {"start": xml_double(v.start)})
    ET.SubElement(root, "ModelStructure")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def _skeleton3(component, guid):
    """An FMI 3.0 modelDescription.xml for model_description.postprocess3(); value reference 0 is time."""
    name = component.model_identifier
    root = ET.Element("fmiModelDescription", fmiVersion="3.0", modelName=name, instantiationToken=guid,
                      generationTool="crane-fmu build (native C)", variableNamingConvention="structured",
                      description=component.description, author="crane anti-sway co-simulation toolkit")
    ET.SubElement(root, "CoSimulation", needsExecutionTool="false", canBeInstantiatedOnlyOncePerProcess="false",
                  canGetAndSetFMUState="true", canSerializeFMUState="true", modelIdentifier=name,
                  canHandleVariableCommunicationStepSize="true", providesIntermediateUpdate="false",
                  canReturnEarlyAfterIntermediateUpdate="false", hasEventMode="false")
    root.append(_unit_definitions({v.unit for v in component.variables if v.unit}, {}))
    _log_categories(root, "fmi3")
    _default_experiment(root, component)
    variables = ET.SubElement(root, "ModelVariables")
    ET.SubElement(variables, "Float64", name="time", valueReference="0", description="simulation time",
                  causality="independent", variability="continuous")
    for vr, v in enumerate(component.variables, start=1):
        attrs = {"name": v.name, "valueReference": str(vr), "description": v.description, "causality": v.causality,
                 "variability": v.variability}
        if v.causality == "output":
            attrs["initial"] = "calculated"
        elif v.type == "String":
            ET.SubElement(ET.SubElement(variables, "String", attrs), "Start", value=v.start)
            continue
        elif v.type == "Enumeration":  # its type declared by model_description.postprocess3
            ET.SubElement(variables, "Int64", attrs, start=str(enumeration_value(v, v.start)))
            continue
        else:
            attrs["start"] = xml_double(v.start)
        attrs["unit"] = v.unit
        ET.SubElement(variables, "Float64", attrs)
    structure = ET.SubElement(root, "ModelStructure")
    outputs = [str(vr) for vr, v in enumerate(component.variables, start=1) if v.causality == "output"]
    for vr in outputs:
        ET.SubElement(structure, "Output", valueReference=vr)
    for vr in outputs:
        ET.SubElement(structure, "InitialUnknown", valueReference=vr)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def _log_categories(root, prefix):
    node = ET.SubElement(root, "LogCategories")
    for status in ("Warning", "Discard", "Error"):
        ET.SubElement(node, "Category", name=f"logStatus{status}",
                      description=f"Log messages with {prefix}{status} status.")
    ET.SubElement(node, "Category", name="logAll", description="Log all messages.")


def _default_experiment(root, component):
    start, stop, step = component.default_experiment
    ET.SubElement(root, "DefaultExperiment", startTime=repr(float(start)), stopTime=repr(float(stop)),
                  stepSize=repr(float(step)))


def model_description(component, fmi_version=2, sources=None, guid=None):
    """The native FMU's modelDescription.xml (bytes), made like the Python FMU's from the same table.

    ``sources`` (the compiled C files) and ``guid`` default to the component's own.
    """
    guid = guid or token(component)
    if fmi_version == 3:
        xml = postprocess3(_skeleton3(component, guid), component.variables, DISPLAY_UNITS, component.dependencies())
        return model_exchange.add_to_fmi3(xml, component) if component.continuous else xml
    sources = sources or compiled(component, 2)
    xml = postprocess(_skeleton2(component, sources, guid), component.variables, DISPLAY_UNITS,
                      component.dependencies())
    return model_exchange.add_to_fmi2(xml, component, sources) if component.continuous else xml


def build_description(component, sources=None):
    """FMI 3.0 ``sources/buildDescription.xml``: every C file, with the portable math (no libm needed)."""
    root = ET.Element("fmiBuildDescription", fmiVersion="3.0")
    config = ET.SubElement(root, "BuildConfiguration", modelIdentifier=component.model_identifier)
    files = ET.SubElement(config, "SourceFileSet", language="C99")
    for source in sources or compiled(component, 3):
        ET.SubElement(files, "SourceFile", name=source)
    ET.SubElement(files, "PreprocessorDefinition", name="CRANE_OWN_MATH")
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def _compile(compiler, sources, include, out, platform):
    objects = OBJECTS.made(compiler, platform, sources, include)
    libs = ["-lm"] if platform == "linux" else ["-static-libgcc"]
    _gcc([compiler, "-shared", *map(str, objects), "-o", str(out), *libs], out.name)


def _gcc(command, what):
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:  # a bug in our C, not a missing tool: stop the build
        raise RuntimeError(f"compiling {what} failed: {done.stderr.strip()}")


class Objects:
    """Object files compiled once per process and linked into every FMU that has the same C file.

    An object is made from its C file, the headers it includes (followed in the include folders) and the
    compiler's flags, and is named by a hash of them: most files (the framework, the shared model code, each
    model file) are the same in many FMUs. Builds on several threads share it: a file one thread compiles,
    the others wait for instead of compiling it again.
    """

    def __init__(self):
        self._lock = threading.Lock()
        self._made = {}  # hash -> Future of the object's path
        self._folder = None

    def made(self, compiler, platform, sources, include):
        """The objects of ``sources`` for ``platform``, compiled here unless made before."""
        flags = [*FLAGS, "-fPIC", "-fvisibility=hidden"] if platform == "linux" else [*FLAGS, "-DCRANE_OWN_MATH"]
        mine, futures = [], []
        with self._lock:
            if self._folder is None:
                self._folder = Path(tempfile.mkdtemp(prefix="crane_objects_"))
                atexit.register(shutil.rmtree, self._folder, True)
            for source in map(Path, sources):
                key = _object_key([compiler, *flags], source, include)
                if key not in self._made:
                    self._made[key] = Future()
                    mine.append((source, key))
                futures.append(self._made[key])
        for source, key in mine:  # those no other thread compiles: first, then wait for the others'
            out = self._folder / f"{key}.o"
            try:
                _gcc([compiler, "-c", *flags, *[f"-I{folder}" for folder in include], str(source), "-o", str(out)],
                     source.name)
                self._made[key].set_result(out)
            except Exception as exc:
                self._made[key].set_exception(exc)
        return [future.result() for future in futures]


def _object_key(command, source, include):
    """A hash of the compile ``command``, of ``source`` and of every header it includes with quotes."""
    digest = hashlib.sha256(repr(command).encode())
    seen, todo = set(), [source]
    while todo:
        path = todo.pop()
        text = path.read_bytes()
        digest.update(path.name.encode() + b"\0" + text)
        for name in re.findall(rb'^\s*#\s*include\s+"([^"]+)"', text, re.MULTILINE):
            places = (Path(folder) / name.decode() for folder in [path.parent, *include])
            header = next((place for place in places if place.exists()), None)
            if header is not None and header not in seen:
                seen.add(header)
                todo.append(header)
    return digest.hexdigest()[:24]


OBJECTS = Objects()


def build_native_fmu(component, out_dir, fmi_version=2, tools=None):
    """Build one component's native FMU into ``out_dir``; return its path.

    ``tools`` is :func:`compilers` (found here if not given); a missing mingw-w64 leaves out the
    Windows binary. The FMU is written under a temporary name and renamed.
    """
    name = component.model_identifier
    c_files, h_files = _sources(component, fmi_version)
    with tempfile.TemporaryDirectory(prefix="crane_native_") as tmp:
        sources = Path(tmp) / "sources"
        copy_sources([*c_files, *h_files], sources)
        (sources / f"{name}_variables.h").write_text(variables_header(component))
        (sources / "fmu_model.c").write_text(fmu_model(name))
        build = build_description(component) if fmi_version == 3 else None
        return write_fmu(name, out_dir, sources, compiled(component, fmi_version),
                         model_description(component, fmi_version), build, fmi_version, tools)


def copy_sources(files, folder):
    """Copy ``files`` (names in fmu_src/framework, models or system) into ``folder``, made if missing."""
    folder.mkdir(parents=True, exist_ok=True)
    for file in files:
        shutil.copy(source_path(file), folder / file)


def write_fmu(name, out_dir, sources, c_files, description, build, fmi_version, tools=None):
    """Compile ``c_files`` of the folder ``sources`` for each platform of ``tools`` and write ``out_dir/<name>.fmu``
    with the binaries, every file of ``sources``, the modelDescription.xml ``description`` and (FMI 3.0) the
    buildDescription.xml ``build``; return its path. Written under a temporary name and renamed."""
    tools = tools or compilers()
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="crane_native_") as tmp:
        binaries = {}
        for platform, compiler in tools.items():
            if compiler:
                suffix = ".so" if platform == "linux" else ".dll"
                binaries[platform] = Path(tmp) / f"{platform}{suffix}"
                _compile(compiler, [sources / f for f in c_files], [sources, fmi_headers()], binaries[platform],
                         platform)
        final, partial = out_dir / f"{name}.fmu", out_dir / f".{name}.fmu.partial"
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as fmu:
            fmu.writestr("modelDescription.xml", description)
            for platform, binary in binaries.items():
                fmu.write(binary, f"binaries/{PLATFORMS[fmi_version][platform]}/{name}{binary.suffix}")
            for file in sorted(sources.iterdir()):
                fmu.write(file, f"sources/{file.name}")
            if build is not None:
                fmu.writestr("sources/buildDescription.xml", build)
        os.replace(partial, final)
    return final


def build_native(out_dir, kinds, required=False, log=print, record=None):
    """The native FMUs of those ``kinds`` that are ported, FMI 2.0 and 3.0, in :func:`native_dir`; their paths.

    The other kinds' Python FMUs (already built in ``out_dir`` and its ``fmi3`` sibling) are
    copied beside them, so that ``--fmu-dir build/native`` runs every built-in system. Without a
    C compiler: a warning and nothing built, or NativeUnavailable when ``required``. With a
    ``record`` (:class:`.incremental.Record`), an FMU made from the same inputs before is kept.
    """
    record = record or incremental.Record()  # keeps nothing

    if not set(kinds) & set(ported()):
        return []
    try:
        tools = compilers()
    except NativeUnavailable as exc:
        if required:
            raise
        log(f"warning: {exc}; no native FMUs built")
        return []
    if tools["windows"] is None:
        log(f"warning: {MINGW} not found; the native FMUs have no Windows binary")
    builds = []
    for version, python_dir in ((2, Path(out_dir)), (3, fmi3_dir(out_dir))):
        native_dir(out_dir, version).mkdir(parents=True, exist_ok=True)
        for kind in kinds:
            folder, python = native_dir(out_dir, version), python_dir / f"{kind}.fmu"
            if components.get(kind).native:
                component = components.get(kind)
                files = [source_path(name) for group in _sources(component, version) for name in group]
                builds.append(partial(record.make, folder / f"{kind}.fmu",
                                      incremental.native_key(component, version, tools, files),
                                      partial(build_native_fmu, component, folder, version, tools)))
            elif python.exists():  # not ported yet: the Python FMU
                builds.append(partial(record.make, folder / python.name, incremental.key("copy", python),
                                      lambda p=python, f=folder: Path(shutil.copy(p, f))))
    return in_parallel(builds)


def in_parallel(calls):
    """Each of ``calls`` (builds that wait on compiler processes) on a thread of its own, as many at once as
    there are cores; their results in the order of the calls."""
    with ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as pool:
        return list(pool.map(lambda call: call(), calls))
