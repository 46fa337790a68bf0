"""A component run from its Python file in this process, no FMU built: ``--use controller=mylaw.py``.

A *law file* names a component by its module, ``mylaw.py`` (the module's one component, or its one
controller) or ``mylaw.py:NAME`` (the component ``NAME``: its model identifier or its variable's name; or a plain
function ``NAME(config, state, inputs) -> (u,)`` of the measured state, made a stateless controller with no
parameters: ``config`` and ``state`` are None). It runs through the runtime its FMU runs once built
(``crane-fmu build --component``, ``fmu_src/python/runtime.py``): the same Python code on the same
doubles, so the same bits; its model description is the one the build writes, made in memory.
"""

import functools
import hashlib
import importlib.util
import io
import re
import sys
import zipfile
from pathlib import Path
from xml.etree.ElementTree import tostring

from crane_fmu.cosim import in_process
from crane_fmu.cosim.instance import FmiError, Instance
from crane_fmu.model.tables import enumeration_name

_PLAIN = set()  # the components made of plain law functions
_SPEC = re.compile(r"(?P<file>.+\.py)(?::(?P<name>[A-Za-z_]\w*))?")


class LawBug(ValueError):
    """What a law file's own function raised other than a ValueError (a bug in it), as one line naming both."""


def is_law(source):
    """Whether an instance's source is a law file (``mylaw.py`` or ``mylaw.py:NAME``)."""
    return _SPEC.fullmatch(str(source)) is not None


def law_file(source):
    """The Python file of a law file's source."""
    return Path(_SPEC.fullmatch(str(source))["file"])


def component(source):
    """The :class:`~crane_fmu.model.component.Component` a law file names (imported once per file version).

    Raises
    ------
    ValueError
        One line: a missing file, an import that fails, no such component or function, or a choice to make.
    """
    path = law_file(source)
    if not path.is_file():
        raise ValueError(f"{source}: {path} not found")
    stat = path.stat()
    return _component(str(path.resolve()), stat.st_size, stat.st_mtime_ns, _SPEC.fullmatch(str(source))["name"],
                      str(source))


def check(source, values):
    """``configure`` of the law file's component on its defaults overridden by ``values``: the validated configuration.

    Raises
    ------
    ValueError
        Its rules' own line, or one naming the file and the function for anything else ``configure`` raises (a bug
        in it): ``"bad/cfgbug.py: configure raised KeyError: 'k_xx'"``.
    """
    return _configured(component(source), source, values)


def _configured(comp, source, values):
    try:
        return comp.check(values)
    except ValueError:
        raise
    except Exception as exc:  # the user's code: one line
        raise LawBug(f"{law_file(source)}: {getattr(comp.configure, '__name__', 'configure')} raised "
                     f"{type(exc).__name__}: {exc}") from None


def is_plain(source):
    """Whether a law file's source names a plain law function (a component made here, no FMU of its own)."""
    return component(source) in _PLAIN


@functools.lru_cache(maxsize=32)
def _component(path, size, mtime, name, source):
    from crane_fmu.model.component import Component

    module = _import(path, source)
    found = [v for v in vars(module).values() if isinstance(v, Component) and v.module == module.__name__]
    if name is not None:  # a variable's name, or a component's model identifier
        value = getattr(module, name, None)
        if not isinstance(value, Component):
            value = next((c for c in found if c.model_identifier == name), value)
        if isinstance(value, Component):
            return usable(value, source)
        if callable(value):
            return _plain(name, value)
        names = ", ".join(c.model_identifier for c in found)
        raise ValueError(f"{source}: {Path(path).name} defines no component or function {name!r}"
                         + (f" (its components: {names})" if names else ""))
    if len(found) > 1:
        found = [c for c in found if c.role == "controller"] or found
    if len(found) != 1:
        names = ", ".join(c.model_identifier for c in found) or "none"
        raise ValueError(f"{source}: expected one Component in {Path(path).name} (found: {names}); name one, or a "
                         f"law function: {Path(path).name}:NAME")
    return usable(found[0], source)


def usable(comp, source):
    """``comp`` of the law file ``source`` (or of a module ``build --component`` builds), once its model identifier
    is none of the registered components' (whose FMUs and rules it would be taken for) and its ``configure`` takes
    its own defaults without a bug (a ValueError of its rules is for the values a run sets)."""
    from crane_fmu import components

    if components.find(comp.model_identifier) not in (None, comp):
        raise ValueError(f"{source}: {comp.model_identifier} is already a component's name; choose another model "
                         "identifier")
    try:
        _configured(comp, source, {})
    except LawBug:
        raise
    except ValueError:
        pass
    return comp


def _import(path, source):
    """The module of the file ``path``, imported under a name of its own (never another module's)."""
    name = f"_crane_law_{Path(path).stem}_{hashlib.sha256(path.encode()).hexdigest()[:8]}"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses and pickling look the module up
    try:
        spec.loader.exec_module(module)
    except Exception as exc:  # the user's code: one line
        del sys.modules[name]
        raise ValueError(f"{source}: importing {Path(path).name} failed: {type(exc).__name__}: {exc}") from None
    return module


def _plain(name, law):
    """A plain law function as a stateless, feedthrough controller of the planar crane's measured state."""
    from crane_fmu.model.component import Component
    from crane_fmu.model.tables import MEASURED_STATE, output

    made = Component(name, "controller", f"the law {name} of {law.__module__}", MEASURED_STATE
                     + (output("u", "m/s2", "demanded trolley acceleration"),), _no_parameters, law,
                     feedthrough=True)
    _PLAIN.add(made)
    return made


