"""The ``crane-fmu`` command: build, simulate, describe, reproduce the paper, sweep, benchmark.

Every command that runs something takes a system by name or as an SSP file.
User mistakes print one line and exit with status 2; an FMU failing during a
run prints one line and exits with status 1.
"""

import argparse
import math
import os
import shutil
import sys
from pathlib import Path

EXAMPLES = {
    "build": ("examples:\n  crane-fmu build\n  crane-fmu build --out my/fmus --bench\n"
              "  crane-fmu build --container transport       # build/containers/CraneTransport.fmu\n"
              "  crane-fmu build --container my_system.ssp"),
    "simulate": (
        "examples:\n"
        "  crane-fmu simulate --out results/section5.csv --plot results/section5.png\n"
        "  crane-fmu simulate --system free --stop-time 10 --out free.csv\n"
        "  crane-fmu simulate --system build/systems/paper.ssp --parameters my.ssv\n"
        "  crane-fmu simulate --master jacobi --step 0.01 --set controller.w_theta2=0\n"
        "  crane-fmu simulate --set plant.l1=1.5 --set controller.l1=1.5 --set plant.theta1_0=0.2"),
    "info": ("examples:\n  crane-fmu info\n  crane-fmu info --markdown\n  crane-fmu info --system lqr\n"
             "  crane-fmu info --system lqr --set controller.l1=1.5 --set controller.h=0.01  # the LQR's gains"),
    "bench": ("examples:\n  crane-fmu bench\n  crane-fmu bench --repeat 7 --stop-time 20\n  crane-fmu bench --sweep\n"
              "  crane-fmu bench --endurance            # one simulated hour at 1 ms\n"
              "  crane-fmu bench --controllers          # every controller against its targets"),
    "reproduce": "examples:\n  crane-fmu reproduce --out results/paper\n  crane-fmu reproduce --quick --out /tmp/q",
    "compare": (
        "examples:\n"
        "  crane-fmu compare --out results/compare                  # every built-in controller, every scenario\n"
        "  crane-fmu compare --controller LqrController --controller my/MyController.fmu --out results/mine\n"
        "  crane-fmu compare --out results/compare --scheduler tcp://scheduler-host:8786\n"
        "Re-running the same command resumes: finished cases are skipped."),
    "plot": ("examples:\n  crane-fmu plot results/paper.csv results/lqr.csv --out results/section5.png\n"
             "  crane-fmu plot run.csv --out run.png --title 'my run'"),
    "animate": ("examples:\n  crane-fmu simulate --system transport --out move.csv\n"
                "  crane-fmu animate move.csv --out move.gif"),
    "sweep": (
        "examples:\n"
        "  crane-fmu sweep study.toml --out results/study --workers 2\n"
        "  crane-fmu sweep builtin:region-of-attraction --out results/roa\n"
        "  crane-fmu sweep builtin:theta2-gain-sensitivity --out results/gains --csv\n"
        "  crane-fmu sweep study.toml --out results/study --scheduler tcp://scheduler-host:8786\n"
        "Re-running the same command resumes: finished cases are skipped."),
}


