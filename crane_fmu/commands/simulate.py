"""``crane-fmu simulate``: co-simulate a system of FMUs."""

import argparse
import os
import re
import signal
import sys
from dataclasses import replace
from pathlib import Path

from crane_fmu import DEFAULT_FMU_DIR, DEFAULT_SYSTEM
from crane_fmu.cosim.algorithms import ALGORITHMS
from crane_fmu.cosim.suggest import did_you_mean

from .common import UsageError, number, parse_sets, writable_file
from .stopping import StopOnSignal, Stopped

NAME = "simulate"
HELP = "co-simulate a system of FMUs"
DESCRIPTION = ("Co-simulate a built-in system or an SSP file with the fixed-step master; write every output of "
               "every instance to a CSV (and a plot).")
EXAMPLES = (
    "examples:\n"
    "  crane-fmu simulate --out results/section5.csv --plot results/section5.png\n"
    "  crane-fmu simulate --system free --stop-time 10 --out free.csv\n"
    "  crane-fmu simulate --system build/systems/paper.ssp --parameters my.ssv\n"
    "  crane-fmu simulate --algorithm jacobi --step 0.01 --set controller.w_theta2=0\n"
    "  crane-fmu simulate --set crane.l1=1.5 --set plant.theta1_0=0.2   # the crane's l1: plant and controller\n"
    "  crane-fmu simulate --system lqr --set crane.l2=0.6 --set controller.l2=0.5   # a controller told another\n"
    "  crane-fmu simulate --system transport --use controller=build/mine/PdSway.fmu --out mine.csv\n"
    "  crane-fmu simulate --system transport --use controller=pd_sway.py --out mine.csv   # no FMU built\n"
    "  crane-fmu simulate --system transport --out move.mat          # for MATLAB: columns and data\n"
    "On a terminal a long run shows its progress on stderr; Ctrl-C stops it and keeps the rows so far."
)


def arguments(p):
    run_options(p, "stop time [s] (default: the system's, 20 s built in)")
    p.add_argument("--no-initial-exchange", action="store_true",
                   help="start with the inputs' start values, not the initial outputs (as fmpy's container FMU does)")
    p.add_argument("--out", default="results/simulation.csv",
                   help="result file: .csv (default results/simulation.csv), .parquet (pyarrow, for long runs) or "
                        ".mat (MATLAB, scipy.io.savemat: the CSV's columns and data)")
    p.add_argument("--plot", help="also write a PNG plot of x, theta1, theta2 and u (or of every output)")
    strict_option(p)


def strict_option(p):
    """``--strict``: refuse a run with an input nothing feeds (simulate, compare, sweep)."""
    p.add_argument("--strict", action="store_true",
                   help="refuse (exit 2) a run with an input that nothing feeds and no value is given for (by "
                        "default: a warning naming the nearest output, and the input keeps its start value)")


def check_unfed(lines, strict, where=""):
    """Each line of an input nothing feeds (:func:`crane_fmu.cosim.system.unfed_inputs`) as a warning on stderr, or
    under ``strict`` one UsageError naming them all."""
    if strict and lines:
        raise UsageError(f"--strict: {where}{'; '.join(lines)}; connect each, or give it a value with --set")
    for line in lines:
        print(f"crane-fmu: warning: {where}{line}", file=sys.stderr)


def run_options(p, stop_time_help):
    """The options that set up a run (system, FMUs, times, algorithm, values), for the commands that run one."""
    p.add_argument("--system", default=DEFAULT_SYSTEM,
                   help=f"a built-in system's name (crane-fmu info lists them) or an SSP file "
                        f"(default: {DEFAULT_SYSTEM})")
    p.add_argument("--fmu-dir", default=DEFAULT_FMU_DIR, help=f"folder of the built FMUs (default: {DEFAULT_FMU_DIR})")
    p.add_argument("--stop-time", type=number, help=stop_time_help)
    p.add_argument("--step", type=number, help="communication step [s] (default: the system's, 1 ms built in)")
    p.add_argument("--algorithm", choices=tuple(ALGORITHMS), default="gauss-seidel",
                   help="the master algorithm (default gauss-seidel; iterative-jacobi repeats the Jacobi exchange "
                        "until the inputs are consistent)")
    p.add_argument("--master", choices=tuple(ALGORITHMS), dest="algorithm", help=argparse.SUPPRESS)  # its old name
    p.add_argument("--parameters", metavar="FILE.ssv",
                   help="SSP parameter set with names INSTANCE.VARIABLE, applied before --set")
    p.add_argument("--set", action="append", default=[], metavar="INSTANCE.VARIABLE=VALUE",
                   help="set any parameter or input before initialisation (repeatable); angles in rad, or with a deg "
                        "suffix: plant.theta1_0=10deg; crane.l2=0.6 sets the crane's l2 on every instance that "
                        "models it (crane-fmu info --system NAME lists them) and has no value of its own")
    p.add_argument("--use", action="append", default=[], metavar="INSTANCE=FILE.fmu",
                   help="run this FMU as the instance instead of the system's (repeatable), e.g. "
                        "controller=mine.fmu; the system's values for the instance are kept where the FMU has them; "
                        "a Python file (controller=mylaw.py, or mylaw.py:NAME for its component or law function "
                        "NAME) runs its law in this process, no FMU built, with the same numbers as its FMU")


