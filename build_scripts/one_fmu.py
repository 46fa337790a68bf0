"""A system of native components as one native FMU, generated from the system's data.

The FMU's model is ``fmu_src/system/system.c`` (a model behind ``model.h``, so the FMI 2.0 and 3.0
frameworks run it as any model) over the generated ``system_config.h``: one model block per
instance, the system's parameter values (``h`` = the system's step where a component has it, as
``crane-fmu simulate`` sets it), the connections as copies by value reference in the Gauss-Seidel
order of our master (``crane_fmu.cosim.master.Wiring``), and the system's step. A host's
communication step must be a whole multiple of that step.

Each component's model file is compiled once, as in its own FMU: it registers ``<Kind>_MODEL``, which
the system reaches through the model interface.

The FMU's interface is the closed loop's, chosen once for it and fmpy's container (``crane_fmu/closed_loop.py``):
the plant's outputs and the controller's ``u``; the crane's masses, lengths and g, ``x_d`` and ``theta1_0`` as
parameters, whose start values are the system's; the plant's inputs that nothing inside feeds as inputs.
A parameter reaches the instances only when a host sets it.
"""

import hashlib
import math
import re
import tempfile
import uuid
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from types import SimpleNamespace

from crane_fmu import closed_loop, components
from crane_fmu import systems as registry
from crane_fmu.build_scripts import incremental, native
from crane_fmu.cosim.connections import connect
from crane_fmu.cosim.exchange import exchange_calls
from crane_fmu.model.tables import enumeration_value


def one_fmu_name(system_name):
    """``hoist-transport`` -> ``CraneHoistTransport``: the FMU's file name and model identifier."""
    return "Crane" + "".join(part.capitalize() for part in re.split(r"[-_ ]", system_name) if part)


def not_native(system):
    """The model identifiers of the system's instances that have no native model yet (sorted)."""
    return sorted({kind for kind in registry.kinds(system).values() if kind not in native.ported()})


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
    kinds = registry.kinds(system)
    missing = not_native(system)
    if missing:
        raise ValueError(f"system {system.name}: {', '.join(missing)} has no native model (ported: "
                         f"{', '.join(native.ported())})")
    tables = {name: {v.name: v for v in components.get(kind).variables} for name, kind in kinds.items()}
    names = {name: {c: [n for n, v in table.items() if v.causality == c] for c in ("input", "output")}
             for name, table in tables.items()}
    connections = connect({name: (n["input"], n["output"]) for name, n in names.items()}, system.connections,
                          system.match_names)
    inputs = {name: [] for name in kinds}
    for c in connections:
        inputs[c.target].append((c.input, (c.source, c.output)))
    calls = exchange_calls(list(kinds), {name: components.get(kind).dependencies() for name, kind in kinds.items()},
                           connections)  # as our master's Wiring: per variable
    exchange = [(op, name) for op, name in calls.exchange if op == "read" or inputs[name]]
    variables, links = _interface(system, kinds, tables, inputs)
    dependencies = closed_loop.system_dependencies(
        {name: components.get(kind).dependencies() for name, kind in kinds.items()}, connections,
        {v.name: links[v.name][0] for v in variables if v.causality == "output"},
        {v.name: links[v.name] for v in variables if v.causality == "input"})
    return Plan(kinds, inputs, _values(system, tables), exchange, calls.order, variables, links, dependencies)


def _values(system, tables):
    """The prepared system's values by instance (``h`` = the system's step where a component has it)."""
    prepared = registry.prepare(system, check=False)  # the components' rules apply inside the FMU
    values = {name: dict(prepared.parameters.get(name, {})) for name in tables}
    for name, table in tables.items():
        for variable in values[name]:
            if variable not in table or table[variable].causality == "output":
                raise ValueError(f"{name} has no parameter or input {variable!r}")
    return values


