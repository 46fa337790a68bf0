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
    "sweep": "cases per second of a Dask sweep with 1 and 2 workers",
    "native": "the native (C) plant and controller FMUs in our master, in a C host and as a whole process",
    "mpc": "the MpcController's solve times and whole simulate process against transport's",
    "endurance": "one long run (default one simulated hour) recorded to CSV, memory sampled",
    "realtime": "the real-time loop at 1 ms and 10 ms (default 2 s each) and the round trips of crane-fmu serve over "
                "OPC UA and Modbus TCP (needs the 'serve' extra)",
    "derivatives": "the cost of the native plant's derivatives and directional derivatives (Model Exchange), in a "
                   "C loop",
    "spatial": "the spatial crane pair (CranePlant3D with the LQR) against the planar pair (CranePlant with the "
               "LQR), Python and native FMUs",
}


def arguments(p):
    p.add_argument("--stop-time", type=number, default=None,
                   help="simulated time per run [s] (default 20, with --sweep 10)")
    p.add_argument("--step", type=number, default=1e-3, help="communication step [s]")
    p.add_argument("--repeat", type=int, default=5,
                   help="runs per pair (with --sweep: batches per cluster); the median is reported")
    p.add_argument("--cases", type=int, default=16, help="with --sweep: cases per measurement")
    modes = p.add_mutually_exclusive_group()  # separate benchmarks: argparse refuses two
    for name, text in MODES.items():
        modes.add_argument("--" + name, action="store_true", help="instead: " + text)


def run(args):
    from crane_fmu.bench import run_bench, run_endurance, run_sweep_bench

    if args.repeat < 1:
        raise UsageError(f"--repeat must be >= 1, got {args.repeat}")
    if args.cases < 2:
        raise UsageError(f"--cases must be >= 2, got {args.cases}")
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
            run_sweep_bench(args.cases, args.stop_time or 10.0, args.step, args.repeat)
        else:
            run_bench(args.stop_time or 20.0, args.step, args.repeat)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    return 0
