"""Component descriptors: what one FMU kind is, independent of FMI.

A component is a model module (plain functions of configuration, state and
inputs, python-control's ``updfcn(t, x, u, params)`` habit) plus one
:class:`Component` that names its variables and functions. The FMI slaves
(``fmu_src``), the build, the systems and the command line work from the
descriptor alone and never name a component.
"""

from collections import namedtuple
from collections.abc import Callable
from dataclasses import dataclass

from .rules import RESERVED
from .tables import BASE_UNITS

ROLES = ("plant", "controller", "planner", "disturbance", "sensor", "estimator", "benchmark")
CAUSALITIES = ("parameter", "input", "output")


Step = namedtuple("Step", "state messages notes", defaults=((),))
Step.__doc__ = ("What ``update`` may return instead of a bare state: the state, warnings for the host's log "
                "(what a user should act on) and notes (information, logged when the host asks for all messages).")


class Discard(Exception):
    """Raised by a component's ``update`` when a step cannot be taken; the FMU discards the step.

    The message says why and is passed to the host's logger.
    """


@dataclass(frozen=True)
class Continuous:
    """What a host needs to integrate a component itself (FMI Model Exchange).

    Attributes
    ----------
    states, derivatives : tuple of str
        The variables that are the continuous states, and those that are their time derivatives,
        in the same order; each names an output or one of :attr:`variables`.
    variables : tuple of tables.Variable
        The variables Model Exchange adds to the table (causality ``local``): states that are no
        output, and derivatives.
    indicators : tuple of str
        What each event indicator watches, in order (for the documentation and the logs).
    initial : callable
        ``initial(config) -> state``: the continuous state at the start, before the first event update.
    derivatives_of : callable
        ``derivatives_of(config, state, inputs, mode, seed=None)``: the derivatives, and with a seed
        ``(d_state, d_inputs)`` also their derivative along it.
    outputs_of : callable
        ``outputs_of(config, state, inputs, mode, seed=None)``: the outputs in table order, likewise.
    indicators_of : callable
        ``indicators_of(config, state, inputs, mode)``: the event indicators.
    event_update : callable
        ``event_update(config, state, inputs, mode, time) -> (state, mode, messages, terminate)``.
    free_mode : object
        The mode before the first event update.
    """

    states: tuple
    derivatives: tuple
    variables: tuple
    indicators: tuple
    initial: Callable
    derivatives_of: Callable
    outputs_of: Callable
    indicators_of: Callable
    event_update: Callable
    free_mode: object


@dataclass(frozen=True)
class Axis:
    """One driven horizontal axis of a crane: the trolley's position and velocity along it, and its demand.

    A controller is told a move along the axis by a parameter ``<position>_d`` (:attr:`target`) or by a
    planner's references ``<position>_ref``, ``d<position>_ref``, ``dd<position>_ref`` (:attr:`references`).
    """

    position: str
    velocity: str
    demand: str

    @property
    def target(self):
        """The parameter that tells a controller where the load goes along this axis: ``x_d``."""
        return self.position + "_d"

    @property
    def references(self):
        """A planner's position, velocity and acceleration along the axis: ``x_ref``, ``dx_ref``, ``ddx_ref``."""
        return (f"{self.position}_ref", f"d{self.position}_ref", f"dd{self.position}_ref")


