"""Where ``crane-fmu build`` puts what it builds, beside the folder of the FMI 2.0 FMUs (``build/fmus``)."""

from pathlib import Path


def fmi3_dir(out_dir):
    """Where the FMI 3.0 FMUs go: ``build/fmi3`` next to ``build/fmus``."""
    return Path(out_dir).parent / "fmi3"


def native_dir(out_dir, fmi_version=2):
    """Where the native FMUs go: ``build/native`` (FMI 2.0) and ``build/native/fmi3`` beside ``build/fmus``."""
    base = Path(out_dir).parent / "native"
    return base if fmi_version == 2 else base / "fmi3"


def systems_dir(out_dir):
    """Where the system files go: ``build/systems`` next to ``build/fmus``."""
    return Path(out_dir).parent / "systems"


def containers_dir(out_dir):
    """Where the container FMUs go: ``build/containers`` next to ``build/fmus``."""
    return Path(out_dir).parent / "containers"


def container_name(system_name):
    """``paper`` -> ``CranePaper``: the container FMU's file and model name."""
    return "Crane" + "".join(part.capitalize() for part in system_name.replace("-", "_").split("_"))
