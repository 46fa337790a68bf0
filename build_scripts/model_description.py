"""Post-processing of pythonfmu's modelDescription.xml from the variable tables.

pythonfmu 0.7 writes no units and no InitialUnknowns and declares no output
dependencies. This module adds them, so that ``fmpy validate`` passes, every
Real carries an SI unit (angles with display unit deg), and a master can see
which outputs are direct feedthrough.

The model structure lists real dependencies: an output (Outputs, FMI 3.0
Output) lists the inputs it reads at the same instant (``Component.dependencies``),
no more and no fewer, since a host reads a missing list as "every input" (a false
algebraic loop) and an empty one as "none". At initialisation (InitialUnknowns,
InitialUnknown) every output follows the parameters: it lists its inputs and
every parameter.
"""

import xml.etree.ElementTree as ET

from crane_fmu.model.tables import BASE_UNITS, DEG_PER_RAD, declared_type, enumeration_value, xml_double


def _unit_definitions(units, display_units):
    node = ET.Element("UnitDefinitions")
    for name in sorted(units):
        unit = ET.SubElement(node, "Unit", name=name)
        ET.SubElement(unit, "BaseUnit", {k: str(v) for k, v in BASE_UNITS[name].items()})
        if name in display_units:
            ET.SubElement(unit, "DisplayUnit", name=display_units[name], factor=repr(DEG_PER_RAD))
    return node


def _type_definitions(table, fmi3):
    """TypeDefinitions of the table's Enumeration variables (None where it has none): one type per variable, its
    items valued 1, 2, ... in order (``tables.enumeration``)."""
    enumerations = [v for v in table if v.type == "Enumeration"]
    if not enumerations:
        return None
    node = ET.Element("TypeDefinitions")
    for v in enumerations:
        if fmi3:
            kind = ET.SubElement(node, "EnumerationType", name=declared_type(v), description=v.description)
        else:
            kind = ET.SubElement(ET.SubElement(node, "SimpleType", name=declared_type(v), description=v.description),
                                 "Enumeration")
        for value, item in enumerate(v.items, start=1):
            ET.SubElement(kind, "Item", name=item, value=str(value))
    return node


def _joined(values):
    return {"dependencies": " ".join(map(str, values)), **(
        {"dependenciesKind": " ".join(["dependent"] * len(values))} if values else {})}


def postprocess(xml_bytes, table, display_units, dependencies):
    """Return modelDescription.xml with units, descriptions and model structure.

    Parameters
    ----------
    xml_bytes : bytes
        pythonfmu's modelDescription.xml.
    table : list of crane_fmu.model.tables.Variable
        The FMU's variable table, in registration order.
    display_units : dict
        ``{unit: display unit}``, e.g. ``{"rad": "deg"}``.
    dependencies : dict
        ``{output: (input, ...)}``: the inputs each output reads at the same
        instant (``Component.dependencies()``).

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
        if v.type == "Enumeration":  # pythonfmu's (and the native skeleton's) Integer
            for child in list(sv):
                sv.remove(child)
            ET.SubElement(sv, "Enumeration", declaredType=declared_type(v), start=str(enumeration_value(v, v.start)))
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
    types = _type_definitions(table, fmi3=False)
    if types is not None:
        root.insert(position + 1, types)

    index = {v.name: i + 1 for i, v in enumerate(table)}  # FMI 2.0 indices: 1-based ScalarVariable positions
    parameters = [index[v.name] for v in table if v.causality == "parameter"]
    structure = root.find("ModelStructure")
    for child in list(structure):
        structure.remove(child)
    outputs = [v.name for v in table if v.causality == "output"]
    if outputs:
        out_node = ET.SubElement(structure, "Outputs")
        init_node = ET.SubElement(structure, "InitialUnknowns")
        for name in outputs:
            read = [index[i] for i in dependencies[name]]
            ET.SubElement(out_node, "Unknown", index=str(index[name]), **_joined(read))
            ET.SubElement(init_node, "Unknown", index=str(index[name]), **_joined(sorted(read + parameters)))
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)



def postprocess3(xml_bytes, table, display_units, dependencies):
    """The FMI 3.0 counterpart of :func:`postprocess` for pythonfmu3's modelDescription.xml.

    pythonfmu3 already declares units natively; this adds display units, exact
    start values and the outputs' dependencies on the inputs (and, at
    initialisation, the parameters).
    """
    root = ET.fromstring(xml_bytes)
    by_name = {v.name: v for v in table}
    vrs = {}
    for node in root.find("ModelVariables"):
        v = by_name.get(node.get("name"))
        if v is None:
            continue
        vrs[v.name] = int(node.get("valueReference"))
        if v.type == "Enumeration":  # pythonfmu3's (and the native skeleton's) Int64
            node.tag = "Enumeration"
            node.attrib.pop("unit", None)
            node.set("declaredType", declared_type(v))
            node.set("start", str(enumeration_value(v, v.start)))
        if node.get("start") is not None and v.type == "Real":
            node.set("start", xml_double(v.start))
        if v.unit in display_units:
            node.set("displayUnit", display_units[v.unit])
    for unit in root.find("UnitDefinitions"):
        if unit.get("name") in display_units:
            ET.SubElement(unit, "DisplayUnit", name=display_units[unit.get("name")], factor=repr(DEG_PER_RAD))
    types = _type_definitions(table, fmi3=True)
    if types is not None:
        old = root.find("TypeDefinitions")
        if old is not None:
            root.remove(old)
        root.insert(list(root).index(root.find("UnitDefinitions")) + 1, types)
    parameters = [vrs[v.name] for v in table if v.causality == "parameter"]
    names = {vr: name for name, vr in vrs.items()}
    structure = root.find("ModelStructure")
    for unknown in list(structure):
        read = sorted(vrs[i] for i in dependencies[names[int(unknown.get("valueReference"))]])
        if unknown.tag == "Output":
            unknown.attrib.update(_joined(read))
        elif unknown.tag == "InitialUnknown":
            unknown.attrib.update(_joined(sorted(read + parameters)))
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)
