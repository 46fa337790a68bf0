"""A system as data: instances, connections, parameter values, times; and the run function.

Nothing here knows what the instances are: a system names each instance's FMU
either by a model identifier (the file ``<identifier>.fmu`` in a folder of built
FMUs) or by the path of an ``.fmu`` file.
"""

from dataclasses import dataclass, field, replace
from pathlib import Path

from .adapters import open_instance
from .connections import check_both_ends, connect, unfed
from .in_process import kind_of
from .instance import FmiError, read_fmu
from .master import Master, communication_points
from .recorder import ArrayRecorder
from .suggest import did_you_mean


@dataclass(frozen=True)
class System:
    """A co-simulation system.

    Attributes
    ----------
    name : str
    instances : dict
        ``{instance name: model identifier or .fmu path}``.
    connections : tuple of Connection
        Written-out connections.
    match_names : bool
        Also connect every input that no written-out connection feeds to the
        output of the same name of another instance, where exactly one has it
        (python-control's ``interconnect`` habit).
    parameters : dict
        ``{instance: {variable: value}}`` set before initialisation.
    stop_time, step, start_time : float
        The default experiment [s].
    description : str
    replaced : dict
        ``{instance: model identifier or .fmu path}``: what the system was designed with, for the
        instances whose FMU :meth:`with_instances` replaced. The connections the design has must keep
        both ends in the FMUs used (:meth:`resolve`).
    tags : tuple of str
        Words that say what else a toolkit does with the system (which of its systems it packs as one
        FMU, say); the master ignores them.
    """

    name: str
    instances: dict
    connections: tuple = ()
    match_names: bool = True
    parameters: dict = field(default_factory=dict)
    stop_time: float = 20.0
    step: float = 1e-3
    start_time: float = 0.0
    description: str = ""
    replaced: dict = field(default_factory=dict)
    tags: tuple = ()

    def fmus(self, fmu_dir):
        """``{instance: Path}`` of the FMU files; a model identifier names ``fmu_dir/<identifier>.fmu``."""
        return {name: Path(source) if is_file(source) else Path(fmu_dir) / f"{source}.fmu"
                for name, source in self.instances.items()}

    def with_parameters(self, overrides):
        """A copy with ``{instance: {variable: value}}`` set over the system's own values."""
        merged = {name: dict(values) for name, values in self.parameters.items()}
        for name, values in overrides.items():
            if name not in self.instances:
                raise ValueError(f"unknown instance {name!r}; instances: {', '.join(self.instances)}"
                                 + did_you_mean(name, self.instances))
            merged.setdefault(name, {}).update(values)
        return replace(self, parameters=merged)

    def with_instances(self, overrides):
        """A copy with some instances' FMUs replaced: ``{instance: model identifier or .fmu path}``.

        The system's parameter values for a replaced instance are kept; connections are matched again
        when the copy is resolved, and those of the original design must keep both ends (:meth:`resolve`).
        """
        unknown = [name for name in overrides if name not in self.instances]
        if unknown:
            raise ValueError(f"unknown instance {unknown[0]!r}; instances: {', '.join(self.instances)}"
                             + did_you_mean(unknown[0], self.instances))
        designed = {name: self.instances[name] for name in overrides if name not in self.replaced}
        return replace(self, instances={**self.instances, **overrides}, replaced={**self.replaced, **designed})

    def designed(self, fmu_dir):
        """Every connection of the system as designed: with the FMUs it had before :meth:`with_instances`."""
        original = replace(self, instances={**self.instances, **self.replaced})
        return connect(_interfaces(original.fmus(fmu_dir)), self.connections, self.match_names)

    def resolve(self, fmu_dir, optional=None):
        """``(fmus, connections)``: the checked FMU paths and every connection, matched ones included.

        An FMU that replaced an instance's (:meth:`with_instances`) must keep both ends of every
        connection the design has: the inputs it feeds and the outputs it is fed from.

        Parameters
        ----------
        fmu_dir : path
        optional : dict, optional
            ``{instance: input names}`` that an FMU replacing the instance may lack (the design's
            connections into them are left out).

        Raises
        ------
        ValueError
            One line: a missing or unreadable FMU, an unknown variable, an ambiguous match, an end of the
            design's connections missing in the FMUs used (naming the instance, the variable and the FMU).
        """
        fmus = self.fmus(fmu_dir)
        interfaces = _interfaces(fmus)
        connections = self.connections
        if self.replaced:
            check_both_ends(self.designed(fmu_dir), interfaces, fmus, optional)
            connections = tuple(c for c in connections if c.target not in self.replaced
                                or c.input in interfaces[c.target][0])
        return fmus, connect(interfaces, connections, self.match_names)


def is_file(source):
    """Whether an instance's source names a file (an ``.fmu``, or a source run in process:
    :mod:`~crane_fmu.cosim.in_process`), not a model identifier."""
    return str(source).endswith(".fmu") or kind_of(source) is not None


