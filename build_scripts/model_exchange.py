"""Model Exchange beside Co-Simulation in a native FMU, from the component's ``Continuous`` description.

A component a host can integrate (``Component.continuous``) gets, after its table's variables (value
references ``len(table)``...), the Model Exchange variables: the states that are no output and the
derivatives that are none (``Continuous.variables``), then one event indicator variable per entry of
``Continuous.indicators`` (FMI 3.0 names each event indicator by a variable). Both the C header
(``<model>_variables.h``: which value references are the states, derivatives and indicators) and the
modelDescription.xml (``<ModelExchange>``, the ``derivative`` attributes, ``Derivatives`` /
``ContinuousStateDerivative``, ``EventIndicator``, the outputs' dependencies on the states and inputs, the
directional derivatives of both interfaces) are made here.

The outputs' and derivatives' dependencies are the structural non-zeros of the component's exact
Jacobians (``Continuous.derivatives_of`` and ``outputs_of`` along each unit seed) at random states and
inputs, for the default parameters and for every parameter moved off its default (so that a term a
default switches off, such as the drive's lag ``tau = 0``, is still listed). An output lists the inputs of
co-simulation's table and the states and inputs Model Exchange reads it by. One ModelStructure serves both
interfaces, so it lists their union: ``ddx`` reads ``u`` in Model Exchange only (the acceleration now, ``u``
through the drive; in co-simulation the acceleration over the last step, which ``u`` does not move). No closed
loop becomes algebraic by that: no built-in system feeds ``ddx`` back into ``u``, and masters that judge loops per
variable (ours, ``crane_fmu.cosim.exchange``) see none.
"""

import math
import random
import xml.etree.ElementTree as ET

from crane_fmu.build_scripts.model_description import _unit_definitions
from crane_fmu.model.tables import DISPLAY_UNITS, local

EVENT_INDICATOR_UNIT = None  # an indicator is a distance or an acceleration, by mode: no one unit


def indicator_name(watched):
    """The variable of the event indicator that watches ``watched`` (``-v_max``: the lower speed limit, v_min)."""
    return "indicator_" + (watched[1:].replace("_max", "_min") if watched.startswith("-") else watched)


def me_variables(component):
    """The Model Exchange variables after the table: ``Continuous.variables``, then the event indicators."""
    q = component.continuous
    indicators = tuple(local(indicator_name(w), EVENT_INDICATOR_UNIT,
                             f"event indicator: zero where the limit {w} is reached (or a held one let go)")
                       for w in q.indicators)
    return q.variables + indicators


def value_references(component):
    """``{name: FMI 2.0 value reference}`` of the table's and the Model Exchange variables."""
    names = [v.name for v in component.variables] + [v.name for v in me_variables(component)]
    return {name: vr for vr, name in enumerate(names)}


def header(component):
    """The C of ``<model>_variables.h`` for Model Exchange (component.h's ContinuousComponent)."""
    q, vrs = component.continuous, value_references(component)
    inputs = [vr for vr, v in enumerate(component.variables) if v.causality == "input"]
    if inputs != list(range(inputs[0], inputs[0] + len(inputs))):
        raise ValueError(f"{component.model_identifier}: Model Exchange expects the inputs together in the table")

    def array(name, values):
        return f"static const unsigned {name}[] = {{{', '.join(str(v) for v in values)}}};"

    return f"""
/* Model Exchange: the continuous states, their derivatives and the event indicators by value reference. */
enum {{
    FIRST_INPUT = {inputs[0]},
    N_INPUTS = {len(inputs)},
    N_CONTINUOUS_STATES = {len(q.states)},
    N_EVENT_INDICATORS = {len(q.indicators)},
    N_LOCALS = {len(me_variables(component))} /* value references N_VARIABLES... */
}};
{array("STATE_VRS", [vrs[n] for n in q.states])}
{array("DERIVATIVE_VRS", [vrs[n] for n in q.derivatives])}
{array("INDICATOR_VRS", [vrs[indicator_name(w)] for w in q.indicators])}
"""


def _generic_values(component):
    """The parameters moved off their defaults: 0 to 0.3, any other finite value by 10 % (limits stay off)."""
    moved = {}
    for v in component.variables:
        if v.causality == "parameter" and v.type == "Real" and abs(v.start) < 1e59:
            moved[v.name] = 0.3 if v.start == 0 else v.start * 1.1
    return moved


ROUNDING = 1e-12  # an exact Jacobian entry this small (at states and inputs of order 1) is rounding, not a term


