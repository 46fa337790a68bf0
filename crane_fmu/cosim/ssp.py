"""SSP 1.0 in and out: a :class:`~crane_fmu.cosim.system.System` as an ``.ssp`` package, ``.ssd`` or ``.ssv`` file.

Written packages hold SystemStructure.ssd (components with their connectors and
units, every connection written out, every parameter value and each input's start value the system sets, the step in
OMSimulator's annotation, the system's own values with the parameters each sets)
and the FMUs under ``resources/``. Read are packages and ``.ssd`` files with
parameter values inline or in ``.ssv`` files, bound to a component (names
``variable``) or to the system (names ``instance.variable``), and parameter
mappings (``.ssm``) of the system's values.

The system's own values (one value an application sets on several components'
parameters) are a system-level ParameterBinding named ``group.variable`` whose
ParameterMapping maps it to each component parameter it sets; each component's own
set carries the same value. Measured: OMSimulator 3.0 applies the system-level
value to the mapped parameters over the components' own; libcosim (libcosimpy 0.0.6)
reads only the components' sets (and refuses a file with a connection from the
system's own connectors, so none is written).
"""

import contextlib
import math
import os
import re
import shutil
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

from .connections import Connection
from .instance import enumeration_value
from .system import System, read_fmu

SSD_NS = "http://ssp-standard.org/SSP1/SystemStructureDescription"
SSC_NS = "http://ssp-standard.org/SSP1/SystemStructureCommon"
SSV_NS = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
# OMSimulator (2.x, 3.0) takes a system's master and step only from its own annotation on the root system, and
# without one refuses the file; every other engine ignores it. It matches the prefixes `oms:`, `ssc:`, `ssd:`.
OMS_NS = "https://raw.githubusercontent.com/OpenModelica/OMSimulator/master/schema/oms.xsd"
SSM_NS = "http://ssp-standard.org/SSP1/SystemStructureParameterMapping"
SSD, SSC, SSV, OMS, SSM = (f"{{{ns}}}" for ns in (SSD_NS, SSC_NS, SSV_NS, OMS_NS, SSM_NS))
# The name of every component's one inline parameter set in the SSDs written here. One name for
# all: Ecos applies the sets of the one name given to it (`ecos simulate --parameterSet
# initialValues`), and none without it; libcosim takes each component's first set, OMSimulator
# every set, and this package's reader every binding. Bindings on the System element and
# `prefix` are left out: neither Ecos nor libcosim reads them. String parameters get no connector and
# a value only where it differs from the FMU's start value: OMSimulator 3.0 applies no String and logs
# an error for each String connector and value.
PARAMETER_SET = "initialValues"
_CONVERT = {"Real": float, "Float64": float, "Integer": int, "Int32": int, "Int64": int,
            "Boolean": lambda v: v.lower() in ("true", "1"), "String": str, "Enumeration": str}
# An FMU's Enumeration parameter is written as an ssv:Integer of the item's value, its connector an ssc:Integer:
# OMSimulator 3.0 applies that, and refuses SSP 1.0's ssv:Enumeration (the item's name) with one error each,
# running the FMU's own value (tried on hoist-transport.ssp). The reader takes either.
ENUMERATION_AS = "Integer"
_BASE_UNITS = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")


# --- reading ------------------------------------------------------------------------

@contextlib.contextmanager
def load_system(path):
    """Yield the :class:`System` of an SSP file; an ``.ssp`` package is unpacked for the duration.

    Raises
    ------
    ValueError
        One line naming the file and what is wrong with it.
    """
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"system file {path} not found")
    workdir = None
    try:
        if path.suffix == ".ssp":
            workdir = Path(tempfile.mkdtemp(prefix="cosim_ssp_"))
            try:
                with zipfile.ZipFile(path) as package:
                    package.extractall(workdir)
            except zipfile.BadZipFile:
                raise ValueError(f"{path} is not an SSP package (not a zip file)") from None
            ssd = workdir / "SystemStructure.ssd"
            if not ssd.is_file():
                raise ValueError(f"{path} holds no SystemStructure.ssd")
        else:
            ssd = path
        yield _parse(ssd, path)
    finally:
        if workdir is not None:
            shutil.rmtree(workdir, ignore_errors=True)


def _xml(path, origin):
    try:
        return ET.parse(path).getroot()
    except (ET.ParseError, OSError) as exc:
        raise ValueError(f"{origin}: {Path(path).name} is not readable XML ({exc})") from None


