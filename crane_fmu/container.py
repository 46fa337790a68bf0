"""A closed-loop system as one FMU, for tools that import a single FMU: fmpy's container FMU.

``fmpy.container_fmu`` (FMPy 0.3.32) packs the system's FMUs, their
connections and a Rust binary into one **FMI 3.0 co-simulation FMU**. The
container steps its inner FMUs at a fixed internal step (the system's step):
a host's communication step must be a whole multiple of it. After each inner
step it copies outputs to inputs along the connections, like this project's
``jacobi`` master without the initial exchange (the first step runs with the
inputs' start values); the two give identical results (``tests/test_container.py``).

What the container exposes is the closed loop's interface (``closed_loop.py``, the
one-FMU's too): the plant's outputs and the controller's ``u``; the masses and
cable lengths, ``x_d`` and ``theta1_0`` as parameters; the plant's inputs that
nothing inside feeds as inputs. fmpy's container sets an inner FMU's variable only
through what it exposes: a system with other values that differ from the FMUs' own
start values (hoist-transport's planners) is refused; the native one-FMU
(``build_scripts/one_fmu.py``) carries them. Values equal to them need no setting: an
SSP file, which holds every parameter's value, packs as the system it was written from.
"""

import shutil
import tempfile
import uuid
from pathlib import Path

import attrs
from fmpy import read_model_description
from fmpy.container_fmu import Configuration
from fmpy.container_fmu.cli import create_container_fmu
from fmpy.container_fmu.config import Component, Connection
from fmpy.model_description import CoSimulation, DefaultExperiment, ModelDescription, ModelVariable, Unknown

from crane_fmu import closed_loop, crane_parameters
from crane_fmu.cosim.instance import enumeration_value


def build_container(system, fmu_dir, path):
    """Write ``system`` (FMUs in ``fmu_dir`` or named by path) as one container FMU at ``path``; return it."""
    fmus, connections = system.resolve(fmu_dir)
    components = {name: Component(name=name, filename=Path(path_), modelDescription=read_model_description(path_))
                  for name, path_ in fmus.items()}
    variables = {name: {v.name: v for v in c.modelDescription.modelVariables} for name, c in components.items()}
    kinds = {name: c.modelDescription.coSimulation.modelIdentifier for name, c in components.items()}
    exposed = closed_loop.interface(system, kinds, {name: {n: (v.causality, _number(v)) for n, v in table.items()}
                                                    for name, table in variables.items()},
                                    {(c.target, c.input) for c in connections})
    carried = {target for e in exposed if e.causality != "output" for target in e.targets}
    lost = [f"{i}.{n}" for i, values in system.parameters.items() if i != crane_parameters.CRANE
            for n, value in values.items() if (i, n) not in carried and not _is_start(variables[i].get(n), value)]
    # the crane's values: its exposed parameters' start values; an FMU's own start value needs no setting (an SSP
    # file holds every parameter's value)
    if lost:
        raise ValueError(f"system {system.name}: fmpy's container sets only the variables it exposes, not "
                         f"{', '.join(lost)}; build it as one native FMU instead (crane-fmu build --one-fmu)")

    def float64(v):  # FMPy 0.3.32 writes a connection's type as declared; its container needs FMI 3.0 names
        return attrs.evolve(v, type="Float64") if v.type == "Real" else v

    links = [Connection(startElement=components[c.source], startConnectors=[float64(variables[c.source][c.output])],
                        endElement=components[c.target], endConnectors=[float64(variables[c.target][c.input])])
             for c in connections]
    md = ModelDescription()
    md.fmiVersion, md.modelName = "3.0", path.stem if isinstance(path, Path) else Path(path).stem
    md.instantiationToken = "{" + str(uuid.uuid4()) + "}"
    md.description = f"{system.name} as one FMU: {system.description}"
    units = {u.name: u for c in components.values() for u in c.modelDescription.unitDefinitions}
    md.unitDefinitions = list(units.values())
    md.coSimulation = CoSimulation(modelIdentifier="container_fmu", fixedInternalStepSize=system.step)
    md.defaultExperiment = DefaultExperiment(startTime=repr(system.start_time), stopTime=repr(system.stop_time),
                                             stepSize=repr(system.step))
    # first, unmapped, value reference 0: the container's k-th mapped variable has value reference k
    md.modelVariables.append(ModelVariable(name="time", causality="independent", variability="continuous",
                                           type="Float64", description="simulation time"))
    mappings = {}
    for e in exposed:
        first = variables[e.targets[0][0]][e.targets[0][1]]
        v = ModelVariable(name=e.name, causality=e.causality, type="Float64",
                          start=None if e.start is None else repr(float(e.start)),
                          variability="fixed" if e.causality == "parameter" else "continuous",
                          description=first.description, unit=first.unit)
        md.modelVariables.append(v)
        mappings[v] = [(components[i], variables[i][n]) for i, n in e.targets]
        if e.causality == "output":
            md.outputs.append(Unknown(index=len(md.modelVariables), variable=v))
            md.initialUnknowns.append(Unknown(index=len(md.modelVariables), variable=v))
    _declare_dependencies(md, mappings, {name: c.modelDescription for name, c in components.items()}, connections)
    config = Configuration(parallelDoStep=False, modelDescription=md, components=list(components.values()),
                           connections=links, variableMappings=mappings)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f".{path.name}.partial")
    with tempfile.TemporaryDirectory(prefix="crane_container_") as tmp:
        create_container_fmu(config, Path(tmp), partial)
    shutil.move(partial, path)
    return path


