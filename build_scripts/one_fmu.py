"""A system of native components as one native FMU, generated from the system's data.

The FMU's model is ``fmu_src/native/system.c`` (it implements ``model.h``, so the FMI 2.0 and 3.0
frameworks wrap it unchanged) over the generated ``system_config.h``: one model block per
instance, the system's parameter values (``h`` = the system's step where a component has it, as
``crane-fmu simulate`` sets it), the connections as copies by value reference in the Gauss-Seidel
order of our master (``crane_fmu.cosim.master.Wiring``), and the system's step. A host's
communication step must be a whole multiple of that step.

Each component's model file is compiled once, through a generated ``<Kind>_unit.c`` that defines
``MODEL_PREFIX`` (``CranePlant_``) before including it: model.h then renames its globals, so that
several model files link into one library.

The FMU's interface is that of fmpy's container (``crane_fmu/container.py``): the plant's outputs and
the controller's ``u``; ``m1``, ``m2``, ``l1``, ``l2`` (to the plant, controller and planner that have
them and agree with the first of them on its value: hoist-transport's planner, designed for l1 = 1.5 m,
keeps its own l1), ``x_d`` (to the planner if there is one, else to the controller) and ``theta1_0`` (to the
plant) as parameters, whose start values are the system's; the plant's inputs that nothing inside
feeds (``F1``, ``F2``, ``hoist``) as inputs. A parameter reaches the instances only when a host sets it.
"""

import hashlib
import math
import re
import subprocess
import tempfile
import uuid
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

from crane_fmu import components
from crane_fmu.build_scripts import native
from crane_fmu.build_scripts.model_description import system_dependencies
from crane_fmu.cosim.connections import connect

ONE_FMUS = ("paper", "lqr", "energy", "transport", "hoist-transport")  # built by default, once their models are native
SHARED = ("m1", "m2", "l1", "l2")
MODELERS = ("plant", "controller", "planner")  # the instances that model the crane (the container's choice)


def one_fmu_name(system_name):
    """``hoist-transport`` -> ``CraneHoistTransport``: the FMU's file name and model identifier."""
    return "Crane" + "".join(part.capitalize() for part in re.split(r"[-_ ]", system_name) if part)


def instance_kinds(system):
    """``{instance: model identifier}``; an instance given as an ``.fmu`` file is named by its modelDescription."""
    from crane_fmu.cosim.instance import read_fmu

    return {name: read_fmu(source).coSimulation.modelIdentifier if str(source).endswith(".fmu") else source
            for name, source in system.instances.items()}


def not_native(system):
    """The model identifiers of the system's instances that have no native model yet (sorted)."""
    return sorted({kind for kind in instance_kinds(system).values() if kind not in native.MODELS})


@dataclass(frozen=True)
class Plan:
    """What the C of one system gets, all by name (value references come from the tables).

    Attributes
    ----------
    kinds : dict
        ``{instance: model identifier}``, in the system's order.
    inputs : dict
        ``{instance: [(input, (source instance, output))]}``: the connected inputs.
    values : dict
        ``{instance: {variable: value}}``: the system's values, ``h`` included.
    exchange : list
        ``[("read" | "write", instance)]``: one exchange in Gauss-Seidel order.
    step_order : list
        The instances in the order they step.
    variables : tuple of tables.Variable
        The FMU's own variables: parameters, inputs, outputs.
    links : dict
        ``{own variable: [(instance, variable)]}``: where a parameter or input goes, where an output comes from.
    dependencies : dict
        ``{own output: (own input, ...)}``: the own inputs each own output reads at the same instant.
    """

    kinds: dict
    inputs: dict
    values: dict
    exchange: list
    step_order: list
    variables: tuple
    links: dict
    dependencies: dict


def plan(system):
    """The :class:`Plan` of a system whose components all have native models; ValueError (one line) else."""
    kinds = instance_kinds(system)
    missing = not_native(system)
    if missing:
        raise ValueError(f"system {system.name}: {', '.join(missing)} has no native model (ported: "
                         f"{', '.join(native.MODELS)})")
    tables = {name: {v.name: v for v in components.get(kind).variables} for name, kind in kinds.items()}
    names = {name: {c: [n for n, v in table.items() if v.causality == c] for c in ("input", "output")}
             for name, table in tables.items()}
    connections = connect({name: (n["input"], n["output"]) for name, n in names.items()}, system.connections,
                          system.match_names)
    inputs = {name: [] for name in kinds}
    for c in connections:
        inputs[c.target].append((c.input, (c.source, c.output)))
    feedthrough = {name: components.get(kind).feedthrough and bool(names[name]["input"])
                   for name, kind in kinds.items()}
    order = _dependency_order(kinds, connections, feedthrough)
    exchange = []
    for name in order:
        exchange += [("write", name), ("read", name)] if feedthrough[name] else [("read", name)]
    exchange += [("write", name) for name in order if not feedthrough[name]]
    exchange = [(op, name) for op, name in exchange if op == "read" or inputs[name]]
    variables, links = _interface(system, tables, inputs)
    dependencies = system_dependencies(
        {name: components.get(kind).dependencies() for name, kind in kinds.items()}, connections,
        {v.name: links[v.name][0] for v in variables if v.causality == "output"},
        {v.name: links[v.name] for v in variables if v.causality == "input"})
    return Plan(kinds, inputs, _values(system, tables), exchange, order, variables, links, dependencies)


