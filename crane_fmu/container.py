"""A closed-loop system as one FMU, for tools that import a single FMU: fmpy's container FMU.

``fmpy.container_fmu`` (FMPy 0.3.32) packs the system's FMUs, their
connections and a Rust binary into one **FMI 3.0 co-simulation FMU**. The
container steps its inner FMUs at a fixed internal step (the system's step):
a host's communication step must be a whole multiple of it. After each inner
step it copies outputs to inputs along the connections, like this project's
``jacobi`` master without the initial exchange (the first step runs with the
inputs' start values); the two give identical results (``tests/test_container.py``).

The container exposes the plant's outputs and the controller's ``u``; as its
own parameters the masses and cable lengths (mapped to the ``plant``,
``controller`` and ``planner`` instances that have them, so plant and models
agree), ``x_d`` (to the planner when there is one, else to the controller)
and the plant's initial swing ``theta1_0``; as inputs the plant's inputs that
nothing inside feeds (``F1``, ``F2``, ``hoist``).
"""

import shutil
import tempfile
import uuid
from pathlib import Path

SHARED = ("m1", "m2", "l1", "l2")


def build_container(system, fmu_dir, path):
    """Write ``system`` (FMUs in ``fmu_dir`` or named by path) as one container FMU at ``path``; return it."""
    import attrs
    from fmpy import read_model_description
    from fmpy.container_fmu import Configuration
    from fmpy.container_fmu.cli import create_container_fmu
    from fmpy.container_fmu.config import Component, Connection
    from fmpy.model_description import CoSimulation, DefaultExperiment, ModelDescription, ModelVariable, Unknown

    fmus, connections = system.resolve(fmu_dir)
    if "plant" not in fmus:
        raise ValueError(f"system {system.name} has no instance named plant to expose")
    components = {name: Component(name=name, filename=Path(path_), modelDescription=read_model_description(path_))
                  for name, path_ in fmus.items()}
    variables = {name: {v.name: v for v in c.modelDescription.modelVariables} for name, c in components.items()}

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

    def expose(name, causality, targets, start=None, description=None):
        first = variables[targets[0][0]][targets[0][1]]
        v = ModelVariable(name=name, causality=causality, type="Float64", start=start,
                          variability="fixed" if causality == "parameter" else "continuous",
                          description=description or first.description, unit=first.unit)
        md.modelVariables.append(v)
        mappings[v] = [(components[i], variables[i][n]) for i, n in targets]
        if causality == "output":
            md.outputs.append(Unknown(index=len(md.modelVariables), variable=v))
            md.initialUnknowns.append(Unknown(index=len(md.modelVariables), variable=v))

    def start(instance, name):
        value = system.parameters.get(instance, {}).get(name, variables[instance][name].start)
        return repr(float(value))

    for name in SHARED:  # to the built-in instances that model the crane
        holders = [i for i in ("plant", "controller", "planner")
                   if i in fmus and name in variables[i] and variables[i][name].causality == "parameter"]
        expose(name, "parameter", [(i, name) for i in holders], start("plant", name))
    target = "planner" if "planner" in fmus else "controller" if "controller" in fmus else None
    if target and "x_d" in variables[target]:
        expose("x_d", "parameter", [(target, "x_d")], start(target, "x_d"))
    expose("theta1_0", "parameter", [("plant", "theta1_0")], start("plant", "theta1_0"))
    fed = {(c.target, c.input) for c in connections}
    for name, v in variables["plant"].items():
        if v.causality == "input" and ("plant", name) not in fed:
            expose(name, "input", [("plant", name)], start("plant", name))
    for name, v in variables["plant"].items():
        if v.causality == "output":
            expose(name, "output", [("plant", name)])
    if "controller" in fmus and "u" in variables["controller"]:
        expose("u", "output", [("controller", "u")])
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
    from crane_fmu.build_scripts.model_description import system_dependencies

    dependencies = {}
    for name, inner_md in inner.items():
        inputs = tuple(v.name for v in inner_md.modelVariables if v.causality == "input")
        dependencies[name] = {u.variable.name: inputs if u.dependencies is None else
                              tuple(v.name for v in u.dependencies) for u in inner_md.outputs}
    own = {v.name: v for v in md.modelVariables}
    targets = {v.name: [(c.name, t.name) for c, t in mapped] for v, mapped in mappings.items()}
    read = system_dependencies(dependencies, connections,
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