def _interface(system, kinds, tables, inputs):
    """The closed loop's interface (``crane_fmu.closed_loop``): ``(variables, links)``."""
    exposed = closed_loop.interface(system, kinds, {name: {n: (v.causality, v.start) for n, v in table.items()}
                                                    for name, table in tables.items()},
                                    {(name, input_) for name, items in inputs.items() for input_, _ in items})
    variables, links = [], {}
    for e in exposed:
        first = tables[e.targets[0][0]][e.targets[0][1]]
        description = first.description
        if e.causality != "output":
            description += f" (sets {', '.join(f'{i}.{n}' for i, n in e.targets)})"
        variables.append(first._replace(name=e.name, start=e.start, description=description))
        links[e.name] = e.targets
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


def system_config(system, p, name):
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
    arrays, rows = [], []
    for i, n in enumerate(instances):
        kind = p.kinds[n]
        reals = {k: v for k, v in p.values[n].items() if tables[n][vr[n][k]].type == "Real"}
        strings = {k: v for k, v in p.values[n].items() if tables[n][vr[n][k]].type == "String"}
        integers = {k: enumeration_value(tables[n][vr[n][k]], v) for k, v in p.values[n].items()
                    if tables[n][vr[n][k]].type == "Enumeration"}
        items = {
            "outputs": ("unsigned", [str(vr[n][o]) for o in outputs[n]]),
            "inputs": ("unsigned", [str(vr[n][inp]) for inp, _ in p.inputs[n]]),
            "sources": ("unsigned", [str(buffer[s] + outputs[s].index(o)) for _, (s, o) in p.inputs[n]]),
            "real_vrs": ("unsigned", [str(vr[n][k]) for k in reals]),
            "reals": ("double", [_c_double(v) for v in reals.values()]),
            "string_vrs": ("unsigned", [str(vr[n][k]) for k in strings]),
            "strings": ("char *const", [_c_string(v) for v in strings.values()]),
            "integer_vrs": ("unsigned", [str(vr[n][k]) for k in integers]),
            "integers": ("long long", [str(v) for v in integers.values()]),
        }
        refs = {}
        for key, (ctype, values) in items.items():
            text, refs[key] = _array(ctype, f"i{i}_{key}", values)
            arrays.append(text)
        rows.append(f"    {{{_c_string(n)}, &{kind}_MODEL, {len(outputs[n])}, {refs['outputs']}, {buffer[n]}, "
                    f"{len(p.inputs[n])}, {refs['inputs']}, {refs['sources']}, {len(reals)}, {refs['real_vrs']}, "
                    f"{refs['reals']}, {len(strings)}, {refs['string_vrs']}, {refs['strings']}, {len(integers)}, "
                    f"{refs['integer_vrs']}, {refs['integers']}}},")
    own = {v.name: i for i, v in enumerate(p.variables)}
    links = []
    for var, targets in p.links.items():
        for n, target in targets:
            at = buffer[n] + outputs[n].index(target) if target in outputs[n] else vr[n][target]
            links.append(f"    {{{own[var]}, {index[n]}, {at}}}, /* {var}: {n}.{target} */")
    exchange = ", ".join(f"{{{op.upper()}, {index[n]}}}" for op, n in p.exchange)
    models = "".join(f"extern const ModelType {kind}_MODEL;\n" for kind in dict.fromkeys(p.kinds.values()))
    return f"""/* Generated by crane-fmu build from the system {system.name} ({name}); do not edit. */
#ifndef SYSTEM_CONFIG_H
#define SYSTEM_CONFIG_H

#include "{name}_variables.h"
#include "system.h"

{models}
#define SYSTEM_STEP {_c_double(system.step)}
enum {{
    N_INSTANCES = {len(instances)},
    N_BUFFER = {position},
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


def compiled_sources(kinds, fmi_version):
    """The C files of fmu_src a one-FMU of components ``kinds`` compiles (besides the generated fmu_model.c)."""
    c_files, _ = native.model_sources([components.get(k).native for k in kinds])
    return [*c_files, *native.COMMON, "system.c", native.FRAMEWORKS[fmi_version][0]]


def copied_sources(kinds, fmi_version):
    """The C files of fmu_src a one-FMU of components ``kinds`` is compiled from, and its headers (besides the
    generated ones)."""
    _, headers = native.model_sources([components.get(k).native for k in kinds])
    return [*compiled_sources(kinds, fmi_version), *native.HEADERS, *headers, "system.h",
            native.FRAMEWORKS[fmi_version][1]]


def build_one_fmu(system, out_dir, fmi_version=2, name=None, tools=None):
    """Write ``system`` as one native FMU ``out_dir/<name>.fmu`` (default name :func:`one_fmu_name`); its path."""
    tools = tools or native.compilers()
    name = name or one_fmu_name(system.name)
    p = plan(system)
    kinds = list(dict.fromkeys(p.kinds.values()))
    compiled = [*compiled_sources(kinds, fmi_version), "fmu_model.c"]
    with tempfile.TemporaryDirectory(prefix="crane_one_fmu_") as tmp:
        sources = Path(tmp) / "sources"
        native.copy_sources(copied_sources(kinds, fmi_version), sources)
        for kind in kinds:
            (sources / f"{kind}_variables.h").write_text(native.variables_header(components.get(kind)))
        (sources / "system_config.h").write_text(system_config(system, p, name))
        (sources / "fmu_model.c").write_text(native.fmu_model(name))
        digest = hashlib.sha256(repr(p.variables).encode())
        for file in sorted(sources.iterdir()):
            digest.update(file.name.encode() + file.read_bytes())
        guid = "{" + str(uuid.UUID(digest.hexdigest()[:32])) + "}"
        model = SimpleNamespace(model_identifier=name, variables=p.variables, dependencies=lambda: p.dependencies,
                                description=f"{system.name} as one native FMU: {system.description}".rstrip(": "),
                                default_experiment=(system.start_time, system.stop_time, system.step),
                                continuous=None)  # a system is co-simulation only
        (sources / f"{name}_variables.h").write_text(native.variables_header(model, guid))
        build = native.build_description(model, compiled) if fmi_version == 3 else None
        return native.write_fmu(name, out_dir, sources, compiled,
                                native.model_description(model, fmi_version, compiled, guid), build, fmi_version,
                                tools)


def build_one_fmus(out_dir, systems=None, kinds=None, log=print, record=None):
    """The one-FMUs (FMI 2.0 into ``build/native``, 3.0 into its ``fmi3``) of ``systems`` (names or System
    objects; default: the built-in systems tagged ``one-fmu`` made of the components ``kinds`` (default:
    any) whose components are all native, with a note for the others); their paths. With a ``record``
    (:class:`.incremental.Record`), a one-FMU made from the same inputs before is kept."""
    record = record or incremental.Record()  # keeps nothing

    if systems is None:
        systems = []
        for system_name in registry.tagged("one-fmu"):
            if kinds is not None and not set(registry.kinds(registry.get(system_name)).values()) <= set(kinds):
                continue
            missing = not_native(registry.get(system_name))
            if missing:
                log(f"note: {one_fmu_name(system_name)} not built: {', '.join(missing)} has no native model yet")
            else:
                systems.append(system_name)
    tools = native.compilers()
    builds = []
    for system in systems:
        system = registry.get(system) if isinstance(system, str) else system
        kinds_used = list(dict.fromkeys(registry.kinds(system).values()))
        for version in (2, 3):
            folder = native.native_dir(out_dir, version)
            builds.append(partial(record.make, folder / f"{one_fmu_name(system.name)}.fmu",
                                  incremental.one_fmu_key(system, kinds_used, version, tools, [
                                      native.source_path(name) for name in copied_sources(kinds_used, version)]),
                                  partial(build_one_fmu, system, folder, version, tools=tools)))
    return native.in_parallel(builds)
