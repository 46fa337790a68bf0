"""A plant FMU linearised at an operating point: ``x' = A x + B u``, ``y = C x + D u``.

Any FMI 2.0 or 3.0 FMU, by what it offers, best first:

1. Model Exchange with directional derivatives: the columns of ``[A; C]`` and ``[B; D]`` are the
   FMU's directional derivatives of its state derivatives and outputs along each state and input;
2. Model Exchange without: central differences of the same values;
3. co-simulation only: the states are the outputs with a start parameter (``NAME0`` or ``NAME_0``,
   as the CranePlant's ``x0`` and ``theta1_0``); central differences of the FMU's map over one
   step of ``horizon`` with the inputs held give its discrete ``(Phi, Gamma)``, and ``(A, B)`` is the
   continuous-time pair whose zero-order-hold discretisation that is (the matrix logarithm of
   ``[[Phi, Gamma], [0, I]]``, divided by the horizon). Over half the horizon the same, and the two
   extrapolated (Richardson). Exact at an equilibrium (to the FMU's own integration error); away
   from one, the map follows the moving state and the result is the Jacobian to about the two
   horizons' difference (stated). Two horizons far apart mean dynamics too fast for the horizon
   (the logarithm's branch is ambiguous): refused.

The operating point is the FMU's initial state (after initialisation with the given parameter
values) and its inputs' start values, with the values of ``at`` in place of those named there.
"""

import xml.etree.ElementTree as ET
import zipfile
from collections import namedtuple

import numpy as np

Linearisation = namedtuple("Linearisation", "A B C D states inputs outputs point method spread")
Linearisation.__doc__ = ("The matrices (numpy arrays), the names of the states, inputs and outputs, the operating "
                         "point ``{name: value}`` of the states and inputs, how the matrices were obtained, and for a "
                         "co-simulation FMU the largest difference of A, B over the two horizons (else None).")

HORIZON = 0.01  # s: a co-simulation FMU's step for its map (rounding / horizon in A; off-equilibrium horizon^2)
CS_DELTA = 1e-4  # relative perturbation of the co-simulation map, Richardson-extrapolated: error delta^4
ME_DELTA = 1e-6  # relative perturbation of Model Exchange values without directional derivatives


def linearize(path, at=None, values=None, horizon=HORIZON):
    """The :class:`Linearisation` of the FMU at ``path``.

    Parameters
    ----------
    path : str or Path
        The FMU file.
    at : dict, optional
        ``{state or input name: value}``: the operating point where it differs from the start.
    values : dict, optional
        ``{parameter: value}`` set before initialisation.
    horizon : float
        The step of a co-simulation FMU's map [s] (not used with Model Exchange).

    Raises
    ------
    ValueError
        One line: an unknown name, an FMU that is none or has no states, a failing FMU call.
    """
    md = describe(path)
    at, values = dict(at or {}), dict(values or {})
    if md.modelExchange is not None:
        return _model_exchange(path, md, at, values)
    return _co_simulation(path, md, at, values, horizon)


def describe(path):
    """The model description of an FMI 2.0 or 3.0 FMU (one-line ValueError otherwise)."""
    from pathlib import Path

    from fmpy import read_model_description

    if not Path(path).is_file():
        raise ValueError(f"{path} not found")
    try:
        md = read_model_description(str(path))
    except Exception as exc:  # zip, XML and schema errors alike
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ValueError(f"{path} is not a readable FMU ({reason})") from None
    if md.fmiVersion not in ("2.0", "3.0"):
        raise ValueError(f"{path} is an FMI {md.fmiVersion} FMU; linearize reads FMI 2.0 and 3.0")
    return md


def _reals(md, causality):
    return [v for v in md.modelVariables if v.causality == causality and v.type in ("Real", "Float64")]


def _split_point(at, states, inputs):
    """``(states' values, inputs' values)`` of ``at``, checked: every name a state or a real input."""
    for name in at:
        if name not in states and name not in inputs:
            raise ValueError(f"--at {name}: not a state or input of the FMU; states: {', '.join(states)}; "
                             f"inputs: {', '.join(inputs) or 'none'}")
    return {n: v for n, v in at.items() if n in states}, {n: v for n, v in at.items() if n in inputs}


