"""A PD law driving the crane over OPC UA from a second process, in place of the controller.

Start the crane with its controller left out, in lock-step::

    crane-fmu serve --system lqr --external controller --lock-step --opcua 127.0.0.1:4840

then, in another terminal::

    python examples/opcua_pd_client.py opc.tcp://127.0.0.1:4840 --target 1.0 --seconds 8

Every cycle (10 ms, as a PLC's task might run) the client reads the measured trolley position and
velocity, computes ``u = k_x (x_d - x) - k_v dx`` limited to +-2 m/s2, writes it as the controller's
output ``u`` and calls ``Step`` for one cycle of communication steps. It needs only asyncua
(``pip install asyncua``), not this project.

Before it writes anything it checks which run it reached: the server's ``System`` must be ``--system``
(default lqr) and, given ``--run-id`` (the id the server's first line prints), its ``RunId`` that one; a
run that has ended (``StatusCode`` 4 finished, 5 failed, 6 stopped) is not driven. Otherwise it says so in
one line and exits with status 2, so that a client started for one server never drives another's run.
"""

import argparse
import asyncio
import logging
import math
import sys

from asyncua import Client, ua

ENDED = {4: "finished", 5: "failed", 6: "stopped"}  # the StatusCode of a run that takes no more steps


class WrongRun(Exception):
    """The server serves another run than the one asked for."""


async def identify(node, system, run_id):
    """``(system, run id)`` of the server, checked against ``system`` and ``run_id`` (None: any): WrongRun."""
    served, served_id, code = [await node(name).read_value() for name in ("System", "RunId", "StatusCode")]
    if served != system:
        raise WrongRun(f"the server runs system {served!r} (run {served_id}), not {system!r}")
    if run_id is not None and served_id != run_id.lower():
        raise WrongRun(f"the server's run is {served_id}, not {run_id}")
    if code in ENDED:
        raise WrongRun(f"run {served_id} has {ENDED[code]}")
    return served, served_id


async def drive(url, target, seconds, cycle, k_x=4.0, k_v=3.0, u_max=2.0, system="lqr", run_id=None):
    """Run the PD law for ``seconds`` of simulated time; returns ``(x, largest |theta1| in deg, run id)`` at the
    end."""
    async with Client(url) as client:
        ns = await client.get_namespace_index("urn:crane-fmu")
        node = lambda name: client.get_node(ua.NodeId(name, ns))  # noqa: E731
        _, served_id = await identify(node, system, run_id)
        x, dx, theta1 = node("controller.x"), node("controller.dx"), node("controller.theta1")
        u, step = node("controller.u"), node("Step")
        system = await step.get_parent()
        t = await node("Time").read_value()
        end = t + seconds
        h = await system.call_method(step, ua.Variant(1, ua.VariantType.UInt32)) - t  # one step: its size
        steps, t, swing = max(1, round(cycle / h)), t + h, 0.0
        while t < end - h / 2:
            position, velocity, angle = await client.read_values([x, dx, theta1])
            swing = max(swing, abs(angle))
            demand = max(-u_max, min(u_max, k_x * (target - position) - k_v * velocity))
            await u.write_value(ua.Variant(demand, ua.VariantType.Double))
            t = await system.call_method(step, ua.Variant(min(steps, round((end - t) / h)), ua.VariantType.UInt32))
        position = await x.read_value()
        return position, math.degrees(swing), served_id


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("url", help="the server's endpoint, e.g. opc.tcp://127.0.0.1:4840")
    parser.add_argument("--target", type=float, default=1.0, help="target trolley position x_d [m] (default 1)")
    parser.add_argument("--seconds", type=float, default=8.0, help="simulated time to drive [s] (default 8)")
    parser.add_argument("--cycle", type=float, default=0.01, help="the law's cycle [s] (default 0.01)")
    parser.add_argument("--system", default="lqr", help="the system the server must run (default lqr)")
    parser.add_argument("--run-id", help="the run the server must serve (its first line prints it)")
    args = parser.parse_args()
    logging.getLogger("asyncua").setLevel(logging.ERROR)  # not its notes on the session's timeout
    try:
        x, swing, run_id = asyncio.run(drive(args.url, args.target, args.seconds, args.cycle, system=args.system,
                                             run_id=args.run_id))
    except WrongRun as exc:
        print(f"opcua_pd_client: {exc}; nothing written", file=sys.stderr)
        sys.exit(2)
    print(f"run {run_id}: x = {x:.4f} m after {args.seconds:g} s (target {args.target:g} m); largest hook swing "
          f"{swing:.2f} deg")


if __name__ == "__main__":
    main()