@dataclass(frozen=True)
class Crane:
    """What a plant is, by role: everything above the model reads these instead of the plant's names.

    Attributes
    ----------
    state : tuple of str
        The outputs that are the state every controller of this plant measures, in order.
    starts : tuple of str
        The parameters that give each state's start value, in the same order.
    axes : tuple of Axis
        One per driven horizontal axis.
    swing : tuple of str
        Outputs: angles from the vertical whose magnitude is the swing the metrics take.
    sensed : tuple of str
        Outputs: what a crane measures of itself (a sensor's inputs).
    model : tuple of str
        The parameters that define the dynamics (masses, lengths, g): the crane's own, set once for every
        instance that models the crane (``crane.l2``).
    hook, load : tuple of str
        Outputs: the hook's and the load's position (horizontal coordinates, then the vertical, up positive);
        empty for a plant that has none.
    hoist : str, optional
        Input: the hoist's acceleration (a plant that hoists).
    cable : str, optional
        Output: the main cable's length now.
    forces : tuple of str
        Inputs: horizontal forces on the hook and the load (wind, a push).
    start_swing : str, optional
        The parameter of the hook cable's start angle (a swing to regulate from; 0: from rest).
    linearised : callable, optional
        ``linearised({parameter: value}) -> (A, B)``: the state's ``x' = A x + B u`` at rest, ``u`` the axes'
        demands in order (lists of rows).
    """

    state: tuple
    starts: tuple
    axes: tuple
    swing: tuple
    sensed: tuple
    model: tuple
    hook: tuple = ()
    load: tuple = ()
    hoist: str | None = None
    cable: str | None = None
    forces: tuple = ()
    start_swing: str | None = None
    linearised: Callable | None = None

    @property
    def demands(self):
        """The inputs a controller drives, one per axis: ``("u",)``."""
        return tuple(a.demand for a in self.axes)

    def check(self, component):
        """Raise ValueError naming a role whose variable the plant ``component`` does not have as it says."""
        wanted = [("output", n) for n in (*self.state, *self.swing, *self.sensed, *self.hook, *self.load)]
        wanted += [("parameter", n) for n in (*self.starts, *self.model, *filter(None, [self.start_swing]))]
        wanted += [("input", n) for n in (*self.demands, *self.forces)] + [("output", a.position) for a in self.axes]
        wanted += [("output", a.velocity) for a in self.axes] + ([("input", self.hoist)] if self.hoist else [])
        wanted += [("output", self.cable)] if self.cable else []
        for causality, name in wanted:
            if name not in component.names(causality):
                raise ValueError(f"{component.model_identifier}: its crane roles name {name!r}, which is no "
                                 f"{causality} of it")
        if len(self.starts) != len(self.state):
            raise ValueError(f"{component.model_identifier}: a start parameter per state, got {len(self.starts)} for "
                             f"{len(self.state)}")


