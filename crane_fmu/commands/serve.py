"""``crane-fmu serve``: a system in real time or lock-step, reachable over OPC UA and Modbus TCP."""

import asyncio
import gc
import importlib.util
import math
import os
import shutil
import signal
import sys
import time
from pathlib import Path

from ..cosim.suggest import did_you_mean
from .common import UsageError, number, writable_file
from .simulate import on_system, open_recorder, prepare, run_options

NAME = "serve"
HELP = "run a system in real time or lock-step for a PLC or any program, over OPC UA and Modbus TCP"
DESCRIPTION = (
    "Run a built-in system or an SSP file in real time (paced against absolute deadlines) or in lock-step (the "
    "client advances it), reachable over OPC UA and Modbus TCP (the optional extra 'serve': "
    "pip install -e '.[serve]'). --external INSTANCE leaves one instance to the client: it writes that instance's "
    "outputs and reads its inputs, so a PLC takes the controller's place. The first line printed names every "
    "endpoint. Every output is recorded to --out; in real time the timing of every cycle goes beside it "
    "(RESULT.timing.csv). Ctrl-C stops cleanly and keeps both.")
EXAMPLES = (
    "examples:\n"
    "  crane-fmu serve --system lqr --external controller --lock-step --opcua 127.0.0.1:4840\n"
    "  crane-fmu serve --system lqr --external controller --period 0.01 --opcua --modbus --watchdog 0.5\n"
    "  crane-fmu serve --system transport --opcua 127.0.0.1:0 --stop-time 10     # port 0: the OS picks one\n"
    "  crane-fmu serve --system lqr --external controller --modbus --print-map   # the register map\n"
    "Binds 127.0.0.1 unless another address is given; no parameter is writable without --writable."
)

OPCUA_DEFAULT = "127.0.0.1:4840"
MODBUS_DEFAULT = "127.0.0.1:5020"  # 502, Modbus' own port, needs root
SWITCH_INTERVAL = 1e-4  # s


def arguments(p):
    run_options(p, "stop time [s] (default: none, run until Ctrl-C)")
    p.add_argument("--lock-step", action="store_true",
                   help="advance only when the client asks (OPC UA method Step, Modbus step register), in virtual "
                        "time (default: real time)")
    p.add_argument("--period", type=number,
                   help="real time: the cycle [s] at whose deadlines the client's values are taken and the system "
                        "advances, a whole number of steps (default: one step)")
    p.add_argument("--external", metavar="INSTANCE",
                   help="leave this instance out: the client writes its outputs and reads its inputs (e.g. "
                        "controller)")
    p.add_argument("--opcua", nargs="?", const=OPCUA_DEFAULT, metavar="HOST:PORT",
                   help=f"serve OPC UA at HOST:PORT (alone: {OPCUA_DEFAULT}; port 0: one the OS picks)")
    p.add_argument("--modbus", nargs="?", const=MODBUS_DEFAULT, metavar="HOST:PORT",
                   help=f"serve Modbus TCP at HOST:PORT (alone: {MODBUS_DEFAULT}; port 0: one the OS picks)")
    p.add_argument("--writable", action="store_true",
                   help="let clients write the parameters the FMUs declare tunable (FMI allows no others during a "
                        "run; default: no parameter is writable)")
    p.add_argument("--watchdog", type=number, metavar="SECONDS",
                   help="real time with --external: after this long without a client write the external outputs "
                        "are held (default 1 s)")
    p.add_argument("--hold", choices=("zero", "last"),
                   help="what the watchdog holds the external outputs at: zero (default) or their last values")
    p.add_argument("--rt-priority", type=int, metavar="N",
                   help="real time on Linux: run the stepping thread under SCHED_FIFO at priority N (1-99), ahead "
                        "of every ordinary process; needs root, CAP_SYS_NICE or an rtprio limit (otherwise a note "
                        "says so and the run goes on with normal scheduling)")
    p.add_argument("--out", default="results/serve.csv",
                   help="result file (.csv, .parquet or .mat; default results/serve.csv); in real time the timing "
                        "of every cycle goes beside it as NAME.timing.csv")
    p.add_argument("--print-map", action="store_true",
                   help="print the Modbus register map (Markdown) of this system and these options, and exit")