def _dependency_order(kinds, connections, feedthrough):
    """As ``Wiring._dependency_order``: every feedthrough instance after its sources; ValueError around a loop."""
    after = {name: {c.source for c in connections if c.target == name and c.source != name and feedthrough[name]}
             for name in kinds}
    order = []
    while after:
        ready = [n for n, deps in after.items() if not deps - set(order)]
        if not ready:
            raise ValueError("algebraic loop through direct-feedthrough instances: " + ", ".join(sorted(after)))
        for n in ready:
            order.append(n)
            del after[n]
    return order


def _values(system, tables):
    """The system's parameter values by instance, with ``h`` set to the system's step where a component has it."""
    values = {name: dict(system.parameters.get(name, {})) for name in tables}
    for name, table in tables.items():
        if "h" in table and table["h"].causality == "parameter":
            values[name].setdefault("h", system.step)
        for variable in values[name]:
            if variable not in table or table[variable].causality == "output":
                raise ValueError(f"{name} has no parameter or input {variable!r}")
    return values


def _interface(system, tables, inputs):
    """The container's interface (module docstring): ``(variables, links)``."""
    if "plant" not in tables:
        raise ValueError(f"system {system.name} has no instance named plant to expose")
    variables, links = [], {}

    def start(instance, name):
        return system.parameters.get(instance, {}).get(name, tables[instance][name].start)

    def expose(name, targets, start_value=None):
        first = tables[targets[0][0]][targets[0][1]]
        description = first.description
        if first.causality != "output":
            description += f" (sets {', '.join(f'{i}.{n}' for i, n in targets)})"
        variables.append(first._replace(name=name, start=start_value, description=description))
        links[name] = targets

    for name in SHARED:
        holders = [i for i in MODELERS
                   if i in tables and name in tables[i] and tables[i][name].causality == "parameter"]
        if holders:  # those that agree with the first: a host setting the start value then changes nothing
            value = start(holders[0], name)
            expose(name, [(i, name) for i in holders if start(i, name) == value], value)
    target = "planner" if "planner" in tables else "controller" if "controller" in tables else None
    if target and "x_d" in tables[target]:
        expose("x_d", [(target, "x_d")], start(target, "x_d"))
    expose("theta1_0", [("plant", "theta1_0")], start("plant", "theta1_0"))
    fed = {name for name, _ in inputs["plant"]}
    for name, v in tables["plant"].items():
        if v.causality == "input" and name not in fed:
            expose(name, [("plant", name)], start("plant", name))
    for name, v in tables["plant"].items():
        if v.causality == "output":
            expose(name, [("plant", name)])
    if "controller" in tables and "u" in tables["controller"]:
        expose("u", [("controller", "u")])
    return tuple(variables), links


# ---- C --------------------------------------------------------------------------------------------------------

def _c_double(value):
    value = float(value)
    return ("INFINITY" if value > 0 else "-INFINITY") if math.isinf(value) else repr(value)


def _c_string(text):
    return '"' + str(text).encode("unicode_escape").decode("ascii").replace('"', '\\"') + '"'


def _array(ctype, name, items):
    """A static C array, or NULL where there are no items (C has no empty arrays)."""
    if not items:
        return "", "NULL"
    return f"static const {ctype} {name}[] = {{{', '.join(items)}}};\n", name


def unit_file(kind):
    """``<Kind>_unit.c``: the model file compiled with its globals renamed ``<Kind>_*``."""
    return f"""/* Generated by crane-fmu build: {native.MODELS[kind]} with its globals renamed {kind}_* (model.h). */
#define MODEL_PREFIX {kind}_
#include "{native.MODELS[kind]}"

#ifdef CRANE_SIZE_PROBE /* the build reads sizeof(Model) from the assembly */
const size_t crane_size_probe = sizeof(Model);
#else
#include "system_blocks.h"
typedef char {kind}_fits_its_block[sizeof(Model) <= {kind}_BLOCK ? 1 : -1]; /* else: built with another layout */
#endif
"""


