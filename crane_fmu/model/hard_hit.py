"""LQR gains scheduled on the swing energy, for a crane that may be hit hard: the HardHitController component.

The LQR (:mod:`.lqr`) saturates the drive from large swings, and its region of
attraction has a hole (it fails from 45 deg, converges from 50-60 deg). This law
blends two discrete LQR designs of :func:`.lqr.design` by the swing energy of
eq (E1) (:mod:`.energy`), computed from the measured state with the controller's model:

    u = ddx_ref - K(w) (s - s_ref),   K(w) = (1 - w) K_near + w K_far,
    w = clamp((E - E_near) / (E_far - E_near), 0, 1),

where ``E_near`` and ``E_far`` are the energies of both angles held at ``theta_near``
and ``theta_far``. Near rest (``w = 0``) it is the LQR with the LQR's default weights;
far out it uses a gentler design (input weight ``r_far``, position weight ``q_x_far``)
that saturates the drive less and lets the trolley travel. The swing energy is
zero at rest, so a move from rest starts on the near design.

What is claimed, and how it is known: it converges from every initial hook angle
0-60 deg in 5-deg steps (payload in line, at rest) under |u| <= 2 m/s2 and
|v| <= 1 m/s, on the Section V crane, in simulation (``crane-fmu sweep
builtin:hard-hits``; a test runs the FMUs). Nothing is proven: the blend of two
stabilising gains is not in general stabilising, and ``theta_near``, ``theta_far``,
``r_far`` and ``q_x_far`` were chosen by simulating that grid.
"""

import math
from collections import namedtuple

from . import limits, linalg
from .component import Component
from .lqr import DEFAULT_WEIGHTS, REFERENCE_INPUTS, WEIGHTS, design
from .parameters import PLANT_RULES, plant_parameters
from .rules import check, finite, non_negative, positive, rule
from .tables import CRANE_MODEL, MEASURED_STATE, controller_model, output, parameter, positions

Config = namedtuple("Config", "near far e_near e_far mu m2 l1 l2 g x_d u_max v_max h")


def swing_energy(c, s):
    """Eq (E1): kinetic energy of hook and payload relative to the trolley plus their potential energy [J]."""
    _, _, a, da, b, db = s
    kinetic = 0.5 * c.mu * (c.l1 * da) ** 2 + 0.5 * c.m2 * ((c.l2 * db) ** 2 + 2.0 * c.l1 * c.l2 * da * db
                                                             * math.cos(a - b))
    return kinetic + c.g * (c.mu * c.l1 * (1.0 - math.cos(a)) + c.m2 * c.l2 * (1.0 - math.cos(b)))


def configure(values):
    """Validated parameters and the two designs."""
    check(RULES, values)
    p = plant_parameters(values)
    near, far = values["theta_near"], values["theta_far"]
    u_max, v_max = limits.of(values)
    weights = [values[name] for name in WEIGHTS]
    mu = p.m1 + p.m2

    def held(angle):  # the energy of both angles held at ``angle``
        return p.g * (mu * p.l1 + p.m2 * p.l2) * (1.0 - math.cos(angle))

    return Config(near=design(p, weights, values["r"], values["h"]),
                  far=design(p, [values["q_x_far"]] + weights[1:], values["r_far"], values["h"]),
                  e_near=held(near), e_far=held(far), mu=mu, m2=p.m2, l1=p.l1, l2=p.l2, g=p.g, x_d=values["x_d"],
                  u_max=u_max, v_max=v_max, h=values["h"])


def blend(c, s):
    """The weight ``w`` of the far design for the measured state ``s``."""
    return min(1.0, max(0.0, (swing_energy(c, s) - c.e_near) / (c.e_far - c.e_near)))


def control(c, measured, reference=(0.0,) * 6, ddx_ref=0.0):
    """``u = ddx_ref - K(w) (s - s_ref)`` within the limits."""
    w = blend(c, measured)
    gains = c.near if w == 0.0 else [(1.0 - w) * a + w * b for a, b in zip(c.near, c.far)]
    error = [s - r for s, r in zip(measured, reference)]
    error[0] -= c.x_d
    return limits.limited(ddx_ref - linalg.dot(gains, error), measured[1], c.u_max, c.v_max, c.h)


def _output(config, state, inputs):
    return (control(config, inputs[IN.x:IN.dtheta2 + 1], inputs[IN.x_ref:IN.dtheta2_ref + 1], inputs[IN.ddx_ref]),)


def report(config):
    """Both designs and the energies of the blend, for ``crane-fmu info``."""
    names = ("x", "dx", "theta1", "dtheta1", "theta2", "dtheta2")
    return {**{"K_near_" + n: k for n, k in zip(names, config.near)},
            **{"K_far_" + n: k for n, k in zip(names, config.far)}, "E_near_J": config.e_near, "E_far_J": config.e_far}


VARIABLES = controller_model() + tuple(
    parameter(name, value, "1", f"near design: LQR state weight on {name[2:]} (as LqrController's)")
    for name, value in DEFAULT_WEIGHTS.items()) + (
    parameter("r", 0.05, "1", "near design: LQR input weight on u (as LqrController's)"),
    parameter("q_x_far", 5.0, "1", "far design: LQR state weight on x (its other state weights: the near ones)"),
    parameter("r_far", 0.5, "1", "far design: LQR input weight on u"),
    parameter("theta_near", math.radians(10.5), "rad", "below the swing energy of both angles at this: the near "
                                                       "design alone"),
    parameter("theta_far", math.radians(14.0), "rad", "above the swing energy of both angles at this: the far "
                                                      "design alone"),
    parameter("h", 1e-3, "s", "communication step the discrete designs are for"),
    parameter("x_d", 0.0, "m", "target trolley position (added to x_ref)"),
    *limits.parameters(),
) + MEASURED_STATE + REFERENCE_INPUTS + (
    output("u", "m/s2", "demanded trolley acceleration, ddx_ref - K(w) (s - s_ref), limited"),
)
IN = positions(VARIABLES, "input")
RULES = (*PLANT_RULES, *non_negative(*WEIGHTS, "q_x_far"), *positive("r", "r_far", "h", "theta_near"),
         rule("finite(theta_far) and theta_near < theta_far < pi / 2",
              "theta_far must be > theta_near = {theta_near} and < pi/2, got {theta_far}"),
         *finite("x_d"), *limits.RULES)  # checked in this order (rules.py)

COMPONENT = Component(
    "HardHitController", "controller",
    "Two discrete LQR designs blended by the swing energy (gentle far out, the LQR near rest), for large swings; "
    "tracks x_ref, dx_ref, ddx_ref; output: trolley acceleration u, direct feedthrough",
    VARIABLES, configure, _output, feedthrough=True, report=report,
    crane_model=CRANE_MODEL, native="hard_hit.c", rules=RULES)