def _no_parameters(values):
    return None


def model_description(source, fmi_version=2):
    """fmpy's model description of the FMU the build makes of the law (made in memory, not written)."""
    return _description(component(source), fmi_version)


@functools.lru_cache(maxsize=32)
def _description(comp, fmi_version):
    from fmpy import read_model_description

    from crane_fmu.build_scripts.model_description import postprocess
    from crane_fmu.fmu_src.python.slave2 import slave_base
    from crane_fmu.model.tables import DISPLAY_UNITS

    slave = type(comp.model_identifier, (slave_base(comp),), {})(instance_name=comp.model_identifier)
    xml = postprocess(tostring(slave.to_xml(), "UTF-8"), comp.variables, DISPLAY_UNITS, comp.dependencies())
    data = io.BytesIO()
    with zipfile.ZipFile(data, "w") as archive:
        archive.writestr("modelDescription.xml", xml)
    data.seek(0)
    return read_model_description(data)


class LawInstance(Instance):
    """An instance of a law file's component: :class:`~crane_fmu.cosim.instance.Instance` over the component's
    runtime, called from Python (the master then steps through its Python loop)."""

    def __init__(self, source, name):
        from crane_fmu.fmu_src.python.runtime import Runtime

        self.component = component(source)
        self.md = _description(self.component, 2)
        self.name = name
        self.variables = {v.name: v for v in self.md.modelVariables}
        self.outputs = [v.name for v in self.md.modelVariables if v.causality == "output"]
        self.inputs = [v.name for v in self.md.modelVariables if v.causality == "input"]
        deps = self.component.dependencies()
        self.dependencies = {n: tuple(deps.get(n, ())) for n in self.outputs}
        self.feedthrough = any(self.dependencies.values())
        self.messages, self.time = [], None
        self.runtime = Runtime(self.component)
        self._by_vr = {v.valueReference: v.name for v in self.md.modelVariables}
        self._step = self.stepper()

    def _guard(self, function, call, *args):
        """``call(*args)``; a Python exception becomes the FmiError of ``function`` (its message the reason)."""
        self.messages.clear()
        try:
            return call(*args)
        except Exception as exc:
            self.messages.append(f"{type(exc).__name__}: {exc}" if not isinstance(exc, ValueError) else str(exc))
            raise FmiError(self.name, function, self.time, "error", self.messages) from exc

    def set(self, name, value):
        v = self._variable(name)
        if v.type == "Enumeration":  # kept by name, as the FMU's runtime keeps it; given by name or value
            row = next(r for r in self.component.variables if r.name == name)
            value = self._guard("fmi2SetInteger", enumeration_name, row, self.enumeration_value(name, value))
            self._guard("fmi2SetInteger", self.runtime.set_parameter, name, value)
            return
        value = str(value) if v.type == "String" else float(value)
        if v.causality == "input":
            i = self.inputs.index(name)
            self._guard("fmi2SetReal", self.runtime.set_inputs, (i,), (value,))
        else:
            self._guard(f"fmi2Set{v.type}", self.runtime.set_parameter, name, value)

    def get(self, name):
        v = self._variable(name)
        if v.causality == "output":
            return self._guard("fmi2GetReal", self.runtime.output, self.outputs.index(name))
        if v.causality == "input":
            return self.runtime.inputs[self.inputs.index(name)]
        return self.runtime.values[name]

    def setup(self, start_time, stop_time=None):
        self.time = self.runtime.time = start_time

    def enter_initialization(self):
        pass

    def exit_initialization(self):
        self._guard("fmi2ExitInitializationMode", self.runtime.initialise)

    def get_state(self):
        return self.runtime.saved()

    def set_state(self, state):
        self.runtime.restore(state)

    def free_state(self, state):
        pass

    def reader(self, vrs, values):
        positions = [self.outputs.index(self._by_vr[vr]) if self._by_vr[vr] in self.outputs else None for vr in vrs]
        names = [self._by_vr[vr] for vr in vrs]
        def read():
            try:
                if None in positions:
                    values[:] = [float(self.get(n)) for n in names]
                else:
                    outputs = self.runtime.outputs()
                    for k, i in enumerate(positions):
                        values[k] = outputs[i]
            except Exception as exc:
                return self._failed(exc)
            return 0
        return read, "fmi2GetReal"

    def writer(self, vrs, values):
        positions = [self.inputs.index(self._by_vr[vr]) for vr in vrs]

        def write():
            try:
                self.runtime.set_inputs(positions, values[:len(positions)])
            except Exception as exc:
                return self._failed(exc)
            return 0
        return write, "fmi2SetReal"

    def stepper(self):
        def do_step(time, size):
            try:
                reason = self.runtime.step(time, size)
            except Exception as exc:
                return self._failed(exc)
            self.messages.extend(self.runtime.messages)
            if reason:
                self.messages.append(reason)
                return 2  # discard
            return 1 if self.runtime.messages else 0
        return do_step, "fmi2DoStep"

    def _failed(self, exc):
        self.messages.clear()
        self.messages.append(str(exc) if isinstance(exc, ValueError) else f"{type(exc).__name__}: {exc}")
        return 3

    def terminate(self):
        pass

    def reset(self):
        from crane_fmu.fmu_src.python.runtime import Runtime

        self.runtime, self.time = Runtime(self.component), None

    def free(self):
        pass



matches, instance = is_law, LawInstance  # the kind of source this module runs (crane_fmu.cosim.in_process)
in_process.register(sys.modules[__name__])