class UsageError(Exception):
    """A mistake in the command line: one line, exit status 2."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        raise UsageError(message)


def _number(text):
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return value


def _dask_options(p):
    """The options that sweep and compare share: the FMUs, the Dask workers, the progress bar."""
    p.add_argument("--fmu-dir", default="build/fmus", help="folder of the built FMUs")
    p.add_argument("--workers", type=int, default=None, help="local worker processes (default: one per core)")
    p.add_argument("--scheduler", help="address of an existing Dask scheduler (no local cluster)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def _parser():
    from crane_fmu import __version__

    parser = _Parser(prog="crane-fmu", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"crane-fmu {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    fmt = argparse.RawDescriptionHelpFormatter

    p = sub.add_parser("build", help="build the FMUs of every component and the files of every built-in system",
                       epilog=EXAMPLES["build"], formatter_class=fmt)
    p.add_argument("--out", default="build/fmus",
                   help="FMI 2.0 FMUs (default: build/fmus); FMI 3.0 ones and systems/ go beside it")
    p.add_argument("--bench", action="store_true", help="also build the benchmark's trivial FMUs")
    p.add_argument("--native", action=argparse.BooleanOptionalAction, default=None,
                   help="also build the native (C) FMUs into build/native (default: when a C compiler is found)")
    p.add_argument("--container", metavar="SYSTEM|FILE.ssp",
                   help="instead: pack one system (a built-in one, or an SSP file) into one FMU in build/containers")

    p = sub.add_parser("simulate", help="co-simulate a system of FMUs", epilog=EXAMPLES["simulate"],
                       formatter_class=fmt,
                       description="Co-simulate a built-in system or an SSP file with the fixed-step master; write "
                                   "every output of every instance to a CSV (and a plot).")
    p.add_argument("--system", default="paper",
                   help="a built-in system's name (crane-fmu info lists them) or an SSP file (default: paper)")
    p.add_argument("--fmu-dir", default="build/fmus", help="folder of the built FMUs (default: build/fmus)")
    p.add_argument("--stop-time", type=_number, help="stop time [s] (default: the system's, 20 s built in)")
    p.add_argument("--step", type=_number, help="communication step [s] (default: the system's, 1 ms built in)")
    p.add_argument("--master", choices=("gauss-seidel", "jacobi"), default="gauss-seidel",
                   help="master algorithm (default gauss-seidel)")
    p.add_argument("--no-initial-exchange", action="store_true",
                   help="start with the inputs' start values, not the initial outputs (as fmpy's container FMU does)")
    p.add_argument("--no-controller", action="store_true", help=argparse.SUPPRESS)  # replaced by --system free
    p.add_argument("--parameters", metavar="FILE.ssv",
                   help="SSP parameter set with names INSTANCE.VARIABLE, applied before --set")
    p.add_argument("--set", action="append", default=[], metavar="INSTANCE.VARIABLE=VALUE",
                   help="set any parameter or input before initialisation (repeatable); angles in rad, or with a deg "
                        "suffix: plant.theta1_0=10deg")
    p.add_argument("--out", default="results/simulation.csv",
                   help="result file: .csv (default results/simulation.csv) or .parquet (pyarrow, for long runs)")
    p.add_argument("--plot", help="also write a PNG plot of x, theta1, theta2 and u (or of every output)")

    p = sub.add_parser("info", help="list the built-in systems and the components' variables",
                       epilog=EXAMPLES["info"], formatter_class=fmt)
    p.add_argument("--markdown", action="store_true", help="print the variable tables as Markdown")
    p.add_argument("--system", help="instead: a built-in system's instances and what their components derive from "
                                    "the parameters (gains, shaper impulses)")
    p.add_argument("--set", action="append", default=[], metavar="INSTANCE.VARIABLE=VALUE",
                   help="with --system: parameter values to derive from (repeatable)")

    p = sub.add_parser("reproduce", help="reproduce the paper's Figures 4, 5, 7, 8 and write REPORT.md",
                       epilog=EXAMPLES["reproduce"], formatter_class=fmt)
    p.add_argument("--out", default="results/paper", help="output folder (default results/paper)")
    p.add_argument("--fmu-dir", default="build/fmus", help="folder of the built FMUs")
    p.add_argument("--quick", action="store_true", help="fewer cases and shorter runs (every figure still)")
    p.add_argument("--workers", type=int, default=None, help="worker processes (default: one per core)")

    p = sub.add_parser("sweep", help="run a parameter study of the FMUs on Dask", epilog=EXAMPLES["sweep"],
                       formatter_class=fmt)
    p.add_argument("study", help="study file (TOML, or YAML with PyYAML) or builtin:NAME")
    p.add_argument("--out", required=True, help="output folder: results.parquet, cases.jsonl, plot.png")
    _dask_options(p)
    p.add_argument("--csv", action="store_true", help="also write results.csv")

    p = sub.add_parser("compare", help="score controller FMUs on the same scenarios (the scoreboard)",
                       epilog=EXAMPLES["compare"], formatter_class=fmt)
    p.add_argument("--controller", action="append", default=[], metavar="NAME|FILE.fmu",
                   help="a built-in controller's name or a controller FMU (repeatable; default: every built-in one)")
    p.add_argument("--out", required=True, help="output folder: scoreboard.md, scores.parquet, plots, animations")
    _dask_options(p)
    p.add_argument("--quick", action="store_true", help="3 of the 27 mismatch plants in S3")

    p = sub.add_parser("plot", help="plot one or more simulate results on shared axes",
                       epilog=EXAMPLES["plot"], formatter_class=fmt)
    p.add_argument("results", nargs="+",
                   help="CSV or Parquet files written by crane-fmu simulate (labelled by file name)")
    p.add_argument("--out", required=True, help="the PNG to write")
    p.add_argument("--title", default="", help="a title over the plot")

    p = sub.add_parser("animate", help="an animation of the crane from a simulate result (GIF, or MP4 with ffmpeg)",
                       epilog=EXAMPLES["animate"], formatter_class=fmt)
    p.add_argument("result", help="a CSV written by crane-fmu simulate")
    p.add_argument("--out", required=True, help="FILE.gif or FILE.mp4")
    p.add_argument("--fps", type=int, default=25, help="frames per second (default 25)")

    p = sub.add_parser("bench", help="microseconds per communication step, crane pair vs framework floor",
                       epilog=EXAMPLES["bench"], formatter_class=fmt)
    p.add_argument("--stop-time", type=_number, default=None,
                   help="simulated time per run [s] (default 20, with --sweep 10)")
    p.add_argument("--step", type=_number, default=1e-3, help="communication step [s]")
    p.add_argument("--repeat", type=int, default=5,
                   help="runs per pair (with --sweep: batches per cluster); the median is reported")
    p.add_argument("--sweep", action="store_true",
                   help="instead: cases per second of a Dask sweep with 1 and 2 workers")
    p.add_argument("--cases", type=int, default=16, help="with --sweep: cases per measurement")
    p.add_argument("--endurance", action="store_true",
                   help="instead: one long run (default one simulated hour) recorded to CSV, memory sampled")
    p.add_argument("--controllers", action="store_true",
                   help="instead: regulation, transport, robustness, region of attraction and coarse steps of every "
                        "controller against its targets")
    p.add_argument("--quick", action="store_true", help="with --controllers: fewer cases")
    p.add_argument("--native", action="store_true",
                   help="instead: the native (C) CranePlant FMU in our master, in a C host and as a whole process")
    return parser


LARGEST_SWING = math.pi / 2  # rad: no swing the model is meant for is larger


def _convert(text, fmi_type, unit=None):
    """A --set value as the variable's FMI type; an angle may be given in degrees (``10deg``, ``5deg/s``)."""
    if fmi_type in ("Real", "Float64", "Float32"):
        for suffix, si in (("deg/s", "rad/s"), ("deg", "rad")):
            if text.endswith(suffix):
                if unit != si:
                    raise ValueError(f"{text!r}: a {suffix} value needs a variable in {si}, this one is in {unit}")
                return math.radians(_number(text[:-len(suffix)]))
        return _number(text)
    if fmi_type in ("Integer", "Int32"):
        return int(text)
    if fmi_type == "Boolean":
        if text.lower() not in ("true", "false", "1", "0"):
            raise ValueError(f"{text!r} is not a Boolean (true, false, 1, 0)")
        return text.lower() in ("true", "1")
    return text