def run(args):
    return on_system(args, _serve)


def timing_path(out):
    """Where the timing CSV of a result file goes: ``results/serve.csv`` -> ``results/serve.timing.csv``."""
    path = Path(out)
    return str(path.with_name(path.stem + ".timing.csv"))


def _check(args, system):
    """The options' rules, before anything is loaded: ``(step, stop_time, period_steps, endpoints)``."""
    from crane_fmu.cosim.master import communication_points
    from crane_fmu.serve import parse_endpoint

    endpoints = {}
    for option, text in (("--opcua", args.opcua), ("--modbus", args.modbus)):
        if text is not None:
            endpoints[option] = parse_endpoint(text, option)
            module = "asyncua" if option == "--opcua" else "pymodbus"
            if importlib.util.find_spec(module) is None:
                raise UsageError(f"{option} needs {module}, which is not installed: pip install -e '.[serve]' "
                                 "(in this project's venv)")
    if not endpoints and not args.print_map:
        raise UsageError("nothing to serve: give --opcua HOST:PORT, --modbus HOST:PORT or both")
    if args.external is not None and args.external not in system.instances:
        raise UsageError(f"--external {args.external}: system {system.name} has no instance {args.external!r}; "
                         f"instances: {', '.join(system.instances)}" + did_you_mean(args.external, system.instances))
    step = system.step if args.step is None else args.step
    if not step > 0:
        raise UsageError(f"--step must be > 0, got {step!r}")
    if args.stop_time is not None:
        communication_points(system.start_time, args.stop_time, step)
    period_steps = 1
    if args.period is not None:
        if args.lock_step:
            raise UsageError("--period paces real time; in lock-step the client takes the steps")
        period_steps = round(args.period / step)
        if period_steps < 1 or not math.isclose(period_steps * step, args.period, rel_tol=1e-9):
            raise UsageError(f"--period {args.period:g}: must be a whole number of steps of {step:g} s")
        if args.stop_time is not None and round((args.stop_time - system.start_time) / step) % period_steps:
            raise UsageError(f"--period {args.period:g}: must divide the run from t = {system.start_time:g} s to "
                             f"--stop-time {args.stop_time:g} s into whole cycles")
    if args.rt_priority is not None:
        if args.lock_step:
            raise UsageError("--rt-priority is for real time; in lock-step the client's requests take the steps")
        if not 1 <= args.rt_priority <= 99:
            raise UsageError(f"--rt-priority must be from 1 to 99, got {args.rt_priority}")
    for option, value in (("--watchdog", args.watchdog), ("--hold", args.hold)):
        if value is not None and args.external is None:
            raise UsageError(f"{option} is the watchdog's, which holds an --external instance's outputs: give "
                             "--external INSTANCE")
        if value is not None and args.lock_step:
            raise UsageError(f"{option} is the watchdog's, for real time; in lock-step time waits for the client")
    if args.watchdog is not None:
        if not args.watchdog > 0:
            raise UsageError(f"--watchdog must be > 0 s, got {args.watchdog:g}")
    return step, args.stop_time, period_steps, endpoints


def _serve(args, system):
    from crane_fmu.cosim import FmiError, Master, open_instance
    from crane_fmu.cosim.external import ExternalInstance
    from crane_fmu.cosim.pacing import Watchdog
    from crane_fmu.cosim.realtime import Runner
    from crane_fmu.cosim.recorder import RESULT_SUFFIXES
    from crane_fmu.serve.rail_ends import CannotStop

    step, stop_time, period_steps, endpoints = _check(args, system)
    system, fmus, connections = prepare(args, system, step)
    if not args.print_map:
        writable_file(args.out, "--out", RESULT_SUFFIXES)
    instances = {}
    try:
        for name, path in fmus.items():
            instances[name] = ExternalInstance(path, name) if name == args.external else open_instance(path, name)
        watchdog = None
        if args.external and not args.lock_step:
            watchdog = Watchdog(1.0 if args.watchdog is None else args.watchdog, args.hold or "zero")
        master = Master(instances, connections, args.algorithm)
        runner = Runner(master, system.start_time, step, stop_time, system.parameters, lock_step=args.lock_step,
                        period_steps=period_steps, watchdog=watchdog, writable=args.writable, log=_say,
                        name=system.name, guard=_rail_guard(args, system, connections))
        if args.print_map:
            from crane_fmu.serve.modbus import markdown, register_map

            print(markdown(register_map(runner.variables)))
            return 0
        return _run(args, system, runner, endpoints)
    except (FmiError, CannotStop) as exc:
        raise UsageError(str(exc)) from None  # at initialisation: the values given
    finally:
        for inst in instances.values():
            inst.free()


