"""``crane-fmu bench --realtime``: the real-time loop and the protocols' round trips.

1. the lqr system (plant and LQR FMUs, recorded to CSV) paced by :class:`~crane_fmu.cosim.realtime.Runner`
   at cycles of 1 ms and of 10 ms for ``seconds`` each, no protocol: lateness percentiles, deadline misses
   and the real-time factor; with normal scheduling, then (where permitted) under SCHED_FIFO as
   ``crane-fmu serve --rt-priority`` runs it;
2. a ``crane-fmu serve --lock-step --external controller`` process with OPC UA and Modbus TCP on loopback,
   driven from this process as a PLC would: per protocol the median and 99th percentile of a write of ``u``
   and a read of the six measured states (one round trip each), and of a whole lock-step cycle (read, write,
   step), with the step rate that gives.
"""

import asyncio
import os
import re
import select
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from crane_fmu import components, systems
from crane_fmu.build_scripts.build_fmus import build_all
from crane_fmu.cosim import CsvRecorder, Master, open_instance
from crane_fmu.cosim.pacing import percentile
from crane_fmu.cosim.realtime import Runner
from crane_fmu.model import lqr
from crane_fmu.serve.modbus import FIRST_HOLDING, float32_words, words_float32

STATE = components.get("CranePlant").crane.state  # what the served plant gives an external controller
RT_PRIORITY = 10  # as in the docs' example of serve --rt-priority


def run_realtime_bench(seconds=2.0, round_trips=500, out=print, fmu_dir=None):
    """Run the benchmark, print its figures and return them; on the FMUs of ``fmu_dir``, or on ones it builds."""
    figures = {}
    with tempfile.TemporaryDirectory(prefix="crane_bench_realtime_") as tmp:
        tmp = Path(tmp)
        system = systems.get("lqr")
        built = Path(fmu_dir) if fmu_dir else tmp / "fmus"
        if not fmu_dir:
            build_all(built, set(system.instances.values()), systems=(), fmi3=False, log=lambda _: None)
        out(f"1. the lqr system (plant and LQR FMUs, CSV of every step) paced for {seconds:g} s, no protocol:")
        for priority in (None, RT_PRIORITY):
            for period in (1e-3, 1e-2):
                timing = _paced(system, built, period, seconds, tmp / "paced.csv", priority)
                if timing is None:
                    out(f"   with --rt-priority {priority}: not permitted here (needs root or CAP_SYS_NICE)")
                    break
                figures[f"loop_{period * 1e3:g}ms" + ("_fifo" if priority else "")] = timing.summary()
                scheduling = f"SCHED_FIFO {priority}" if priority else "normal scheduling"
                out(f"   {scheduling}: {timing.describe(seconds)}")
        out(f"2. crane-fmu serve --lock-step, a client in this process, {round_trips} round trips each "
            "(median / p99):")
        figures.update(_round_trips(built, tmp, round_trips, out))
    return figures


def _paced(system, fmu_dir, period, seconds, csv, priority=None):
    """The lqr system in real time at cycles of ``period`` (its step 1 ms) for ``seconds``: the Timing; with a
    ``priority``, under SCHED_FIFO as ``serve --rt-priority`` runs it (None where that is not permitted)."""
    if priority:
        try:
            before = (os.sched_getscheduler(0), os.sched_getparam(0))
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
        except (AttributeError, OSError):
            return None
    try:
        return _paced_run(system, fmu_dir, period, seconds, csv)
    finally:
        if priority:
            os.sched_setscheduler(0, *before)


def _paced_run(system, fmu_dir, period, seconds, csv):
    system = systems.prepare(system, 1e-3, seconds)
    fmus, connections = system.resolve(fmu_dir)
    instances = {name: open_instance(path, name) for name, path in fmus.items()}
    try:
        recorder = CsvRecorder(csv)
        runner = Runner(Master(instances, connections), 0.0, 1e-3, seconds, system.parameters, [recorder],
                        period_steps=round(period / 1e-3))
        runner.run()
        runner.finish()
        recorder.close()
    finally:
        for inst in instances.values():
            inst.free()
    return runner.pacer.timing


