"""The Modbus TCP face of a :class:`~crane_fmu.cosim.realtime.Runner` (pymodbus, an optional extra).

The register map is generated from the runner's served variables (:func:`register_map`; printed by
``crane-fmu serve --print-map``). Every value is an IEEE 754 number in consecutive registers, the most
significant word first and each word big-endian (byte order ABCD, the Modbus convention); the variables
are float32 (two registers).

Input registers (function 4, read-only):

- 0-3: the simulated time [s], float64; 4-5: steps taken, uint32; 6: the status code
  (:data:`~crane_fmu.cosim.realtime.STATUS_CODES`); 7: reserved (0);
- which run this is: 8-11: the run id, uint64 (OPC UA's ``RunId``, in hex); 12-15: the start time, Unix time [s]
  UTC, float64; 16-31: the system's name, ASCII, two characters a register (the first in the high byte),
  padded with zeros (32 characters; a longer name is cut);
- from 32: every variable that is not writable (outputs, the external instance's inputs, parameters).

Holding registers (function 3 to read, 16 to write; 6 only for the step register):

- 0: the step register: writing ``n`` (1-65535) takes n communication steps in lock-step; the reply comes
  when they are taken; reads 0;
- 1: reserved (reads 0; a write is refused);
- from 2: the writable variables (the external instance's outputs), each written whole: both registers
  in one request.

A request outside the map, a write that splits a float32 or touches a read-only register, is answered with
exception 02 (illegal data address); a non-finite value, a step count of 0, a step in real time or past the
stop time with 03 (illegal data value); any other function (coils, discrete inputs, function 23) with 01. Any
unit id is answered. Every client is served: writes by any (the last wins), steps one after another in the
order they arrive.
"""

import asyncio
import logging
import math
import socket
import struct
from collections import namedtuple

from crane_fmu.cosim.realtime import STATUS_CODES

from . import cannot_listen

Register = namedtuple("Register", "table address name type unit access description")
Register.__doc__ = "One entry of the map: ``table`` is ``input`` or ``holding``; ``address`` of its first register."

FIRST_INPUT = 32  # the first variable's input register
NAME_CHARACTERS = 32  # the system's name in registers 16-31
FIRST_HOLDING = 2  # the first writable variable's holding register
STEP_REGISTER = 0
HEADER = (Register("input", 0, "Time", "float64", "s", "read", "simulated time"),
          Register("input", 4, "Steps", "uint32", "1", "read", "communication steps taken"),
          Register("input", 6, "Status", "uint16", "1", "read",
                   "status: " + ", ".join(f"{code} {name}" for name, code in STATUS_CODES.items())),
          Register("input", 8, "RunId", "uint64", "1", "read", "run id, new for every run"),
          Register("input", 12, "StartTime", "float64", "s", "read", "when the run started (Unix time, UTC)"),
          Register("input", 16, "System", "char[32]", "1", "read", "the system's name (ASCII, zero-padded)"),
          Register("holding", STEP_REGISTER, "Step", "uint16", "1", "write",
                   "lock-step: write n to take n communication steps; reads 0"))


def register_map(variables):
    """The registers of the served ``variables`` after the :data:`HEADER`, in the variables' order."""
    entries, next_input, next_holding = list(HEADER), FIRST_INPUT, FIRST_HOLDING
    for v in variables:
        if v.writable:
            entries.append(Register("holding", next_holding, v.name, "float32", v.unit, "read/write", v.description))
            next_holding += 2
        else:
            entries.append(Register("input", next_input, v.name, "float32", v.unit, "read", v.description))
            next_input += 2
    return entries


def markdown(entries):
    """The map as a Markdown table (the docs' page prints the one of a built-in system)."""
    lines = ["| table | registers | name | type | unit | access | description |", "|---|---|---|---|---|---|---|"]
    sizes = {"float64": 4, "uint32": 2, "float32": 2, "uint16": 1, "uint64": 4, "char[32]": 16}
    for r in sorted(entries, key=lambda r: (r.table != "input", r.address)):
        span = f"{r.address}" if sizes[r.type] == 1 else f"{r.address}-{r.address + sizes[r.type] - 1}"
        description = r.description.replace("|", "&#124;")  # a bar would end the cell
        lines.append(f"| {r.table} | {span} | `{r.name}` | {r.type} | {r.unit} | {r.access} | {description} |")
    return "\n".join(lines)


def float32_words(value):
    """The two registers of ``value`` as float32, high word first (a finite value beyond float32 is +-inf)."""
    try:
        packed = struct.pack(">f", value)
    except OverflowError:
        packed = struct.pack(">f", math.copysign(math.inf, value))
    return list(struct.unpack(">HH", packed))


