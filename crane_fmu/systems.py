"""The built-in systems by name, and where a command finds the system it is given.

A system is data (``crane_fmu.cosim.System``): instances named by component
model identifiers, connections matched by signal name, parameter values, times.
Every command takes a system by name or as an SSP file; nothing else knows
which instances exist.
"""

import contextlib

from crane_fmu import components
from crane_fmu.cosim.connections import Connection
from crane_fmu.cosim.system import System, read_fmu
from crane_fmu.registry import Registry

_SYSTEMS = Registry("system", lambda s: s.name, " (or an .ssp/.ssd file)")
register, unregister, get, registered = _SYSTEMS.register, _SYSTEMS.unregister, _SYSTEMS.get, _SYSTEMS.registered


@contextlib.contextmanager
def open_system(name_or_file):
    """Yield the system of a registered name or of an SSP file (``.ssp`` or ``.ssd``)."""
    text = str(name_or_file)
    if text.endswith((".ssp", ".ssd")):
        from crane_fmu.cosim.ssp import load_system

        with load_system(text) as system:
            yield system
    else:
        yield get(text)


def resolve(system, fmu_dir):
    """``system.resolve(fmu_dir)``, with a hint where a built FMU is missing."""
    for path in system.fmus(fmu_dir).values():
        if not path.is_file():
            raise ValueError(f"{path} not found: build the FMUs first (crane-fmu build)")
    return system.resolve(fmu_dir)


def at_step(system, fmu_dir, step):
    """``system`` with ``h`` set to ``step`` on every instance whose component has that parameter, unless set.

    A component's parameter ``h`` is the communication step it is designed for
    (the LQR's discrete design, the speed guards); a run at another step gets a
    design for its own step.
    """
    overrides = {}
    for name, path in system.fmus(fmu_dir).items():
        component = components.find(read_fmu(path).coSimulation.modelIdentifier)
        if component and "h" in component.names("parameter") and "h" not in system.parameters.get(name, {}):
            overrides[name] = {"h": step}
    return system.with_parameters(overrides)


def check_parameters(system, fmu_dir):
    """Apply each instance's component rules (by model identifier, never by instance name).

    Raises
    ------
    ValueError
        ``"plant: l1 must be > 0 and finite, got -1.0"``.
    """
    for name, path in system.fmus(fmu_dir).items():
        identifier = read_fmu(path).coSimulation.modelIdentifier
        try:
            components.check_parameters(identifier, system.parameters.get(name, {}))
        except ValueError as exc:
            raise ValueError(f"{name}: {exc}") from None


register(System("paper", {"plant": "CranePlant", "controller": "BacksteppingController"},
                description="Section V: the plant and the paper's backstepping controller (eq 21, derived b3), "
                            "theta1(0) = 10 deg"))
register(System("free", {"plant": "CranePlant"}, description="the plant alone, u = 0: free swing from 10 deg"))
register(System("lqr", {"plant": "CranePlant", "controller": "LqrController"},
                description="Section V regulation from theta1(0) = 10 deg by the discrete LQR, |u| <= 2 m/s2, "
                            "|v| <= 1 m/s"))
register(System("energy", {"plant": "CranePlant", "controller": "EnergyController"},
                description="Section V regulation from theta1(0) = 10 deg by the energy-coupling law (proof in "
                            "crane_fmu/model/energy.py)"))
register(System("transport", {"plant": "CranePlant", "planner": "TrajectoryPlanner", "controller": "LqrController"},
                parameters={"plant": {"theta1_0": 0.0}, "planner": {"x_d": 2.0}}, stop_time=10.0,
                description="a 2 m move from rest: ZV-shaped reference (planner.x_d) tracked by the LQR"))
register(System("hoist-transport",
                {"plant": "CranePlant", "planner": "TrajectoryPlanner", "hoist": "TrajectoryPlanner",
                 "controller": "LqrController"},
                connections=tuple(Connection("planner", name, "controller", name) for name in (
                    "x_ref", "dx_ref", "ddx_ref", "theta1_ref", "dtheta1_ref", "theta2_ref", "dtheta2_ref"))
                + (Connection("hoist", "ddx_ref", "plant", "hoist"),),
                parameters={"plant": {"theta1_0": 0.0, "l1": 2.0, "l1_min": 1.0, "l1_max": 2.0},
                            "planner": {"x_d": 2.0, "l1": 1.5, "shaper": "zvd"},
                            "hoist": {"x0": 2.0, "x_d": 1.0, "shaper": "none", "u_max": 0.5, "v_max": 0.5},
                            "controller": {"l1": 2.0, "l1_low": 1.0, "l1_high": 2.0}},
                stop_time=12.0,
                description="a 2 m move while the hoist lifts the load from l1 = 2 m to 1 m; the LQR's gains "
                            "follow the measured cable length"))

# What a crane measures: the sensor sees the plant's true x, theta1, theta2 and outputs x_meas, theta1_meas,
# theta2_meas (to the estimator by name); the estimator's x, ..., dtheta2 feed the controller (written out: the
# plant has outputs of those names too); u and l1_now connect by name.
MEASURING = tuple(Connection("plant", name, "sensor", name) for name in ("x", "theta1", "theta2")) + tuple(
    Connection("estimator", name, "controller", name) for name in ("x", "dx", "theta1", "dtheta1", "theta2",
                                                                   "dtheta2"))
register(System("lqg", {"plant": "CranePlant", "controller": "LqrController", "sensor": "CraneSensor",
                        "estimator": "StateEstimator"},
                connections=MEASURING, parameters={"plant": {"u_max": 2.0, "v_max": 1.0}},
                description="Section V regulation from theta1(0) = 10 deg with only x and theta1 measured (1 mm, "
                            "0.1 deg noise, one step late): a Kalman filter in front of the LQR, |u| <= 2 m/s2, "
                            "|v| <= 1 m/s"))
register(System("lqg-transport", {"plant": "CranePlant", "planner": "TrajectoryPlanner", "controller": "LqrController",
                                  "sensor": "CraneSensor", "estimator": "StateEstimator"},
                connections=MEASURING,
                parameters={"plant": {"theta1_0": 0.0, "u_max": 2.0, "v_max": 1.0}, "planner": {"x_d": 2.0}},
                stop_time=10.0,
                description="the 2 m move of transport with only x and theta1 measured: a Kalman filter in front of "
                            "the LQR"))
register(System("hard-hit", {"plant": "CranePlant", "controller": "HardHitController"},
                parameters={"plant": {"theta1_0": 1.0471975511965976, "u_max": 2.0, "v_max": 1.0}},
                description="a hard hit: regulation from theta1(0) = 60 deg by LQR gains scheduled on the swing "
                            "energy, |u| <= 2 m/s2, |v| <= 1 m/s"))
register(System("mpc", {"plant": "CranePlant", "controller": "MpcController"},
                parameters={"plant": {"u_max": 2.0, "v_max": 1.0}},
                description="Section V regulation from theta1(0) = 10 deg by the constrained MPC: the shortest move "
                            "to rest within |u| <= 2 m/s2, |v| <= 1 m/s, tracked by a QP every 50 ms"))
register(System("mpc-transport", {"plant": "CranePlant", "controller": "MpcController"},
                parameters={"plant": {"theta1_0": 0.0, "u_max": 2.0, "v_max": 1.0}, "controller": {"x_d": 2.0}},
                stop_time=10.0,
                description="a 2 m move from rest by the constrained MPC: its own shortest move within the drive's "
                            "limits, tracked by a QP every 50 ms"))
