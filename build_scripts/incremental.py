"""The incremental build: an output is made again only when what it is made from changed.

Every output has a key, a SHA-256 of everything it is made from: the source files by content
(the Python core an FMU bundles, the C sources, this build's own code), the component's variable
table, the system's data, the FMUs a system file packs, and the tools (this Python, pythonfmu,
fmpy, the C compilers and their versions). ``.crane-build.json`` in the build's folder records each
output's key and the SHA-256 of the file written; an output whose key and file both match is kept.
Where an input is hard to name exactly, a whole folder is hashed: a needless rebuild costs seconds,
a missed one a stale FMU.

The record is read and written under a lock on the build's folder, so builds running at once
(test workers sharing one build) take turns and each finds the others' outputs.
"""

import functools
import hashlib
import importlib.metadata
import json
import os
import shutil
import subprocess
import sys
import sysconfig
import threading
from contextlib import contextmanager
from pathlib import Path

import crane_fmu
import crane_fmu.fmu_src
from crane_fmu import components

RECORD = ".crane-build.json"
FORMAT = 1  # the version of the keys: another one makes every output again
PACKAGE = Path(crane_fmu.__file__).parent
MODEL = PACKAGE / "model"
COSIM = PACKAGE / "cosim"
CLOSED_LOOP = PACKAGE / "closed_loop.py"  # the interface of a closed loop as one FMU (one-FMU and container)
CRANE = PACKAGE / "crane_parameters.py"  # which instances the crane's parameters bind (the files, the loops' interface)
FMU_SRC = Path(crane_fmu.fmu_src.__file__).parent
HERE = Path(__file__).parent


class Record:
    """The outputs made so far and what each was made from; :meth:`make` keeps or makes one output.

    Attributes
    ----------
    made, kept : list of Path
        The outputs made in this build, and those kept as they were.
    """

    def __init__(self, root=None, force=False):
        """``root``: the build's folder, where the record is kept (None: a build that keeps nothing)."""
        self.root, self.force = (Path(root).resolve() if root is not None else None), force
        self.made, self.kept, self.entries = [], [], {}
        self._lock = threading.Lock()  # the native builds run on threads (native.in_parallel)
        try:
            record = json.loads((self.root / RECORD).read_text()) if root is not None else {}
            if record.get("format") == FORMAT:
                self.entries = dict(record["outputs"])
        except (OSError, ValueError, KeyError, TypeError, AttributeError):
            pass

    def _name(self, path):
        path = Path(path).resolve()
        return str(path.relative_to(self.root)) if path.is_relative_to(self.root) else str(path)

    def fresh(self, path, key):
        """True when ``path`` was made from inputs of this ``key`` and is unchanged since (never with ``force``)."""
        if self.root is None or self.force:
            return False
        entry = self.entries.get(self._name(path))
        return (entry is not None and entry["key"] == key and Path(path).is_file()
                and file_digest(path) == entry["output"])

    def make(self, path, key, produce):
        """``path`` as it is when fresh (:meth:`fresh`), else made by ``produce()`` (which returns it) and recorded."""
        if self.fresh(path, key):
            with self._lock:
                self.kept.append(Path(path))
            return Path(path)
        made = Path(produce())
        with self._lock:
            self.made.append(made)
            if self.root is not None:
                self.entries[self._name(made)] = {"key": key, "output": file_digest(made)}
                self._write()
        return made

    def _write(self):
        partial = self.root / f".{RECORD}.partial"
        partial.write_text(json.dumps({"format": FORMAT, "outputs": self.entries}, indent=1, sort_keys=True))
        os.replace(partial, self.root / RECORD)


@contextmanager
def building(root, force=False):
    """Yield the :class:`Record` of the build folder ``root`` (made if missing), holding its lock."""
    root = Path(root)
    root.mkdir(parents=True, exist_ok=True)
    with open(root / ".crane-build.lock", "w") as lock:
        try:
            import fcntl
        except ImportError:  # not POSIX: builds at once are not coordinated
            fcntl = None
        if fcntl is not None:
            fcntl.flock(lock, fcntl.LOCK_EX)
        yield Record(root, force)


@functools.lru_cache(maxsize=4096)
def _content(path, size, mtime_ns):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def file_digest(path):
    """SHA-256 of a file's content (read once per file version: path, size, modification time)."""
    stat = Path(path).stat()
    return _content(str(Path(path).resolve()), stat.st_size, stat.st_mtime_ns)


def _files(folder, skip=()):
    """Every file under ``folder`` but those in a subfolder named in ``skip`` and bytecode caches, sorted."""
    return sorted(p for p in Path(folder).rglob("*") if p.is_file() and "__pycache__" not in p.parts
                  and not set(p.relative_to(folder).parts[:-1]) & set(skip))


