"""A PD law driving the crane over OPC UA from a second process, in place of the controller.

Start the crane with its controller left out, in lock-step::

    crane-fmu serve --system lqr --external controller --lock-step --opcua 127.0.0.1:4840

then, in another terminal::

    python examples/opcua_pd_client.py opc.tcp://127.0.0.1:4840 --target 1.0 --seconds 8

Every cycle (10 ms, as a PLC's task might run) the client reads the measured trolley position and
velocity, computes ``u = k_x (x_d - x) - k_v dx`` limited to +-2 m/s2, writes it as the controller's
output ``u`` and calls ``Step`` for one cycle of communication steps. It needs only asyncua
(``pip install asyncua``), not this project.
"""

import argparse
import asyncio
import math

from asyncua import Client, ua


async def drive(url, target, seconds, cycle, k_x=4.0, k_v=3.0, u_max=2.0):
    """Run the PD law for ``seconds`` of simulated time; returns ``(x, largest |theta1| in deg)`` at the end."""
    async with Client(url) as client:
        ns = await client.get_namespace_index("urn:crane-fmu")
        node = lambda name: client.get_node(ua.NodeId(name, ns))  # noqa: E731
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
        return position, math.degrees(swing)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("url", help="the server's endpoint, e.g. opc.tcp://127.0.0.1:4840")
    parser.add_argument("--target", type=float, default=1.0, help="target trolley position x_d [m] (default 1)")
    parser.add_argument("--seconds", type=float, default=8.0, help="simulated time to drive [s] (default 8)")
    parser.add_argument("--cycle", type=float, default=0.01, help="the law's cycle [s] (default 0.01)")
    args = parser.parse_args()
    x, swing = asyncio.run(drive(args.url, args.target, args.seconds, args.cycle))
    print(f"x = {x:.4f} m after {args.seconds:g} s (target {args.target:g} m); largest hook swing {swing:.2f} deg")


if __name__ == "__main__":
    main()
