"""``crane-fmu simulate``: co-simulate a system of FMUs."""

import os
import sys

from crane_fmu import DEFAULT_FMU_DIR, DEFAULT_SYSTEM
from crane_fmu.cosim.algorithms import ALGORITHMS

from .common import UsageError, number, parse_sets, writable_file

NAME = "simulate"
HELP = "co-simulate a system of FMUs"
DESCRIPTION = ("Co-simulate a built-in system or an SSP file with the fixed-step master; write every output of "
               "every instance to a CSV (and a plot).")
EXAMPLES = (
    "examples:\n"
    "  crane-fmu simulate --out results/section5.csv --plot results/section5.png\n"
    "  crane-fmu simulate --system free --stop-time 10 --out free.csv\n"
    "  crane-fmu simulate --system build/systems/paper.ssp --parameters my.ssv\n"
    "  crane-fmu simulate --master jacobi --step 0.01 --set controller.w_theta2=0\n"
    "  crane-fmu simulate --set plant.l1=1.5 --set controller.l1=1.5 --set plant.theta1_0=0.2"
)


def arguments(p):
    p.add_argument("--system", default=DEFAULT_SYSTEM,
                   help=f"a built-in system's name (crane-fmu info lists them) or an SSP file "
                        f"(default: {DEFAULT_SYSTEM})")
    p.add_argument("--fmu-dir", default=DEFAULT_FMU_DIR, help=f"folder of the built FMUs (default: {DEFAULT_FMU_DIR})")
    p.add_argument("--stop-time", type=number, help="stop time [s] (default: the system's, 20 s built in)")
    p.add_argument("--step", type=number, help="communication step [s] (default: the system's, 1 ms built in)")
    p.add_argument("--master", choices=tuple(ALGORITHMS), default="gauss-seidel",
                   help="master algorithm (default gauss-seidel; iterative-jacobi repeats the Jacobi exchange "
                        "until the inputs are consistent)")
    p.add_argument("--no-initial-exchange", action="store_true",
                   help="start with the inputs' start values, not the initial outputs (as fmpy's container FMU does)")
    p.add_argument("--parameters", metavar="FILE.ssv",
                   help="SSP parameter set with names INSTANCE.VARIABLE, applied before --set")
    p.add_argument("--set", action="append", default=[], metavar="INSTANCE.VARIABLE=VALUE",
                   help="set any parameter or input before initialisation (repeatable); angles in rad, or with a deg "
                        "suffix: plant.theta1_0=10deg")
    p.add_argument("--out", default="results/simulation.csv",
                   help="result file: .csv (default results/simulation.csv) or .parquet (pyarrow, for long runs)")
    p.add_argument("--plot", help="also write a PNG plot of x, theta1, theta2 and u (or of every output)")


def run(args):
    from crane_fmu import systems

    try:
        with systems.open_system(args.system) as system:
            return _simulate(args, system)
    except ValueError as exc:
        raise UsageError(str(exc)) from None


def _simulate(args, system):
    """Run a system, writing the CSV (and plot) of ``args``; ``--parameters`` and ``--set`` override its values."""
    from crane_fmu import systems
    from crane_fmu.cosim import FmiError, read_result, recorder_for, simulate
    from crane_fmu.cosim.master import communication_points
    from crane_fmu.cosim.system import settable, split_name

    stop_time = system.stop_time if args.stop_time is None else args.stop_time
    step = system.step if args.step is None else args.step
    communication_points(system.start_time, stop_time, step)
    fmus, connections = systems.resolve(system, args.fmu_dir)
    system = systems.at_step(system, args.fmu_dir, step)
    variables = settable(fmus)
    if args.parameters:
        from crane_fmu.cosim.ssp import load_parameters

        loaded = load_parameters(args.parameters)
        for instance, values in loaded.items():
            for name in values:
                try:
                    split_name(f"{instance}.{name}", variables)
                except ValueError as exc:
                    raise UsageError(f"--parameters {args.parameters}: {instance}.{name}: {exc}") from None
        system = system.with_parameters(loaded)
    system = system.with_parameters(parse_sets(args.set, variables))
    systems.check_parameters(system, args.fmu_dir)
    writable_file(args.out, "--out", ".parquet" if args.out.endswith(".parquet") else ".csv")
    if args.plot:
        writable_file(args.plot, "--plot", ".png")
    try:
        recorder = recorder_for(args.out)
    except OSError as exc:
        raise UsageError(f"--out {args.out}: cannot be written ({exc.strerror})") from None
    except ImportError:
        raise UsageError(f"--out {args.out}: writing Parquet needs pyarrow (pip install pyarrow)") from None
    try:
        simulate(fmus, connections, stop_time, step, args.master, system.parameters, recorder, system.start_time,
                 not args.no_initial_exchange)
    except FmiError as exc:
        # Bad parameter values are refused when initialisation ends: the user's mistake.
        if exc.time is None or exc.function.endswith(("ExitInitializationMode", "SetReal", "SetFloat64",
                                                       "SetString")):
            raise UsageError(str(exc)) from None
        print(f"crane-fmu: simulation failed: {exc} (results up to t={exc.time:.9g} s in {args.out})",
              file=sys.stderr)
        return 1
    finally:
        recorder.close(reason="interrupted")  # no-op when the run finished
    print(f"wrote {args.out}")
    if args.plot:
        from crane_fmu.analysis.plots import plot_run

        partial = args.plot + ".partial.png"
        settings = ", ".join(item.split("=", 1)[0] + "=" + item.split("=", 1)[1] for item in args.set)
        plot_run(read_result(args.out), partial, f"{system.name} ({args.master}, h={step:g} s)"
                 + (f"\n{settings}" if settings else ""))
        os.replace(partial, args.plot)
        print(f"wrote {args.plot}")
    return 0
