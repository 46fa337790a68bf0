"""The crane system (plant + controller) and the high-level run function."""

from pathlib import Path

from crane_fmu.model.tables import STATE

from .fmi import FmiError
from .fmi3 import open_instance
from .master import Connection, Master, communication_points
from .recorder import ArrayRecorder

DEFAULT_FMU_DIR = Path("build/fmus")
DEFAULT_SYSTEM = Path("build/CraneSystem.ssp")  # written by crane-fmu build beside build/fmus
FMU_FILES = {"plant": "CranePlant.fmu", "controller": "BacksteppingController.fmu"}
CRANE_CONNECTIONS = [Connection("plant", s, "controller", s) for s in STATE] + [
    Connection("controller", "u", "plant", "u")]


def crane_system(fmu_dir=DEFAULT_FMU_DIR, controller=True):
    """``({instance: fmu path}, connections)`` of the closed loop, or of the plant alone."""
    fmu_dir = Path(fmu_dir)
    names = ["plant", "controller"] if controller else ["plant"]
    fmus = {name: fmu_dir / FMU_FILES[name] for name in names}
    for path in fmus.values():
        if not path.is_file():
            raise FileNotFoundError(f"{path} not found: build the FMUs first (crane-fmu build)")
        check_fmu(path)
    return fmus, (CRANE_CONNECTIONS if controller else [])


def check_fmu(path):
    """Raise ValueError (one line) unless ``path`` is a readable FMI 2.0 or 3.0 co-simulation FMU."""
    from fmpy import read_model_description

    try:
        md = read_model_description(str(path))
    except Exception as exc:  # zip, XML and schema errors alike
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ValueError(f"{path} is not a readable FMU ({reason})") from None
    if md.fmiVersion not in ("2.0", "3.0") or md.coSimulation is None:
        raise ValueError(f"{path} is not an FMI 2.0 or 3.0 co-simulation FMU")


def settable_variables(fmu_path):
    """``{name: FMI type}`` of the parameters and inputs of an FMU, from its modelDescription.xml."""
    from fmpy import read_model_description

    md = read_model_description(str(fmu_path))
    return {v.name: v.type for v in md.modelVariables if v.causality in ("parameter", "input")}


def check_crane_parameters(parameters, instances=("plant", "controller")):
    """Apply the model's rules to the crane FMUs' parameters (defaults overridden by ``parameters``).

    The FMUs apply the same rules when initialisation ends, but pythonfmu FMUs
    cannot tell their host why they failed; checking first gives the reason.

    Raises
    ------
    ValueError
        ``"plant: l1 must be > 0 and finite, got -1.0"``.
    """
    from crane_fmu.model import tables
    from crane_fmu.model.parameters import controller_setup, plant_setup

    checks = {"plant": (tables.PLANT, plant_setup), "controller": (tables.CONTROLLER, controller_setup)}
    for instance in instances:
        table, setup = checks[instance]
        try:
            setup({**tables.defaults(table), **parameters.get(instance, {})})
        except ValueError as exc:
            raise ValueError(f"{instance}: {exc}") from None


def simulate(fmus, connections, stop_time, step, mode="gauss-seidel", parameters=None,
             recorder=None, start_time=0.0):
    """Co-simulate FMUs with the fixed-step master.

    Parameters
    ----------
    fmus : dict
        ``{instance name: .fmu path}``.
    connections : list of Connection
    stop_time, step : float
        Stop time and communication step [s]; the step must divide the interval.
    mode : {"gauss-seidel", "jacobi"}
    parameters : dict, optional
        ``{instance: {variable: value}}`` set before initialisation.
    recorder : observer, optional
        Defaults to an :class:`ArrayRecorder`.

    Returns
    -------
    recorder
        The recorder, holding every output at every communication point. On an
        FMU error, a :class:`CsvRecorder` is closed with the rows up to the last
        good step before the :class:`FmiError` propagates.
    """
    communication_points(start_time, stop_time, step)  # fail before loading anything
    for name in parameters or {}:
        if name not in fmus:
            raise KeyError(f"unknown instance {name!r}; instances: {', '.join(fmus)}")
    recorder = ArrayRecorder() if recorder is None else recorder
    instances = {}
    try:
        for name, path in fmus.items():
            instances[name] = open_instance(path, name)
        master = Master(instances, connections, mode)
        master.run(start_time, stop_time, step, [recorder], parameters)
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
