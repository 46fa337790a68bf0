"""Parameters of the crane plant and of the backstepping controller, and their rules.

Defaults are the paper's Section V values. Every class validates itself on
construction by its rules (:mod:`.rules`) and raises ``ValueError`` naming the
field, the rule and the value; the components that take these parameters list
the same rules among theirs.
"""

from dataclasses import dataclass, fields

from . import rules
from .rules import non_negative

B3_FORMS = ("derived", "printed")

# The rules of the crane model's parameters (eqs (4)-(9)), in their order: every component that models the crane.
PLANT_RULES = (*rules.positive("m1"), *non_negative("m2"), *rules.positive("l1", "l2", "g"))

# The rules of the backstepping law's gains, targets and options (ControllerGains).
GAIN_RULES = (
    *rules.finite("K1_x", "K1_theta1", "K1_theta2", "K2_x", "K2_theta1", "K2_theta2", "x_d", "theta1_d", "theta2_d"),
    *non_negative("w_x", "w_theta1", "w_theta2"),
    # b1 = 1 always, so b'Wb > 0 exactly when w_x > 0 or a swing row is weighted where its b entry is non-zero;
    # w_x = 0 can be singular.
    rules.in_range("w_x", 0, low_open=True, finite=False, note="b'Wb must not vanish"),
    rules.one_of("b3_form", B3_FORMS),
)


def positive(name, value):
    """Raise ValueError naming ``name`` unless ``value`` is a finite number > 0 (:func:`.rules.positive`)."""
    rules.check(rules.positive(name), {name: value})


def finite(name, value):
    """Raise ValueError naming ``name`` unless ``value`` is a finite number (:func:`.rules.finite`)."""
    rules.check(rules.finite(name), {name: value})


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
        rules.check(PLANT_RULES, {f.name: getattr(self, f.name) for f in fields(self)})


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
        rules.check(GAIN_RULES, {f.name: getattr(self, f.name) for f in fields(self)})


PLANT_FIELDS = ("m1", "m2", "l1", "l2", "g")


def plant_parameters(values):
    """Validated :class:`PlantParameters` from the m1, m2, l1, l2, g entries of ``values``."""
    return PlantParameters(**{name: values[name] for name in PLANT_FIELDS})