def identity_words(run_id, started, system):
    """Registers 8-31: the run id (uint64), the start time (float64) and the system's name (ASCII)."""
    name = system.encode("ascii", "replace")[:NAME_CHARACTERS].ljust(NAME_CHARACTERS, b"\0")
    return list(struct.unpack(">4H4H16H", struct.pack(">Qd", run_id, started) + name))


def words_float32(high, low):
    """The float32 of two registers, high word first."""
    return struct.unpack(">f", struct.pack(">HH", high, low))[0]


class ModbusServer:
    """Serves ``runner`` over Modbus TCP at ``host:port`` (port 0: one the OS picks); call in the network loop."""

    def __init__(self, runner, host, port):
        self.runner, self.host, self.port = runner, host, port
        self.entries = register_map(runner.variables)
        self._inputs = [i for i, v in enumerate(runner.variables) if not v.writable]
        self._holding = [i for i, v in enumerate(runner.variables) if v.writable]
        self.server = None
        self._identity = identity_words(runner.run_id, runner.started or 0.0, runner.name)

    async def start(self):
        """Listen; returns ``host:port`` (with the port the OS chose)."""
        from pymodbus.server import ModbusTcpServer  # optional: the serve extra
        from pymodbus.simulator import DataType, SimData, SimDevice

        n_input = FIRST_INPUT + 2 * len(self._inputs)
        n_holding = FIRST_HOLDING + 2 * len(self._holding)
        unused = SimData(0, values=False, datatype=DataType.BITS, readonly=True)  # no coils or discrete inputs
        blocks = ([unused], [unused],
                  [SimData(0, count=n_holding, datatype=DataType.REGISTERS)],
                  [SimData(0, count=n_input, datatype=DataType.REGISTERS, readonly=True)])
        device = SimDevice(0, simdata=blocks, action=self._action)
        logging.getLogger("pymodbus").setLevel(logging.CRITICAL)  # what goes wrong is said here, in one line
        if self.port:  # pymodbus says only that it could not listen: ask the OS why
            try:
                with socket.create_server((self.host, self.port)):
                    pass
            except OSError as exc:
                raise cannot_listen("--modbus", self.host, self.port, exc) from None
        self.server = ModbusTcpServer(device, address=(self.host, self.port))
        try:
            await self.server.serve_forever(background=True)
        except RuntimeError as exc:
            raise cannot_listen("--modbus", self.host, self.port, exc) from None
        self.port = self.server.transport.sockets[0].getsockname()[1]
        return f"{self.host}:{self.port}"

    async def stop(self):
        if self.server is not None:
            await self.server.shutdown()

    async def _action(self, function, start, address, count, registers, written):
        """Every request: fill the registers read from the latest snapshot; check and carry out writes."""
        from pymodbus.constants import ExcCodes  # optional: the serve extra

        if function not in (3, 4, 6, 16):  # coils, discrete inputs, the rarer register functions
            return ExcCodes.ILLEGAL_FUNCTION
        if function == 4:
            self._fill_inputs(registers)
            return None
        if written is None:  # a read of holding registers
            self._fill_holding(registers)
            return None
        first, last = address, address + len(written)  # the registers written: [first, last)
        if first == STEP_REGISTER and last == STEP_REGISTER + 1:
            return await self._step(written[0], ExcCodes)
        if first < FIRST_HOLDING or (first - FIRST_HOLDING) % 2 or (last - FIRST_HOLDING) % 2:
            return ExcCodes.ILLEGAL_ADDRESS  # the step register with others, the reserved one, or half a float
        values = {}
        for position in range(first, last, 2):
            i = self._holding[(position - FIRST_HOLDING) // 2]
            values[self.runner.variables[i].name] = words_float32(*written[position - first:position - first + 2])
        try:
            self.runner.write(values)
        except ValueError:
            return ExcCodes.ILLEGAL_VALUE
        return None

    async def _step(self, n, codes):
        try:
            await asyncio.wrap_future(self.runner.request_steps(n))
        except ValueError:
            return codes.ILLEGAL_VALUE
        return None

    def _fill_inputs(self, registers):
        snapshot = self.runner.snapshot()
        header = (list(struct.unpack(">HHHH", struct.pack(">d", snapshot.time)))
                  + list(struct.unpack(">HH", struct.pack(">I", snapshot.steps % 2**32))) + [snapshot.code, 0]
                  + self._identity)
        words = header + [w for i in self._inputs for w in float32_words(snapshot.values[i])]
        registers[:len(words)] = words

    def _fill_holding(self, registers):
        snapshot = self.runner.snapshot()
        words = [0, 0] + [w for i in self._holding for w in float32_words(snapshot.values[i])]
        registers[:len(words)] = words
