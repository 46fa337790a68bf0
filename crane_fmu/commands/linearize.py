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
    "  crane-fmu linearize build/native/CranePlant.fmu --at theta1=0\n"
    "  crane-fmu linearize build/fmus/CranePlant.fmu --at theta1=5deg --at u=0.5 --set l1=1.5\n"
    "  crane-fmu linearize build/native/CranePlant.fmu --at theta1=0 --out results/plant.npz   # or .mat"
)


def arguments(p):
    p.add_argument("fmu", metavar="FMU", help="the FMU file (FMI 2.0 or 3.0)")
    p.add_argument("--at", action="append", default=[], metavar="NAME=VALUE",
                   help="a state or input at the operating point (repeatable); angles in rad, or with a deg suffix")
    p.add_argument("--set", action="append", default=[], metavar="VARIABLE=VALUE",
                   help="a parameter before initialisation (repeatable), as simulate's --set without the instance")
    p.add_argument("--out", help="also write the matrices and the names: .npz (numpy) or .mat (MATLAB)")
    p.add_argument("--horizon", type=number, default=None,
                   help="a co-simulation-only FMU's step for its map [s] (default 0.01)")


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