def _parse_sets(items, instances, variables_of):
    """``["plant.l1=1.5"]`` -> ``{"plant": {"l1": 1.5}}``, checked against the instances' variables.

    ``variables_of(instance)`` gives ``{name: (FMI type, unit)}`` of its parameters and inputs. An
    angle given without a unit and larger than any swing the model is meant for gets a warning.
    """
    known, result = {}, {}
    for item in items:
        target, sep, text = item.partition("=")
        instance, dot, name = target.partition(".")
        if not sep or not dot:
            raise UsageError(f"--set {item!r}: expected INSTANCE.VARIABLE=VALUE")
        if instance not in instances:
            raise UsageError(f"--set {item!r}: unknown instance {instance!r}; instances: {', '.join(instances)}")
        if instance not in known:
            known[instance] = variables_of(instance)
        if name not in known[instance]:
            raise UsageError(f"--set {item!r}: {instance} has no parameter or input {name!r}; valid: "
                             + ", ".join(known[instance]))
        fmi_type, unit = known[instance][name]
        try:
            value = _convert(text, fmi_type, unit)
        except (argparse.ArgumentTypeError, ValueError) as exc:
            raise UsageError(f"--set {item!r}: {exc}") from None
        if unit == "rad" and not text.endswith("deg") and abs(value) > LARGEST_SWING:
            print(f"crane-fmu: warning: {instance}.{name} = {value:g} rad ({math.degrees(value):.0f} deg); "
                  f"for degrees write {text}deg", file=sys.stderr)
        result.setdefault(instance, {})[name] = value
    return result


