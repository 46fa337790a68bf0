"""The OPC UA face of a :class:`~crane_fmu.cosim.realtime.Runner` (asyncua, an optional extra: LGPL-3.0).

Namespace ``urn:crane-fmu``; under ``Objects``, one object named after the system holds:

- a Double variable per served variable, browse name and string NodeId exactly ``instance.variable``
  (``ns=<urn:crane-fmu>;s=plant.x``), its SI unit in the description (``trolley position [m]``);
  read-only, except the external instance's outputs (and, with ``--writable``, the tunable parameters);
- ``Time`` (Double, the simulated time [s]), ``StatusCode`` (UInt16, :data:`~crane_fmu.cosim.realtime.STATUS_CODES`:
  1 waiting, 2 running, 3 holding, 4 finished, 5 failed, 6 stopped) and beside it ``Status`` (String, the line
  that says more);
- which run this is: ``System`` (String, the system's name), ``RunId`` (String, 16 hex digits, new for every
  run: the Modbus registers' number) and ``StartTime`` (DateTime, when the run started, UTC);
- the method ``Step(n)`` (UInt32; ``Step()``: one step): in lock-step, takes ``n`` communication steps and
  returns the new time; a Bad status code otherwise (``BadInvalidArgument``: n is not a whole number from 1 to
  65535; ``BadInvalidState``: the run is in real time, has ended, the steps would pass the stop time, or it
  was stopped on the way; ``BadOutOfRange``: an FMU refused a step, which was rolled back, the run going on).

A write of a non-finite number or one outside the variable's range (its description gives it: the plant's
drive limit, :mod:`crane_fmu.cosim.write_ranges`) is refused (``BadOutOfRange``, the whole write request), of
another type than Double too (``BadTypeMismatch``), to a read-only node too (``BadUserAccessDenied``).
Anonymous access without encryption; logging in as ``admin`` grants nothing more. Every client is served:
reads by all, writes by any (the last write wins), Step calls one after another in the order they arrive.
"""

import asyncio
import logging
import math
from datetime import datetime, timezone

from asyncua import Server, ua
from asyncua.common.callback import CallbackType

from crane_fmu.cosim.realtime import MAX_STEPS, StepRefused

from . import cannot_listen

NAMESPACE = "urn:crane-fmu"


