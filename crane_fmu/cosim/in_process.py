"""Sources that run in this process instead of an FMU file, registered by the application (:func:`register`)."""

_KINDS = []


def register(kind):
    """Add ``kind``: an object with ``matches(source)``, ``model_description(source)`` (fmpy's) and
    ``instance(source, name)`` (an :class:`~crane_fmu.cosim.instance.Instance`)."""
    if kind not in _KINDS:
        _KINDS.append(kind)


def kind_of(source):
    """The registered kind that runs ``source``, or None (an FMU file)."""
    return next((k for k in _KINDS if k.matches(source)), None)