@dataclass(frozen=True)
class Component:
    """One FMU kind.

    Attributes
    ----------
    model_identifier : str
        The FMU's model identifier and file name (``CranePlant`` -> ``CranePlant.fmu``).
    role : str
        One of :data:`ROLES`. Built-in systems and the harness choose components by role.
    description : str
        One line, written into modelDescription.xml.
    variables : tuple of tables.Variable
        Every parameter, input and output, in value-reference order.
    configure : callable
        ``configure({parameter: value}) -> config``: validates the parameter values
        (``ValueError`` naming the field, the rule and the value) and returns
        what ``output`` and ``update`` need.
    output : callable
        ``output(config, state, inputs) -> tuple`` of the outputs in table order;
        ``inputs`` is the tuple of input values in table order.
    feedthrough : bool
        True when ``output`` depends on the inputs of the same instant.
    depends_on : dict, optional
        ``{output: (input, ...)}``: the inputs each output reads at the same instant,
        where they are not all of them (a feedthrough component) or none; what
        modelDescription.xml declares (:meth:`dependencies`). An output may list an
        input it reads only for some parameter values (the LQR's ``l1_now``, read
        when its gains are scheduled).
    initial_state : callable, optional
        ``initial_state(config) -> state`` for a component with a state.
    update : callable, optional
        ``update(config, state, inputs, time, step) -> state``: the state after
        one communication step with the inputs held (or a :class:`Step` with
        messages for the log); raises :class:`Discard` when the step cannot be
        taken and ``ValueError`` for an unusable step.
    default_experiment : tuple, optional
        ``(start, stop, step)`` [s] written into modelDescription.xml, what a host
        runs by default: the built-in systems' 20 s at 1 ms unless given.
    report : callable, optional
        ``report(config) -> {name: value}``: what ``configure`` derived from the
        parameters (gains, shaper impulses), shown by ``crane-fmu info``.
    continuous : Continuous, optional
        For a component that a host may integrate itself (Model Exchange).
    native : str, optional
        The file of the component's C twin in ``fmu_src/models`` (``crane_plant.c``): ``crane-fmu
        build`` then builds its native FMU too, and systems of such components as one native FMU.
    crane : Crane, optional
        A plant's roles (:class:`Crane`): what the application layer reads of it.
    rules : tuple of rules.Rule, optional
        The parameter rules, in the order they are checked: ``configure`` checks them first
        (:func:`.rules.check`), and the native twin's generated header holds them in C.
    crane_model : tuple of str
        The parameters that are its model of the crane (the plant's own, a model-based controller's, planner's,
        estimator's, the wind's): a system's ``crane.<name>`` sets them (the application's crane_parameters.py).
    """

    model_identifier: str
    role: str
    description: str
    variables: tuple
    configure: Callable
    output: Callable
    feedthrough: bool = False
    initial_state: Callable | None = None
    update: Callable | None = None
    default_experiment: tuple = (0.0, 20.0, 1e-3)
    report: Callable | None = None
    depends_on: dict | None = None
    continuous: Continuous | None = None
    native: str | None = None
    crane: Crane | None = None
    rules: tuple = ()
    crane_model: tuple = ()

    def __post_init__(self):
        if not self.model_identifier.isidentifier():
            raise ValueError(f"model_identifier must be a Python identifier, got {self.model_identifier!r}")
        if self.role not in ROLES:
            raise ValueError(f"role must be one of {', '.join(ROLES)}, got {self.role!r}")
        names = [v.name for v in self.variables]
        for v in self.variables:
            if names.count(v.name) > 1:
                raise ValueError(f"{self.model_identifier}: variable {v.name!r} is listed twice")
            if v.causality not in CAUSALITIES:
                raise ValueError(f"{self.model_identifier}.{v.name}: causality must be one of "
                                 f"{', '.join(CAUSALITIES)}, got {v.causality!r}")
            if v.type == "Real" and v.unit not in BASE_UNITS:
                raise ValueError(f"{self.model_identifier}.{v.name}: unit must be one of tables.BASE_UNITS "
                                 f"({', '.join(BASE_UNITS)}), got {v.unit!r}")
        if self.crane is not None:
            if self.role != "plant":
                raise ValueError(f"{self.model_identifier}: only a plant has crane roles, this is a {self.role}")
            self.crane.check(self)
            if tuple(self.crane_model) != tuple(self.crane.model):
                raise ValueError(f"{self.model_identifier}: a plant's crane_model is its crane roles' model, "
                                 f"{self.crane.model!r}, got {self.crane_model!r}")
        self._check_rules()
        for name in self.crane_model:
            if name not in self.names("parameter"):
                raise ValueError(f"{self.model_identifier}: crane_model names {name!r}, which is no parameter of it")
        if (self.initial_state is None) != (self.update is None):
            raise ValueError(f"{self.model_identifier}: a state needs both initial_state and update")
        if self.depends_on is not None:
            inputs, outputs = self.names("input"), self.names("output")
            for output, read in self.depends_on.items():
                if output not in outputs or not set(read) <= set(inputs):
                    raise ValueError(f"{self.model_identifier}: depends_on maps outputs to inputs, got "
                                     f"{output!r}: {read!r}")
            if any(self.depends_on.values()) != self.feedthrough:
                raise ValueError(f"{self.model_identifier}: depends_on must name an input exactly when feedthrough "
                                 "is True")

    def _check_rules(self):
        """Every rule reads parameters of the table, a String one (or an Enumeration, by its items' names) only as a
        string."""
        kinds = {v.name: "String" if v.type == "Enumeration" else v.type for v in self.variables
                 if v.causality == "parameter"}
        for name in set(kinds) & RESERVED:
            raise ValueError(f"{self.model_identifier}: parameter {name!r} has a name the rules reserve")
        for rule in self.rules:
            for name in rule.names:
                if name not in kinds or (kinds[name] == "String") != (name in rule.strings):
                    raise ValueError(f"{self.model_identifier}: rule {rule.test!r} reads {name!r}, which is no "
                                     f"{'String' if name in rule.strings else 'Real'} parameter")

    @property
    def stateful(self):
        return self.update is not None

    @property
    def module(self):
        """The name of the model module that defines the component's functions."""
        return self.output.__module__

    def names(self, causality):
        """Names of the variables of one causality, in table order."""
        return tuple(v.name for v in self.variables if v.causality == causality)

    def dependencies(self):
        """``{output: (input, ...)}``: the inputs each output reads at the same instant, in table order."""
        inputs = self.names("input")
        if self.depends_on is None:
            return {name: inputs if self.feedthrough else () for name in self.names("output")}
        return {name: tuple(i for i in inputs if i in self.depends_on.get(name, ())) for name in self.names("output")}

    def defaults(self, causality="parameter"):
        """``{name: start}`` of the variables of one causality."""
        return {v.name: v.start for v in self.variables if v.causality == causality}

    def check(self, values):
        """``configure`` of the defaults overridden by ``values``: the validated configuration."""
        return self.configure({**self.defaults(), **values})


def find(module, model_identifier):
    """The :class:`Component` named ``model_identifier`` among a module's globals."""
    for value in vars(module).values():
        if isinstance(value, Component) and value.model_identifier == model_identifier:
            return value
    raise LookupError(f"module {module.__name__} defines no component {model_identifier!r}")
