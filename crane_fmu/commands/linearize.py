"""``crane-fmu linearize``: a plant FMU's A, B, C, D at an operating point."""

from argparse import ArgumentTypeError

from ..cosim.suggest import did_you_mean
from .common import UsageError, convert, number, writable_file

NAME = "linearize"
HELP = "a plant FMU's A, B, C, D matrices at an operating point"
DESCRIPTION = ("Linearise an FMU at an operating point: x' = A x + B u, y = C x + D u. From the FMU's directional "
               "derivatives (Model Exchange) where it gives them, else from central differences (said in the "
               "output). The operating point is the FMU's initial state and its inputs' start values, with --at "
               "in place of those named.")
EXAMPLES = (
    "examples:\n"
    "  crane-fmu linearize --loop --system lqr --plot results/lqr-loop.png\n"
    "  crane-fmu linearize --loop --system transport --use controller=pd_sway.py --at theta1=2deg\n"
    "  crane-fmu linearize build/native/CranePlant.fmu --at theta1=0\n"
    "  crane-fmu linearize build/fmus/CranePlant.fmu --at theta1=5deg --at u=0.5 --set l1=1.5\n"
    "  crane-fmu linearize build/native/CranePlant.fmu --at theta1=0 --out results/plant.npz   # or .mat"
)


def arguments(p):
    p.add_argument("fmu", metavar="FMU", nargs="?", help="the FMU file (FMI 2.0 or 3.0)")
    p.add_argument("--at", action="append", default=[], metavar="NAME=VALUE",
                   help="a state or input at the operating point (repeatable); angles in rad, or with a deg suffix")
    p.add_argument("--set", action="append", default=[], metavar="VARIABLE=VALUE",
                   help="a parameter before initialisation (repeatable), as simulate's --set without the instance; "
                        "with --loop, as simulate's: INSTANCE.VARIABLE=VALUE")
    p.add_argument("--out", help="also write the matrices and the names: .npz (numpy) or .mat (MATLAB)")
    p.add_argument("--horizon", type=number, default=None,
                   help="a co-simulation-only FMU's step for its map [s] (default 0.01)")
    loop = p.add_argument_group("the closed loop (instead of an FMU)")
    loop.add_argument("--loop", action="store_true",
                      help="a system's loop of plant and controller, sampled at its step, broken at the plant's "
                           "input: closed-loop poles and damping, gain and phase margins, sensitivity peak")
    loop.add_argument("--system", help="with --loop: a built-in system's name or an SSP file")
    loop.add_argument("--fmu-dir", default="build/fmus", help="with --loop: folder of the built FMUs")
    loop.add_argument("--use", action="append", default=[], metavar="INSTANCE=FILE.fmu",
                      help="with --loop: your FMU or law file (FILE.py) in the instance's place, as simulate's")
    loop.add_argument("--plot", help="with --loop: Bode and Nyquist plots into a PNG")
    loop.add_argument("--memory", type=number, default=None, metavar="SECONDS",
                      help="with --loop: the window of the controller's impulse response taken [s] (default 0.5); "
                           "a response still alive at its end is refused unless it is one mode (an integrator)")


def _pairs(items, option, variables):
    """``{name: value}`` of ``NAME=VALUE`` items, each a variable of ``variables`` ({name: variable})."""
    result = {}
    for item in items:
        name, sep, text = item.partition("=")
        if not sep or not name:
            raise UsageError(f"{option} {item!r}: expected NAME=VALUE")
        variable = variables.get(name)
        if variable is None:
            what = "parameter" if option == "--set" else "state or input"
            raise UsageError(f"{option} {item!r}: the FMU has no {what} {name!r}; valid: {', '.join(variables)}"
                             + did_you_mean(name, variables))
        try:
            result[name] = convert(text, variable.type, variable.unit, infinite=option == "--set")
        except (ArgumentTypeError, ValueError) as exc:
            raise UsageError(f"{option} {item!r}: {exc}") from None
    return result


def run(args):
    from pathlib import Path

    if args.loop or args.system:
        return _loop(args)
    if args.fmu is None:
        raise UsageError("give an FMU to linearise, or --loop --system NAME for a system's closed loop")
    if args.memory is not None:
        raise UsageError("--memory is for --loop: the window of a system's controller")

    from crane_fmu.analysis import linearize as lin

    if args.out:
        writable_file(args.out, "--out", (".npz", ".mat"))
    if args.horizon is not None and not args.horizon > 0:
        raise UsageError(f"--horizon must be > 0, got {args.horizon!r}")
    try:
        md = lin.describe(args.fmu)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    variables = {v.name: v for v in md.modelVariables}
    parameters = {n: v for n, v in variables.items() if v.causality == "parameter"}
    if md.modelExchange is not None:
        states = [d.variable.derivative.name for d in md.derivatives]
    else:
        states = list(lin.start_parameters(md))
    point = {n: variables[n] for n in states}
    point.update({n: v for n, v in variables.items() if v.causality == "input"})
    at, values = _pairs(args.at, "--at", point), _pairs(args.set, "--set", parameters)
    try:
        result = lin.linearize(args.fmu, at, values, lin.HORIZON if args.horizon is None else args.horizon)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    print(lin.report(result, f"{Path(args.fmu).name}: x' = A x + B u, y = C x + D u"))
    if args.out:
        lin.save(result, args.out)
        print(f"wrote {args.out}")
    return 0


def _loop(args):
    """``--loop``: the closed loop of a system's plant and controller (crane_fmu/analysis/loop.py)."""
    from types import SimpleNamespace

    from crane_fmu.analysis import loop

    from .simulate import on_system, prepare

    if args.fmu is not None:
        raise UsageError(f"--loop analyses a system's loop; leave out the FMU {args.fmu} (or --loop)")
    if not args.loop or not args.system:
        raise UsageError("--loop and --system go together: crane-fmu linearize --loop --system NAME")
    if args.plot:
        writable_file(args.plot, "--plot", ".png")
    if args.memory is not None and not args.memory > 0:
        raise UsageError(f"--memory must be > 0 s, got {args.memory!r}")
    memory = loop.MEMORY if args.memory is None else args.memory

    def analyse(args, system):
        run_args = SimpleNamespace(fmu_dir=args.fmu_dir, parameters=None, set=args.set)
        system, fmus, connections = prepare(run_args, system, system.step)
        from crane_fmu import components, systems

        kinds = systems.kinds(system)
        plant = components.by_role(kinds).get("plant")
        crane = components.get(kinds[plant]).crane if plant else None
        point = {n: SimpleNamespace(type="Real", unit="rad" if n.startswith("theta") else None)
                 for n in (crane.state if crane else ())}
        at = _pairs(args.at, "--at", point)
        result = loop.of_system(system, fmus, connections, at, memory)
        print(loop.report(result))
        if args.plot:
            used = "".join(f" with {n}={Path(system.instances[n]).name}" for n in system.replaced)
            loop.plot(result, args.plot, f"{system.name}{used}: loop broken at {plant}.u, h = {system.step:g} s")
            print(f"wrote {args.plot}")
        return 0

    from pathlib import Path

    return on_system(args, analyse)