def blocks_header(sizes):
    """``system_blocks.h``: the bytes reserved for each kind's model (the size this build's compiler gives)."""
    lines = "".join(f"#define {kind}_BLOCK {size}\n" for kind, size in sizes.items())
    return f"/* Generated by crane-fmu build; do not edit. */\n#ifndef SYSTEM_BLOCKS_H\n#define SYSTEM_BLOCKS_H\n" \
           f"{lines}#endif\n"


def system_config(system, p, sizes, name):
    """``system_config.h``: the instances, the exchange, the step and the links of ``system`` for system.c."""
    instances = list(p.kinds)
    index = {n: i for i, n in enumerate(instances)}
    tables = {n: components.get(kind).variables for n, kind in p.kinds.items()}
    vr = {n: {v.name: i for i, v in enumerate(table)} for n, table in tables.items()}
    outputs = {n: [v.name for v in table if v.causality == "output"] for n, table in tables.items()}
    buffer, position = {}, 0
    for n in instances:
        buffer[n] = position
        position += len(outputs[n])
    arrays, rows, offset = [], [], 0
    for i, n in enumerate(instances):
        kind = p.kinds[n]
        reals = {k: v for k, v in p.values[n].items() if tables[n][vr[n][k]].type != "String"}
        strings = {k: v for k, v in p.values[n].items() if tables[n][vr[n][k]].type == "String"}
        items = {
            "outputs": ("unsigned", [str(vr[n][o]) for o in outputs[n]]),
            "inputs": ("unsigned", [str(vr[n][inp]) for inp, _ in p.inputs[n]]),
            "sources": ("unsigned", [str(buffer[s] + outputs[s].index(o)) for _, (s, o) in p.inputs[n]]),
            "real_vrs": ("unsigned", [str(vr[n][k]) for k in reals]),
            "reals": ("double", [_c_double(v) for v in reals.values()]),
            "string_vrs": ("unsigned", [str(vr[n][k]) for k in strings]),
            "strings": ("char *const", [_c_string(v) for v in strings.values()]),
        }
        refs = {}
        for key, (ctype, values) in items.items():
            text, refs[key] = _array(ctype, f"i{i}_{key}", values)
            arrays.append(text)
        rows.append(f"    {{{_c_string(n)}, &{kind}_API, {offset}, {len(outputs[n])}, {refs['outputs']}, {buffer[n]}, "
                    f"{len(p.inputs[n])}, {refs['inputs']}, {refs['sources']}, {len(reals)}, {refs['real_vrs']}, "
                    f"{refs['reals']}, {len(strings)}, {refs['string_vrs']}, {refs['strings']}}}, /* {kind} */")
        offset += -(-sizes[kind] // 8)  # in doubles
    own = {v.name: i for i, v in enumerate(p.variables)}
    links = []
    for var, targets in p.links.items():
        for n, target in targets:
            at = buffer[n] + outputs[n].index(target) if target in outputs[n] else vr[n][target]
            links.append(f"    {{{own[var]}, {index[n]}, {at}}}, /* {var}: {n}.{target} */")
    exchange = ", ".join(f"{{{op.upper()}, {index[n]}}}" for op, n in p.exchange)
    apis = "".join(f"MODEL_API({kind}_)\n" for kind in dict.fromkeys(p.kinds.values()))
    return f"""/* Generated by crane-fmu build from the system {system.name} ({name}); do not edit. */
#ifndef SYSTEM_CONFIG_H
#define SYSTEM_CONFIG_H

#include "{name}_variables.h"
#include "system.h"

{apis}
#define SYSTEM_STEP {_c_double(system.step)}
enum {{
    N_INSTANCES = {len(instances)},
    N_BUFFER = {position},
    N_BLOCKS = {offset},
    N_EXCHANGE = {len(p.exchange)},
    N_LINKS = {len(links)},
    MAX_INPUTS = {max([1, *(len(p.inputs[n]) for n in instances)])}
}};

{"".join(arrays)}
static const InstanceRow INSTANCES[N_INSTANCES] = {{
{chr(10).join(rows)}
}};

static const Exchange EXCHANGE[N_EXCHANGE] = {{{exchange}}};
static const unsigned STEP_ORDER[N_INSTANCES] = {{{", ".join(str(index[n]) for n in p.step_order)}}};

static const Link LINKS[N_LINKS] = {{
{chr(10).join(links)}
}};

#endif
"""


def _model_size(compiler, sources, kind):
    """sizeof the kind's Model with this compiler, read from the assembly of its unit file."""
    done = subprocess.run([compiler, "-S", "-O0", "-DCRANE_SIZE_PROBE", f"-I{sources}",
                           f"-I{native.fmi_headers()}", str(sources / f"{kind}_unit.c"), "-o", "-"],
                          capture_output=True, text=True)
    found = re.search(r"crane_size_probe:\s*\.(?:quad|long|8byte)\s+(\d+)", done.stdout)
    if done.returncode != 0 or not found:
        raise RuntimeError(f"cannot read the size of {kind}'s model: {done.stderr.strip()[:500]}")
    return int(found.group(1))


def copied_sources(kinds, fmi_version):
    """The C files of fmu_src a one-FMU of components ``kinds`` is compiled from (besides the generated ones)."""
    return [*(native.MODELS[k] for k in kinds), *native.COMMON, *native.HEADERS, "system.c", "system.h",
            *native.FRAMEWORKS[fmi_version]]


def build_one_fmu(system, out_dir, fmi_version=2, name=None, tools=None):
    """Write ``system`` as one native FMU ``out_dir/<name>.fmu`` (default name :func:`one_fmu_name`); its path."""
    tools = tools or native.compilers()
    name = name or one_fmu_name(system.name)
    p = plan(system)
    kinds = list(dict.fromkeys(p.kinds.values()))
    framework = native.FRAMEWORKS[fmi_version]
    compiled = [f"{kind}_unit.c" for kind in kinds] + [*native.COMMON, "system.c", framework[0]]
    with tempfile.TemporaryDirectory(prefix="crane_one_fmu_") as tmp:
        sources = Path(tmp) / "sources"
        native.copy_sources(copied_sources(kinds, fmi_version), sources)
        for kind in kinds:
            (sources / f"{kind}_variables.h").write_text(native.variables_header(components.get(kind)))
            (sources / f"{kind}_unit.c").write_text(unit_file(kind))
        sizes = {kind: _model_size(tools["linux"], sources, kind) for kind in kinds}
        (sources / "system_blocks.h").write_text(blocks_header(sizes))
        (sources / "system_config.h").write_text(system_config(system, p, sizes, name))
        digest = hashlib.sha256(repr(p.variables).encode())
        for file in sorted(sources.iterdir()):
            digest.update(file.name.encode() + file.read_bytes())
        guid = "{" + str(uuid.UUID(digest.hexdigest()[:32])) + "}"
        model = SimpleNamespace(model_identifier=name, variables=p.variables, dependencies=lambda: p.dependencies,
                                description=f"{system.name} as one native FMU: {system.description}".rstrip(": "),
                                default_experiment=(system.start_time, system.stop_time, system.step))
        (sources / f"{name}_variables.h").write_text(native.variables_header(model, guid))
        build = native.build_description(model, compiled) if fmi_version == 3 else None
        return native.write_fmu(name, out_dir, sources, compiled,
                                native.model_description(model, fmi_version, compiled, guid), build, fmi_version,
                                tools)


def build_one_fmus(out_dir, systems=None, kinds=None, log=print, record=None):
    """The one-FMUs (FMI 2.0 into ``build/native``, 3.0 into its ``fmi3``) of ``systems`` (names or System
    objects; default: those of :data:`ONE_FMUS` made of the components ``kinds`` (default: any) whose
    components are all native, with a note for the others); their paths. With a ``record``
    (:class:`.incremental.Record`), a one-FMU made from the same inputs before is kept."""
    from crane_fmu import systems as registry
    from crane_fmu.build_scripts import incremental

    record = record or incremental.Record()  # keeps nothing

    if systems is None:
        systems = []
        for system_name in ONE_FMUS:
            if kinds is not None and not set(instance_kinds(registry.get(system_name)).values()) <= set(kinds):
                continue
            missing = not_native(registry.get(system_name))
            if missing:
                log(f"note: {one_fmu_name(system_name)} not built: {', '.join(missing)} has no native model yet")
            else:
                systems.append(system_name)
    tools = native.compilers()
    paths = []
    for system in systems:
        system = registry.get(system) if isinstance(system, str) else system
        kinds_used = list(dict.fromkeys(instance_kinds(system).values()))
        for version in (2, 3):
            folder = native.native_dir(out_dir, version)
            paths.append(record.make(folder / f"{one_fmu_name(system.name)}.fmu",
                                     incremental.one_fmu_key(system, kinds_used, version, tools),
                                     lambda s=system, f=folder, v=version: build_one_fmu(s, f, v, tools=tools)))
    return paths
