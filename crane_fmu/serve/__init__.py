"""Network faces of a real-time or lock-step run: OPC UA (:mod:`.opcua`) and Modbus TCP (:mod:`.modbus`).

They are adapters around a :class:`~crane_fmu.cosim.realtime.Runner`, as observers and input sources are
around the master: they read its snapshots and pass on what clients write and ask. Both run on one asyncio
loop in a background thread (:class:`Network`); the runner keeps the FMUs on its own thread. asyncua and
pymodbus are the optional extra ``serve``; nothing else in the project imports this package.
"""

import asyncio
import ipaddress
import threading

LOOPBACK = "127.0.0.1"


def parse_endpoint(text, option):
    """``(host, port)`` of ``HOST:PORT``, ``:PORT`` or ``PORT`` (host 127.0.0.1); port 0: the OS picks one. For
    ``--opcua`` also the URL the server's first line prints, ``opc.tcp://HOST:PORT``.

    ValueError (one line) naming the option and the rule.
    """
    scheme, slashes, rest = text.partition("://")
    if slashes and option == "--opcua" and scheme == "opc.tcp" and "/" not in rest.rstrip("/"):
        text = rest.rstrip("/")
    host, colon, port = text.rpartition(":")
    if not colon:
        host, port = "", text
    host = host.strip("[]") or LOOPBACK
    if "/" in host or not port.isdigit() or not 0 <= int(port) <= 65535:
        raise ValueError(f"{option} {text!r}: expected HOST:PORT with a port from 0 to 65535 (0: one the OS picks), "
                         f"e.g. 127.0.0.1:4840")
    return host, int(port)


def cannot_listen(protocol, host, port, error):
    """The one-line OSError of a server that cannot listen at ``host:port`` (address in use, not this
    machine's, ...)."""
    text = getattr(error, "strerror", None) or str(error)
    reason = text.rpartition("): ")[2].split(" (while")[0] or text
    return OSError(f"{protocol} {host}:{port}: cannot listen ({reason})")


def is_loopback(host):
    """Whether ``host`` (an address or ``localhost``) reaches only this machine."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


class Network:
    """One asyncio loop in a daemon thread that runs the protocol servers.

    :meth:`start` starts servers (objects with async ``start() -> endpoint`` and ``stop()``) and returns their
    endpoints; :meth:`stop` stops them and the loop.
    """

    def __init__(self):
        self.loop = asyncio.new_event_loop()
        self.servers = []
        self._thread = threading.Thread(target=self.loop.run_forever, name="crane-fmu network", daemon=True)
        self._thread.start()

    def run(self, coroutine, timeout=None):
        """Run ``coroutine`` on the loop and wait for its result."""
        return asyncio.run_coroutine_threadsafe(coroutine, self.loop).result(timeout)

    def start(self, servers, timeout=30.0):
        """Start ``servers`` one after another; their endpoints. The exception of a server that fails to start
        propagates (:meth:`stop` then stops those started before it)."""
        endpoints = []
        for server in servers:
            endpoints.append(self.run(server.start(), timeout))
            self.servers.append(server)
        return endpoints

    def stop(self, timeout=10.0):
        """Stop the servers (their connections close) and the loop."""
        for server in reversed(self.servers):
            try:
                self.run(server.stop(), timeout)
            except Exception:  # a server that cannot close cleanly still must not keep the process alive
                pass
        self.servers = []
        self.loop.call_soon_threadsafe(self.loop.stop)
        self._thread.join(timeout)
