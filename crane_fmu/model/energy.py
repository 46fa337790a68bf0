"""An energy-coupling anti-swing law with a Lyapunov proof: the EnergyController component.

The law belongs to the energy-coupling family of Fang, Dixon, Dawson and
Zergeroglu ("Nonlinear coupling control laws for an underactuated overhead
crane system", IEEE/ASME Trans. Mechatronics 8(3), 2003) and its extensions to
double-pendulum cranes by Sun, Fang et al. (e.g. "Nonlinear antiswing control
for crane systems with double-pendulum swing effects and uncertain parameters:
design and experiments", IEEE Trans. Autom. Sci. Eng. 15(3), 2018), which couple
the trolley to a generalised horizontal displacement of the load and prove
convergence with Lyapunov's method and LaSalle's invariance principle. Those
papers take the trolley force as input; the derivation and proof below are
redone here for this model's input, the trolley acceleration ``u = x''``, and
are this module's own (numbered (E1)-(E6)).

Derivation. With ``q = (theta1, theta2)``, ``mu = m1 + m2`` and eqs (8)-(9),
the swing energy in the trolley's frame

    (E1)  E = T_rel(q, q') + g (mu l1 (1 - cos theta1) + m2 l2 (1 - cos theta2)),

where ``T_rel`` is the kinetic energy of hook and payload relative to the
trolley, obeys ``E' = -u xi'`` with the mass-weighted horizontal offset of hook
and payload from the trolley

    (E2)  xi = mu l1 sin theta1 + m2 l2 sin theta2.

Take ``e = x - x_d``, ``v = x'``, a coupling weight ``k_c > 0``, the coupled
position and velocity

    (E3)  chi = e - xi / (mu k_c),       s = k_c v - xi' / mu,

and, with ``phi(z) = a tanh(k z / a)`` (odd, increasing, |phi| < a), the law

    (E4)  u = -phi_p(chi) - phi_d(s),    a_p = a_d = u_max / 2,  gains k_p, k_d.

Proof. ``V = E / mu + k_c v^2 / 2 + k_c Phi(chi)`` with ``Phi' = phi_p`` is positive
definite about the target and radially unbounded in ``v``, ``chi`` and the rates
(``Phi(z) = (a_p^2 / k_p) ln cosh(k_p z / a_p) >= 0``, ``E >= 0``); with ``chi' = s / k_c``

    (E5)  V' = -u xi'/mu + k_c v u + phi_p(chi) s = s (u + phi_p(chi)) = -s phi_d(s) <= 0.

On the largest invariant set in ``{s = 0}``: ``chi' = s / k_c = 0`` so ``chi`` and
``u = -phi_p(chi)`` are constant; ``v = xi' / (mu k_c)`` has a bounded integral
(``|xi|`` is bounded), which a constant acceleration allows only if ``u = 0``
and ``v = 0``. Then ``xi' = 0``: the horizontal force of the upper cable on the
load, ``xi''``, vanishes, so ``theta1 = 0`` (the cable tension is positive) and,
by eq (8), ``sin theta2`` is constant, which eq (9) allows only at ``theta2 = 0``.
So ``chi = e = 0``:

    (E6)  every motion with |theta1|, |theta2| < 90 deg and taut cables converges to x = x_d at rest.

The saturations keep ``|u| <= u_max`` inside the proof. The speed guard
(``v_max``) acts only where ``|v|`` would pass ``v_max`` and is outside it.
"""

import math
from collections import namedtuple

from . import limits
from .component import Component
from .parameters import PLANT_RULES, plant_parameters
from .rules import check, finite, positive, rule
from .tables import CRANE_MODEL, MEASURED_STATE, controller_model, output, parameter

Config = namedtuple("Config", "mu m2 l1 l2 k_c k_p k_d x_d u_max v_max h")


def configure(values):
    check(RULES, values)
    p = plant_parameters(values)
    u_max, v_max = limits.of(values)
    return Config(mu=p.m1 + p.m2, m2=p.m2, l1=p.l1, l2=p.l2, k_c=values["k_c"], k_p=values["k_p"], k_d=values["k_d"],
                  x_d=values["x_d"], u_max=u_max, v_max=v_max, h=values["h"])


def control(c, measured):
    """Eq (E4) with the speed guard: the trolley acceleration [m/s2]."""
    x, v, theta1, dtheta1, theta2, dtheta2 = measured
    xi = (c.mu * c.l1 * math.sin(theta1) + c.m2 * c.l2 * math.sin(theta2)) / c.mu  # (E2) / mu
    dxi = (c.mu * c.l1 * math.cos(theta1) * dtheta1 + c.m2 * c.l2 * math.cos(theta2) * dtheta2) / c.mu
    chi, s = x - c.x_d - xi / c.k_c, c.k_c * v - dxi  # (E3)
    a = 0.5 * c.u_max
    u = -a * math.tanh(c.k_p * chi / a) - a * math.tanh(c.k_d * s / a)  # (E4)
    return limits.limited(u, v, c.u_max, c.v_max, c.h)


VARIABLES = controller_model() + (
    parameter("k_c", 0.1, "1", "coupling weight of the trolley speed, eq (E3)"),
    parameter("k_p", 0.75, "1/s2", "gain on the coupled position chi, eq (E4)"),
    parameter("k_d", 7.5, "1/s", "gain on the coupled velocity s, eq (E4)"),
    parameter("x_d", 0.0, "m", "target trolley position"),
    parameter("h", 1e-3, "s", "communication step (for the speed guard)"),
    *limits.parameters(),
) + MEASURED_STATE + (
    output("u", "m/s2", "demanded trolley acceleration, eq (E4), limited"),
)
RULES = (*PLANT_RULES, *positive("k_c", "k_p", "k_d", "h"), *finite("x_d"), *limits.RULES,
         rule("finite(unlimited(u_max))", "u_max must be finite for the saturated law (E4), got {unlimited(u_max)}"))

COMPONENT = Component(
    "EnergyController", "controller",
    "Energy-coupling anti-swing law with a Lyapunov/LaSalle proof (saturated, |u| <= u_max); "
    "output: trolley acceleration u, direct feedthrough",
    VARIABLES, configure, lambda config, state, inputs: (control(config, inputs),), feedthrough=True,
    crane_model=CRANE_MODEL, native="energy.c", rules=RULES)