def _round_trips(fmu_dir, tmp, n, out):
    controller = components.by_role(systems.get("lqr").instances)["controller"]  # the instance a client replaces
    command = [sys.executable, "-m", "crane_fmu", "serve", "--system", "lqr", "--external", controller,
               "--lock-step", "--fmu-dir", str(fmu_dir), "--out", str(tmp / "served.csv"), "--opcua", "127.0.0.1:0",
               "--modbus", "127.0.0.1:0"]
    server = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        ready, _, _ = select.select([server.stdout], [], [], 120)
        line = server.stdout.readline() if ready else ""
        url = re.search(r"(opc\.tcp://\S+?)(;|$)", line.strip())
        modbus = re.search(r"Modbus TCP (\S+?):(\d+)", line)
        if not (url and modbus):
            raise RuntimeError(f"crane-fmu serve did not start: {line!r} {server.stderr.read()[-1000:]}")
        opcua = asyncio.run(_opcua_round_trips(url.group(1), n, controller))
        printed = subprocess.run([*command[:command.index("--out")], "--print-map"], capture_output=True, text=True,
                                 check=True).stdout
        first = int(re.search(rf"\| input \| (\d+)-\d+ \| `{re.escape(controller)}\.x`", printed).group(1))
        mb = _modbus_round_trips(modbus.group(1), int(modbus.group(2)), first, n)
    finally:
        server.send_signal(signal.SIGINT)
        try:
            server.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            server.kill()
    figures = {}
    for protocol, times in (("OPC UA", opcua), ("Modbus TCP", mb)):
        for what, label in (("write_read", "write u + read the 6 states"), ("cycle", "lock-step cycle")):
            samples = times[what]
            median, p99 = statistics.median(samples), percentile(samples, 99)
            figures[f"{protocol}_{what}"] = (median, p99)
            rate = f", {1 / median:.0f} steps/s" if what == "cycle" else ""
            out(f"   {protocol:10s} {label:28s} {median * 1e3:6.3f} ms / {p99 * 1e3:6.3f} ms{rate}")
    return figures


async def _opcua_round_trips(url, n, controller):
    from asyncua import Client, ua  # optional: the serve extra


    law = lqr.COMPONENT.check({"h": 1e-3})
    async with Client(url) as client:
        ns = await client.get_namespace_index("urn:crane-fmu")
        node = lambda name: client.get_node(ua.NodeId(name, ns))  # noqa: E731
        inputs, u, step = [node(f"{controller}.{s}") for s in STATE], node(f"{controller}.u"), node("Step")
        system = await step.get_parent()
        times = {"write_read": [], "cycle": []}
        for _ in range(n):
            start = time.perf_counter()
            await u.write_value(ua.Variant(0.0, ua.VariantType.Double))
            await client.read_values(inputs)
            times["write_read"].append(time.perf_counter() - start)
        for _ in range(n):
            start = time.perf_counter()
            state = await client.read_values(inputs)
            await u.write_value(ua.Variant(lqr.control(law, state), ua.VariantType.Double))
            await system.call_method(step, ua.Variant(1, ua.VariantType.UInt32))
            times["cycle"].append(time.perf_counter() - start)
    return times


def _modbus_round_trips(host, port, first, n):
    """``first``: the input register of the controller's x, the first of the six measured states."""
    from pymodbus.client import ModbusTcpClient  # optional: the serve extra


    law = lqr.COMPONENT.check({"h": 1e-3})
    client = ModbusTcpClient(host, port=port, timeout=10)
    client.connect()
    times = {"write_read": [], "cycle": []}
    try:
        for _ in range(n):
            start = time.perf_counter()
            client.write_registers(FIRST_HOLDING, float32_words(0.0), device_id=1)
            client.read_input_registers(first, count=12, device_id=1)
            times["write_read"].append(time.perf_counter() - start)
        for _ in range(n):
            start = time.perf_counter()
            words = client.read_input_registers(first, count=12, device_id=1).registers
            state = [words_float32(*words[i:i + 2]) for i in range(0, 12, 2)]
            client.write_registers(FIRST_HOLDING, float32_words(lqr.control(law, state)), device_id=1)
            client.write_register(0, 1, device_id=1)
            times["cycle"].append(time.perf_counter() - start)
    finally:
        client.close()
    return times