def dependencies(component, points=3):
    """``({derivative: states and inputs}, {output: states and inputs})``: the structural non-zeros.

    The union over random states and inputs of the exact Jacobians' non-zero entries, for the default
    parameters and the moved ones (:func:`_generic_values`), every limit free. An entry within rounding of zero
    (:data:`ROUNDING`) is zero: the tangent of a term that cancels (der(dtheta2) by dl1_now) leaves 1e-16.
    """
    q = component.continuous
    inputs = [v.name for v in component.variables if v.causality == "input"]
    outputs = [v.name for v in component.variables if v.causality == "output"]
    n, m = len(q.states), len(inputs)
    rng = random.Random(38)
    found_d, found_o = {d: set() for d in q.derivatives}, {o: set() for o in outputs}
    for values in ({}, _generic_values(component)):
        config = component.check(values)
        for _ in range(points):
            state = [rng.uniform(-0.5, 0.5) for _ in range(n)]
            state[q.states.index("l1_now")] = rng.uniform(0.5, 1.5) if "l1_now" in q.states else 0.0
            u = [rng.uniform(-0.5, 0.5) for _ in range(m)]
            for k, known in enumerate(q.states + tuple(inputs)):
                seed = (tuple(float(j == k) for j in range(n)), tuple(float(n + j == k) for j in range(m)))
                _, d_derivatives = q.derivatives_of(config, tuple(state), tuple(u), q.free_mode, seed)
                _, d_outputs = q.outputs_of(config, tuple(state), tuple(u), q.free_mode, seed)
                for name, value in zip(q.derivatives, d_derivatives):
                    if abs(value) > ROUNDING and math.isfinite(value):
                        found_d[name].add(known)
                for name, value in zip(outputs, d_outputs):
                    if abs(value) > ROUNDING and math.isfinite(value):
                        found_o[name].add(known)
    order = {name: i for i, name in enumerate(q.states + tuple(inputs))}
    return ({k: sorted(v, key=order.get) for k, v in found_d.items()},
            {k: sorted(v, key=order.get) for k, v in found_o.items()})


def _with_units(root, component, display_units):
    """Unit definitions for the table's and the Model Exchange variables' units (schema position kept)."""
    old = root.find("UnitDefinitions")
    units = {v.unit for v in component.variables + me_variables(component) if v.unit}
    shown = {u: d for u, d in display_units.items() if u in units}
    root[list(root).index(old)] = _unit_definitions(units, shown)


def _joined(references):
    references = sorted(references)
    return {"dependencies": " ".join(map(str, references)),
            **({"dependenciesKind": " ".join(["dependent"] * len(references))} if references else {})}


def _more_initial_unknowns(component, ids, listed):
    """The continuous states and derivatives not ``listed`` among the initial unknowns yet, as ``(id,
    dependencies)`` (``ids``: name -> index or value reference): each depends on every parameter and input."""
    q = component.continuous
    sources = [ids[v.name] for v in component.variables if v.causality in ("parameter", "input")]
    new = dict.fromkeys(ids[name] for name in q.states + q.derivatives if ids[name] not in listed)
    return [(i, _joined(sources)) for i in new]


def _list_initial_inputs(initial, name_of, ids, component, by_output):
    """An output reads in initialisation mode the inputs it reads after it: its initial unknown lists them too
    (``name_of(unknown)``: the unknown's variable; ``ids``: name -> index or value reference)."""
    inputs = {ids[v.name] for v in component.variables if v.causality == "input"}
    for unknown in initial:
        name = name_of(unknown)
        if name in by_output:
            listed = {int(i) for i in unknown.get("dependencies", "").split()}
            unknown.attrib.update(_joined(listed | ({ids[k] for k in by_output[name]} & inputs)))


