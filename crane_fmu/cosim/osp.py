"""A :class:`~crane_fmu.cosim.system.System` as an OspSystemStructure.xml for OSP / libcosim."""

import os
import xml.etree.ElementTree as ET
from pathlib import Path

from .ssp import parameter_values, value_text
from .system import read_fmu

OSP_NS = "http://opensimulationplatform.com/MSMI/OSPSystemStructure"
OSP = f"{{{OSP_NS}}}"


def write_osp(system, fmu_dir, path):
    """Write the OSP file of ``system`` at ``path``; FMU sources are relative to its folder. Return the path."""
    fmus, connections = system.resolve(fmu_dir)
    path = Path(path)
    ET.register_namespace("", OSP_NS)
    root = ET.Element(f"{OSP}OspSystemStructure", version="0.1")
    ET.SubElement(root, f"{OSP}StartTime").text = repr(float(system.start_time))
    ET.SubElement(root, f"{OSP}BaseStepSize").text = repr(float(system.step))
    ET.SubElement(root, f"{OSP}Algorithm").text = "fixedStep"
    simulators = ET.SubElement(root, f"{OSP}Simulators")
    for name, fmu in fmus.items():
        simulator = ET.SubElement(simulators, f"{OSP}Simulator", name=name,
                                  source=os.path.relpath(Path(fmu).resolve(), path.parent.resolve()),
                                  stepSize=repr(float(system.step)))
        initial = ET.SubElement(simulator, f"{OSP}InitialValues")
        for pname, (v, value) in parameter_values(read_fmu(fmu), system.parameters.get(name, {})).items():
            if value is not None:
                kind = {"Float64": "Real", "Int32": "Integer", "Int64": "Integer", "Enumeration": "Integer"}.get(
                    v.type, v.type)  # an Enumeration by its item's value
                node = ET.SubElement(ET.SubElement(initial, f"{OSP}InitialValue", variable=pname), f"{OSP}{kind}")
                node.set("value", value_text(value))
    links = ET.SubElement(root, f"{OSP}Connections")
    for c in connections:
        link = ET.SubElement(links, f"{OSP}VariableConnection")
        ET.SubElement(link, f"{OSP}Variable", simulator=c.source, name=c.output)
        ET.SubElement(link, f"{OSP}Variable", simulator=c.target, name=c.input)
    ET.indent(root)
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f".{path.name}.partial")
    ET.ElementTree(root).write(partial, encoding="UTF-8", xml_declaration=True)
    os.replace(partial, path)
    return path