def _fmu_variables(path):
    """``{name: (FMI type, unit)}`` of an FMU's parameters and inputs."""
    from crane_fmu.cosim.system import read_fmu

    return {v.name: (v.type, v.unit) for v in read_fmu(path).modelVariables if v.causality in ("parameter", "input")}


def _writable_file(path, option, suffix=None):
    """One line, exit 2, unless ``path`` can be written: not a folder, the right suffix, a writable folder."""
    if Path(path).is_dir() or str(path).endswith(os.sep):
        example = Path(path) / ("result" + (suffix or ""))
        raise UsageError(f"{option} {path}: is a folder; give a file name, e.g. {example}")
    if suffix and Path(path).suffix != suffix:
        raise UsageError(f"{option} {path}: writes a {suffix} file; the name must end in {suffix}")
    folder = Path(path).resolve().parent
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UsageError(f"{option} {path}: cannot create folder {folder} ({exc.strerror})") from None
    if not os.access(folder, os.W_OK):
        raise UsageError(f"{option} {path}: folder {folder} is not writable")


def _cmd_build(args):
    from crane_fmu import components, systems
    from crane_fmu.build_scripts.build_fmus import build_all, container_name, containers_dir
    from crane_fmu.container import build_container

    if args.container:
        try:
            with systems.open_system(args.container) as system:
                name = container_name(Path(args.container).stem if args.container.endswith((".ssp", ".ssd"))
                                      else system.name)
                path = build_container(system, args.out, containers_dir(args.out) / f"{name}.fmu")
        except ValueError as exc:
            raise UsageError(str(exc)) from None
        print(path)
        return 0
    kinds = [c.model_identifier for c in components.all() if args.bench or c.role != "benchmark"]
    from crane_fmu.build_scripts.native import NativeUnavailable

    try:
        built = build_all(args.out, kinds, native=args.native)
    except NativeUnavailable as exc:
        raise UsageError(f"--native: {exc}") from None
    for path in built:
        print(path)
    return 0


def _cmd_simulate(args):
    from crane_fmu import systems

    if args.no_controller:
        raise UsageError("--no-controller is gone: run the plant alone with --system free")
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

    stop_time = system.stop_time if args.stop_time is None else args.stop_time
    step = system.step if args.step is None else args.step
    communication_points(system.start_time, stop_time, step)
    fmus, connections = systems.resolve(system, args.fmu_dir)
    system = systems.at_step(system, args.fmu_dir, step)
    if args.parameters:
        from crane_fmu.cosim.ssp import load_parameters

        system = system.with_parameters(load_parameters(args.parameters))
    system = system.with_parameters(_parse_sets(args.set, list(fmus), lambda i: _fmu_variables(fmus[i])))
    systems.check_parameters(system, args.fmu_dir)
    _writable_file(args.out, "--out", ".parquet" if args.out.endswith(".parquet") else ".csv")
    if args.plot:
        _writable_file(args.plot, "--plot", ".png")
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