def add_to_fmi2(xml_bytes, component, sources):
    """modelDescription.xml (FMI 2.0) with Model Exchange beside its co-simulation."""
    q, vrs = component.continuous, value_references(component)
    root = ET.fromstring(xml_bytes)
    root.set("numberOfEventIndicators", str(len(q.indicators)))
    cs = root.find("CoSimulation")
    me = ET.Element("ModelExchange", modelIdentifier=cs.get("modelIdentifier"), needsExecutionTool="false",
                    completedIntegratorStepNotNeeded="true", canBeInstantiatedOnlyOncePerProcess="false",
                    canNotUseMemoryManagementFunctions="true", canGetAndSetFMUstate="true",
                    canSerializeFMUstate="true", providesDirectionalDerivative="true")
    files = ET.SubElement(me, "SourceFiles")
    for source in sources:
        ET.SubElement(files, "File", name=source)
    root.insert(list(root).index(cs), me)
    cs.set("providesDirectionalDerivative", "true")  # at the communication points (continuous.c)
    _with_units(root, component, DISPLAY_UNITS)
    index = {name: vr + 1 for name, vr in vrs.items()}  # FMI 2.0 indices: 1-based positions (vr + 1 here)
    variables = root.find("ModelVariables")
    for v in me_variables(component):
        sv = ET.SubElement(variables, "ScalarVariable", name=v.name, valueReference=str(vrs[v.name]),
                           description=v.description, causality="local", variability="continuous",
                           initial="calculated")
        ET.SubElement(sv, "Real", {"unit": v.unit} if v.unit else {})
    scalars = variables.findall("ScalarVariable")
    for state, derivative in zip(q.states, q.derivatives):
        scalars[index[derivative] - 1].find("Real").set("derivative", str(index[state]))
    by_derivative, by_output = dependencies(component)
    structure = root.find("ModelStructure")
    for unknown in structure.find("Outputs"):
        name = scalars[int(unknown.get("index")) - 1].get("name")
        listed = unknown.get("dependencies", "").split()
        unknown.attrib.update(_joined({int(i) for i in listed} | {index[s] for s in by_output[name]}))
    derivatives = ET.Element("Derivatives")
    for name in q.derivatives:
        ET.SubElement(derivatives, "Unknown", index=str(index[name]),
                      **_joined(index[k] for k in by_derivative[name]))
    structure.insert(1, derivatives)
    initial = structure.find("InitialUnknowns")
    _list_initial_inputs(initial, lambda u: scalars[int(u.get("index")) - 1].get("name"), index, component,
                         by_output)
    listed = {int(u.get("index")) for u in initial}
    for i, depends in _more_initial_unknowns(component, index, listed):
        ET.SubElement(initial, "Unknown", index=str(i), **depends)
    initial[:] = sorted(initial, key=lambda u: int(u.get("index")))
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def add_to_fmi3(xml_bytes, component):
    """modelDescription.xml (FMI 3.0) with Model Exchange beside its co-simulation."""
    q = component.continuous
    vrs = {name: vr + 1 for name, vr in value_references(component).items()}  # FMI 3.0: time is 0
    root = ET.fromstring(xml_bytes)
    cs = root.find("CoSimulation")
    me = ET.Element("ModelExchange", modelIdentifier=cs.get("modelIdentifier"), needsExecutionTool="false",
                    needsCompletedIntegratorStep="false", canBeInstantiatedOnlyOncePerProcess="false",
                    canGetAndSetFMUState="true", canSerializeFMUState="true", providesDirectionalDerivatives="true",
                    providesAdjointDerivatives="true")
    root.insert(list(root).index(cs), me)
    cs.set("providesDirectionalDerivatives", "true")  # at the communication points (continuous.c)
    cs.set("providesAdjointDerivatives", "true")
    _with_units(root, component, DISPLAY_UNITS)
    variables = root.find("ModelVariables")
    for v in me_variables(component):
        attrs = {"name": v.name, "valueReference": str(vrs[v.name]), "description": v.description,
                 "causality": "local", "variability": "continuous", "initial": "calculated"}
        if v.unit:
            attrs["unit"] = v.unit
        ET.SubElement(variables, "Float64", attrs)
    nodes = {node.get("name"): node for node in variables}
    for state, derivative in zip(q.states, q.derivatives):
        nodes[derivative].set("derivative", str(vrs[state]))
    by_derivative, by_output = dependencies(component)
    names = {vr: name for name, vr in vrs.items()}
    structure = root.find("ModelStructure")
    outputs = [u for u in structure if u.tag == "Output"]
    initial = [u for u in structure if u.tag == "InitialUnknown"]
    for unknown in outputs:
        name = names[int(unknown.get("valueReference"))]
        listed = unknown.get("dependencies", "").split()
        unknown.attrib.update(_joined({int(i) for i in listed} | {vrs[s] for s in by_output[name]}))
    derivatives = [ET.Element("ContinuousStateDerivative", valueReference=str(vrs[name]),
                              **_joined(vrs[k] for k in by_derivative[name])) for name in q.derivatives]
    _list_initial_inputs(initial, lambda u: names[int(u.get("valueReference"))], vrs, component, by_output)
    listed = {int(u.get("valueReference")) for u in initial}
    initial += [ET.Element("InitialUnknown", valueReference=str(vr), **depends)
                for vr, depends in _more_initial_unknowns(component, vrs, listed)]
    initial.sort(key=lambda u: int(u.get("valueReference")))
    indicators = [ET.Element("EventIndicator", valueReference=str(vrs[indicator_name(w)])) for w in q.indicators]
    structure[:] = outputs + derivatives + initial + indicators
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)
