"""``crane-fmu info``: list the built-in systems and the components' variables."""



from crane_fmu.model.tables import variable_table

from .common import UsageError, parse_sets

NAME = "info"
HELP = "list the built-in systems and the components' variables"
EXAMPLES = (
    "examples:\n"
    "  crane-fmu info\n"
    "  crane-fmu info --markdown\n"
    "  crane-fmu info --system lqr\n"
    "  crane-fmu info --system lqr --set controller.l1=1.5 --set controller.h=0.01  # the LQR's gains"
)


def arguments(p):
    p.add_argument("--markdown", action="store_true", help="print the variable tables as Markdown")
    p.add_argument("--system", help="instead: a built-in system's instances and what their components derive from "
                                    "the parameters (gains, shaper impulses)")
    p.add_argument("--set", action="append", default=[], metavar="INSTANCE.VARIABLE=VALUE",
                   help="with --system: parameter values to derive from (repeatable)")


def run(args):
    from crane_fmu import components, systems

    if args.system:
        try:
            system = systems.get(args.system)
        except ValueError as exc:
            raise UsageError(str(exc)) from None
        print("\n".join(_derived(system, args.set)))
        return 0
    chosen = [c for c in components.registered() if c.role != "benchmark"]
    if args.markdown:
        print("\n".join(variable_table(c, True) for c in chosen), end="")
        return 0
    print("systems (crane-fmu simulate --system NAME):")
    for system in systems.registered():
        instances = ", ".join(f"{name} = {kind}" for name, kind in system.instances.items())
        print(f"  {system.name:<10} {instances}: {system.description}")
    print()
    for c in chosen:
        print(variable_table(c, False))
    return 0


def _derived(system, sets):
    """Lines describing each instance of a built-in system and what its component derives from the parameters."""
    from crane_fmu import components

    variables = {}
    for instance, kind in system.instances.items():
        component = components.find(kind)
        variables[instance] = {v.name: (v.type, v.unit) for v in (component.variables if component else ())
                               if v.causality != "output"}
    parameters = parse_sets(sets, variables)
    system = system.with_parameters(parameters)
    lines = [f"{system.name}: {system.description}"]
    for name, kind in system.instances.items():
        component = components.find(kind)
        lines.append(f"  {name} = {kind}" + ("" if component else " (not a registered component)"))
        if component and component.report:
            try:
                derived = component.report(component.check(system.parameters.get(name, {})))
            except (ValueError, ArithmeticError) as exc:
                raise UsageError(f"{name}: {exc}") from None
            lines += [f"    {key} = {value:.6g}" if isinstance(value, float) else f"    {key} = {value}"
                      for key, value in derived.items()]
    return lines
