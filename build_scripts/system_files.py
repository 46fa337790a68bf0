"""System descriptions of the crane pair for other tools: an SSP 1.0 package and an OSP file.

Both are generated from the FMU variable tables and the master's connection
list, so they describe exactly the system that ``crane-fmu simulate`` runs.
"""

import os
import shutil
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

from crane_fmu.cosim.system import CRANE_CONNECTIONS, FMU_FILES
from crane_fmu.model import tables
from crane_fmu.model.tables import BASE_UNITS

SSD = "http://ssp-standard.org/SSP1/SystemStructureDescription"
SSC = "http://ssp-standard.org/SSP1/SystemStructureCommon"
SSV = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
OSP = "http://opensimulationplatform.com/MSMI/OSPSystemStructure"
TABLES = {"plant": tables.PLANT, "controller": tables.CONTROLLER}


def _write_xml(root, path):
    ET.indent(root)
    partial = Path(path).with_name(Path(path).name + ".partial")
    ET.ElementTree(root).write(partial, encoding="UTF-8", xml_declaration=True)
    os.replace(partial, path)


def system_structure(step=1e-3, stop_time=20.0):
    """SystemStructure.ssd: components, connectors, connections, parameter values, units."""
    ET.register_namespace("ssd", SSD)
    ET.register_namespace("ssc", SSC)
    ET.register_namespace("ssv", SSV)
    root = ET.Element(f"{{{SSD}}}SystemStructureDescription", version="1.0", name="CraneSystem")
    system = ET.SubElement(root, f"{{{SSD}}}System", name="CraneSystem")
    elements = ET.SubElement(system, f"{{{SSD}}}Elements")
    units = set()
    for instance, table in TABLES.items():
        component = ET.SubElement(elements, f"{{{SSD}}}Component", name=instance,
                                  type="application/x-fmu-sharedlibrary", source=f"resources/{FMU_FILES[instance]}")
        connectors = ET.SubElement(component, f"{{{SSD}}}Connectors")
        for v in table:
            connector = ET.SubElement(connectors, f"{{{SSD}}}Connector", name=v.name, kind=v.causality)
            if v.type == "Real":
                ET.SubElement(connector, f"{{{SSC}}}Real", unit=v.unit)
                units.add(v.unit)
            else:
                ET.SubElement(connector, f"{{{SSC}}}String")
        binding = ET.SubElement(ET.SubElement(component, f"{{{SSD}}}ParameterBindings"), f"{{{SSD}}}ParameterBinding")
        parameter_set = ET.SubElement(ET.SubElement(binding, f"{{{SSD}}}ParameterValues"), f"{{{SSV}}}ParameterSet",
                                      version="1.0", name=f"{instance}_parameters")
        parameters = ET.SubElement(parameter_set, f"{{{SSV}}}Parameters")
        for v in table:
            if v.causality == "parameter":
                parameter = ET.SubElement(parameters, f"{{{SSV}}}Parameter", name=v.name)
                if v.type == "Real":
                    ET.SubElement(parameter, f"{{{SSV}}}Real", value=repr(float(v.start)), unit=v.unit)
                else:
                    ET.SubElement(parameter, f"{{{SSV}}}String", value=v.start)
    connections = ET.SubElement(system, f"{{{SSD}}}Connections")
    for c in CRANE_CONNECTIONS:
        ET.SubElement(connections, f"{{{SSD}}}Connection", startElement=c.source, startConnector=c.output,
                      endElement=c.target, endConnector=c.input)
    unit_node = ET.SubElement(root, f"{{{SSD}}}Units")
    for name in sorted(units):
        unit = ET.SubElement(unit_node, f"{{{SSC}}}Unit", name=name)
        ET.SubElement(unit, f"{{{SSC}}}BaseUnit", {k: str(e) for k, e in BASE_UNITS[name].items()})
    ET.SubElement(root, f"{{{SSD}}}DefaultExperiment", startTime="0.0", stopTime=repr(stop_time))
    return root


def write_ssp(fmu_dir, path):
    """The SSP package: SystemStructure.ssd plus the two FMUs under resources/."""
    path = Path(path)
    staging = path.with_name(path.name + ".d")
    shutil.rmtree(staging, ignore_errors=True)
    staging.mkdir(parents=True)
    try:
        _write_xml(system_structure(), staging / "SystemStructure.ssd")
        partial = path.with_name(path.name + ".partial")
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as ssp:
            ssp.write(staging / "SystemStructure.ssd", "SystemStructure.ssd")
            for instance in TABLES:
                ssp.write(Path(fmu_dir) / FMU_FILES[instance], f"resources/{FMU_FILES[instance]}")
        os.replace(partial, path)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return path


def write_osp(fmu_dir, step=1e-3):
    """OspSystemStructure.xml beside the FMUs: simulators, initial values, connections."""
    ET.register_namespace("", OSP)
    root = ET.Element(f"{{{OSP}}}OspSystemStructure", version="0.1")
    ET.SubElement(root, f"{{{OSP}}}StartTime").text = "0.0"
    ET.SubElement(root, f"{{{OSP}}}BaseStepSize").text = repr(step)
    ET.SubElement(root, f"{{{OSP}}}Algorithm").text = "fixedStep"
    simulators = ET.SubElement(root, f"{{{OSP}}}Simulators")
    for instance, table in TABLES.items():
        simulator = ET.SubElement(simulators, f"{{{OSP}}}Simulator", name=instance, source=FMU_FILES[instance],
                                  stepSize=repr(step))
        initial = ET.SubElement(simulator, f"{{{OSP}}}InitialValues")
        for v in table:
            if v.causality == "parameter":
                value = ET.SubElement(ET.SubElement(initial, f"{{{OSP}}}InitialValue", variable=v.name),
                                      f"{{{OSP}}}{v.type}")
                value.set("value", repr(float(v.start)) if v.type == "Real" else v.start)
    connections = ET.SubElement(root, f"{{{OSP}}}Connections")
    for c in CRANE_CONNECTIONS:
        link = ET.SubElement(connections, f"{{{OSP}}}VariableConnection")
        ET.SubElement(link, f"{{{OSP}}}Variable", simulator=c.source, name=c.output)
        ET.SubElement(link, f"{{{OSP}}}Variable", simulator=c.target, name=c.input)
    path = Path(fmu_dir) / "OspSystemStructure.xml"
    _write_xml(root, path)
    return path
