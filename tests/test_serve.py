"""`crane-fmu serve` as a PLC meets it: a server process on loopback ports the OS picks, clients in this process.

Every loop is bounded in count and time, every server stops by itself (at its stop time, or on the Ctrl-C
the test sends) and is killed if it does not. The FMUs are the session's build (conftest.fmu_dir).
"""

import asyncio
import math
import re
import select
import signal
import socket
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pd_xy
import pytest
from asyncua import Client, ua
from pymodbus.client import ModbusTcpClient

from crane_fmu import components, systems
from crane_fmu.build_scripts.build_fmus import build_all, systems_dir
from crane_fmu.cli import main
from crane_fmu.cosim import System, read_csv, simulate
from crane_fmu.cosim.ssp import load_system
from crane_fmu.model import lqr
from crane_fmu.serve.modbus import FIRST_HOLDING, FIRST_INPUT, float32_words, register_map, words_float32

ROOT = Path(__file__).resolve().parent.parent
STATE = ("x", "dx", "theta1", "dtheta1", "theta2", "dtheta2")
LQR_LAW = lqr.COMPONENT.check({"h": 1e-3})  # the LQR FMU's law at the lqr system's step


class Server:
    """A ``crane-fmu serve`` process; ``opcua`` and ``modbus`` are the endpoints its first line names."""

    def __init__(self, fmu_dir, folder, *args):
        self.out = Path(folder) / "serve.csv"
        self.proc = subprocess.Popen([sys.executable, "-m", "crane_fmu", "serve", "--fmu-dir", str(fmu_dir),
                                      "--out", str(self.out), *args],
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        ready, _, _ = select.select([self.proc.stdout], [], [], 120)
        self.first_line = self.proc.stdout.readline() if ready else ""
        if not self.first_line.startswith("crane-fmu serve: "):
            self.proc.kill()
            raise AssertionError(f"no first line: {self.first_line!r} {self.proc.stderr.read()[-2000:]}")
        opcua = re.search(r"OPC UA (opc\.tcp://\S+?)(;|$)", self.first_line.strip())
        modbus = re.search(r"Modbus TCP (\S+?):(\d+)(;|$)", self.first_line.strip())
        self.opcua = opcua.group(1) if opcua else None
        self.modbus = (modbus.group(1), int(modbus.group(2))) if modbus else None

    def wait(self, timeout=60):
        """``(exit status, the rest of stdout, stderr)`` once the process has ended by itself."""
        try:
            out, err = self.proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            out, err = self.proc.communicate()
            raise AssertionError(f"the server did not end by itself: {err[-2000:]}") from None
        return self.proc.returncode, out, err

    def stop(self, timeout=60):
        """Ctrl-C, then :meth:`wait`."""
        self.proc.send_signal(signal.SIGINT)
        return self.wait(timeout)


def _offline(fmu_dir, stop_time):
    """The lqr system run offline with the LQR FMU, as `crane-fmu simulate --system lqr` runs it."""
    system = systems.prepare(systems.get("lqr"), 1e-3)
    return simulate(*system.resolve(fmu_dir), stop_time, 1e-3, parameters=system.parameters).columns()


def _run(coroutine, timeout=120):
    return asyncio.run(asyncio.wait_for(coroutine, timeout))


async def _nodes(client):
    ns = await client.get_namespace_index("urn:crane-fmu")
    return ns, lambda name: client.get_node(ua.NodeId(name, ns))


async def _call_step(client, n, variant=ua.VariantType.UInt32):
    ns, node = await _nodes(client)
    step = node("Step")
    return await (await step.get_parent()).call_method(step, ua.Variant(n, variant))


# --- the done-when runs: lock-step with the LQR's law in this process equals the offline run ---


async def _lqr_over_opcua(url, steps):
    """Apply the LQR's law over OPC UA before every step: what the client read and wrote, per step."""
    async with Client(url) as client:
        ns, node = await _nodes(client)
        inputs = [node(f"controller.{name}") for name in STATE]
        u, time_node = node("controller.u"), node("Time")
        seen = []
        for k in range(steps + 1):
            state = await client.read_values(inputs + [time_node])
            demand = lqr.control(LQR_LAW, state[:6])
            await u.write_value(ua.Variant(demand, ua.VariantType.Double))
            seen.append(state + [demand])
            if k < steps:
                await _call_step(client, 1)
        return np.array(seen)


def test_lock_step_over_opcua_equals_the_offline_run_and_ctrl_c_keeps_it(fmu_dir, tmp_path):
    """A PLC's place: the controller left out, this process applies the LQR's law over OPC UA before every
    Step(1). What it reads, and what the server records, equal the offline run of the LQR FMU to 1e-12
    (doubles travel as doubles: the same Gauss-Seidel exchange). Ctrl-C then ends the server cleanly, its
    results (every row, the client's last u included) at --out."""
    steps = 200
    server = Server(fmu_dir, tmp_path, "--system", "lqr", "--external", "controller", "--lock-step", "--opcua",
                    "127.0.0.1:0")
    try:
        seen = _run(_lqr_over_opcua(server.opcua, steps))
    finally:
        status, out, err = server.stop()
    offline = _offline(fmu_dir, steps * 1e-3)
    assert np.max(np.abs(seen[:, 6] - offline["time"])) <= 1e-12
    for i, name in enumerate(STATE):
        assert np.max(np.abs(seen[:, i] - offline[f"plant.{name}"])) <= 1e-12, name
    assert np.max(np.abs(seen[:, 7] - offline["controller.u"])) <= 1e-12
    assert status == 0, err[-2000:]
    assert f"stopped at t = 0.2 s; wrote {server.out}" in out
    assert "lock-step: 200 steps in" in out
    served = read_csv(server.out)
    assert list(served) == list(offline)
    for name in offline:
        assert np.max(np.abs(served[name] - offline[name])) <= 1e-12, name


# --- a plant of two axes: a PD law for x and y in this process, the spatial crane served ---

PD_XY = System("pd-xy", {"plant": "CranePlant3D", "controller": "PdXyController"},
               parameters={"plant": {"theta1y_0": 0.05}, "controller": {"x_d": 0.5, "y_d": -0.3}},
               description="test: PD on the trolley's x and y of the crane in three dimensions")
XY = ("x", "dx", "y", "dy")


@pytest.fixture(scope="module")
def pd_xy_ssp(tmp_path_factory):
    """The pd-xy system's SSP file (CranePlant3D and PdXyController, Python FMUs): a registered system only here."""
    components.register(pd_xy.COMPONENT)
    systems.register(PD_XY)
    try:
        out = tmp_path_factory.mktemp("pd_xy") / "fmus"
        build_all(out, ["CranePlant3D", "PdXyController"], systems=["pd-xy"], fmi3=False, native=False,
                  log=lambda _: None)
        yield systems_dir(out) / "pd-xy.ssp"
    finally:
        components.unregister("PdXyController")
        systems.unregister("pd-xy")


async def _pd_xy_over_opcua(url, steps, config):
    """Apply the PD law for x and y over OPC UA before every step: what the client read and wrote, per step."""
    async with Client(url) as client:
        ns, node = await _nodes(client)
        inputs, demands = [node(f"controller.{name}") for name in XY], [node("controller.ux"), node("controller.uy")]
        seen = []
        for k in range(steps + 1):
            state = await client.read_values(inputs + [node("Time")])
            ux, uy = pd_xy.law(state[:4], *config)
            for demand, value in zip(demands, (ux, uy)):
                await demand.write_value(ua.Variant(value, ua.VariantType.Double))
            seen.append(state + [ux, uy])
            if k < steps:
                await _call_step(client, 1)
        return np.array(seen)


def test_a_two_axis_plant_served_in_lock_step_equals_the_offline_run(pd_xy_ssp, tmp_path):
    """CranePlant3D with the controller external: this process applies a PD law for x and y (tests/pd_xy.py) over
    OPC UA before every Step(1), 200 steps. What it reads (x, dx, y, dy, time), what it writes (ux, uy) and every
    column the server records equal the offline run of the same system file with the PdXyController FMU to 1e-12;
    both axes moved."""
    steps = 200
    server = Server(pd_xy_ssp.parent, tmp_path, "--system", str(pd_xy_ssp), "--external", "controller",
                    "--lock-step", "--opcua", "127.0.0.1:0")
    try:
        seen = _run(_pd_xy_over_opcua(server.opcua, steps, pd_xy.configure(
            {"k_x": 4.0, "k_v": 3.0, **PD_XY.parameters["controller"]})))
    finally:
        status, out, err = server.stop()
    assert status == 0, err[-2000:]
    with load_system(pd_xy_ssp) as system:
        offline = simulate(*system.resolve(pd_xy_ssp.parent), steps * 1e-3, 1e-3,
                           parameters=systems.bind(system).parameters).columns()
    assert np.max(np.abs(seen[:, 4] - offline["time"])) <= 1e-12
    for i, name in enumerate(XY):
        assert np.max(np.abs(seen[:, i] - offline[f"plant.{name}"])) <= 1e-12, name
    for i, name in enumerate(("ux", "uy"), start=5):
        assert np.max(np.abs(seen[:, i] - offline[f"controller.{name}"])) <= 1e-12, name
    served = read_csv(server.out)
    assert list(served) == list(offline)
    for name in offline:
        assert np.max(np.abs(served[name] - offline[name])) <= 1e-12, name
    assert abs(offline["plant.x"][-1]) > 0.01 and abs(offline["plant.y"][-1]) > 0.005  # both axes moved
    assert np.abs(offline["plant.theta1y"]).max() > 0.04  # the swing out of the plane


def test_lock_step_over_modbus_matches_the_offline_run_to_float32(fmu_dir, tmp_path):
    """The same over Modbus: values travel as float32 (high word first). Exactly: each value read is the
    server's double rounded to float32, each u the server applies is the client's rounded to float32. The run
    then differs from the offline run only by that rounding: within 1e-5 in SI units (float32 keeps 7
    digits of these values, of order 0.1 to 2; the rounding of the state, fed back through gains of at most
    165, moves u by ~1e-5 m/s2 a step, and 200 steps of 1 ms integrate that to well under 1e-5)."""
    steps = 200
    server = Server(fmu_dir, tmp_path, "--system", "lqr", "--external", "controller", "--lock-step", "--modbus",
                    "127.0.0.1:0")
    variables = [r for r in register_map(_served_lqr(fmu_dir)) if r.type == "float32"]
    address = {r.name: r.address for r in variables}
    first = address["controller.x"]
    assert [address[f"controller.{n}"] for n in STATE] == list(range(first, first + 12, 2))
    client = ModbusTcpClient(server.modbus[0], port=server.modbus[1], timeout=10)
    read, applied = [], []
    try:
        assert client.connect()
        for k in range(steps + 1):
            words = client.read_input_registers(first, count=12, device_id=1).registers
            state = [words_float32(*words[i:i + 2]) for i in range(0, 12, 2)]
            demand = lqr.control(LQR_LAW, state)
            assert not client.write_registers(address["controller.u"], float32_words(demand), device_id=1).isError()
            read.append(state)
            applied.append(demand)
            if k < steps:
                assert not client.write_register(0, 1, device_id=1).isError()
    finally:
        client.close()
        status, out, err = server.stop()
    assert status == 0, err[-2000:]
    served, offline = read_csv(server.out), _offline(fmu_dir, steps * 1e-3)
    read, applied = np.array(read), np.array(applied)
    for i, name in enumerate(STATE):
        assert np.array_equal(read[:, i], served[f"plant.{name}"].astype(np.float32).astype(float)), name
    assert np.array_equal(served["controller.u"], applied.astype(np.float32).astype(float))
    assert not np.array_equal(served["controller.u"], offline["controller.u"])  # float32 did travel
    for name in offline:
        assert np.max(np.abs(served[name] - offline[name])) <= 1e-5, name


def _served_lqr(fmu_dir):
    """The served variables of the lqr system with an external controller, as the server makes them."""
    from crane_fmu.cosim import Master, open_instance
    from crane_fmu.cosim.external import ExternalInstance
    from crane_fmu.cosim.realtime import Runner

    fmus, connections = systems.get("lqr").resolve(fmu_dir)
    instances = {"plant": open_instance(fmus["plant"], "plant"),
                 "controller": ExternalInstance(fmus["controller"], "controller")}
    try:
        return Runner(Master(instances, connections), 0.0, 1e-3, lock_step=True).variables
    finally:
        instances["plant"].free()


# --- one shared lock-step server: the address space, the register map, bad requests, two clients ---


@pytest.fixture(scope="module")
def server(fmu_dir, tmp_path_factory):
    """lqr in lock-step with the controller external, over OPC UA and Modbus; stopped with Ctrl-C."""
    server = Server(fmu_dir, tmp_path_factory.mktemp("serve"), "--system", "lqr", "--external", "controller",
                    "--lock-step", "--stop-time", "5", "--opcua", "127.0.0.1:0", "--modbus", "127.0.0.1:0")
    yield server
    status, _, err = server.stop()
    assert status == 0, err[-2000:]


def test_the_first_line_names_every_endpoint_on_ports_the_os_picked(server):
    assert server.first_line.startswith("crane-fmu serve: lqr in lock-step (h = 0.001 s, controller external); ")
    url = re.fullmatch(r"opc\.tcp://127\.0\.0\.1:(\d+)", server.opcua)
    assert url and int(url.group(1)) > 0 and server.modbus[0] == "127.0.0.1" and server.modbus[1] > 0


def test_the_opcua_address_space(server, printed_names):
    """Namespace urn:crane-fmu; one object named after the system; a Double per instance.variable with that
    browse name and its unit in the description; outputs and parameters read-only, the external instance's
    outputs writable; Time, Status and Step(n)."""

    async def look():
        async with Client(server.opcua) as client:
            ns, node = await _nodes(client)
            system = await client.nodes.objects.get_child(f"{ns}:lqr")
            children = {(await child.read_browse_name()).Name: child for child in await system.get_children()}
            facts = {}
            for name in ("plant.x", "plant.theta1", "plant.l1", "controller.theta1", "controller.u", "Time",
                         "Status", "Step"):
                child = children[name]
                browse = await child.read_browse_name()
                assert browse.NamespaceIndex == ns and child.nodeid == ua.NodeId(name, ns)
                if name != "Step":
                    facts[name] = ((await child.read_description()).Text,
                                   await child.read_attribute(ua.AttributeIds.UserAccessLevel),
                                   await child.read_data_type_as_variant_type())
            arguments = await children["Step"].get_child("0:InputArguments")
            return len(children), facts, (await arguments.read_value())[0]

    count, facts, step_argument = _run(look())
    writable = ua.AccessLevel.CurrentWrite
    for name, unit in (("plant.x", "[m]"), ("plant.theta1", "[rad]"), ("plant.l1", "[m]"),
                       ("controller.theta1", "[rad]"), ("controller.u", "[m/s2]")):
        description, access, variant = facts[name]
        assert description.endswith(unit) and variant == ua.VariantType.Double, name
        assert bool(access.Value.Value & (1 << writable)) == (name == "controller.u"), name
    assert facts["Time"][2] == ua.VariantType.Double and facts["Status"][2] == ua.VariantType.String
    assert step_argument.Name == "n" and step_argument.DataType == ua.NodeId(ua.ObjectIds.UInt32)
    assert count == len(printed_names) + 7  # Time, Status, StatusCode, System, RunId, StartTime, Step


@pytest.fixture(scope="module")
def printed_map(server):
    """What `crane-fmu serve --print-map` prints for the shared server's system and options."""
    done = subprocess.run([sys.executable, "-m", "crane_fmu", "serve", "--system", "lqr", "--external", "controller",
                           "--lock-step", "--fmu-dir", str(_fmu_dir_of(server)), "--print-map"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return done.stdout


@pytest.fixture(scope="module")
def printed_names(printed_map):
    """The variables' names in the order the printed map lists their registers."""
    return re.findall(r"\| `(\w+\.\w+)` \| float32", printed_map)


def test_the_docs_register_map_is_the_generated_one(printed_map):
    page = (ROOT / "docs" / "guide" / "virtual-commissioning.md").read_text()
    section = re.search(r"<!-- register-map:start -->\n(.*)\n<!-- register-map:end -->", page, re.S).group(1)
    assert section.strip() == printed_map.strip()


def _fmu_dir_of(server):
    return server.proc.args[server.proc.args.index("--fmu-dir") + 1]


def test_modbus_registers_hold_what_opcua_serves(server, printed_names):
    """The generated map: every float32 pair read where --print-map says, high word first, is the OPC UA
    node's double rounded to float32; the header's time (float64) and steps (uint32) are OPC UA's Time."""
    names = printed_names
    entries = {r.name: r for r in register_map(_served_lqr(_fmu_dir_of(server)))}
    assert names == [n for n in entries if "." in n]
    inputs = [n for n in names if entries[n].table == "input"]
    assert [entries[n].address for n in inputs] == list(range(FIRST_INPUT, FIRST_INPUT + 2 * len(inputs), 2))
    assert [n for n in names if entries[n].table == "holding"] == ["controller.u"]
    assert entries["controller.u"].address == FIRST_HOLDING

    async def opcua_values():
        async with Client(server.opcua) as client:
            ns, node = await _nodes(client)
            return await client.read_values([node(n) for n in names] + [node("Time")])

    values = _run(opcua_values())
    client = ModbusTcpClient(server.modbus[0], port=server.modbus[1], timeout=10)
    try:
        assert client.connect()
        count = FIRST_INPUT + 2 * len(inputs)  # in requests of at most 100 (Modbus reads at most 125 at once)
        words = [w for start in range(0, count, 100)
                 for w in client.read_input_registers(start, count=min(100, count - start), device_id=1).registers]
        held = client.read_holding_registers(0, count=FIRST_HOLDING + 2, device_id=1).registers
    finally:
        client.close()
    time_ = struct.unpack(">d", struct.pack(">4H", *words[:4]))[0]
    assert time_ == values[-1] and words[4] * 65536 + words[5] == round(time_ / 1e-3) and words[6] == 1
    for name, value in zip(names, values):
        r = entries[name]
        pair = words[r.address:r.address + 2] if r.table == "input" else held[r.address:r.address + 2]
        with np.errstate(over="ignore"):  # u_max = 1e60 (no limit) is inf in float32
            assert words_float32(*pair) == float(np.float32(value)), name
    assert held[0] == 0  # the step register reads 0


def test_bad_opcua_requests_get_error_replies_and_change_nothing(server):
    async def misbehave():
        async with Client(server.opcua) as client:
            ns, node = await _nodes(client)
            before = await client.read_values([node("Time"), node("controller.u")])
            codes = {}
            for label, name, value in (("string", "controller.u", ua.Variant("fast", ua.VariantType.String)),
                                       ("nan", "controller.u", ua.Variant(math.nan, ua.VariantType.Double)),
                                       ("output", "plant.x", ua.Variant(1.0, ua.VariantType.Double)),
                                       ("parameter", "plant.l1", ua.Variant(2.0, ua.VariantType.Double))):
                try:
                    await node(name).write_value(value)
                    codes[label] = "Good"
                except ua.UaStatusCodeError as exc:
                    codes[label] = type(exc).__name__
            for label, n, variant in (("zero steps", 0, ua.VariantType.UInt32),
                                      ("text steps", "1", ua.VariantType.String),
                                      ("past the stop time", 10**4, ua.VariantType.UInt32)):
                try:
                    await _call_step(client, n, variant)
                    codes[label] = "Good"
                except ua.UaStatusCodeError as exc:
                    codes[label] = type(exc).__name__
            after = await client.read_values([node("Time"), node("controller.u")])
            return codes, before, after

    codes, before, after = _run(misbehave())
    assert codes == {"string": "BadTypeMismatch", "nan": "BadOutOfRange", "output": "BadUserAccessDenied",
                     "parameter": "BadUserAccessDenied", "zero steps": "BadInvalidArgument",
                     "text steps": "BadInvalidArgument", "past the stop time": "BadInvalidState"}
    assert after == before
    _garbage(server.opcua.rpartition(":")[0].removeprefix("opc.tcp://"), int(server.opcua.rpartition(":")[2]),
             b"HELF\x05\x00\x00\x00\xff")
    assert _run(_read_time(server.opcua)) == before[0]  # still serving


async def _read_time(url):
    async with Client(url) as client:
        ns, node = await _nodes(client)
        return await node("Time").read_value()


def _garbage(host, port, data):
    """Send bytes that are no valid request on a raw connection; read what comes back until it closes."""
    with socket.create_connection((host, port), timeout=10) as raw:
        raw.sendall(data)
        raw.settimeout(2)
        try:
            return raw.recv(1024)
        except TimeoutError:
            return None


def test_bad_modbus_requests_get_exception_replies(server):
    client = ModbusTcpClient(server.modbus[0], port=server.modbus[1], timeout=10)
    try:
        assert client.connect()
        t0 = client.read_input_registers(0, count=4, device_id=1).registers
        replies = {
            "beyond the map": client.read_input_registers(2000, count=2, device_id=1),
            "half a float": client.write_registers(FIRST_HOLDING + 1, [0], device_id=1),
            "the reserved register": client.write_registers(1, [0, 0, 0], device_id=1),
            "nan": client.write_registers(FIRST_HOLDING, float32_words(math.nan), device_id=1),
            "zero steps": client.write_register(0, 0, device_id=1),
            "past the stop time": client.write_register(0, 65535, device_id=1),
            "a coil": client.read_coils(0, count=1, device_id=1),
        }
        codes = {label: (reply.isError(), getattr(reply, "exception_code", None)) for label, reply in replies.items()}
        unknown = _garbage(*server.modbus, bytes([0, 7, 0, 0, 0, 2, 1, 0x63]))  # function 0x63: none
        t1 = client.read_input_registers(0, count=4, device_id=1).registers
    finally:
        client.close()
    assert codes == {"beyond the map": (True, 2), "half a float": (True, 2), "the reserved register": (True, 2),
                     "nan": (True, 3), "zero steps": (True, 3), "past the stop time": (True, 3), "a coil": (True, 1)}
    assert unknown is None or (unknown[7] & 0x80 and unknown[8] == 1)  # "illegal function", or closed
    assert t1 == t0  # nothing stepped, still serving


def test_a_second_client_is_served_and_steps_are_taken_one_after_another(server):
    """Two OPC UA clients ask for 5 steps at once and a Modbus client reads meanwhile: both are served, the
    steps are not lost or interleaved (the two replies are 5 and 10 steps on), the Modbus client sees them."""

    async def two_at_once():
        async with Client(server.opcua) as first, Client(server.opcua) as second:
            t0 = await _read_time(server.opcua)
            times = await asyncio.gather(_call_step(first, 5), _call_step(second, 5))
            return t0, times

    t0, times = _run(two_at_once())
    assert sorted(round((t - t0) / 1e-3) for t in times) == [5, 10]
    client = ModbusTcpClient(server.modbus[0], port=server.modbus[1], timeout=10)
    try:
        assert client.connect()
        words = client.read_input_registers(0, count=4, device_id=1).registers
    finally:
        client.close()
    assert struct.unpack(">d", struct.pack(">4H", *words))[0] == max(times)


def test_the_example_pd_client_moves_the_trolley(server):
    """examples/opcua_pd_client.py, in its own process, as the docs run it (1 s of its PD law)."""
    done = subprocess.run([sys.executable, str(ROOT / "examples" / "opcua_pd_client.py"), server.opcua,
                           "--target", "0.5", "--seconds", "1"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    found = re.fullmatch(r"run [0-9a-f]{16}: x = (-?\d+\.\d+) m after 1 s \(target 0\.5 m\); largest hook swing "
                         r"(\d+\.\d+) deg\n", done.stdout)
    assert found and 0.2 < float(found.group(1)) < 0.7, done.stdout


# --- real time against the wall clock, with a client that falls silent ---


def test_real_time_at_10_ms_keeps_its_deadlines_and_the_watchdog_holds_a_silent_client(fmu_dir, tmp_path):
    """10 ms cycles for 3 s (>= 99 % of cycles on time; the run ends by itself at its stop time), the stepping
    thread under SCHED_FIFO where the OS permits it (this machine's cores are shared with other jobs). The
    client writes u = 0.5 for 0.3 s and falls silent: the watchdog (0.5 s) holds u at zero and says so, on
    stderr and in Status; the timing of every cycle is written beside the results."""
    server = Server(fmu_dir, tmp_path, "--system", "lqr", "--external", "controller", "--period", "0.01",
                    "--stop-time", "3", "--watchdog", "0.5", "--rt-priority", "10", "--opcua", "127.0.0.1:0")

    async def write_then_fall_silent():
        async with Client(server.opcua) as client:
            ns, node = await _nodes(client)
            for _ in range(15):
                await node("controller.u").write_value(ua.Variant(0.5, ua.VariantType.Double))
                await asyncio.sleep(0.02)
            for _ in range(100):  # at most 2 s
                status = await node("Status").read_value()
                if status.startswith("holding"):
                    return status
                await asyncio.sleep(0.02)
            return status

    try:
        status_seen = _run(write_then_fall_silent())
    finally:
        code, out, err = server.wait()
    assert code == 0, err[-2000:]
    assert status_seen.startswith("holding: no client write for") and "held at zero" in status_seen
    timing = read_csv(tmp_path / "serve.timing.csv")
    assert len(timing["cycle"]) == 300 and np.all(np.diff(timing["deadline_s"]) == pytest.approx(0.01))
    assert np.mean(timing["missed"] == 0) >= 0.99, out
    assert re.search(r"timing: 300 cycles of 10 ms: .*; real-time factor", out)
    u = read_csv(server.out)["controller.u"]
    assert len(u) == 3001 and u[-1] == 0.0
    last_written = np.flatnonzero(u == 0.5)
    assert last_written.size and np.all(u[last_written[-1] + 1:] == 0.0)
    holds = [line for line in err.splitlines() if "watchdog" in line]
    assert holds and holds[-1].endswith("controller's outputs held at zero")


# --- the command line's rules, in this process ---


@pytest.mark.parametrize("argv, message", [
    (["--system", "lqr"], "nothing to serve: give --opcua HOST:PORT, --modbus HOST:PORT or both"),
    (["--opcua", "127.0.0.1:70000"], "--opcua '127.0.0.1:70000': expected HOST:PORT with a port from 0 to 65535"),
    (["--modbus", "localhost:x"], "--modbus 'localhost:x': expected HOST:PORT"),
    (["--opcua", "--external", "crane"], "--external crane: system paper has no instance 'crane'"),
    (["--opcua", "--period", "0.0025"], "--period 0.0025: must be a whole number of steps of 0.001 s"),
    (["--opcua", "--period", "0.3", "--stop-time", "0.5"],
     "--period 0.3: must divide the run from t = 0 s to --stop-time 0.5 s into whole cycles"),
    (["--opcua", "--period", "1000", "--stop-time", "0.5"], "--period 1000: must divide the run"),
    (["--opcua", "--lock-step", "--period", "0.01"], "--period paces real time; in lock-step the client"),
    (["--opcua", "--lock-step", "--external", "controller", "--watchdog", "1"],
     "--watchdog is the watchdog's, for real time; in lock-step time waits for the client"),
    (["--opcua", "--watchdog", "1"], "--watchdog is the watchdog's, which holds an --external instance's outputs"),
    (["--opcua", "--hold", "last"], "--hold is the watchdog's, which holds an --external instance's outputs"),
    (["--modbus", "opc.tcp://127.0.0.1:502"], "--modbus 'opc.tcp://127.0.0.1:502': expected HOST:PORT"),
    (["--opcua", "--external", "controller", "--watchdog", "0"], "--watchdog must be > 0 s, got 0"),
    (["--opcua", "--stop-time", "0.0005"], "must divide the interval"),
    (["--opcua", "--lock-step", "--rt-priority", "10"], "--rt-priority is for real time"),
    (["--opcua", "--rt-priority", "100"], "--rt-priority must be from 1 to 99, got 100"),
    (["--opcua", "--out", "r.txt"], "--out r.txt: writes a .csv"),
])
def test_serve_mistakes_are_one_line_and_status_2(fmu_dir, argv, message, capsys):
    assert main(["serve", "--fmu-dir", str(fmu_dir), *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err, err


def test_a_missing_protocol_package_is_one_line(fmu_dir, capsys, monkeypatch):
    import importlib.util

    find_spec = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "asyncua" else find_spec(name))
    assert main(["serve", "--fmu-dir", str(fmu_dir), "--opcua"]) == 2
    assert "--opcua needs asyncua, which is not installed: pip install -e '.[serve]'" in capsys.readouterr().err


@pytest.mark.quick
def test_the_register_map_and_the_float32_words_of_a_value():
    """The map's rule (crane_fmu/serve/modbus.py): the variables in their order, read-only ones from input
    register 32 (after the header and the run's identity), writable ones from holding register 2, two registers
    each; a value is its IEEE 754 float32,
    high word first (1.0 is 0x3F80 0x0000), read back as that float32; beyond float32 it is +-inf."""
    from types import SimpleNamespace

    from crane_fmu.serve import parse_endpoint

    served = [SimpleNamespace(name=name, unit="1", description="", writable=writable)
              for name, writable in (("plant.x", False), ("controller.u", True), ("plant.theta1", False))]
    placed = [(r.table, r.address, r.name) for r in register_map(served) if r.type == "float32"]
    assert placed == [("input", FIRST_INPUT, "plant.x"), ("holding", FIRST_HOLDING, "controller.u"),
                      ("input", FIRST_INPUT + 2, "plant.theta1")] and (FIRST_INPUT, FIRST_HOLDING) == (32, 2)
    assert float32_words(1.0) == [0x3F80, 0x0000] and words_float32(0x3F80, 0x0000) == 1.0
    assert words_float32(*float32_words(0.1)) == float(np.float32(0.1))
    assert float32_words(-1e39) == float32_words(-math.inf)
    assert parse_endpoint(":4840", "--opcua") == ("127.0.0.1", 4840)
    assert parse_endpoint("opc.tcp://10.0.0.2:4840/", "--opcua") == ("10.0.0.2", 4840)  # the first line's URL


@pytest.mark.quick
def test_the_core_imports_no_protocol_package():
    """asyncua (LGPL-3.0) and pymodbus are an optional extra: importing the toolkit, its master, its real-time
    runner and its command line loads neither."""
    code = ("import sys, crane_fmu.cli, crane_fmu.cosim.realtime, crane_fmu.commands.serve; "
            "print(sorted(m for m in sys.modules if m.split('.')[0] in ('asyncua', 'pymodbus')))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.stdout.strip() == "[]", done.stderr


def test_a_port_in_use_is_one_line(fmu_dir, tmp_path, capsys):
    with socket.create_server(("127.0.0.1", 0)) as taken:
        port = taken.getsockname()[1]
        assert main(["serve", "--fmu-dir", str(fmu_dir), "--system", "lqr", "--lock-step", "--modbus",
                     f"127.0.0.1:{port}", "--out", str(tmp_path / "serve.csv")]) == 2
    err = capsys.readouterr().err
    assert err == f"crane-fmu: error: --modbus 127.0.0.1:{port}: cannot listen (Address already in use)\n"


# --- no client write ends a run: ranges, refused steps rolled back, bounded requests, signals (issue 50) ---


async def _write(node, value):
    """The name of the status a write of the Double ``value`` got."""
    try:
        await node.write_value(ua.Variant(value, ua.VariantType.Double))
        return "Good"
    except ua.UaStatusCodeError as exc:
        return type(exc).__name__


async def _step_status(client, *n):
    """The name of the status of ``Step(*n)`` (``Step()`` without one)."""
    ns, node = await _nodes(client)
    step = node("Step")
    try:
        await (await step.get_parent()).call_method(step, *(ua.Variant(k, ua.VariantType.UInt32) for k in n))
        return "Good"
    except ua.UaStatusCodeError as exc:
        return type(exc).__name__


def test_a_write_outside_the_drive_range_is_refused_over_both_protocols(fmu_dir, tmp_path):
    """The plant's drive limit (--set plant.u_max=3) is the range of the controller's u that drives it: 3.5 and
    1e20 are refused with BadOutOfRange, 3.4e38 and -3.5 over Modbus with exception 03, +-3 and 2.5 taken. Without
    a limit (the lqr plant's u_max is INF) the stated default of an unlimited drive holds instead: 1e20 refused,
    the default itself taken. After every refusal the run steps on, its values finite."""
    from crane_fmu.cosim.write_ranges import DEFAULT_LIMITS

    limited = Server(fmu_dir, tmp_path / "limited", "--system", "lqr", "--external", "controller", "--lock-step",
                     "--set", "plant.u_max=3", "--opcua", "127.0.0.1:0", "--modbus", "127.0.0.1:0")
    address = {r.name: r.address for r in register_map(_served_lqr(fmu_dir))}["controller.u"]

    async def opcua(url, values):
        async with Client(url) as client:
            ns, node = await _nodes(client)
            codes = [await _write(node("controller.u"), value) for value in values]
            codes.append(await _step_status(client, 10))
            state = await client.read_values([node(f"plant.{name}") for name in STATE] + [node("Time")])
            return codes, state

    client = ModbusTcpClient(limited.modbus[0], port=limited.modbus[1], timeout=10)
    try:
        codes, state = _run(opcua(limited.opcua, [3.5, 1e20, -3.0, 3.0, 2.5]))
        assert client.connect()
        replies = [client.write_registers(address, float32_words(v), device_id=1) for v in (3.4e38, -3.5, -2.5)]
        replies.append(client.write_register(0, 10, device_id=1))
    finally:
        client.close()
        status, _, err = limited.stop()
    assert codes == ["BadOutOfRange", "BadOutOfRange", "Good", "Good", "Good", "Good"]
    assert [(r.isError(), r.exception_code if r.isError() else None) for r in replies] == [
        (True, 3), (True, 3), (False, None), (False, None)]
    assert all(map(math.isfinite, state)) and state[-1] == pytest.approx(0.01)
    assert status == 0, err[-2000:]
    served = read_csv(limited.out)
    assert set(served["controller.u"]) <= {0.0, 2.5, -2.5}  # never 3.5, 1e20 or 3.4e38

    default = DEFAULT_LIMITS["m/s2"]
    unlimited = Server(fmu_dir, tmp_path / "unlimited", "--system", "lqr", "--external", "controller", "--lock-step",
                       "--opcua", "127.0.0.1:0")
    try:
        codes, state = _run(opcua(unlimited.opcua, [1e20, default * 1.01, -default]))
    finally:
        status, _, err = unlimited.stop()
    assert codes == ["BadOutOfRange", "BadOutOfRange", "Good", "Good"]
    assert all(map(math.isfinite, state)) and status == 0, err[-2000:]


def test_a_step_the_plant_refuses_is_rolled_back_and_the_run_goes_on(fmu_dir, tmp_path):
    """A step the plant refuses ends nothing: with a drive limit of 1e30 a written u of 1e20 is in range, and the
    step makes the plant's state non-finite (the issue's case); with a rail end at x_min = -0.05 m, u = -3 drives
    the trolley past it. Each Step is answered BadOutOfRange (Modbus: 03), the run rolled back to where the
    request began (time and state as before); the next request with a sane u steps on. The recorded file has
    every time once, in order, and only finite values."""
    server = Server(fmu_dir, tmp_path, "--system", "lqr", "--external", "controller", "--lock-step", "--set",
                    "plant.u_max=1e30", "--set", "plant.x_min=-0.05", "--opcua", "127.0.0.1:0", "--modbus",
                    "127.0.0.1:0")

    async def drive(url):
        async with Client(url) as client:
            ns, node = await _nodes(client)
            watched = [node("Time"), node("plant.x"), node("plant.dx")]
            seen = [await _write(node("controller.u"), 0.5), await _step_status(client, 20),
                    await client.read_values(watched)]
            for u in (1e20, -3.0):
                seen += [await _write(node("controller.u"), u), await _step_status(client, 500),
                         await client.read_values(watched)]
            seen += [await _write(node("controller.u"), 0.5), await _step_status(client, 30),
                     await client.read_values(watched)]
            return seen

    client = ModbusTcpClient(server.modbus[0], port=server.modbus[1], timeout=10)
    address = {r.name: r.address for r in register_map(_served_lqr(fmu_dir))}["controller.u"]
    try:
        seen = _run(drive(server.opcua))
        assert client.connect()
        assert not client.write_registers(address, float32_words(-3.0), device_id=1).isError()
        refused = client.write_register(0, 500, device_id=1)
        t_modbus = client.read_input_registers(0, count=4, device_id=1).registers
    finally:
        client.close()
        status, out, err = server.stop()
    assert seen[:2] == ["Good", "Good"] and seen[2][0] == pytest.approx(0.02)
    for k in (3, 6):  # 1e20, then -3 past the rail end: refused, nothing moved
        assert seen[k:k + 2] == ["Good", "BadOutOfRange"] and seen[k + 2] == seen[2], seen[k:k + 3]
    assert seen[9:11] == ["Good", "Good"] and seen[11][0] == pytest.approx(0.05) and seen[11][1] > seen[2][1]
    assert (refused.isError(), refused.exception_code) == (True, 3)
    assert struct.unpack(">d", struct.pack(">4H", *t_modbus))[0] == seen[11][0]
    assert status == 0, err[-2000:]
    assert "non-finite" in err and "rail end x_min" in err and err.count("rolled back") == 3
    served = read_csv(server.out)
    assert np.all(np.diff(served["time"]) > 0) and served["time"][-1] == pytest.approx(0.05)
    assert all(np.all(np.isfinite(column)) for column in served.values())


def test_step_without_n_takes_one_and_a_request_is_bounded(fmu_dir, tmp_path):
    """Step() takes one step (not BadUnexpectedError); Step(n) takes at most 65535 (the Modbus step register's
    range; one call of 2**32 - 1 steps would hold the server for hours): more is BadInvalidArgument. Without a stop
    time the bound is that; with one, no request passes it."""
    server = Server(fmu_dir, tmp_path, "--system", "lqr", "--external", "controller", "--lock-step", "--opcua",
                    "127.0.0.1:0")

    async def ask(url):
        async with Client(url) as client:
            codes = [await _step_status(client), await _step_status(client, 2**32 - 1),
                     await _step_status(client, 65536)]
            ns, node = await _nodes(client)
            return codes, await node("Time").read_value()

    try:
        codes, t = _run(ask(server.opcua))
    finally:
        status, _, err = server.stop()
    assert codes == ["Good", "BadInvalidArgument", "BadInvalidArgument"] and t == pytest.approx(1e-3)
    assert status == 0, err[-2000:]


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_signal_stops_a_long_step_request_at_the_next_step_boundary(fmu_dir, tmp_path, signum):
    """Step(65535) (over a minute of simulated time, seconds of work) running when SIGINT or SIGTERM comes (once its
    first rows are written): the server ends within a few seconds, the request cut at a step boundary (Bad status,
    the steps taken kept), status 0, the rows up to there recorded, each time once."""
    import time

    server = Server(fmu_dir, tmp_path, "--system", "lqr", "--external", "controller", "--lock-step", "--opcua",
                    "127.0.0.1:0")

    async def long_request(url):
        async with Client(url) as client:
            return await _step_status(client, 65535)

    async def signal_meanwhile():
        request = asyncio.ensure_future(long_request(server.opcua))
        partial = Path(str(server.out) + ".partial")
        while not request.done() and not (partial.exists() and partial.stat().st_size > 100_000):
            await asyncio.sleep(0.005)  # the request runs: its rows are being written
        server.proc.send_signal(signum)
        sent = time.monotonic()
        code = await request
        return code, time.monotonic() - sent

    try:
        code, after = _run(signal_meanwhile())
    finally:
        status, out, err = server.wait(60)
    assert code == "BadInvalidState" and after < 5.0, (code, after)
    assert status == 0, err[-2000:]
    stopped = re.search(r"stopped at t = (\S+) s", out)
    assert stopped and 0 < float(stopped.group(1)) < 65.0, out
    served = read_csv(server.out)
    assert np.all(np.diff(served["time"]) > 0) and served["time"][-1] == pytest.approx(float(stopped.group(1)))


# --- which run, and its end: identity nodes and registers, finished, one value table (issue 50) ---


def _run_id(server):
    return re.search(r"; run ([0-9a-f]{16})$", server.first_line.strip()).group(1)


def test_the_run_says_which_it_is_and_when_it_finished_over_both_protocols(fmu_dir, tmp_path):
    """System, RunId (the first line's) and StartTime (between the launch and now) as OPC UA nodes, and the same
    in Modbus input registers 8-31 (uint64, float64 Unix time, ASCII name). At --stop-time in lock-step the
    status is finished, as a code (4, in StatusCode and in register 6) with the line beside it; a further Step
    is refused. A u written over Modbus is what the OPC UA node reads at once, and the other way round."""
    import time
    from datetime import timezone

    launched = time.time()
    server = Server(fmu_dir, tmp_path, "--system", "lqr", "--external", "controller", "--lock-step", "--stop-time",
                    "0.05", "--opcua", "127.0.0.1:0", "--modbus", "127.0.0.1:0")
    address = {r.name: r.address for r in register_map(_served_lqr(fmu_dir))}["controller.u"]
    client = ModbusTcpClient(server.modbus[0], port=server.modbus[1], timeout=10)

    async def identity_and_end(url):
        async with Client(url) as opc:
            ns, node = await _nodes(opc)
            identity = await opc.read_values([node("System"), node("RunId"), node("StartTime"), node("StatusCode")])
            assert not client.write_registers(address, float32_words(1.25), device_id=1).isError()
            after_modbus = await node("controller.u").read_value()
            await node("controller.u").write_value(ua.Variant(-0.75, ua.VariantType.Double))
            held = client.read_holding_registers(address, count=2, device_id=1).registers
            steps = [await _step_status(opc, 20), await _step_status(opc, 30), await _step_status(opc)]
            end = await opc.read_values([node("StatusCode"), node("Status"), node("Time")])
            return identity, after_modbus, words_float32(*held), steps, end

    try:
        assert client.connect()
        identity, after_modbus, held, steps, end = _run(identity_and_end(server.opcua))
        words = client.read_input_registers(0, count=32, device_id=1).registers
    finally:
        client.close()
        status, out, err = server.stop()
    system, run_id, started, code = identity
    assert system == "lqr" and run_id == _run_id(server) and code == 1
    assert launched <= started.replace(tzinfo=timezone.utc).timestamp() <= time.time()
    header = struct.unpack(">Qd", struct.pack(">8H", *words[8:16]))
    assert f"{header[0]:016x}" == run_id
    assert header[1] == pytest.approx(started.replace(tzinfo=timezone.utc).timestamp(), abs=1e-3)
    assert struct.pack(">16H", *words[16:32]).rstrip(b"\0") == b"lqr"
    assert after_modbus == 1.25 and held == -0.75
    assert steps == ["Good", "Good", "BadInvalidState"]
    assert end[0] == 4 and end[1].startswith("finished") and end[2] == pytest.approx(0.05) and words[6] == 4
    assert status == 0 and "finished at t = 0.05 s" in out, err[-2000:]


def test_real_time_reads_finished_at_the_stop_time(fmu_dir, tmp_path):
    """In real time the run ends by itself at --stop-time; a client polling StatusCode sees 4 (finished) before
    the server goes, with Status saying so."""
    server = Server(fmu_dir, tmp_path, "--system", "lqr", "--stop-time", "0.5", "--opcua", "127.0.0.1:0")

    async def poll(url):
        seen = []
        async with Client(url) as opc:
            ns, node = await _nodes(opc)
            for _ in range(500):  # at most ~10 s
                try:
                    seen.append(tuple(await opc.read_values([node("StatusCode"), node("Status")])))
                except (ConnectionError, ua.UaError, asyncio.TimeoutError):
                    break
                if seen[-1][0] == 4:
                    break
                await asyncio.sleep(0.02)
        return seen

    try:
        seen = _run(poll(server.opcua))
    finally:
        status, out, err = server.wait(60)
    assert seen and seen[0][0] == 2 and seen[-1][0] == 4 and seen[-1][1].startswith("finished"), seen[-3:]
    assert status == 0, err[-2000:]


def test_the_example_client_drives_only_the_run_it_was_started_for(server):
    """examples/opcua_pd_client.py against the shared lqr server: told another system, or another run id, it says
    so in one line, exits 2 and writes nothing; told the server's own run id it drives it."""
    example = [sys.executable, str(ROOT / "examples" / "opcua_pd_client.py"), server.opcua, "--seconds", "0.05"]
    t0 = _run(_read_time(server.opcua))
    wrong = [subprocess.run(example + extra, capture_output=True, text=True, timeout=120)
             for extra in (["--system", "transport"], ["--run-id", "0123456789abcdef"])]
    assert _run(_read_time(server.opcua)) == t0  # nothing stepped
    for done, says in zip(wrong, ("runs system 'lqr'", "not 0123456789abcdef")):
        assert done.returncode == 2 and done.stdout == "", done.stderr
        assert len(done.stderr.splitlines()) == 1 and says in done.stderr and "nothing written" in done.stderr
    right = subprocess.run(example + ["--run-id", _run_id(server)], capture_output=True, text=True, timeout=120)
    assert right.returncode == 0 and right.stdout.startswith(f"run {_run_id(server)}: "), right.stderr


# --- a derandomised fuzz of both protocols (issue 50) ---

FUZZ_SEED, FUZZ_OPERATIONS = 50, 600  # operations in all, both protocols interleaved; the seed fixes every one


def _fuzz_value(rng):
    """A value a careless or hostile client might send: in range, out of it, huge, non-finite, of another type."""
    kind = rng.randrange(8)
    if kind < 3:
        return ua.Variant(rng.uniform(-3.0, 3.0), ua.VariantType.Double)
    if kind == 3:
        return ua.Variant(rng.choice([3.0000001, -3.5, 1e20, -3.4e38, 1e308, 5e-324]), ua.VariantType.Double)
    if kind == 4:
        return ua.Variant(rng.choice([math.nan, math.inf, -math.inf]), ua.VariantType.Double)
    if kind == 5:
        return ua.Variant(rng.uniform(-5, 5), ua.VariantType.Float)
    if kind == 6:
        return ua.Variant(rng.randrange(-10, 10), ua.VariantType.Int32)
    return rng.choice([ua.Variant("1.0", ua.VariantType.String), ua.Variant(True, ua.VariantType.Boolean)])


async def _fuzz_opcua(client, node, names, rng):
    """One random OPC UA request: a write of a random node, a read, or a Step call with random arguments."""
    action = rng.randrange(4)
    target = rng.choice(names + ["Time", "Status", "StatusCode", "RunId", "System", "Step", "nosuch.node", "",
                                 "x" * 300])
    try:
        if action == 0:
            await node(target).write_value(_fuzz_value(rng))
        elif action == 1:
            await node(target).read_value()
        else:
            step = node("Step")
            n = rng.choice([0, 1, 2, rng.randrange(1, 200), 65536, 2**32 - 1])
            kind = rng.choice([ua.VariantType.UInt32, ua.VariantType.UInt32, ua.VariantType.Int32,
                               ua.VariantType.Double, ua.VariantType.String])
            arguments = [] if rng.random() < 0.1 else [ua.Variant(str(n) if kind == ua.VariantType.String else
                                                                  float(n) if kind == ua.VariantType.Double else
                                                                  n if kind == ua.VariantType.UInt32 else
                                                                  max(-2**31, min(2**31 - 1, n)), kind)]
            if rng.random() < 0.05:
                arguments.append(ua.Variant(1, ua.VariantType.UInt32))
            await (await step.get_parent()).call_method(step, *arguments)
    except (ua.UaError, ua.UaStatusCodeError):
        pass  # a refused request: the reply is the point


def _fuzz_modbus(client, rng):
    """One random Modbus request: any function on any address with any count and words."""
    address, count = rng.randrange(0, 140), rng.randrange(1, 20)
    words = [rng.randrange(0, 65536) for _ in range(count)]
    if rng.random() < 0.4:  # a float32 value whole at a random even address
        words = float32_words(rng.choice([rng.uniform(-3.0, 3.0), 1e20, -3.4e38, math.nan, 3.01]))
    action = rng.randrange(6)
    reply = (client.read_input_registers(address, count=count, device_id=1) if action == 0 else
             client.read_holding_registers(address, count=count, device_id=1) if action == 1 else
             client.write_registers(address, words, device_id=1) if action == 2 else
             client.write_register(rng.choice([0, 0, 1, address]), rng.choice([0, 1, 5, 199, 65535]), device_id=1)
             if action == 3 else
             client.read_coils(address, count=count, device_id=1) if action == 4 else
             client.write_coil(address, True, device_id=1))
    return reply


def _fuzz_clients(fmu_dir, server):
    """``(served names, controller.u's Modbus address, a Modbus client of the server)`` for a fuzz of the lqr run."""
    served = _served_lqr(fmu_dir)
    address = {r.name: r.address for r in register_map(served)}["controller.u"]
    return [v.name for v in served], address, ModbusTcpClient(server.modbus[0], port=server.modbus[1], timeout=10)


def _fuzzed_run_held(checks, operations, server, status, err):
    """A fuzzed run's requirements: u within +-3 over both protocols and time never back at every check, status 0,
    every recorded value finite, u within its range, each time once. Returns the recorded columns."""
    assert len(checks) == operations // 50
    for u, u_modbus, t, before in checks:
        assert -3.0 <= u <= 3.0 and -3.0 <= u_modbus <= 3.0 and t >= before
    assert status == 0, err[-2000:]
    recorded = read_csv(server.out)
    assert all(np.all(np.isfinite(column)) for column in recorded.values())
    assert np.all(np.abs(recorded["controller.u"]) <= 3.0) and np.all(np.diff(recorded["time"]) > 0)
    return recorded


async def _fuzz_requests(server, opc, node, modbus, names, address, rng, operations):
    """``operations`` random requests, OPC UA or Modbus by a coin; the server running after each; every 50 and at the
    end ``(u over OPC UA, u over Modbus, time, the time read before)``."""
    checks, last_time = [], 0.0
    for k in range(operations):
        if rng.random() < 0.5:
            await _fuzz_opcua(opc, node, names, rng)
        else:
            _fuzz_modbus(modbus, rng)
        assert server.proc.poll() is None, f"the server ended at request {k}"
        if k % 50 == 49 or k == operations - 1:
            u, t = await opc.read_values([node("controller.u"), node("Time")])
            held = modbus.read_holding_registers(address, count=2, device_id=1).registers
            checks.append((u, words_float32(*held), t, last_time))
            last_time = t
    return checks


def test_a_fuzz_of_both_protocols_never_ends_the_server_nor_leaves_a_value_out_of_range(fmu_dir, tmp_path):
    """600 random requests (seed 50: the same every run), OPC UA and Modbus interleaved, against a lock-step server
    with a drive limit of 3 m/s2 and rail ends at +-0.3 m (so that steps are refused too): random node ids,
    registers, values (in and out of range, non-finite, of other types), functions, Step arguments and orders.
    After every request the server is running; every 50, and at the end, u as both protocols read it lies within
    +-3 and time has not gone back; then u = 3 held drives the trolley into a rail end (a refused step whatever
    the draws did). Ctrl-C then ends it with status 0, and every recorded value is finite, u within its range, each
    time once."""
    import random

    rng = random.Random(FUZZ_SEED)
    server = Server(fmu_dir, tmp_path, "--system", "lqr", "--external", "controller", "--lock-step", "--set",
                    "plant.u_max=3", "--set", "plant.x_min=-0.3", "--set", "plant.x_max=0.3", "--opcua", "127.0.0.1:0",
                    "--modbus", "127.0.0.1:0")
    names, address, modbus = _fuzz_clients(fmu_dir, server)

    async def fuzz(url):
        async with Client(url) as opc:
            ns, node = await _nodes(opc)
            checks = await _fuzz_requests(server, opc, node, modbus, names, address, rng, FUZZ_OPERATIONS)
            # whatever the draws did: the drive's limit held into a rail end, so that a step is refused for certain
            await node("controller.u").write_value(ua.Variant(3.0, ua.VariantType.Double))
            step = node("Step")
            for _ in range(3):
                try:
                    await (await step.get_parent()).call_method(step, ua.Variant(1000, ua.VariantType.UInt32))
                except (ua.UaError, ua.UaStatusCodeError):
                    pass
        return checks

    try:
        assert modbus.connect()
        checks = _run(fuzz(server.opcua), timeout=600)
    finally:
        modbus.close()
        status, out, err = server.stop()
    _fuzzed_run_held(checks, FUZZ_OPERATIONS, server, status, err)
    assert checks[-1][2] > 0 and "rolled back" in err  # steps were taken, and refused (rail ends)


def test_real_time_a_refused_step_holds_the_client_at_zero_and_the_run_goes_on(fmu_dir, tmp_path):
    """In real time a cycle the plant refuses (u = 1e20 within a drive limit of 1e30 makes its state non-finite) is
    rolled back: the controller's u is held at zero, one line on stderr says so (Status: holding and why, code 3);
    with u = 0 the next cycle steps ("the steps are taken again"), and the run goes on to its stop time
    and ends with status 0, every recorded value finite, u never 1e20."""
    server = Server(fmu_dir, tmp_path, "--system", "lqr", "--external", "controller", "--period", "0.01",
                    "--watchdog", "5", "--stop-time", "1.0", "--set", "plant.u_max=1e30", "--opcua", "127.0.0.1:0")

    async def push(url):
        async with Client(url) as opc:
            ns, node = await _nodes(opc)
            await asyncio.sleep(0.2)
            await node("controller.u").write_value(ua.Variant(1e20, ua.VariantType.Double))
            seen = []
            for _ in range(300):  # until the server ends, at most ~6 s
                try:
                    seen.append(tuple(await opc.read_values([node("StatusCode"), node("Status"),
                                                              node("controller.u")])))
                except (ConnectionError, ua.UaError, asyncio.TimeoutError):
                    break
                if seen[-1][0] == 4:
                    break
                await asyncio.sleep(0.01)
            return seen

    try:
        seen = _run(push(server.opcua))
    finally:
        status, out, err = server.wait(60)
    assert seen[-1][0] == 4, seen[-3:]  # (the holding lasts one 10 ms cycle: stderr says it, not a poll)
    assert status == 0 and "finished at t = 1 s" in out, err[-2000:]
    assert err.count("rolled back") == 1 and "non-finite" in err and "held at zero" in err, err
    assert "the steps are taken again" in err
    served = read_csv(server.out)
    assert all(np.all(np.isfinite(column)) for column in served.values()) and served["time"][-1] == 1.0
    assert np.all(np.abs(served["controller.u"]) < 1e20) and served["controller.u"][-1] == 0.0


def _driven_at_u_max(server, name="controller.u", value=3.0):
    """A real-time run whose client writes ``name`` = ``value`` (u = 3) once and leaves it: ``(status, stdout,
    stderr)`` at its end."""
    async def push(url):
        async with Client(url) as opc:
            ns, node = await _nodes(opc)
            await node(name).write_value(ua.Variant(value, ua.VariantType.Double))

    try:
        _run(push(server.opcua))
    finally:
        ended = server.wait(40)
    return ended


def test_real_time_a_trolley_driven_at_a_rail_end_is_braked_and_the_run_reaches_its_stop_time(fmu_dir, tmp_path):
    """A client writes u = 3 (the drive's limit) towards the rail end x_max = 0.3 m and then nothing more. Without a
    guard the trolley reached a point before the rail end from where no demand within the limit stops it (v^2 / 2U
    = 0.29 m at 1.32 m/s): every cycle was refused and the run held until Ctrl-C. Now the cycle that would end
    where the trolley can no longer stop is refused (one line naming the rail end), u is held at -3 and then at
    what brings the trolley to rest, and the run goes on to its stop time by itself: status 0, the trolley never past
    x_max, at rest at the end, every recorded value finite."""
    server = Server(fmu_dir, tmp_path, "--system", "lqr", "--external", "controller", "--period", "0.01",
                    "--watchdog", "30", "--stop-time", "1.5", "--set", "plant.u_max=3", "--set", "plant.x_max=0.3",
                    "--opcua", "127.0.0.1:0")
    status, out, err = _driven_at_u_max(server)
    assert status == 0 and "finished at t = 1.5 s" in out, err[-2000:]
    assert "could not stop before the rail end x_max = 0.3 m" in err and "held at u = -3" in err, err
    served = read_csv(server.out)
    assert all(np.all(np.isfinite(column)) for column in served.values()) and served["time"][-1] == 1.5
    assert np.max(served["plant.x"]) <= 0.3 and served["plant.x"][-1] > 0.2  # braked before the end, not back
    assert abs(served["plant.dx"][-1]) < 1e-9 and served["controller.u"][-1] == 0.0  # at rest, u held at zero
    assert set(np.unique(served["controller.u"])) >= {3.0, -3.0}


@pytest.mark.parametrize("system, demand, position", [("lqr", "u", "x"), ("lqr3d", "ux", "x"), ("lqr3d", "uy", "y")])
def test_lock_step_a_client_that_brakes_after_a_refusal_at_a_rail_end_steps_on(fmu_dir, tmp_path, system, demand,
                                                                               position):
    """Lock-step: the demand at its limit (3 m/s2) towards the rail end at 0.3 m, in requests of 10 steps until one
    is refused (BadOutOfRange); the client then brakes (-3) and every request is taken again until the trolley moves
    back. Without the guard the refusal came at the rail end itself, where braking cannot stop the trolley: every
    later request was refused too. The planar crane, and each axis of the crane in three dimensions."""
    server = Server(fmu_dir, tmp_path, "--system", system, "--external", "controller", "--lock-step", "--set",
                    f"plant.{demand}_max=3", "--set", f"plant.{position}_max=0.3", "--opcua", "127.0.0.1:0")

    async def drive(url):
        async with Client(url) as opc:
            ns, node = await _nodes(opc)
            await node(f"controller.{demand}").write_value(ua.Variant(3.0, ua.VariantType.Double))
            codes = []
            while len(codes) < 100 and (not codes or codes[-1] == "Good"):
                codes.append(await _step_status(opc, 10))
            await node(f"controller.{demand}").write_value(ua.Variant(-3.0, ua.VariantType.Double))
            braking = []
            for _ in range(100):
                braking.append(await _step_status(opc, 10))
                if (await node(f"plant.d{position}").read_value()) <= 0:
                    break
            return codes, braking, await opc.read_values([node(f"plant.{position}"), node(f"plant.d{position}")])

    try:
        codes, braking, (x, dx) = _run(drive(server.opcua))
    finally:
        status, out, err = server.stop()
    assert codes[-1] == "BadOutOfRange" and set(codes[:-1]) == {"Good"} and len(codes) > 10, codes
    assert set(braking) == {"Good"} and dx <= 0 < x <= 0.3, (braking, x, dx)
    assert status == 0 and f"could not stop before the rail end {position}_max" in err, err[-2000:]


def test_the_guards_braking_distance_is_the_held_brakings_and_the_least_one_plus_half_a_cycle():
    """The guard's braking distance against the braking it holds, cycle by cycle with the trolley's exact
    kinematics (x += v T + u T^2 / 2, v += u T, u = -sign(v) min(U, |v| / T)): equal, at rest after it; and within
    the closed-form bounds v^2 / 2U (braking at U throughout) and v^2 / 2U + |v| T / 2."""
    import random

    from crane_fmu.serve.rail_ends import braking_distance

    rng = random.Random(50)
    for _ in range(200):
        v, limit, cycle = rng.uniform(-5, 5), rng.choice((0.5, 3.0, 50.0)), rng.choice((1e-3, 0.01, 0.1))
        x, speed = 0.0, v
        for _ in range(100_000):
            if speed == 0.0:
                break
            u = -math.copysign(min(limit, abs(speed) / cycle), speed)
            x, speed = x + speed * cycle + u * cycle * cycle / 2, speed + u * cycle
            speed = 0.0 if abs(speed) < 1e-12 else speed
        d = braking_distance(v, limit, cycle)
        assert speed == 0.0 and d == pytest.approx(abs(x), rel=1e-9, abs=1e-12), (v, limit, cycle)
        assert v * v / (2 * limit) - 1e-12 <= d <= v * v / (2 * limit) + abs(v) * cycle / 2 + 1e-12


def test_the_lagging_drives_reach_holds_against_the_plant_braked_from_the_worst_states():
    """A drive with a lag tau: the guard's bound (rail_ends.lagged_reach) against the Python plant's own
    general_update braked as the hold brakes it (u = -sign(s) min(U, |s| / T), s = v + a tau, a the plant's drive
    state), from 60 random states (seed 50) with the drive's acceleration at either limit (the worst: +-U) or
    between: the plant, given rail ends 1e-9 m beyond the bound on both sides, never refuses a step (it refuses any
    sub-step past them), and it comes to rest."""
    import random

    from crane_fmu.model import plant
    from crane_fmu.model.component import Discard
    from crane_fmu.serve.rail_ends import lagged_reach

    rng = random.Random(50)
    defaults = {v.name: v.start for v in plant.VARIABLES if v.causality == "parameter"}
    for case in range(60):
        tau, limit, cycle = rng.choice((0.05, 0.1, 0.4)), rng.choice((0.5, 3.0)), rng.choice((0.01, 0.05))
        v = rng.uniform(-3, 3)
        a = rng.choice((-limit, limit, rng.uniform(-limit, limit)))
        farthest, least = lagged_reach(0.0, v, a, tau, limit, cycle)
        config = plant.configure({**defaults, "tau": tau, "u_max": limit, "x_min": least - 1e-9,
                                  "x_max": farthest + 1e-9, "dx0": v})
        state = config.state0[:plant.DRIVE] + (a, a)
        for k in range(int(20 * (tau + abs(v) / limit + cycle) / cycle)):
            s = state[plant.DX] + state[plant.DRIVE] * tau
            u = -math.copysign(min(limit, abs(s) / cycle), s) if s else 0.0
            try:
                state = plant.general_update(config, state, (u, 0.0, 0.0, 0.0), k * cycle, cycle)
            except Discard as exc:
                raise AssertionError((case, tau, limit, cycle, v, a, str(exc))) from None
            state = getattr(state, "state", state)
        assert abs(state[plant.DX]) < 1e-6 and abs(state[plant.DRIVE]) < 1e-3 * limit, (case, state)


@pytest.mark.parametrize("system, demand, position, lag", [("lqr", "u", "x", "tau"), ("lqr3d", "ux", "x", "tau_x"),
                                                           ("lqr3d", "uy", "y", "tau_y")])
def test_lock_step_a_lagging_drive_braked_after_a_refusal_at_a_rail_end_steps_on(fmu_dir, tmp_path, system, demand,
                                                                                 position, lag):
    """As the lock-step test above with the drive lagging by 0.1 s: the demand at its limit towards the rail end at
    0.3 m until a request is refused; the client then brakes and every request is taken until the trolley moves
    back, never past the rail end. On main a lagging drive was not guarded: the trolley ran into the rail end and
    every braking request was refused."""
    server = Server(fmu_dir, tmp_path, "--system", system, "--external", "controller", "--lock-step", "--set",
                    f"plant.{demand}_max=3", "--set", f"plant.{position}_max=0.3", "--set", f"plant.{lag}=0.1",
                    "--opcua", "127.0.0.1:0")

    async def drive(url):
        async with Client(url) as opc:
            ns, node = await _nodes(opc)
            await node(f"controller.{demand}").write_value(ua.Variant(3.0, ua.VariantType.Double))
            codes = []
            while len(codes) < 100 and (not codes or codes[-1] == "Good"):
                codes.append(await _step_status(opc, 10))
            await node(f"controller.{demand}").write_value(ua.Variant(-3.0, ua.VariantType.Double))
            braking, most = [], 0.0
            for _ in range(100):
                braking.append(await _step_status(opc, 10))
                most = max(most, await node(f"plant.{position}").read_value())
                if (await node(f"plant.d{position}").read_value()) <= 0:
                    break
            return codes, braking, most, await node(f"plant.d{position}").read_value()

    try:
        codes, braking, most, dx = _run(drive(server.opcua))
    finally:
        status, out, err = server.stop()
    assert codes[-1] == "BadOutOfRange" and set(codes[:-1]) == {"Good"} and len(codes) > 10, codes
    assert set(braking) == {"Good"} and dx <= 0 < most <= 0.3, (braking, most, dx)
    assert status == 0 and f"could not stop before the rail end {position}_max" in err, err[-2000:]


def test_real_time_a_lagging_drive_driven_at_a_rail_end_is_braked_and_the_run_reaches_its_stop_time(fmu_dir,
                                                                                                  tmp_path):
    """The real-time rail-end test with the drive lagging by tau = 0.1 s: u = 3 written once towards x_max = 0.3 m,
    then nothing. The guard follows the drive's acceleration from the demands, refuses the cycle after which the
    trolley could no longer stop, and holds u braking it; the run ends by itself at its stop time, status 0, the
    trolley never past x_max and nearly at rest at the end. On main the run held at the rail end until Ctrl-C."""
    server = Server(fmu_dir, tmp_path, "--system", "lqr", "--external", "controller", "--period", "0.01",
                    "--watchdog", "30", "--stop-time", "2", "--set", "plant.u_max=3", "--set", "plant.x_max=0.3",
                    "--set", "plant.tau=0.1", "--opcua", "127.0.0.1:0")
    status, out, err = _driven_at_u_max(server)
    assert status == 0 and "finished at t = 2 s" in out, err[-2000:]
    assert "could not stop before the rail end x_max = 0.3 m" in err, err
    served = read_csv(server.out)
    assert all(np.all(np.isfinite(column)) for column in served.values()) and served["time"][-1] == 2
    assert np.max(served["plant.x"]) <= 0.3 and served["plant.x"][-1] > 0.1
    assert abs(served["plant.dx"][-1]) < 1e-3 and set(np.unique(served["controller.u"])) >= {3.0, -3.0}


REAL_TIME_FUZZ_OPERATIONS = 300  # in real time: OPC UA and Modbus interleaved, the same seed as the lock-step fuzz


@pytest.mark.parametrize("lag", ["0", "0.1"])
def test_a_real_time_fuzz_of_both_protocols_never_ends_the_server_nor_holds_it(fmu_dir, tmp_path, lag):
    """300 random requests (seed 50: the same every run), OPC UA and Modbus interleaved, against a real-time server
    (10 ms cycles) with a drive limit of 3 m/s2, rail ends at +-0.3 m and the drive lagging by ``lag`` s: random
    node ids, registers, values (in and out of range, non-finite, of other types), functions, Step calls. After
    every request the server is running; every 50, and at the end, u as both protocols read it lies within +-3 and
    the time has not gone back. Then u = 3 is written (into a rail end, whatever the draws did) and nothing more:
    simulated time must still advance (the guard brakes; nothing holds the run). Ctrl-C ends it with status 0;
    every recorded value is finite, u within its range, the trolley never past a rail end, each time once."""
    import random

    rng = random.Random(FUZZ_SEED)
    server = Server(fmu_dir, tmp_path, "--system", "lqr", "--external", "controller", "--period", "0.01",
                    "--watchdog", "60", "--stop-time", "1000", "--set", "plant.u_max=3", "--set", "plant.x_min=-0.3",
                    "--set", "plant.x_max=0.3", "--set", f"plant.tau={lag}", "--opcua", "127.0.0.1:0",
                    "--modbus", "127.0.0.1:0")
    names, address, modbus = _fuzz_clients(fmu_dir, server)

    async def fuzz(url):
        async with Client(url) as opc:
            ns, node = await _nodes(opc)
            checks = await _fuzz_requests(server, opc, node, modbus, names, address, rng, REAL_TIME_FUZZ_OPERATIONS)
            await node("controller.u").write_value(ua.Variant(3.0, ua.VariantType.Double))
            await asyncio.sleep(1.5)
            first = await node("Time").read_value()
            await asyncio.sleep(1.0)
            return checks, first, await node("Time").read_value()

    try:
        assert modbus.connect()
        checks, first, last = _run(fuzz(server.opcua), timeout=600)
    finally:
        modbus.close()
        status, out, err = server.stop()
    assert last > first + 0.5, (first, last, err[-2000:])  # the run is not held at a rail end
    recorded = _fuzzed_run_held(checks, REAL_TIME_FUZZ_OPERATIONS, server, status, err)
    assert np.all(np.abs(recorded["plant.x"]) <= 0.3)


def test_lock_step_a_reference_written_past_the_rail_end_is_refused_before_the_trolley_cannot_stop(fmu_dir,
                                                                                                   tmp_path):
    """The client is the planner (`--external planner`): it writes a target past the rail end (x_ref = 1e6 m, x_max
    = 2.5 m) and the built-in LQR drives the trolley there at 1 m/s. The request that would end where the LQR's
    2 m/s2 can no longer stop it is refused (BadOutOfRange); with x_ref = 0 written every request is taken again
    and the trolley moves back, never past the rail end. On main the guard watched only a client that writes the
    demand: the trolley ran into the rail end, and every request after it was refused, whatever was written."""
    server = Server(fmu_dir, tmp_path, "--system", "transport", "--external", "planner", "--lock-step", "--set",
                    "plant.x_max=2.5", "--opcua", "127.0.0.1:0")

    async def drive(url):
        async with Client(url) as opc:
            ns, node = await _nodes(opc)
            await node("planner.x_ref").write_value(ua.Variant(1e6, ua.VariantType.Double))
            codes, most = [], 0.0
            while len(codes) < 1000 and (not codes or codes[-1] == "Good"):
                codes.append(await _step_status(opc, 10))
            await node("planner.x_ref").write_value(ua.Variant(0.0, ua.VariantType.Double))
            back = []
            for _ in range(200):
                back.append(await _step_status(opc, 10))
                most = max(most, await node("plant.x").read_value())
                if (await node("plant.dx").read_value()) < 0:
                    break
            return codes, back, most, await node("plant.dx").read_value()

    try:
        codes, back, most, dx = _run(drive(server.opcua))
    finally:
        status, out, err = server.stop()
    assert codes[-1] == "BadOutOfRange" and set(codes[:-1]) == {"Good"} and len(codes) > 100, codes[-3:]
    assert set(back) == {"Good"} and dx < 0 and 2.4 < most <= 2.5, (back[-3:], most, dx)
    assert status == 0 and "could not stop before the rail end x_max = 2.5 m with its drive's 2 m/s2" in err, err


def test_real_time_a_reference_written_past_the_rail_end_leaves_the_run_going_to_its_stop_time(fmu_dir, tmp_path):
    """Real time, the client the planner: x_ref = 3 m written once (x_max = 2.5 m), then nothing. The cycle after
    which the LQR could no longer stop the trolley is refused, the planner's outputs are held at zero (the LQR
    brakes and takes the trolley back), and the run ends by itself at its stop time: status 0, the trolley never
    past x_max. On main the trolley reached the rail end and the run held there until Ctrl-C."""
    server = Server(fmu_dir, tmp_path, "--system", "transport", "--external", "planner", "--period", "0.01",
                    "--watchdog", "30", "--stop-time", "5", "--set", "plant.x_max=2.5", "--opcua", "127.0.0.1:0")
    status, out, err = _driven_at_u_max(server, "planner.x_ref", 3.0)
    assert status == 0 and "finished at t = 5 s" in out, err[-2000:]
    assert "could not stop before the rail end x_max = 2.5 m" in err and "held at zero" in err, err
    served = read_csv(server.out)
    assert 2.4 < np.max(served["plant.x"]) <= 2.5 and served["plant.x"][-1] < 2.4  # braked before the end, back


def test_a_start_from_which_the_trolley_cannot_stop_before_a_rail_end_is_refused_in_one_line(fmu_dir, tmp_path):
    """x0 = 1.9 m at 3 m/s towards x_max = 2 m with a drive of 2 m/s2: braked from the first instant the trolley comes
    to rest at 1.9 + 9/4 = 4.15 m. On main the server started and then refused every step for ever; now it does not
    start: status 2, one line naming the start, the rest point and the rail end, and no result file."""
    out = tmp_path / "serve.csv"
    done = subprocess.run([sys.executable, "-m", "crane_fmu", "serve", "--fmu-dir", str(fmu_dir), "--out", str(out),
                           "--system", "lqr", "--external", "controller", "--lock-step", "--set", "plant.x_max=2",
                           "--set", "plant.u_max=2", "--set", "plant.x0=1.9", "--set", "plant.dx0=3",
                           "--opcua", "127.0.0.1:0"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and done.stderr == (
        "crane-fmu: error: the trolley starts at x = 1.9 m moving at 3 m/s: braked at its drive's 2 m/s2 from the "
        "start it comes to rest at 4.15 m, past the rail end x_max = 2 m; no run can step from there\n"), done.stderr
    assert list(tmp_path.iterdir()) == []


def test_refused_writes_are_said_on_the_log_at_most_once_a_second_and_counted(fmu_dir, tmp_path):
    """The server says on stderr which client write it refused and why, so an operator sees a PLC sending NaN (on
    main a refused write left no line): NaN, then 200 writes out of range as fast as the client goes, then after a
    pause one more. Every refusal is said or counted in the next line said ("N more refused since"), and a client
    that floods is no more than a line a second."""
    import time

    server = Server(fmu_dir, tmp_path, "--system", "lqr", "--external", "controller", "--lock-step", "--set",
                    "plant.u_max=3", "--opcua", "127.0.0.1:0")

    async def flood(url):
        async with Client(url) as opc:
            ns, node = await _nodes(opc)
            codes, begun = [], time.monotonic()
            for value in [math.nan] + [1e9] * 200:
                try:
                    await node("controller.u").write_value(ua.Variant(value, ua.VariantType.Double))
                    codes.append("Good")
                except ua.UaStatusCodeError as exc:
                    codes.append(type(exc).__name__)
            took = time.monotonic() - begun
            await asyncio.sleep(1.1)
            try:
                await node("controller.u").write_value(ua.Variant(math.inf, ua.VariantType.Double))
            except ua.UaStatusCodeError as exc:
                codes.append(type(exc).__name__)
            return codes, took

    try:
        codes, took = _run(flood(server.opcua))
    finally:
        status, out, err = server.stop()
    assert set(codes) == {"BadOutOfRange"} and len(codes) == 202, codes[:3]
    said = [line for line in err.splitlines() if "a client's write refused: " in line]
    assert said[0].endswith("a client's write refused: controller.u must be a finite number, got nan"), err
    assert "controller.u must be a finite number, got inf" in said[-1], said[-1]
    counted = sum(int(m) for m in re.findall(r"\((\d+) more refused since the last such line\)", "\n".join(said)))
    assert len(said) + counted == 202 and len(said) <= took + 3, (said, took)