def run(args):
    return on_system(args, _simulate)


def on_system(args, command):
    """``command(args, system)`` on the system of ``--system`` with the FMUs of ``--use`` in its place (simulate,
    serve); a system or FMU it refuses is one line (UsageError)."""
    from crane_fmu import systems

    try:
        with systems.open_system(args.system) as system:
            return command(args, _use(args.use, system))
    except ValueError as exc:
        raise UsageError(str(exc)) from None


def _use(items, system):
    """``system`` with the FMUs of ``--use INSTANCE=FILE.fmu`` in place of its own (checked: one line each)."""
    overrides = {}
    for item in items:
        instance, sep, path = item.partition("=")
        if not sep or not instance or not path:
            raise UsageError(f"--use {item!r}: expected INSTANCE=FILE.fmu, e.g. controller=mine.fmu")
        if instance not in system.instances:
            raise UsageError(f"--use {item!r}: system {system.name} has no instance {instance!r}; instances: "
                             f"{', '.join(system.instances)}" + did_you_mean(instance, system.instances))
        overrides[instance] = used_file(item, path)
    return system.with_instances(overrides) if overrides else system


def used_file(item, path):
    """The resolved source of ``--use INSTANCE=path``: an FMU file, or a law file (``mylaw.py``, ``mylaw.py:NAME``:
    a component or law function run in this process, no FMU built); one line for anything else."""
    from crane_fmu import laws

    if laws.is_law(path):
        try:
            laws.component(path)
        except ValueError as exc:
            raise UsageError(f"--use {item!r}: {exc}") from None
        name = path[len(str(laws.law_file(path))):]
        return str(laws.law_file(path).resolve()) + name
    if Path(path).suffix != ".fmu":
        raise UsageError(f"--use {item!r}: {path} is neither an FMU file (.fmu) nor a law file (.py, .py:NAME)")
    if not Path(path).is_file():
        raise UsageError(f"--use {item!r}: {path} not found")
    return str(Path(path).resolve())


def _keep_known(system, fmus, replaced):
    """The system's values for the ``replaced`` instances that their new FMUs have; a note on stderr for the rest."""
    from crane_fmu.cosim.system import settable

    variables = settable({name: fmus[name] for name in replaced})
    parameters = {name: dict(values) for name, values in system.parameters.items()}
    for name in replaced:
        dropped = [v for v in parameters.get(name, {}) if v not in variables[name]]
        for variable in dropped:
            del parameters[name][variable]
        if dropped:
            print(f"crane-fmu: note: {name} ({Path(fmus[name]).name}) has no {', '.join(dropped)}: the system's "
                  "values for them are not set", file=sys.stderr)
    return replace(system, parameters=parameters)


def prepare(args, system, step):
    """``(system, fmus, connections)`` of a run of ``system`` at ``step`` as ``args`` set it up: the FMUs of
    ``--use`` (the system's values kept where they fit), then the run prepared as every run is
    (``systems.prepare``: ``--parameters`` then ``--set`` applied, the step's designs, every instance's
    parameters checked). A mistake raises UsageError or ValueError (one line)."""
    from crane_fmu import systems

    fmus, connections = systems.resolve(system, args.fmu_dir)
    system = _keep_known(system, fmus, list(system.replaced))
    variables = systems.settable(system, fmus)
    values = [_parameter_file(args.parameters, variables)] if args.parameters else []
    values.append(parse_sets(args.set, variables))
    system, notes = systems.tell_controllers(system, args.fmu_dir, values)
    for note in notes:
        print(f"crane-fmu: note: {note}", file=sys.stderr)
    system = systems.prepare(system, step, values=values)
    return system, fmus, connections


def _parameter_file(path, variables):
    """``{instance: {variable: value}}`` of an SSP parameter set, every name checked against ``variables``."""
    from crane_fmu.cosim.ssp import load_parameters
    from crane_fmu.cosim.system import split_name

    if not Path(path).is_file():
        raise UsageError(f"--parameters {path}: not found (an SSP parameter set, e.g. examples/parameters.ssv)")
    loaded = load_parameters(path)
    for instance, values in loaded.items():
        for name in values:
            try:
                split_name(f"{instance}.{name}", variables)
            except ValueError as exc:
                raise UsageError(f"--parameters {path}: {instance}.{name}: {exc}") from None
    return loaded


