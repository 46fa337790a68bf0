"""What the commands share: the one-line usage error, number and value parsing, file checks."""

import argparse
import importlib.util
import math
import os
import socket
import sys
from pathlib import Path

from crane_fmu import DEFAULT_FMU_DIR


class UsageError(Exception):
    """A mistake in the command line: one line, exit status 2."""


class Parser(argparse.ArgumentParser):
    def error(self, message):
        raise UsageError(message)


def number(text):
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return value


def dask_options(p):
    """The options that sweep and compare share: the FMUs, the Dask workers, the progress bar."""
    p.add_argument("--fmu-dir", default=DEFAULT_FMU_DIR, help=f"folder of the built FMUs (default {DEFAULT_FMU_DIR})")
    p.add_argument("--workers", type=int, default=None, help="local worker processes (default: one per core)")
    p.add_argument("--scheduler", help="address of an existing Dask scheduler (no local cluster)")
    p.add_argument("--dashboard", metavar="HOST:PORT",
                   help="where the local cluster's Dask dashboard listens (default 127.0.0.1 at a port the OS picks: "
                        "this machine only; another address lets any machine that reaches it watch the run); compare "
                        "runs on a local Dask cluster only when it is given (else in a local process pool)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


LARGEST_SWING = math.pi / 2  # rad: no swing the model is meant for is larger


def convert(text, fmi_type, unit=None, infinite=False):
    """A --set value as the variable's FMI type; an angle may be given in degrees (``10deg``, ``5deg/s``).

    ``infinite``: a Real may be ``INF`` or ``-INF`` (any case; a limit's "no limit", which the component's rules
    refuse where a value must be finite); NaN never. A ValueError (or argparse's) names the value and the rule."""
    if fmi_type in ("Real", "Float64", "Float32"):
        for suffix, si in (("deg/s", "rad/s"), ("deg", "rad")):
            if text.endswith(suffix):
                if unit != si:
                    raise ValueError(f"{text!r}: a {suffix} value needs a variable in {si}, this one is in {unit}")
                return math.radians(number(text[:-len(suffix)]))
        if infinite and text.strip().lower().lstrip("+-") in ("inf", "infinity"):
            return float(text)
        return number(text)
    if fmi_type in ("Integer", "Int32"):
        return int(text)
    if fmi_type == "Boolean":
        if text.lower() not in ("true", "false", "1", "0"):
            raise ValueError(f"{text!r} is not a Boolean (true, false, 1, 0)")
        return text.lower() in ("true", "1")
    return text


def parse_sets(items, variables):
    """``["plant.l1=1.5"]`` -> ``{"plant": {"l1": 1.5}}``, checked against ``variables``.

    ``variables`` is ``{instance: {name: (FMI type, unit)}}`` of the parameters and inputs. An
    angle given without a unit and larger than any swing the model is meant for gets a warning.
    """
    from crane_fmu.cosim.system import split_name

    result = {}
    for item in items:
        target, sep, text = item.partition("=")
        try:
            if not sep:
                raise ValueError("expected INSTANCE.VARIABLE=VALUE")
            instance, name = split_name(target, variables)
            fmi_type, unit = variables[instance][name]
            value = convert(text, fmi_type, unit, infinite=True)
        except (argparse.ArgumentTypeError, ValueError) as exc:
            raise UsageError(f"--set {item!r}: {exc}") from None
        if unit == "rad" and not text.endswith("deg") and abs(value) > LARGEST_SWING:
            print(f"crane-fmu: warning: {instance}.{name} = {value:g} rad ({math.degrees(value):.0f} deg); "
                  f"for degrees write {text}deg", file=sys.stderr)
        result.setdefault(instance, {})[name] = value
    return result


def writable_file(path, option, suffix=None):
    """One line, exit 2, unless ``path`` can be written: not a folder, an accepted suffix, a writable folder.

    ``suffix`` is one suffix (``".png"``) or a tuple of the accepted ones, named in the message. Nothing is
    created here: a folder that does not exist yet must be creatable (its nearest existing parent a writable
    folder); the writer creates it when it writes, so a refused command leaves no empty folder behind.
    """
    suffixes = (suffix,) if isinstance(suffix, str) else tuple(suffix or ())
    if Path(path).is_dir() or str(path).endswith(os.sep):
        example = Path(path) / ("result" + (suffixes[0] if suffixes else ""))
        raise UsageError(f"{option} {path}: is a folder; give a file name, e.g. {example}")
    if suffixes and Path(path).suffix not in suffixes:
        names = suffixes[0] if len(suffixes) == 1 else ", ".join(suffixes[:-1]) + " or " + suffixes[-1]
        raise UsageError(f"{option} {path}: writes a {names} file; the name must end in {names}")
    writable_folder(Path(path).resolve().parent, f"{option} {path}")


def writable_folder(folder, what):
    """One line, exit 2, unless ``folder`` is a writable folder or can be created (without creating it)."""
    folder = Path(folder).resolve()
    existing = folder
    while not existing.exists():
        existing = existing.parent
    if not existing.is_dir():
        raise UsageError(f"{what}: cannot create folder {folder} ({existing} is a file)")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise UsageError(f"{what}: folder {existing} is not writable")


def check_scheduler(address, timeout=3.0):
    """One line, exit 2, unless a server answers at a ``tcp://HOST:PORT`` (or ``HOST:PORT``) scheduler address.

    Dask itself retries a refused connection for 30 s and then raises a long ``OSError``; this asks once.
    Other protocols (``tls://``, ``ucx://``, ...) are left to Dask.
    """
    protocol, sep, rest = address.rpartition("://")
    if sep and protocol != "tcp":
        return
    host, colon, port = rest.rpartition(":")
    if not colon or not port.isdigit():
        raise UsageError(f"--scheduler {address}: expected an address tcp://HOST:PORT, e.g. tcp://127.0.0.1:8786")
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=timeout).close()
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__.replace("Error", " error").strip()
        raise UsageError(f"--scheduler {address}: no Dask scheduler answers there ({reason}); start one with "
                         f"`dask scheduler` or leave out --scheduler for a local cluster") from None


def check_workers(args):
    """--workers, and with --scheduler (where the command has it) not both: one line each."""
    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers must be >= 1, got {args.workers}")
    if args.workers is not None and getattr(args, "scheduler", None):
        raise UsageError("--workers and --scheduler exclude each other: the scheduler's cluster has its workers")
    if getattr(args, "dashboard", None) is not None and getattr(args, "scheduler", None):
        raise UsageError("--dashboard and --scheduler exclude each other: the scheduler's cluster has its dashboard")
    if getattr(args, "scheduler", None):
        check_scheduler(args.scheduler)
    if getattr(args, "dashboard", None) is not None:
        from crane_fmu import batch
        from crane_fmu.serve import is_loopback, parse_endpoint

        try:
            host, port = parse_endpoint(args.dashboard, "--dashboard")
        except ValueError as exc:
            raise UsageError(str(exc)) from None
        batch.DASHBOARD = f"{host}:{port}"
        where = "" if is_loopback(host) else " (any machine that reaches it can watch the run)"
        print(f"crane-fmu: the Dask dashboard listens on {host}:{port}{where}", file=sys.stderr)


def require_dask(command):
    """One line, exit 2, when Dask (the ``dask`` extra) is not installed: before anything is written."""
    if importlib.util.find_spec("distributed") is None:
        raise UsageError(f"{command} runs its cases on Dask, which is not installed: "
                         "pip install -e '.[dask]' (in this project's venv)")