def _rail_guard(args, system, connections):
    """The guard that keeps the trolley able to stop before its rail ends when a client drives it (an external
    instance other than the plant: the demand's, or a reference a controller follows), else None."""
    from crane_fmu import components, systems
    from crane_fmu.serve.rail_ends import RailGuard

    plant = components.by_role(systems.kinds(system)).get("plant")
    crane = systems.plant_of(system)
    if args.external in (None, plant) or plant is None or crane is None or crane.crane is None:
        return None
    guard = RailGuard(plant, crane.crane.axes, args.external, connections)
    return guard if guard.axes else None


def _run(args, system, runner, endpoints):
    recorder = open_recorder(args.out)
    runner.observers.append(recorder)
    try:
        runner.start()
    except BaseException:
        recorder.close()  # nothing recorded: no file is left behind
        raise
    previous = _stop_on_signals(runner)  # from here Ctrl-C stops the run cleanly, also while it starts
    try:
        return _serve_until_stopped(args, system, runner, recorder, endpoints)
    finally:
        _restore_signals(previous)


def _serve_until_stopped(args, system, runner, recorder, endpoints):
    from crane_fmu.cosim import FmiError
    from crane_fmu.serve import Network, is_loopback

    network = Network()
    try:
        endpoints = network.start(_servers(runner, system, endpoints))
    except OSError as exc:
        network.stop()
        raise UsageError(str(exc)) from None
    print(_first_line(args, system, runner, endpoints), flush=True)
    for host in {h for h, _ in _hosts(args)}:
        if not is_loopback(host):
            _say(f"warning: listening on {host}: any machine that reaches it can read and drive this run "
                 "(no encryption, no login)")
    if args.external and runner.external.parameters:
        values = ", ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}"
                           for k, v in runner.external.parameters.items())
        _say(f"note: {args.external} is external: the system's values for it ({values}) are the client's to apply")
    for line in getattr(runner.guard, "notes", ()):
        _say(f"note: {line}")
    if args.writable and not any(v.writable and v.role == "parameter" for v in runner.variables):
        _say("note: --writable: no FMU of this system declares a tunable parameter, so none is writable")
    live = _LiveLine(runner) if sys.stderr.isatty() else None
    if live:
        runner.listeners.append(live)
    _ready_for_real_time(args.out)
    normal = _real_time_priority(args.rt_priority) if args.rt_priority else None
    started = time.monotonic()
    try:
        runner.run()
    except FmiError as exc:
        recorder.close(reason=str(exc))
        _say(f"simulation failed: {exc} (results up to t={exc.time:.9g} s in {recorder.written})")
    finally:
        wall = time.monotonic() - started
        if normal is not None:
            os.sched_setscheduler(0, *normal)
        runner.wait_idle()  # a request cut short by the stop ends at a step boundary, and its reply goes out
        network.run(asyncio.sleep(0.2))
        network.stop()  # no client request comes after this
        if live:
            runner.listeners.remove(live)
            live.close()
    if runner.error is None:
        runner.finish()
        recorder.close()
        print(f"{runner.snapshot().status}; wrote {args.out}")
    simulated = runner.time() - system.start_time
    if runner.pacer is not None:
        timing = runner.pacer.timing
        timing.write_csv(timing_path(args.out), system.start_time)
        print(f"timing: {timing.describe(simulated)}; wrote {timing_path(args.out)}")
    elif runner.steps:
        print(f"lock-step: {runner.steps} steps in {wall:.3g} s of wall time (real-time factor "
              f"{simulated / wall:.3g})")
    return 0 if runner.error is None else 1