# --- Model Exchange ---------------------------------------------------------------------------------------


class _Model:
    """An FMU's Model Exchange instance in continuous-time mode, the FMI version hidden."""

    def __init__(self, path, md, values):
        from fmpy import extract, instantiate_fmu
        from fmpy.simulation import apply_start_values

        self.md, self.fmi3 = md, md.fmiVersion.startswith("3")
        self.unzip = extract(str(path))
        self.fmu = self._call("Instantiate", instantiate_fmu, self.unzip, md, fmi_type="ModelExchange")
        if not self.fmi3:
            self._call("SetupExperiment", self.fmu.setupExperiment, startTime=0.0)
        unknown = apply_start_values(self.fmu, md, values)
        if unknown:
            raise ValueError(f"--set {next(iter(unknown))}: the FMU has no such variable")
        if self.fmi3:
            self._call("EnterInitializationMode", self.fmu.enterInitializationMode, startTime=0.0)
        else:
            self._call("EnterInitializationMode", self.fmu.enterInitializationMode)
        self._call("ExitInitializationMode", self.fmu.exitInitializationMode)
        update = self.fmu.updateDiscreteStates if self.fmi3 else self.fmu.newDiscreteStates
        for _ in range(100):
            needed, terminate, *_ = self._call("UpdateDiscreteStates" if self.fmi3 else "NewDiscreteStates", update)
            if terminate:
                raise ValueError("the FMU ends the simulation at its start (terminateSimulation)")
            if not needed:
                break
        self._call("EnterContinuousTimeMode", self.fmu.enterContinuousTimeMode)
        self.n = len(md.derivatives)
        self.x = np.zeros(self.n)

    def _call(self, function, call, *args, **kwargs):
        try:
            return call(*args, **kwargs)
        except ValueError:
            raise
        except Exception as exc:
            name = ("fmi3" if self.fmi3 else "fmi2") + function
            raise ValueError(f"{name} failed ({exc})") from None

    def states(self):
        self._call("GetContinuousStates", self.fmu.getContinuousStates, self._ptr(self.x), self.n)
        return self.x.copy()

    def set_states(self, x):
        self.x[:] = x
        self._call("SetContinuousStates", self.fmu.setContinuousStates, self._ptr(self.x), self.n)

    def derivatives(self):
        dx = np.zeros(self.n)
        get = self.fmu.getContinuousStateDerivatives if self.fmi3 else self.fmu.getDerivatives
        self._call("GetContinuousStateDerivatives" if self.fmi3 else "GetDerivatives", get, self._ptr(dx), self.n)
        return dx

    def get(self, vrs):
        return np.array(self._call("GetReal", self.fmu.getFloat64 if self.fmi3 else self.fmu.getReal, vrs))

    def set(self, vrs, values):
        self._call("SetReal", self.fmu.setFloat64 if self.fmi3 else self.fmu.setReal, vrs, list(values))

    def directional(self, unknowns, known):
        return np.array(self._call("GetDirectionalDerivative", self.fmu.getDirectionalDerivative,
                                   unknowns, [known], [1.0]))

    def free(self):
        import shutil

        try:
            self.fmu.terminate()
            self.fmu.freeInstance()
        finally:
            shutil.rmtree(self.unzip, ignore_errors=True)

    @staticmethod
    def _ptr(array):
        import ctypes

        return array.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


def _provides_directional_derivatives(path, md):
    """The ModelExchange element's flag; fmpy reads FMI 2.0's and not FMI 3.0's ``providesDirectionalDerivatives``."""
    if not md.fmiVersion.startswith("3"):
        return bool(md.modelExchange.providesDirectionalDerivative)
    with zipfile.ZipFile(path) as fmu:
        me = ET.fromstring(fmu.read("modelDescription.xml")).find("ModelExchange")
    return me.get("providesDirectionalDerivatives") in ("true", "1")


