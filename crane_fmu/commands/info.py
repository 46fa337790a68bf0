"""``crane-fmu info``: list the built-in systems and the components' variables."""

from pathlib import Path

from crane_fmu.model.tables import variable_table

from .common import UsageError, parse_sets

NAME = "info"
HELP = "list the built-in systems and the components' variables"
EXAMPLES = (
    "examples:\n"
    "  crane-fmu info\n"
    "  crane-fmu info --markdown\n"
    "  crane-fmu info --system lqr\n"
    "  crane-fmu info --system lqr --set controller.l1=1.5 --set controller.h=0.01  # the LQR's gains\n"
    "  crane-fmu info --system hoist-transport --set crane.l2=0.6   # the crane's parameters and what they bind\n"
    "  crane-fmu info --system transport --use controller=build/mine/PdSway.fmu   # your FMU in the system"
)


def arguments(p):
    from crane_fmu import DEFAULT_FMU_DIR

    p.add_argument("--markdown", action="store_true", help="print the variable tables as Markdown")
    p.add_argument("--system", help="instead: a built-in system's (or an .ssp file's) crane parameters (crane.l2: "
                                    "which instances they set), its instances and what their components derive from "
                                    "the parameters (gains, shaper impulses)")
    p.add_argument("--set", action="append", default=[], metavar="INSTANCE.VARIABLE=VALUE",
                   help="with --system: parameter values to derive from (repeatable)")
    p.add_argument("--use", action="append", default=[], metavar="INSTANCE=FILE.fmu",
                   help="with --system: your FMU (or law file, mylaw.py) in the instance's place, as simulate --use "
                        "puts it: its parameters, and which of the system's values it takes (repeatable)")
    p.add_argument("--fmu-dir", default=DEFAULT_FMU_DIR,
                   help=f"with --use: folder of the built FMUs, for the move a controller is told (default: "
                        f"{DEFAULT_FMU_DIR})")


def run(args):
    from crane_fmu import components, crane_parameters, systems

    from .simulate import _use

    if args.system:
        try:
            with systems.open_system(args.system) as system:
                system, notes = _told(_use(args.use, system), args.fmu_dir, args.set)
                print("\n".join(_derived(system, args.set) + notes))
        except ValueError as exc:
            raise UsageError(str(exc)) from None
        return 0
    if args.use:
        raise UsageError("--use needs --system NAME: the system whose instance your FMU takes the place of")
    chosen = [c for c in components.registered() if c.role != "benchmark"]
    if args.markdown:
        print("\n".join(variable_table(c, True) for c in chosen), end="")
        return 0
    print("crane parameters (--set crane.NAME=VALUE sets every instance that models the crane, unless it has its own "
          "value; crane-fmu info --system NAME lists them):")
    for v in crane_parameters.model():
        print(f"  crane.{v.name:<3} [{v.unit}] {v.description}")
    print()
    print("systems (crane-fmu simulate --system NAME):")
    for system in systems.registered():
        instances = ", ".join(f"{name} = {kind}" for name, kind in system.instances.items())
        print(f"  {system.name:<10} {instances}: {system.description}")
    print()
    for c in chosen:
        print(variable_table(c, False))
    return 0


def _derived(system, sets):
    """Lines describing a system's (built-in, or of an SSP file) crane parameters, each instance and what its component
    derives from the parameters."""
    from crane_fmu import components, crane_parameters, systems

    variables, kinds = {}, systems.kinds(system)  # an SSP's instances are FMU files: named by their model identifier
    for instance, kind in kinds.items():
        component = components.find(kind)
        variables[instance] = {v.name: (v.type, v.unit) for v in (component.variables if component else ())
                               if v.causality != "output"}
        if instance in system.replaced:  # your FMU: the variables it has
            variables[instance] = {v.name: (v.type, v.unit) for v in read_fmu(system.instances[instance]).modelVariables
                                   if v.causality in ("parameter", "input")}
    models = systems.modelled(system)
    variables.update(crane_parameters.settable(models))
    system = crane_parameters.with_values(system, parse_sets(sets, variables))
    lines = [f"{system.name}: {system.description}" if system.description else system.name, *_crane(system, models)]
    bound = systems.named_items(systems.bind(system))  # an SSP file's Enumeration: its item's value, read by name
    for name, kind in kinds.items():
        if name in system.replaced:
            lines += _yours(system, name, bound.parameters.get(name, {}))
            continue
        component = components.find(kind)
        lines.append(f"  {name} = {kind}" + ("" if component else " (not a registered component)"))
        if component and component.report:
            try:
                derived = component.report(component.check(bound.parameters.get(name, {})))
            except (ValueError, ArithmeticError) as exc:
                raise UsageError(f"{name}: {exc}") from None
            lines += [f"    {key} = {value:.6g}" if isinstance(value, float) else f"    {key} = {value}"
                      for key, value in derived.items()]
    return lines


def _told(system, fmu_dir, sets):
    """``(system, note lines)``: with ``--use``, each controller told the move as simulate tells it (the target as
    ``--set`` gives it)."""
    from crane_fmu import systems

    if not system.replaced:
        return system, []
    try:
        values = [parse_sets(sets, systems.settable(system, system.fmus(fmu_dir)))]
        system, notes = systems.tell_controllers(system, fmu_dir, values)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    return system, [f"  note: {note}" for note in notes]


def _yours(system, name, values):
    """Lines on an instance that ``--use`` replaced: the file, its parameters (the system's value where it takes one)
    and the system's values it has no parameter for."""
    md = read_fmu(system.instances[name])
    parameters = {v.name: v for v in md.modelVariables if v.causality == "parameter"}
    lines = [f"  {name} = {Path(system.instances[name]).name} (yours: {md.coSimulation.modelIdentifier}, in place of "
             f"{system.replaced[name]})"]
    for variable in parameters.values():
        value = values.get(variable.name)
        lines.append(f"    {variable.name} = " + (f"{value:.6g} (set)" if value is not None
                                                  else f"{variable.start} (its start value)"))
    dropped = [v for v in values if v not in parameters]
    if dropped:
        lines.append(f"    the system's {', '.join(dropped)}: not set (it has no such parameter)")
    return lines


def read_fmu(source):
    from crane_fmu.cosim.instance import read_fmu as read

    return read(source)


def _crane(system, models):
    """The crane's parameters: each one's value and unit, the instances it sets and those with a value of their own."""
    from crane_fmu import components, crane_parameters
    from crane_fmu.cosim.system import is_file

    def start(instance, name):  # a component's default, or an FMU file's start value (an SSP's instances)
        source = system.instances[instance]
        if not is_file(source):
            return components.get(source).defaults()[name]
        return next(float(v.start) for v in read_fmu(source).modelVariables if v.name == name)

    shared, values = crane_parameters.shared(system, models, start), crane_parameters.values(system)
    lines = ["  crane parameters (crane.NAME=VALUE sets each on the instances listed; a value of an instance's own "
             "overrides it):"]
    for v in crane_parameters.model():
        value, instances = shared.get(v.name, (None, []))
        own = [f"{i} = {system.parameters[i][v.name]:g}" for i, names in models.items()
               if v.name in names and v.name in system.parameters.get(i, {})]
        where = ", ".join(instances) or "no instance"
        lines.append(f"    crane.{v.name} = " + (f"{value:g} {v.unit}" if value is not None else "(none)")
                     + (" (set)" if v.name in values else "") + f": {where}"
                     + (f"; own values: {', '.join(own)}" if own else ""))
    return lines