def key(*parts):
    """SHA-256 of ``parts``: a Path by its name and content (a folder: every file in it), anything else by repr."""
    digest = hashlib.sha256(f"crane-build {FORMAT}".encode())
    for part in parts:
        if isinstance(part, Path):
            for path in _files(part) if part.is_dir() else [part]:
                digest.update(f"\0{path.name}\0{file_digest(path)}".encode())
        else:
            digest.update(b"\0" + repr(part).encode())
    return digest.hexdigest()


def component_data(component):
    """What the build reads of a component descriptor besides its module's source (its functions are there):
    every field that is data, whatever fields the descriptor gains, and the output dependencies."""
    import dataclasses

    data = [(f.name, _data(getattr(component, f.name))) for f in dataclasses.fields(component)
            if not callable(getattr(component, f.name))]
    return data + [("dependencies", component.dependencies())] if hasattr(component, "dependencies") else data


def _data(value):
    """``value`` with each function in it (e.g. in the plant's ``continuous``) by its name, not by its repr: the
    repr holds the function's address, another in every process, and would make every build anew."""
    import dataclasses

    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return type(value).__name__, tuple((f.name, _data(getattr(value, f.name))) for f in dataclasses.fields(value))
    if isinstance(value, (list, tuple)):
        return tuple(_data(item) for item in value)
    if isinstance(value, dict):
        return tuple((key, _data(item)) for key, item in value.items())
    if callable(value) and not isinstance(value, type):
        return f"{getattr(value, '__module__', '')}.{getattr(value, '__qualname__', repr(type(value)))}"
    return value


@functools.cache
def tool(command):
    """``(path, first line of --version)`` of a program on PATH, or None."""
    path = shutil.which(command)
    if path is None:
        return None
    try:
        done = subprocess.run([path, "--version"], capture_output=True, text=True, timeout=30)
        return path, (done.stdout or done.stderr).strip().splitlines()[0] if (done.stdout or done.stderr) else ""
    except (OSError, subprocess.SubprocessError):
        return path, None


def _version(distribution):
    try:
        return importlib.metadata.version(distribution)
    except importlib.metadata.PackageNotFoundError:
        return None


def python_tools():
    """This Python (its bytecode, its libpython and headers) and the packages that build and read the FMUs."""
    config = {name: sysconfig.get_config_var(name) for name in ("LDLIBRARY", "INSTSONAME", "LIBDIR")}
    return (sys.version, sys.implementation.cache_tag, config, sysconfig.get_paths()["include"],
            tool(os.environ.get("CC", "cc")) or tool("gcc"),
            {name: _version(name) for name in ("pythonfmu", "pythonfmu3", "fmpy")})


def python_fmu_key(component, fmi_version, sources):
    """A Python FMU: the core it bundles (``sources``), its table, the wrapper's C sources, the build, the tools."""
    wrapper_sources = [*_files(FMU_SRC / "framework"), *_files(FMU_SRC / "python")]
    build = [HERE / name for name in ("build_fmus.py", "model_description.py", "wrapper.py")]
    return key("python", fmi_version, component_data(component), *sources, *wrapper_sources, *build,
               python_tools())


def _compilers(tools):
    return {platform: compiler and tool(compiler) for platform, compiler in tools.items()}


def native_key(component, fmi_version, tools, files):
    """A native FMU: its table, the C sources it is compiled from (``files``), the tables its XML is written with,
    the build, the compilers."""
    build = [HERE / name for name in ("native.py", "model_description.py", "wrapper.py")]
    return key("native", fmi_version, component_data(component), *files, MODEL / "tables.py", *build,
               _compilers(tools), _version("fmpy"))


def one_fmu_key(system, kinds, fmi_version, tools, files):
    """A system as one native FMU: the system's data, its components' tables, the C sources it is compiled from
    (``files``), the closed loop's interface."""
    build = [HERE / name for name in ("one_fmu.py", "native.py", "model_description.py", "wrapper.py")]
    return key("one-fmu", fmi_version, repr(system), [component_data(components.get(k)) for k in kinds], *files,
               MODEL / "tables.py", CLOSED_LOOP, CRANE, *build, _compilers(tools), _version("fmpy"))


def system_file_key(kind, system, fmus, *writers):
    """A system file (SSP, OSP, container FMU): the system's data, the FMUs it names or packs, the modules that
    write it."""
    return key(kind, repr(system), *[Path(p) for p in fmus], COSIM, *writers, _version("fmpy"), sys.version)


def container_key(system, fmus):
    """A container FMU: a system file written by container.py with the closed loop's interface."""
    return system_file_key("container", system, fmus, PACKAGE / "container.py", CLOSED_LOOP, CRANE)