def _model_exchange(path, md, at, values):
    states = [d.variable.derivative for d in md.derivatives]
    derivatives = [d.variable.valueReference for d in md.derivatives]
    inputs, outputs = _reals(md, "input"), _reals(md, "output")
    names = [s.name for s in states], [v.name for v in inputs], [v.name for v in outputs]
    at_states, at_inputs = _split_point(at, names[0], names[1])
    exact = _provides_directional_derivatives(path, md)
    model = _Model(path, md, values)
    try:
        x = model.states()
        for i, name in enumerate(names[0]):
            x[i] = at_states.get(name, x[i])
        model.set_states(x)
        u = np.array([at_inputs.get(v.name, v.start if v.start is not None else 0.0) for v in inputs], dtype=float)
        in_vrs, out_vrs = [v.valueReference for v in inputs], [v.valueReference for v in outputs]
        if in_vrs:
            model.set(in_vrs, u)
        if exact:
            unknowns = derivatives + out_vrs
            columns = [model.directional(unknowns, s.valueReference) for s in states]
            columns += [model.directional(unknowns, vr) for vr in in_vrs]
            method = "directional derivatives (Model Exchange)"
        else:
            def values_at(dx, du):
                model.set_states(x + dx)
                if in_vrs:
                    model.set(in_vrs, u + du)
                return np.concatenate([model.derivatives(), model.get(out_vrs) if out_vrs else []])

            columns = _central(values_at, x, u, ME_DELTA)
            method = "central differences of the derivatives and outputs (Model Exchange without directional " \
                     "derivatives)"
    finally:
        model.free()
    jac = np.array(columns).T.reshape(len(derivatives) + len(out_vrs), len(x) + len(u))
    n = len(x)
    point = dict(zip(names[0] + names[1], np.concatenate([x, u]).tolist()))
    return Linearisation(jac[:n, :n], jac[:n, n:], jac[n:, :n], jac[n:, n:], *names, point, method, None)


def _central(values_at, x, u, delta, richardson=False):
    """Columns of the Jacobian of ``values_at(dx, du)`` by central differences, states first.

    Each perturbation is ``delta`` relative (absolute below 1). Central differences err by
    ``delta^2 f'''/6``; with ``richardson`` those at ``delta`` and ``2 delta`` are combined to cancel
    that term (an error of order ``delta^4``, for four evaluations instead of two).
    """
    columns = []
    n = len(x) + len(u)
    for k in range(n):
        base = x[k] if k < len(x) else u[k - len(x)]

        def difference(h, k=k):
            step = np.zeros(n)
            step[k] = h
            return (values_at(step[:len(x)], step[len(x):]) - values_at(-step[:len(x)], -step[len(x):])) / (2 * h)

        h = delta * max(1.0, abs(base))
        near = difference(h)
        columns.append((4.0 * near - difference(2 * h)) / 3.0 if richardson else near)
    return columns


# --- co-simulation ---------------------------------------------------------------------------------------


def start_parameters(md):
    """``{output: parameter}``: the outputs a co-simulation FMU lets one start, by ``NAME0`` or ``NAME_0``."""
    parameters = {v.name for v in md.modelVariables if v.causality == "parameter"}
    found = {}
    for v in _reals(md, "output"):
        for name in (v.name + "0", v.name + "_0"):
            if name in parameters:
                found[v.name] = name
    return found


