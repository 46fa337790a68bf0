"""Post-processing of pythonfmu's modelDescription.xml from the variable tables.

pythonfmu 0.7 writes no units and no InitialUnknowns and declares no output
dependencies. This module adds them, so that ``fmpy validate`` passes, every
Real carries an SI unit (angles with display unit deg), and a master can see
which outputs are direct feedthrough.
"""

import xml.etree.ElementTree as ET

from crane_fmu.model.tables import BASE_UNITS, DEG_PER_RAD, xml_double


def _unit_definitions(units, display_units):
    node = ET.Element("UnitDefinitions")
    for name in sorted(units):
        unit = ET.SubElement(node, "Unit", name=name)
        ET.SubElement(unit, "BaseUnit", {k: str(v) for k, v in BASE_UNITS[name].items()})
        if name in display_units:
            ET.SubElement(unit, "DisplayUnit", name=display_units[name], factor=repr(DEG_PER_RAD))
    return node


def postprocess(xml_bytes, table, display_units, feedthrough):
    """Return modelDescription.xml with units, descriptions and model structure.

    Parameters
    ----------
    xml_bytes : bytes
        pythonfmu's modelDescription.xml.
    table : list of crane_fmu.model.tables.Variable
        The FMU's variable table, in registration order.
    display_units : dict
        ``{unit: display unit}``, e.g. ``{"rad": "deg"}``.
    feedthrough : bool
        True when the outputs are computed from the current inputs (the
        controller); False when they are states (the plant).

    Returns
    -------
    bytes
        The new modelDescription.xml (UTF-8).
    """
    root = ET.fromstring(xml_bytes)
    scalars = root.find("ModelVariables").findall("ScalarVariable")
    names = [sv.get("name") for sv in scalars]
    if names != [v.name for v in table]:
        raise ValueError(f"modelDescription variables {names} differ from the table")

    units = set()
    for sv, v in zip(scalars, table):
        sv.set("description", v.description)
        real = sv.find("Real")
        if real is not None and real.get("start") is not None:
            real.set("start", xml_double(v.start))  # pythonfmu's %.16g turns 9.8 into 9.800000000000001
        if real is not None:
            real.set("unit", v.unit)
            units.add(v.unit)
            if v.unit in display_units:
                real.set("displayUnit", display_units[v.unit])

    # Schema order: CoSimulation, UnitDefinitions, ..., LogCategories, ...
    position = list(root).index(root.find("CoSimulation")) + 1
    root.insert(position, _unit_definitions(units, display_units))

    inputs = [str(i + 1) for i, v in enumerate(table) if v.causality == "input"]
    structure = root.find("ModelStructure")
    for child in list(structure):
        structure.remove(child)
    outputs = [i + 1 for i, v in enumerate(table) if v.causality == "output"]
    if outputs:
        out_node = ET.SubElement(structure, "Outputs")
        init_node = ET.SubElement(structure, "InitialUnknowns")
        deps = inputs if feedthrough else []
        for index in outputs:
            attrs = {"index": str(index), "dependencies": " ".join(deps)}
            if deps:
                attrs["dependenciesKind"] = " ".join(["dependent"] * len(deps))
            ET.SubElement(out_node, "Unknown", attrs)
            ET.SubElement(init_node, "Unknown", index=str(index))
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)



def postprocess3(xml_bytes, table, display_units, feedthrough):
    """The FMI 3.0 counterpart of :func:`postprocess` for pythonfmu3's modelDescription.xml.

    pythonfmu3 already declares units natively; this adds display units, exact
    start values and the outputs' dependencies on the inputs.
    """
    root = ET.fromstring(xml_bytes)
    by_name = {v.name: v for v in table}
    inputs = []
    for node in root.find("ModelVariables"):
        v = by_name.get(node.get("name"))
        if v is None:
            continue
        if node.get("start") is not None and v.type == "Real":
            node.set("start", xml_double(v.start))
        if v.unit in display_units:
            node.set("displayUnit", display_units[v.unit])
        if v.causality == "input":
            inputs.append(node.get("valueReference"))
    for unit in root.find("UnitDefinitions"):
        if unit.get("name") in display_units:
            ET.SubElement(unit, "DisplayUnit", name=display_units[unit.get("name")], factor=repr(DEG_PER_RAD))
    for output in root.find("ModelStructure").iter("Output"):
        output.set("dependencies", " ".join(inputs) if feedthrough else "")
        if feedthrough:
            output.set("dependenciesKind", " ".join(["dependent"] * len(inputs)))
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)