def _parameter_set(node, origin):
    """``{name: value}`` of an ssv:ParameterSet element."""
    values = {}
    for parameter in node.iter(f"{SSV}Parameter"):
        for kind, convert in _CONVERT.items():
            value = parameter.find(f"{SSV}{kind}")
            if value is not None:
                try:
                    values[parameter.get("name")] = convert(value.get("value"))
                except (TypeError, ValueError):
                    raise ValueError(f"{origin}: parameter {parameter.get('name')!r} has no valid {kind} value "
                                     f"({value.get('value')!r})") from None
    return values


def _bindings(element, base, origin):
    """``({name: value}, {source: [target, ...]})`` of every ParameterBinding of ``element`` (inline or from .ssv
    and .ssm files): the values and where the parameter mapping sends them."""
    values, mapping = {}, {}
    for binding in element.findall(f"{SSD}ParameterBindings/{SSD}ParameterBinding"):
        prefix = binding.get("prefix", "")
        if binding.get("source"):
            found = _parameter_set(_xml(base / binding.get("source"), origin), origin)
        else:
            found = _parameter_set(binding, origin)
        values.update({name.removeprefix(prefix): value for name, value in found.items()})
        node = binding.find(f"{SSD}ParameterMapping")
        if node is not None:
            entries = _xml(base / node.get("source"), origin) if node.get("source") else node
            for entry in entries.iter(f"{SSM}MappingEntry"):
                mapping.setdefault(entry.get("source"), []).append(entry.get("target"))
    return values, mapping


def _parse(ssd, origin):
    root = _xml(ssd, origin)
    system = root.find(f"{SSD}System")
    if root.tag != f"{SSD}SystemStructureDescription" or system is None:
        raise ValueError(f"{origin}: not an SSP 1.0 SystemStructureDescription")
    instances, parameters = {}, {}
    for component in system.iter(f"{SSD}Component"):
        name, source = component.get("name"), component.get("source")
        fmu = (ssd.parent / source) if source else None
        if fmu is None or not fmu.is_file():
            raise ValueError(f"{origin}: component {name!r} has no FMU at {source!r}")
        read_fmu(fmu)
        instances[name] = str(fmu)
        parameters[name] = _bindings(component, ssd.parent, origin)[0]
    _system_values(*_bindings(system, ssd.parent, origin), instances, parameters, origin)
    connections = tuple(Connection(c.get("startElement"), c.get("startConnector"), c.get("endElement"),
                                   c.get("endConnector")) for c in system.iter(f"{SSD}Connection"))
    for c in connections:
        for instance in (c.source, c.target):
            if instance not in instances:
                raise ValueError(f"{origin}: a connection names the unknown component {instance!r}")
    times = {}
    master = system.find(f"{SSD}Annotations/{SSC}Annotation/{OMS}Annotations/{OMS}SimulationInformation/"
                         f"{OMS}FixedStepMaster")
    if master is not None and master.get("stepSize") is not None:
        times["step"] = float(master.get("stepSize"))
    experiment = root.find(f"{SSD}DefaultExperiment")
    if experiment is not None:
        for attr, key in (("startTime", "start_time"), ("stopTime", "stop_time")):
            if experiment.get(attr) is not None:
                times[key] = float(experiment.get(attr))
    return System(system.get("name") or Path(origin).stem, instances, connections, match_names=False,
                  parameters=parameters, **times)


def _system_values(values, mapping, instances, parameters, origin):
    """Put the system-level values into ``parameters``: ``instance.variable`` on the instance; mapped, on each
    target; a system's own (``group.variable``, the group no instance) under ``parameters[group]``,
    and the parameters its mapping names keep no value of their own (the system's sets them)."""
    def split(key):
        instance, _, variable = key.partition(".")
        if not instance or not variable:
            raise ValueError(f"{origin}: system parameter {key!r} must be INSTANCE.VARIABLE (or GROUP.VARIABLE, a "
                             f"value of the system's own)")
        return instance, variable

    for key, value in values.items():
        group, variable = split(key)
        own = group not in instances
        if own:
            parameters.setdefault(group, {})[variable] = value
        for target in mapping.get(key, [] if own else [key]):
            instance, variable = split(target)
            if instance not in instances:
                raise ValueError(f"{origin}: system parameter {key!r} is mapped to {target!r}, which names no "
                                 f"component of {', '.join(instances)}")
            if own:
                parameters[instance].pop(variable, None)
            else:
                parameters[instance][variable] = value


def load_parameters(path):
    """``{instance: {variable: value}}`` from an ``.ssv`` file whose names are ``instance.variable``."""
    values = {}
    for key, value in _parameter_set(_xml(path, path), path).items():
        instance, dot, variable = key.partition(".")
        if not dot or not variable:
            raise ValueError(f"{path}: parameter {key!r} must be named INSTANCE.VARIABLE")
        values.setdefault(instance, {})[variable] = value
    return values