def _simulate(args, system):
    """Run a system, writing the CSV (and plot) of ``args``; ``--parameters`` and ``--set`` override its values."""
    from crane_fmu.cosim import FmiError, ProgressLine, read_result, simulate
    from crane_fmu.cosim.master import communication_points
    from crane_fmu.cosim.recorder import RESULT_SUFFIXES, WriteError
    from crane_fmu.cosim.system import unfed_inputs

    stop_time = system.stop_time if args.stop_time is None else args.stop_time
    step = system.step if args.step is None else args.step
    communication_points(system.start_time, stop_time, step)
    system, fmus, connections = prepare(args, system, step)
    check_unfed(unfed_inputs(fmus, connections, system.parameters), args.strict)
    writable_file(args.out, "--out", RESULT_SUFFIXES)
    if args.plot:
        writable_file(args.plot, "--plot", ".png")
    recorder = open_recorder(args.out)
    progress = [ProgressLine(system.start_time, stop_time, sys.stderr)] if sys.stderr.isatty() else []
    try:
        with StopOnSignal() as stopper:
            simulate(fmus, connections, stop_time, step, args.algorithm, system.parameters, recorder,
                     system.start_time, not args.no_initial_exchange, observers=[*progress, stopper])
    except Stopped as exc:  # SIGINT or SIGTERM: at a communication point, outside every FMU
        _end(progress)
        return _interrupted(recorder, exc.signum)
    except WriteError as exc:  # a full disk, a file-size limit
        _end(progress)
        return _cannot_write(args.out, recorder, exc)
    except FmiError as exc:
        if "KeyboardInterrupt" in str(exc):  # a second Ctrl-C while an FMU's Python code ran: it returned an error
            _end(progress)
            return _interrupted(recorder)
        # Bad parameter values are refused before the run or when initialisation ends: the user's mistake. A value
        # set during the run is an input another instance gave: the run failed.
        if exc.time is None or exc.function.endswith("ExitInitializationMode"):
            raise UsageError(str(exc)) from None
        _end(progress)
        where = (f"results up to t={exc.time:.9g} s in {recorder.written}" if recorder.written else
                 f"no results: it failed at t={exc.time:.9g} s")
        print(f"crane-fmu: simulation failed: {exc}{_fed_by(exc, connections)} ({where}; "
              f"{args.out} is {'as it was' if os.path.exists(args.out) else 'not written'})", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        _end(progress)
        return _interrupted(recorder)
    finally:
        recorder.close(reason="interrupted")  # no-op when the run finished or failed
    _end(progress)
    print(f"wrote {args.out}")
    if args.plot:
        from crane_fmu.analysis.plots import plot_run

        partial = args.plot + ".partial.png"
        Path(partial).parent.mkdir(parents=True, exist_ok=True)
        settings = ", ".join(item.split("=", 1)[0] + "=" + item.split("=", 1)[1] for item in args.set)
        used = "".join(f" with {name}={Path(system.instances[name]).name}" for name in system.replaced)
        plot_run(read_result(args.out), partial, f"{system.name}{used} ({args.algorithm}, h={step:g} s)"
                 + (f"\n{settings}" if settings else ""))
        os.replace(partial, args.plot)
        print(f"wrote {args.plot}")
    return 0


def open_recorder(out):
    """The recorder of the result file ``--out`` (simulate, serve); one line if it cannot be written."""
    from crane_fmu.cosim import recorder_for

    try:
        return recorder_for(out)
    except OSError as exc:
        raise UsageError(f"--out {out}: cannot be written ({exc.strerror})") from None
    except ImportError as exc:
        raise UsageError(f"--out {out}: writing it needs {exc.name} (pip install {exc.name})") from None


def _fed_by(exc, connections):
    """``" (plant.u is controller.u)"``: where an input an instance refused during the run came from."""
    found = re.search(r"\binput (\w+)", str(exc)) if exc.function.endswith(("SetReal", "SetFloat64")) else None
    source = next((c for c in connections if found and c.target == exc.instance and c.input == found[1]), None)
    return f" ({exc.instance}.{source.input} is {source.source}.{source.output})" if source else ""


def _end(progress):
    for line in progress:
        line.close()


def _cannot_write(out, recorder, error):
    """A result that cannot be written: one line saying why and where the rows written before it are; status 1."""
    try:
        recorder.close()  # after a write error: the rows written before kept, a no-op where closing failed
    except OSError:
        pass
    kept = f"the rows written before are in {recorder.written}" if recorder.written else "no row could be kept"
    print(f"crane-fmu: cannot write {out}: {error.strerror}; {kept}", file=sys.stderr)
    return 1


def _interrupted(recorder, signum=signal.SIGINT):
    """Ctrl-C, SIGTERM or SIGHUP (the terminal closed): one line saying where the rows so far went; exit status 128 +
    the signal's number (130, 143, 129: the shell's)."""
    name = signal.Signals(signum).name
    recorder.close(reason=f"interrupted ({name})")
    where = f"the rows so far are in {recorder.written}" if recorder.written else "nothing was recorded"
    print(f"crane-fmu: interrupted ({name}); {where}", file=sys.stderr)
    return 128 + signum
