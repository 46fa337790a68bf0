"""``crane-fmu bench``: microseconds per communication step, crane pair vs framework floor."""



from .common import UsageError, number

NAME = "bench"
HELP = "microseconds per communication step, crane pair vs framework floor"
EXAMPLES = (
    "examples:\n"
    "  crane-fmu bench\n"
    "  crane-fmu bench --repeat 7 --stop-time 20\n"
    "  crane-fmu bench --sweep\n"
    "  crane-fmu bench --endurance            # one simulated hour at 1 ms\n"
    "  crane-fmu bench --realtime             # the real-time loop, OPC UA and Modbus round trips\n"
    "  crane-fmu bench --mpc                  # the MPC's solve and its whole process against transport's\n"
    "  crane-fmu bench --derivatives          # the native plant's Model Exchange derivatives\n"
    "  crane-fmu bench --spatial              # the crane in three dimensions against the planar crane"
)


# The other benchmarks, one flag each, run instead of the default one: what each measures.
MODES = {
    "sweep": "cases per second of a Dask sweep with 1 and 2 workers; the batch path of the native FMUs against the "
             "C host's limit, a large study and the full board on them",
    "native": "the native (C) plant and controller FMUs in our master, in a C host and as a whole process",
    "mpc": "the MpcController's solve times and whole simulate process against transport's",
    "endurance": "one long run (default one simulated hour) recorded to CSV, memory sampled",
    "realtime": "the real-time loop at 1 ms and 10 ms (default 2 s each) and the round trips of crane-fmu serve over "
                "OPC UA and Modbus TCP (needs the 'serve' extra)",
    "derivatives": "the cost of the native plant's derivatives and directional derivatives (Model Exchange), in a "
                   "C loop",
    "spatial": "the spatial crane against the planar crane, Python and native FMUs: the LQR pair, the planned pair "
               "(a TrajectoryPlanner, no LQR) and the open loop of two axes (open-loop-3d)",
}


def arguments(p):
    p.add_argument("--stop-time", type=number, default=None,
                   help="simulated time per run [s] (default 20, with --sweep 10)")
    p.add_argument("--step", type=number, default=1e-3, help="communication step [s]")
    p.add_argument("--repeat", type=int, default=5,
                   help="runs per pair (with --sweep: batches per cluster); the median is reported")
    p.add_argument("--cases", type=int, default=16, help="with --sweep: cases per measurement")
    p.add_argument("--native-dir", default="build/native", help="with --sweep: the native FMUs of the batch path's "
                   "figures (default build/native)")
    p.add_argument("--batch-cases", type=int, default=240, help="with --sweep: cases of the native sweep (default 240)")
    p.add_argument("--study-cases", type=int, default=10_000,
                   help="with --sweep: cases of the large study (default 10000)")
    p.add_argument("--board-cases", type=int, default=None,
                   help="with --sweep: paired cases of the native board (default: the full board's; 0: no board)")
    modes = p.add_mutually_exclusive_group()  # separate benchmarks: argparse refuses two
    for name, text in MODES.items():
        modes.add_argument("--" + name, action="store_true", help="instead: " + text)


def run(args):
    from crane_fmu.bench import run_bench, run_endurance, run_sweep_bench

    if args.repeat < 1:
        raise UsageError(f"--repeat must be >= 1, got {args.repeat}")
    for name in ("cases", "batch_cases", "study_cases"):
        if getattr(args, name) < 2:
            raise UsageError(f"--{name.replace('_', '-')} must be >= 2, got {getattr(args, name)}")
    if args.board_cases is not None and args.board_cases < 0:
        raise UsageError(f"--board-cases must be >= 0, got {args.board_cases}")
    try:
        if args.spatial:
            from crane_fmu.bench_spatial import run_spatial_bench

            run_spatial_bench(args.stop_time or 20.0, args.step, args.repeat)
        elif args.derivatives:
            from crane_fmu.bench_native import run_derivative_bench

            run_derivative_bench(repeat=args.repeat)
        elif args.realtime:
            from crane_fmu.bench_realtime import run_realtime_bench

            run_realtime_bench(args.stop_time or 2.0)
        elif args.mpc:
            from crane_fmu.bench_mpc import run_mpc_bench

            run_mpc_bench(args.repeat)
        elif args.native:
            from crane_fmu.bench_native import run_native_bench

            run_native_bench(args.stop_time or 20.0, args.step, args.repeat)
        elif args.endurance:
            run_endurance(args.stop_time or 3600.0, args.step)
        elif args.sweep:
            from crane_fmu.bench_batch import run_batch_bench

            run_sweep_bench(args.cases, args.stop_time or 10.0, args.step, args.repeat)
            run_batch_bench(args.native_dir, args.batch_cases, args.stop_time or 20.0, args.step, args.repeat,
                            args.study_cases, args.board_cases)
        else:
            run_bench(args.stop_time or 20.0, args.step, args.repeat)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    return 0