# --- writing ------------------------------------------------------------------------

def _write_xml(root, path):
    ET.indent(root)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f".{path.name}.partial")
    ET.ElementTree(root).write(partial, encoding="UTF-8", xml_declaration=True)
    os.replace(partial, path)
    return path


def _typed(parent, ns, kind, **attrs):
    """An ssc/ssv typed element: Real (units) or String, Integer, Boolean."""
    kind = {"Float64": "Real", "Int32": "Integer", "Int64": "Integer", "Enumeration": ENUMERATION_AS}.get(kind, kind)
    return ET.SubElement(parent, f"{ns}{kind}", {k: v for k, v in attrs.items() if v is not None})


def value_text(value):
    """A parameter value as SSP/OSP text: floats exactly (``INF`` for infinity), booleans lower case."""
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float):
        return repr(value) if abs(value) != float("inf") else ("INF" if value > 0 else "-INF")
    return str(value)


def parameter_values(md, overrides):
    """``{name: (variable, value)}`` of the parameters to write for an FMU: its start values with ``overrides``,
    and the inputs ``overrides`` gives a value (a start value the system sets: the free swing's ``u = 0``).

    A start value that is not finite (``INF``: no limit) and not overridden is
    left to the FMU: libcosim (0.10) refuses such values in system files; so is
    a String equal to the FMU's start value (OMSimulator 3.0 applies no String), and an Enumeration equal to
    it (an engine that sets it only as what it is, not as an Integer, is not asked to).
    """
    values = {}
    for v in md.modelVariables:
        if v.type == "Enumeration" and v.causality == "parameter":  # the item's value, by name or value
            value = enumeration_value(v, overrides.get(v.name, v.start))
            if value != enumeration_value(v, v.start):  # as a String: only where it is not the FMU's own
                values[v.name] = (v, value)
        elif v.causality == "input" and v.name in overrides:
            values[v.name] = (v, _CONVERT.get(v.type, str)(overrides[v.name]))
        elif v.causality == "parameter":
            value = overrides.get(v.name, v.start)
            value = _CONVERT.get(v.type, str)(value) if value is not None else None
            if v.name not in overrides and isinstance(value, float) and not math.isfinite(value):
                continue
            if v.type == "String" and value == v.start:
                continue
            values[v.name] = (v, value)
    return values


def system_structure(system, fmus, connections, sources, shared=None):
    """The SystemStructure.ssd element of a resolved system; ``sources`` maps instances to package paths;
    ``shared`` as :func:`write_ssp` takes it."""
    for prefix, ns in (("ssd", SSD_NS), ("ssc", SSC_NS), ("ssv", SSV_NS), ("oms", OMS_NS), ("ssm", SSM_NS)):
        ET.register_namespace(prefix, ns)
    name = re.sub(r"\W", "_", system.name)  # OMSimulator refuses names that are not identifiers (hoist-transport)
    root = ET.Element(f"{SSD}SystemStructureDescription", version="1.0", name=name)
    node = ET.SubElement(root, f"{SSD}System", name=name)
    if shared:
        _shared_values(node, shared, fmus)
    elements = ET.SubElement(node, f"{SSD}Elements")
    units = {}
    for name, path in fmus.items():
        md = read_fmu(path)
        units.update({u.name: u for u in md.unitDefinitions})
        component = ET.SubElement(elements, f"{SSD}Component", name=name, type="application/x-fmu-sharedlibrary",
                                  source=sources[name])
        connectors = ET.SubElement(component, f"{SSD}Connectors")
        for v in md.modelVariables:
            if v.causality in ("parameter", "input", "output") and v.type != "String":
                connector = ET.SubElement(connectors, f"{SSD}Connector", name=v.name, kind=v.causality)
                _typed(connector, SSC, v.type, unit=v.unit if v.type in ("Real", "Float64") else None)
        binding = ET.SubElement(ET.SubElement(component, f"{SSD}ParameterBindings"), f"{SSD}ParameterBinding")
        parameter_set = ET.SubElement(ET.SubElement(binding, f"{SSD}ParameterValues"), f"{SSV}ParameterSet",
                                      version="1.0", name=PARAMETER_SET)
        parameters = ET.SubElement(parameter_set, f"{SSV}Parameters")
        for pname, (v, value) in parameter_values(md, system.parameters.get(name, {})).items():
            if value is not None:
                _typed(ET.SubElement(parameters, f"{SSV}Parameter", name=pname), SSV, v.type,
                       value=value_text(value), unit=v.unit if v.type in ("Real", "Float64") else None)
    links = ET.SubElement(node, f"{SSD}Connections")
    for c in connections:
        ET.SubElement(links, f"{SSD}Connection", startElement=c.source, startConnector=c.output,
                      endElement=c.target, endConnector=c.input)
    information = ET.SubElement(_oms_annotation(node), f"{OMS}SimulationInformation")
    ET.SubElement(information, f"{OMS}FixedStepMaster", description="oms-ma", stepSize=repr(float(system.step)))
    if units:
        unit_node = ET.SubElement(root, f"{SSD}Units")
        for name in sorted(units):
            unit = ET.SubElement(unit_node, f"{SSC}Unit", name=name)
            base = units[name].baseUnit
            exponents = {k: str(getattr(base, k)) for k in _BASE_UNITS if base is not None and getattr(base, k)}
            ET.SubElement(unit, f"{SSC}BaseUnit", exponents)
    experiment = ET.SubElement(root, f"{SSD}DefaultExperiment", startTime=repr(float(system.start_time)),
                               stopTime=repr(float(system.stop_time)))
    _oms_annotation(experiment)  # empty: without one OMSimulator warns of "wrong/deprecated content"
    return root