def _interfaces(fmus):
    """``{instance: (input names, output names)}`` of the FMUs ``{instance: path}``."""
    interfaces = {}
    for name, path in fmus.items():
        md = read_fmu(path)
        interfaces[name] = ([v.name for v in md.modelVariables if v.causality == "input"],
                            [v.name for v in md.modelVariables if v.causality == "output"])
    return interfaces


def unfed_inputs(fmus, connections, parameters=None):
    """One line per input of the FMUs ``{instance: path}`` that no connection feeds and ``parameters`` (``{instance:
    {variable: value}}``) gives no value: it is read as its start value through the run. An input whose description
    says what it means unconnected (:data:`~crane_fmu.cosim.connections.UNCONNECTED`) is left out."""
    inputs, outputs, starts = {}, {}, {}
    for name, path in fmus.items():
        variables = read_fmu(path).modelVariables
        inputs[name] = {v.name: v.description for v in variables if v.causality == "input"}
        outputs[name] = [v.name for v in variables if v.causality == "output"]
        starts.update({(name, v.name): v.start for v in variables if v.causality == "input"})
    given = [(instance, variable) for instance, values in (parameters or {}).items() for variable in values]
    return [f"input {instance}.{name} is fed by nothing: it stays at its start value {starts[instance, name]}"
            + (f" (the nearest output: {near})" if near else "")
            for instance, name, near in unfed(inputs, outputs, connections, given)]


def settable(fmus):
    """``{instance: {name: (FMI type, unit)}}``: the parameters and inputs of the FMUs ``{instance: path}``."""
    return {name: {v.name: (v.type, v.unit) for v in read_fmu(path).modelVariables
                   if v.causality in ("parameter", "input")} for name, path in fmus.items()}


def split_name(name, variables):
    """``(instance, variable)`` of ``"instance.variable"``, where ``variables`` (as :func:`settable` gives)
    has it; else a ValueError naming what is unknown and what is valid. The one check of such names."""
    instance, dot, variable = name.partition(".")
    if not dot or not instance or not variable:
        raise ValueError("expected INSTANCE.VARIABLE")
    if instance not in variables:
        raise ValueError(f"unknown instance {instance!r}; instances: {', '.join(variables)}"
                         + did_you_mean(instance, variables))
    if variable not in variables[instance]:
        raise ValueError(f"{instance} has no parameter or input {variable!r}; valid: "
                         + ", ".join(variables[instance]) + did_you_mean(variable, variables[instance]))
    return instance, variable


def simulate(fmus, connections, stop_time, step, algorithm="gauss-seidel", parameters=None,
             recorder=None, start_time=0.0, initial_exchange=True, observers=()):
    """Co-simulate FMUs with the fixed-step master.

    Parameters
    ----------
    fmus : dict
        ``{instance name: .fmu path}``.
    connections : list of Connection
    stop_time, step : float
        Stop time and communication step [s]; the step must divide the interval.
    algorithm : str or Algorithm
        The master algorithm: a registered name (``crane_fmu.cosim.algorithms``) or object.
    parameters : dict, optional
        ``{instance: {variable: value}}`` set before initialisation.
    recorder : observer, optional
        Defaults to an :class:`ArrayRecorder`.
    initial_exchange : bool
        See :class:`~crane_fmu.cosim.master.Master`.
    observers : sequence, optional
        More observers (e.g. a :class:`~crane_fmu.cosim.recorder.ProgressLine`), told of every
        communication point after the recorder.

    Returns
    -------
    recorder
        The recorder, holding every output at every communication point. On an
        FMU error, a file recorder is closed with the rows up to the last good
        step (written to :func:`~crane_fmu.cosim.recorder.cut_short_path`, never
        over an earlier result) before the :class:`FmiError` propagates.
    """
    communication_points(start_time, stop_time, step)  # fail before loading anything
    for name in parameters or {}:
        if name not in fmus:
            raise KeyError(f"unknown instance {name!r}; instances: {', '.join(fmus)}" + did_you_mean(name, fmus))
    recorder = ArrayRecorder() if recorder is None else recorder
    instances = {}
    try:
        for name, path in fmus.items():
            instances[name] = open_instance(path, name)
        master = Master(instances, connections, algorithm, initial_exchange)
        master.run(start_time, stop_time, step, [recorder, *observers], parameters)
        master.terminate()
    except FmiError as exc:
        if hasattr(recorder, "close"):
            recorder.close(reason=str(exc))
        raise
    finally:
        for inst in instances.values():
            inst.free()
    if hasattr(recorder, "close"):
        recorder.close()
    return recorder


def run(system, fmu_dir, algorithm="gauss-seidel", recorder=None, stop_time=None, initial_exchange=True):
    """Co-simulate a :class:`System` whose FMUs are in ``fmu_dir`` (or named by path); return the recorder.

    It runs at the system's own step, with its own values: a system to be run at another step is made by
    the toolkit's one preparation of a run (``crane_fmu.systems.prepare``), which also tells every
    component designed for a step (its parameter ``h``) the new one.
    """
    fmus, connections = system.resolve(fmu_dir)
    return simulate(fmus, connections, system.stop_time if stop_time is None else stop_time, system.step, algorithm,
                    system.parameters, recorder, system.start_time, initial_exchange)