def _variable_table(component, markdown):
    from crane_fmu.model.tables import DISPLAY_UNITS

    lines = ([f"#### {component.model_identifier}", "", "| name | causality | start | unit | description |",
              "|---|---|---|---|---|"] if markdown else
             [f"{component.model_identifier}.fmu ({component.role}): {component.description}"])
    for v in component.variables:
        start = "" if v.start is None else f"{v.start:.6g}" if v.type == "Real" else v.start
        unit = v.unit or ""
        if unit in DISPLAY_UNITS:
            unit += f" (display {DISPLAY_UNITS[unit]})"
        lines.append(f"| `{v.name}` | {v.causality} | {start} | {unit} | {v.description} |" if markdown else
                     f"  {v.name:<12} {v.causality:<10} {start:>10} {unit:<22} {v.description}")
    return "\n".join(lines) + "\n"


def _derived(system, sets):
    """Lines describing each instance of a built-in system and what its component derives from the parameters."""
    from crane_fmu import components

    def variables_of(instance):
        component = components.find(system.instances[instance])
        rows = component.variables if component else ()
        return {v.name: (v.type, v.unit) for v in rows if v.causality != "output"}

    parameters = _parse_sets(sets, list(system.instances), variables_of)
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


def _cmd_info(args):
    from crane_fmu import components, systems

    if args.system:
        try:
            system = systems.get(args.system)
        except ValueError as exc:
            raise UsageError(str(exc)) from None
        print("\n".join(_derived(system, args.set)))
        return 0
    chosen = [c for c in components.all() if c.role != "benchmark"]
    if args.markdown:
        print("\n".join(_variable_table(c, True) for c in chosen), end="")
        return 0
    print("systems (crane-fmu simulate --system NAME):")
    for system in systems.all():
        instances = ", ".join(f"{name} = {kind}" for name, kind in system.instances.items())
        print(f"  {system.name:<10} {instances}: {system.description}")
    print()
    for c in chosen:
        print(_variable_table(c, False))
    return 0


def _cmd_reproduce(args):
    from crane_fmu import systems
    from crane_fmu.analysis.reproduce import reproduce

    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers must be >= 1, got {args.workers}")
    try:
        systems.resolve(systems.get("paper"), args.fmu_dir)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    _writable_file(Path(args.out) / "REPORT.md", "--out")
    reproduce(args.out, args.fmu_dir, quick=args.quick, workers=args.workers)
    return 0


def _cmd_sweep(args):
    from crane_fmu.sweep import spec
    from crane_fmu.sweep.runner import run_study

    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers must be >= 1, got {args.workers}")
    if args.workers is not None and args.scheduler:
        raise UsageError("--workers and --scheduler exclude each other: the scheduler's cluster has its workers")
    try:
        study = spec.load(args.study)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    _writable_file(Path(args.out) / "results.parquet", "--out")
    try:
        summary = run_study(study, args.out, args.fmu_dir, args.workers, args.scheduler, args.csv,
                            progress=not args.no_progress)
    except (ValueError, FileNotFoundError) as exc:
        raise UsageError(str(exc)) from None
    print(f"{summary['cases']} cases: {summary['ran']} run now, {summary['skipped']} already done, "
          f"{summary['not_ok']} not ok; results in {Path(args.out) / 'results.parquet'}")
    return 0