def _shared_values(node, shared, fmus):
    """The system's own values as a system-level ParameterBinding whose ParameterMapping sends each to the
    component parameters it sets (typed and in the unit of the first of them)."""
    binding = ET.SubElement(ET.SubElement(node, f"{SSD}ParameterBindings"), f"{SSD}ParameterBinding")
    parameter_set = ET.SubElement(ET.SubElement(binding, f"{SSD}ParameterValues"), f"{SSV}ParameterSet",
                                  version="1.0", name=PARAMETER_SET)
    parameters = ET.SubElement(parameter_set, f"{SSV}Parameters")
    mapping = ET.SubElement(ET.SubElement(binding, f"{SSD}ParameterMapping"), f"{SSM}ParameterMapping",
                            version="1.0")
    for name, (value, targets) in shared.items():
        instance, variable = targets[0]
        v = next(v for v in read_fmu(fmus[instance]).modelVariables if v.name == variable)
        _typed(ET.SubElement(parameters, f"{SSV}Parameter", name=name), SSV, v.type, value=value_text(value),
               unit=v.unit if v.type in ("Real", "Float64") else None)
        for instance, variable in targets:
            ET.SubElement(mapping, f"{SSM}MappingEntry", source=name, target=f"{instance}.{variable}")


def _oms_annotation(parent):
    """An ``ssd:Annotations`` of type org.openmodelica under ``parent``; its ``oms:Annotations`` element."""
    annotation = ET.SubElement(ET.SubElement(parent, f"{SSD}Annotations"), f"{SSC}Annotation", type="org.openmodelica")
    return ET.SubElement(annotation, f"{OMS}Annotations")


def write_ssp(system, fmu_dir, path, shared=None):
    """Write ``system`` (FMUs in ``fmu_dir`` or named by path) as an SSP package at ``path``; return it.

    ``shared`` is ``{"group.variable": (value, [(instance, variable), ...])}``: values of the system's own, each
    written once at the system's level with the component parameters it sets (which ``system`` gives the same
    value: the hosts that read only the components' sets apply it too).
    """
    fmus, connections = system.resolve(fmu_dir)
    sources = {name: f"resources/{Path(p).name}" for name, p in fmus.items()}
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="cosim_ssp_") as staging:
        ssd = _write_xml(system_structure(system, fmus, connections, sources, shared),
                         Path(staging) / "SystemStructure.ssd")
        partial = path.with_name(f".{path.name}.partial")
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as ssp:
            ssp.write(ssd, "SystemStructure.ssd")
            for name in sorted(set(sources.values())):
                ssp.write(next(fmus[n] for n in fmus if sources[n] == name), name)
        os.replace(partial, path)
    return path


def write_ssv(parameters, path):
    """Write ``{instance: {variable: value}}`` as an ``.ssv`` parameter set named ``instance.variable``."""
    ET.register_namespace("ssv", SSV_NS)
    root = ET.Element(f"{SSV}ParameterSet", version="1.0", name=Path(path).stem)
    node = ET.SubElement(root, f"{SSV}Parameters")
    for instance, values in parameters.items():
        for name, value in values.items():
            kind = "String" if isinstance(value, str) else "Boolean" if isinstance(value, bool) else "Real"
            _typed(ET.SubElement(node, f"{SSV}Parameter", name=f"{instance}.{name}"), SSV, kind,
                   value=value_text(float(value) if kind == "Real" else value))
    return _write_xml(root, path)