def _ready_for_real_time(out):
    """What keeps a cycle from stalling: the recorder's writer loaded now, not at its first chunk in a cycle
    (pyarrow's import takes 100 ms and more); the start-up's objects out of the garbage collector's way; and
    a thread that wakes (the runner at its deadline) given the GIL within 0.1 ms, not the default 5 ms."""
    if Path(out).suffix in (".csv", ".parquet"):
        import pyarrow.csv  # noqa: F401
    gc.collect()
    gc.freeze()
    sys.setswitchinterval(SWITCH_INTERVAL)


def _real_time_priority(priority):
    """This thread (the runner's) under SCHED_FIFO at ``priority``; its scheduling before, to restore, or None
    (with a note) where the OS does not permit it."""
    try:
        before = (os.sched_getscheduler(0), os.sched_getparam(0))
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
        return before
    except (AttributeError, OSError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) else "not on this OS"
        _say(f"note: --rt-priority {priority}: real-time scheduling not permitted ({reason}); normal scheduling")
        return None


def _servers(runner, system, endpoints):
    servers = []
    if "--opcua" in endpoints:
        from crane_fmu.serve.opcua import OpcUaServer

        servers.append(OpcUaServer(runner, *endpoints["--opcua"], system.name))
    if "--modbus" in endpoints:
        from crane_fmu.serve.modbus import ModbusServer

        servers.append(ModbusServer(runner, *endpoints["--modbus"]))
    return servers


def _hosts(args):
    from crane_fmu.serve import parse_endpoint

    return [parse_endpoint(text, option) for option, text in (("--opcua", args.opcua), ("--modbus", args.modbus))
            if text is not None]


def _first_line(args, system, runner, endpoints):
    mode = "in lock-step" if args.lock_step else f"in real time every {runner.period_steps * runner.step:g} s"
    external = f", {args.external} external" if args.external else ""
    names = [("OPC UA" if "opc.tcp" in e else "Modbus TCP") + " " + e for e in endpoints]
    return (f"crane-fmu serve: {system.name} {mode} (h = {runner.step:g} s{external}); " + "; ".join(names)
            + f"; run {runner.run_id:016x}")


def _say(line):
    if _LiveLine.shown:  # end the live line first
        sys.stderr.write("\n")
        _LiveLine.shown = False
    print(f"crane-fmu: {line}", file=sys.stderr, flush=True)


def _stop_on_signals(runner):
    """Ctrl-C (and SIGTERM) stop the run at its next safe point; a second Ctrl-C interrupts at once."""

    def stop(signum, frame):
        if runner._stopping.is_set() and signum == signal.SIGINT:
            raise KeyboardInterrupt
        runner.stop()

    return {s: signal.signal(s, stop) for s in (signal.SIGINT, signal.SIGTERM)}


def _restore_signals(previous):
    for s, handler in previous.items():
        signal.signal(s, handler)


class _LiveLine:
    """On a terminal: the simulated time, the status and the latest cycles' timing, twice a second, on stderr."""

    WINDOW = 1000  # the cycles the live percentiles are of
    shown = False  # a live line is on the terminal, not yet ended

    def __init__(self, runner):
        self.runner, self.next = runner, 0.0
        self.width = max(20, shutil.get_terminal_size().columns - 1)

    def __call__(self, snapshot):
        now = time.monotonic()
        if now < self.next:
            return
        self.next = now + 0.5
        line = f"t = {snapshot.time:.3f} s  "
        pacer = self.runner.pacer
        if pacer is not None and len(pacer.timing):
            from crane_fmu.cosim.pacing import percentile

            recent = pacer.timing.lateness[-self.WINDOW:]
            line += (f"lateness p50 {percentile(recent, 50) * 1e3:.2f} ms p99 {percentile(recent, 99) * 1e3:.2f} ms  "
                     f"misses {pacer.timing.misses}/{len(pacer.timing)}  ")
        line += snapshot.status
        sys.stderr.write("\r" + line[:self.width].ljust(self.width))
        sys.stderr.flush()
        _LiveLine.shown = True

    def close(self):
        if _LiveLine.shown:
            sys.stderr.write("\n")
            _LiveLine.shown = False
