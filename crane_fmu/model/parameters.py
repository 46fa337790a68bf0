"""Parameters of the crane plant and of the backstepping controller.

Defaults are the paper's Section V values. Every class validates itself on
construction and raises ``ValueError`` naming the field, the rule and the value.
"""

import math
from dataclasses import dataclass

B3_FORMS = ("derived", "printed")


def _check(name, value, rule, ok):
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        raise ValueError(f"{name} must be a number, got {value!r}")
    if not math.isfinite(value) or not ok(value):
        raise ValueError(f"{name} must be {rule}, got {value!r}")


def positive(name, value):
    """Raise ValueError naming ``name`` unless ``value`` is a finite number > 0."""
    _check(name, value, "> 0 and finite", lambda v: v > 0)


def finite(name, value):
    """Raise ValueError naming ``name`` unless ``value`` is a finite number."""
    _check(name, value, "finite", lambda v: True)


@dataclass(frozen=True)
class PlantParameters:
    """Physical parameters of the double-pendulum payload (Table I, Section V).

    Attributes
    ----------
    m1 : float
        Hook mass [kg], > 0.
    m2 : float
        Payload mass [kg], >= 0.
    l1 : float
        Trolley-to-hook cable length [m], > 0.
    l2 : float
        Hook-to-payload cable length [m], > 0.
    g : float
        Gravitational acceleration [m/s2], > 0.
    """

    m1: float = 3.0
    m2: float = 7.0
    l1: float = 1.0
    l2: float = 0.5
    g: float = 9.8

    def __post_init__(self):
        positive("m1", self.m1)
        _check("m2", self.m2, ">= 0 and finite", lambda v: v >= 0)
        positive("l1", self.l1)
        positive("l2", self.l2)
        positive("g", self.g)


@dataclass(frozen=True)
class ControllerGains:
    """Gains, targets and options of the backstepping law, eqs (16)-(21).

    Attributes
    ----------
    K1_x, K1_theta1, K1_theta2 : float
        Diagonal of K1 [1/s], eq (18).
    K2_x, K2_theta1, K2_theta2 : float
        Diagonal of K2 [1/s], eq (19).
    x_d : float
        Target trolley position [m].
    theta1_d, theta2_d : float
        Target swing angles [rad].
    w_x, w_theta1, w_theta2 : float
        Row weights W of the weighted least-squares solution of eq (20);
        W = I is the paper's eq (21). Each >= 0, not all zero.
    b3_form : str
        ``"derived"`` (re-derived sign of b3, the default) or ``"printed"``
        (b3 exactly as printed in eq (14)).
    """

    K1_x: float = 0.92
    K1_theta1: float = 4.0
    K1_theta2: float = 122.0
    K2_x: float = 0.84
    K2_theta1: float = 2.0
    K2_theta2: float = 310.0
    x_d: float = 0.0
    theta1_d: float = 0.0
    theta2_d: float = 0.0
    w_x: float = 1.0
    w_theta1: float = 1.0
    w_theta2: float = 1.0
    b3_form: str = "derived"

    def __post_init__(self):
        for name in ("K1_x", "K1_theta1", "K1_theta2", "K2_x", "K2_theta1",
                     "K2_theta2", "x_d", "theta1_d", "theta2_d"):
            finite(name, getattr(self, name))
        for name in ("w_x", "w_theta1", "w_theta2"):
            _check(name, getattr(self, name), ">= 0 and finite", lambda v: v >= 0)
        if self.w_x == 0:
            # b1 = 1 always, so b'Wb > 0 exactly when w_x > 0 or a swing row is
            # weighted where its b entry is non-zero; w_x = 0 can be singular.
            raise ValueError(f"w_x must be > 0 (b'Wb must not vanish), got {self.w_x!r}")
        if self.b3_form not in B3_FORMS:
            raise ValueError(f"b3_form must be one of {', '.join(B3_FORMS)}, got {self.b3_form!r}")


PLANT_FIELDS = ("m1", "m2", "l1", "l2", "g")


def plant_parameters(values):
    """Validated :class:`PlantParameters` from the m1, m2, l1, l2, g entries of ``values``."""
    return PlantParameters(**{name: values[name] for name in PLANT_FIELDS})