def _declare_dependencies(md, mappings, inner, connections):
    """The container's real model structure: each output lists the own inputs it reads at the same instant
    (through the inner FMUs' declared feedthrough, along the connections), at initialisation also every
    parameter; without a list a host would take every input (a false algebraic loop).

    ``inner`` is ``{instance: its modelDescription}``; an inner output without a list reads every input.
    """
    dependencies = {}
    for name, inner_md in inner.items():
        inputs = tuple(v.name for v in inner_md.modelVariables if v.causality == "input")
        dependencies[name] = {u.variable.name: inputs if u.dependencies is None else
                              tuple(v.name for v in u.dependencies if v.causality == "input")
                              for u in inner_md.outputs}  # a continuous state an output lists is no input
    own = {v.name: v for v in md.modelVariables}
    targets = {v.name: [(c.name, t.name) for c, t in mapped] for v, mapped in mappings.items()}
    read = closed_loop.system_dependencies(dependencies, connections,
                                           {n: targets[n][0] for n, v in own.items() if v.causality == "output"},
                                           {n: targets[n] for n, v in own.items() if v.causality == "input"})
    parameters = [v for v in md.modelVariables if v.causality == "parameter"]
    for unknown in md.outputs:
        unknown.dependencies = [own[n] for n in read[unknown.variable.name]]
        unknown.dependenciesKind = ["dependent"] * len(unknown.dependencies) or None
    for unknown in md.initialUnknowns:
        unknown.dependencies = sorted([own[n] for n in read[unknown.variable.name]] + parameters,
                                      key=md.modelVariables.index)
        unknown.dependenciesKind = ["dependent"] * len(unknown.dependencies) or None


def _is_start(v, value):
    """Whether ``value`` (a system's, an SSP file's) is fmpy's variable ``v``'s start value as the FMU parses it: an
    Enumeration by its item's value (an SSP file holds that) or name, a Boolean as ``true``/``1``, a number exactly."""
    if v is None or v.start is None:
        return False
    if v.type == "Enumeration":
        try:
            return enumeration_value(v, value) == enumeration_value(v, v.start)
        except ValueError:  # not one of its items: refused by name
            return False
    if v.type == "String":
        return value == v.start
    if v.type == "Boolean":
        return isinstance(value, bool) and value == (v.start.strip().lower() in ("true", "1"))
    try:
        return not isinstance(value, (bool, str)) and value == (float(v.start) if v.type in ("Real", "Float64")
                                                                else int(v.start))
    except (TypeError, ValueError):
        return False


def _number(v):
    """A Real's start value as a float (fmpy reads it as text), any other's as it is."""
    return float(v.start) if v.type in ("Real", "Float64") and v.start is not None else v.start