def _cmd_compare(args):
    from crane_fmu.compare import compare

    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers must be >= 1, got {args.workers}")
    if args.workers is not None and args.scheduler:
        raise UsageError("--workers and --scheduler exclude each other: the scheduler's cluster has its workers")
    _writable_file(Path(args.out) / "scoreboard.md", "--out")
    try:
        compare(args.out, args.controller, args.fmu_dir, args.workers, args.scheduler, args.quick,
                progress=not args.no_progress)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    return 0


def _cmd_plot(args):
    from crane_fmu.analysis.plots import plot_overlay
    from crane_fmu.cosim import read_result

    if Path(args.out).suffix != ".png":
        raise UsageError(f"--out {args.out}: the plot is written as .png")
    runs = {}
    for path in args.results:
        try:
            runs[Path(path).stem] = read_result(path)
        except (OSError, ValueError) as exc:
            raise UsageError(f"cannot read {path}: {exc}") from None
    _writable_file(args.out, "--out")
    partial = str(Path(args.out).with_name(f".{Path(args.out).stem}.partial.png"))
    try:
        plot_overlay(runs, partial, args.title)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    os.replace(partial, args.out)
    print(f"wrote {args.out}")
    return 0


def _cmd_animate(args):
    from crane_fmu.analysis.score_plots import animate
    from crane_fmu.cosim import read_result

    if Path(args.out).suffix not in (".gif", ".mp4"):
        raise UsageError(f"--out {args.out}: the animation is written as .gif or .mp4")
    if Path(args.out).suffix == ".mp4" and not shutil.which("ffmpeg"):
        raise UsageError(f"--out {args.out}: MP4 needs ffmpeg, which is not installed; write a .gif instead")
    if args.fps < 1:
        raise UsageError(f"--fps must be >= 1, got {args.fps}")
    try:
        columns = read_result(args.result)
    except (OSError, ValueError) as exc:
        raise UsageError(f"cannot read {args.result}: {exc}") from None
    needed = [n for n in ("x", "x1", "y1", "x2", "y2") if not any(k == n or k.endswith("." + n) for k in columns)]
    if needed:
        raise UsageError(f"{args.result} has no crane to animate: it needs the plant outputs "
                         f"{', '.join(needed)}")
    _writable_file(args.out, "--out")
    print(f"wrote {animate(columns, args.out, Path(args.result).stem, args.fps)}")
    return 0


def _cmd_bench(args):
    from crane_fmu.bench import run_bench, run_controllers, run_endurance, run_sweep_bench

    if args.repeat < 1:
        raise UsageError(f"--repeat must be >= 1, got {args.repeat}")
    if args.cases < 2:
        raise UsageError(f"--cases must be >= 2, got {args.cases}")
    try:
        if args.sweep + args.endurance + args.controllers + args.native > 1:
            raise UsageError("--sweep, --endurance, --controllers and --native are separate benchmarks: choose one")
        if args.native:
            from crane_fmu.bench_native import run_native_bench

            run_native_bench(args.stop_time or 20.0, args.step, args.repeat)
        elif args.controllers:
            run_controllers(args.quick)
        elif args.endurance:
            run_endurance(args.stop_time or 3600.0, args.step)
        elif args.sweep:
            run_sweep_bench(args.cases, args.stop_time or 10.0, args.step, args.repeat)
        else:
            run_bench(args.stop_time or 20.0, args.step, args.repeat)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    return 0


def main(argv=None):
    """Run the command line; return the exit status."""
    try:
        args = _parser().parse_args(argv)
        return {"build": _cmd_build, "simulate": _cmd_simulate, "info": _cmd_info, "reproduce": _cmd_reproduce,
                "sweep": _cmd_sweep, "compare": _cmd_compare, "plot": _cmd_plot, "animate": _cmd_animate,
                "bench": _cmd_bench}[args.command](args)
    except UsageError as exc:
        print(f"crane-fmu: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # the reader (e.g. head) has gone: not an error
        sys.stdout = open(os.devnull, "w")
        return 0


if __name__ == "__main__":
    sys.exit(main())
