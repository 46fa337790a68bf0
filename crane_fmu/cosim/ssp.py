"""Reads an SSP 1.0 system (``.ssp`` package or ``.ssd`` file): FMUs, connections, parameter values."""

import contextlib
import shutil
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from collections import namedtuple
from pathlib import Path

from .master import Connection
from .system import check_fmu

SSD = "{http://ssp-standard.org/SSP1/SystemStructureDescription}"
SSV = "{http://ssp-standard.org/SSP1/SystemStructureParameterValues}"
System = namedtuple("System", "fmus connections parameters")
System.__doc__ = "``fmus`` {instance: path}, ``connections`` [Connection], ``parameters`` {instance: {name: value}}."
_CONVERT = {"Real": float, "Integer": int, "Boolean": lambda v: v.lower() in ("true", "1"), "String": str}


@contextlib.contextmanager
def load_system(path):
    """Yield the :class:`System` of an SSP file; an ``.ssp`` package is unpacked for the duration.

    Raises
    ------
    ValueError
        One line naming the file and what is wrong with it.
    """
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"system file {path} not found")
    workdir = None
    try:
        if path.suffix == ".ssp":
            workdir = Path(tempfile.mkdtemp(prefix="crane_ssp_"))
            try:
                with zipfile.ZipFile(path) as package:
                    package.extractall(workdir)
            except zipfile.BadZipFile:
                raise ValueError(f"{path} is not an SSP package (not a zip file)") from None
            ssd = workdir / "SystemStructure.ssd"
            if not ssd.is_file():
                raise ValueError(f"{path} holds no SystemStructure.ssd")
        else:
            ssd = path
        yield _parse(ssd, path)
    finally:
        if workdir is not None:
            shutil.rmtree(workdir, ignore_errors=True)


def _parse(ssd, origin):
    try:
        root = ET.parse(ssd).getroot()
    except ET.ParseError as exc:
        raise ValueError(f"{origin}: SystemStructure.ssd is not valid XML ({exc})") from None
    system = root.find(f"{SSD}System")
    if root.tag != f"{SSD}SystemStructureDescription" or system is None:
        raise ValueError(f"{origin}: not an SSP 1.0 SystemStructureDescription")
    fmus, parameters = {}, {}
    for component in system.iter(f"{SSD}Component"):
        name, source = component.get("name"), component.get("source")
        fmu = (ssd.parent / source) if source else None
        if fmu is None or not fmu.is_file():
            raise ValueError(f"{origin}: component {name!r} has no FMU at {source!r}")
        check_fmu(fmu)
        fmus[name] = fmu
        values = parameters.setdefault(name, {})
        for parameter in component.iter(f"{SSV}Parameter"):
            for kind, convert in _CONVERT.items():
                node = parameter.find(f"{SSV}{kind}")
                if node is not None:
                    values[parameter.get("name")] = convert(node.get("value"))
    connections = [Connection(c.get("startElement"), c.get("startConnector"), c.get("endElement"),
                              c.get("endConnector")) for c in system.iter(f"{SSD}Connection")]
    for c in connections:
        for instance in (c.source, c.target):
            if instance not in fmus:
                raise ValueError(f"{origin}: a connection names the unknown component {instance!r}")
    return System(fmus, connections, parameters)
