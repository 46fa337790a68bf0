"""Opening an FMU: the one place where its FMI version chooses the adapter."""

from .instance import read_fmu


def open_instance(path, name):
    """An instance of the FMU at ``path`` (FMI 2.0 or 3.0 co-simulation), named ``name``; a law file
    (``mylaw.py``: a source registered in :mod:`~crane_fmu.cosim.in_process`) runs in this process."""
    from .in_process import kind_of

    if kind_of(path) is not None:
        return kind_of(path).instance(path, name)
    if read_fmu(path).fmiVersion.startswith("3"):
        from .fmi3 import Fmi3Instance as Adapter  # fmpy is imported with the first FMU opened
    else:
        from .fmi2 import Fmi2Instance as Adapter
    return Adapter(path, name)