class OpcUaServer:
    """Serves ``runner`` at ``opc.tcp://host:port`` (port 0: one the OS picks); call in the network loop.

    Parameters
    ----------
    runner : Runner
    host : str
    port : int
    system : str
        The name of the object that holds the variables.
    """

    def __init__(self, runner, host, port, system):
        self.runner, self.host, self.port, self.system = runner, host, port, system
        self.server = None
        self._latest, self._pending = None, False

    async def start(self):
        """Build the address space and listen; returns the endpoint URL (with the port the OS chose)."""
        for name in ("asyncua", "asyncua.server.address_space", "asyncua.server.uaprocessor"):
            logging.getLogger(name).setLevel(logging.CRITICAL)  # refused requests are answered, not logged
        server = self.server = Server()
        await server.init()
        server.set_endpoint(f"opc.tcp://{_url_host(self.host)}:{self.port}")
        server.set_server_name("crane-fmu serve")
        server.set_security_policy([ua.SecurityPolicyType.NoSecurity])
        server.allow_remote_admin(False)
        idx = await server.register_namespace(NAMESPACE)
        folder = await server.nodes.objects.add_object(ua.NodeId(self.system, idx), ua.QualifiedName(self.system, idx))
        snapshot = self._written = self.runner.snapshot()  # the nodes start with its values
        self.nodes, self.writable = [], {}
        for v, value in zip(self.runner.variables, snapshot.values):
            node = await folder.add_variable(ua.NodeId(v.name, idx), ua.QualifiedName(v.name, idx),
                                             ua.Variant(value, ua.VariantType.Double))
            await node.write_attribute(ua.AttributeIds.Description, ua.DataValue(ua.Variant(
                ua.LocalizedText(_description(v, self.runner.ranges.get(v.name))), ua.VariantType.LocalizedText)))
            if v.writable:
                await node.set_writable()
                server.iserver.aspace.set_attribute_value_setter(node.nodeid, ua.AttributeIds.Value,
                                                                 self._checked_setter(v.name))
                self.writable[node.nodeid] = v.name
            self.nodes.append(node.nodeid)
        self.time_node = (await folder.add_variable(ua.NodeId("Time", idx), ua.QualifiedName("Time", idx),
                                                    ua.Variant(snapshot.time, ua.VariantType.Double))).nodeid
        self.status_node = (await folder.add_variable(ua.NodeId("Status", idx), ua.QualifiedName("Status", idx),
                                                      ua.Variant(snapshot.status, ua.VariantType.String))).nodeid
        self.code_node = (await folder.add_variable(ua.NodeId("StatusCode", idx), ua.QualifiedName("StatusCode", idx),
                                                    ua.Variant(snapshot.code, ua.VariantType.UInt16))).nodeid
        started = datetime.fromtimestamp(self.runner.started, timezone.utc)
        for name, value, kind in (("System", self.system, ua.VariantType.String),
                                  ("RunId", f"{self.runner.run_id:016x}", ua.VariantType.String),
                                  ("StartTime", started, ua.VariantType.DateTime)):
            await folder.add_variable(ua.NodeId(name, idx), ua.QualifiedName(name, idx), ua.Variant(value, kind))
        steps = ua.Argument(Name="n", DataType=ua.NodeId(ua.ObjectIds.UInt32), ValueRank=-1,
                            Description=ua.LocalizedText("communication steps to take"))
        time = ua.Argument(Name="time", DataType=ua.NodeId(ua.ObjectIds.Double), ValueRank=-1,
                           Description=ua.LocalizedText("the simulated time after them [s]"))
        await folder.add_method(ua.NodeId("Step", idx), ua.QualifiedName("Step", idx), self._step, [steps], [time])
        server.subscribe_server_callback(CallbackType.PostWrite, self._client_wrote)
        try:
            await server.start()
        except OSError as exc:
            raise cannot_listen("--opcua", self.host, self.port, exc) from None
        self.port = server.bserver.port
        self._loop = asyncio.get_running_loop()
        self.runner.listeners.append(self.publish)
        return f"opc.tcp://{_url_host(self.host)}:{self.port}"

    async def stop(self):
        if self.server is not None:
            await self.server.stop()

    # --- the runner's snapshots into the nodes ---

    def publish(self, snapshot):
        """From the runner's thread: serve ``snapshot`` (only the latest one if the loop is behind)."""
        self._latest = snapshot
        if not self._pending:
            self._pending = True
            self._loop.call_soon_threadsafe(lambda: asyncio.ensure_future(self._write_latest()))

    async def _write_latest(self):
        self._pending = False
        await self._write(self._latest)

    async def _write(self, snapshot):
        """Write the values of ``snapshot`` that changed since the last one written into their nodes (a node a
        client wrote keeps that value until the value in effect changes)."""
        if snapshot is self._written:
            return
        now = datetime.now(timezone.utc)
        write = self.server.write_attribute_value
        for nodeid, value, before in zip(self.nodes, snapshot.values, self._written.values):
            if value != before:
                await write(nodeid, ua.DataValue(ua.Variant(value, ua.VariantType.Double), SourceTimestamp=now,
                                                 ServerTimestamp=now))
        self._written = snapshot
        await write(self.time_node, ua.DataValue(ua.Variant(snapshot.time, ua.VariantType.Double),
                                                 SourceTimestamp=now, ServerTimestamp=now))
        await write(self.status_node, ua.DataValue(ua.Variant(snapshot.status, ua.VariantType.String),
                                                   SourceTimestamp=now, ServerTimestamp=now))
        await write(self.code_node, ua.DataValue(ua.Variant(snapshot.code, ua.VariantType.UInt16),
                                                 SourceTimestamp=now, ServerTimestamp=now))

    # --- what clients do ---

    async def _client_wrote(self, event, _dispatcher):
        """After a client's write: the values of writable nodes that were accepted go to the runner."""
        if not event.is_external:  # the server's own writes
            return
        values = {}
        for item, status in zip(event.request_params.NodesToWrite, event.response_params):
            name = self.writable.get(item.NodeId)
            if name and item.AttributeId == ua.AttributeIds.Value and status.is_good():
                values[name] = item.Value.Value.Value
        if values:
            self.runner.write(values)

    def _checked_setter(self, name):
        """The setter of the writable node of ``name``: a Double the runner accepts (:meth:`Runner.check`: finite,
        within its range), else the write is refused (BadOutOfRange)."""
        def setter(node, attribute, value):
            number = value.Value.Value if value.Value is not None else None
            if not isinstance(number, float):
                self.runner.refused(f"{name} takes a Double, got {number!r}")
                raise ua.uaerrors.BadOutOfRange()
            try:
                self.runner.check(name, number)
            except ValueError:
                raise ua.uaerrors.BadOutOfRange() from None
            node.attributes[attribute].value = value

        return setter

    async def _step(self, _parent, *arguments):
        """``Step(n)``, ``Step()`` one step: the new time, or a Bad status code."""
        if len(arguments) > 1:
            return ua.StatusCode(ua.StatusCodes.BadTooManyArguments)
        n = arguments[0] if arguments else 1
        count = n.Value if isinstance(n, ua.Variant) else n
        if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= MAX_STEPS:
            return ua.StatusCode(ua.StatusCodes.BadInvalidArgument)
        try:
            time = await asyncio.wrap_future(self.runner.request_steps(count))
        except StepRefused:
            await self._write(self.runner.snapshot())
            return ua.StatusCode(ua.StatusCodes.BadOutOfRange)
        except ValueError:
            await self._write(self.runner.snapshot())
            return ua.StatusCode(ua.StatusCodes.BadInvalidState)
        await self._write(self.runner.snapshot())  # the client reads the new values after the reply
        return [ua.Variant(time, ua.VariantType.Double)]


def _description(v, limits=None):
    """``trolley position [m]``; of a writable variable with a range: ``...; written within [-2, 2] [m/s2]``."""
    text = v.description.rstrip(".") if v.description else v.name
    if limits is not None and any(map(math.isfinite, limits)):
        text += f"; written within [{limits[0]:g}, {limits[1]:g}]"
    return f"{text} [{v.unit}]"


def _url_host(host):
    return f"[{host}]" if ":" in host else host