def _co_simulation(path, md, at, values, horizon):
    from scipy.linalg import logm

    from crane_fmu.cosim.adapters import open_instance

    if not horizon > 0:
        raise ValueError(f"--horizon must be > 0, got {horizon!r}")
    starts = start_parameters(md)
    if not starts:
        raise ValueError(f"{path} has no Model Exchange and no output with a start parameter (NAME0 or NAME_0): "
                         "it has no states to linearise about")
    inputs, outputs = _reals(md, "input"), _reals(md, "output")
    names = list(starts), [v.name for v in inputs], [v.name for v in outputs]
    at_states, at_inputs = _split_point(at, names[0], names[1])
    for name, parameter in starts.items():
        if name in at_states and parameter in values:
            raise ValueError(f"--at {name} and --set {parameter} both set the state {name}: give one")
    variables = {v.name: v for v in md.modelVariables}
    x = np.array([at_states.get(n, values.get(starts[n], variables[starts[n]].start)) for n in names[0]], dtype=float)
    u = np.array([at_inputs.get(v.name, v.start if v.start is not None else 0.0) for v in inputs], dtype=float)

    def run(dx, du):
        """The outputs at the start, and the states after half the horizon and after the horizon."""
        instance = open_instance(path, "linearize")
        try:
            for name, value in values.items():
                instance.set(name, value)
            for name, value in zip(names[0], x + dx):
                instance.set(starts[name], value)
            for name, value in zip(names[1], u + du):
                instance.set(name, value)
            instance.setup(0.0, horizon)
            instance.enter_initialization()
            instance.exit_initialization()
            y0 = [instance.get(n) for n in names[2]]
            instance.do_step(0.0, horizon / 2)
            half = [instance.get(n) for n in names[0]]
            instance.do_step(horizon / 2, horizon / 2)
            return np.array(y0 + half + [instance.get(n) for n in names[0]])
        finally:
            instance.free()

    from crane_fmu.cosim import FmiError

    try:
        columns = np.array(_central(run, x, u, CS_DELTA, richardson=True)).T
    except FmiError as exc:
        raise ValueError(str(exc)) from None
    n, m, p = len(x), len(u), len(names[2])
    c_d = columns[:p]
    estimates = []
    for rows, h in ((columns[p:p + n], horizon / 2), (columns[p + n:], horizon)):
        block = np.block([[rows], [np.zeros((m, n)), np.eye(m)]])
        estimates.append(np.real_if_close(logm(block), tol=1e6) / h)
    half, full = estimates
    # Away from an equilibrium the map's logarithm is the Jacobian averaged along the first horizon, an error
    # of order horizon; the two horizons extrapolate it away (Richardson) and tell aliasing, which differs in O(1).
    result, spread = 2.0 * half - full, float(np.abs(full - half).max())
    if np.iscomplexobj(full) or np.abs(full - half).max() > 0.1 * max(1.0, float(np.abs(full).max())):
        raise ValueError(f"the FMU's map over {horizon!r} s and over half of it give different A, B: its dynamics are "
                         "too fast for the horizon; give a shorter --horizon")
    method = (f"central differences of the co-simulation's map over {horizon:g} s and {horizon / 2:g} s, "
              f"matrix logarithm, extrapolated; the two differ by {spread:.1g} (no Model Exchange; "
              f"states set by {', '.join(starts.values())})")
    point = dict(zip(names[0] + names[1], np.concatenate([x, u]).tolist()))
    return Linearisation(result[:n, :n], result[:n, n:], c_d[:, :n], c_d[:, n:], *names, point, method, spread)


# --- text and files --------------------------------------------------------------------------------------


def report(lin, title):
    """The linearisation as text: the operating point, the method, and the four matrices with their names."""
    lines = [title, "at " + ", ".join(f"{k} = {v:.6g}" for k, v in lin.point.items()), f"from {lin.method}"]
    for name, matrix, rows, cols in (("A", lin.A, lin.states, lin.states), ("B", lin.B, lin.states, lin.inputs),
                                     ("C", lin.C, lin.outputs, lin.states), ("D", lin.D, lin.outputs, lin.inputs)):
        lines.append(f"{name} ({matrix.shape[0]} x {matrix.shape[1]}): rows {', '.join(rows)}")
        width = max([len(r) for r in rows] + [0])
        lines.append(" " * width + "".join(f"{c[:12]:>13}" for c in cols))
        lines += [f"{r:<{width}}" + "".join(f"{v:13.6g}" for v in row) for r, row in zip(rows, matrix)]
    return "\n".join(lines)


def save(lin, path):
    """Write ``A``, ``B``, ``C``, ``D`` and the names of the states, inputs and outputs to .npz or .mat."""
    from pathlib import Path

    arrays = {"A": lin.A, "B": lin.B, "C": lin.C, "D": lin.D, "states": np.array(lin.states, dtype=object),
              "inputs": np.array(lin.inputs, dtype=object), "outputs": np.array(lin.outputs, dtype=object)}
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    partial = Path(str(path) + ".partial")
    if str(path).endswith(".mat"):
        from scipy.io import savemat

        savemat(partial, arrays)
    else:
        arrays.update({k: np.array(v, dtype=str) for k, v in arrays.items() if k in ("states", "inputs", "outputs")})
        with open(partial, "wb") as f:
            np.savez(f, **arrays)
    partial.replace(path)
