"""``crane-fmu export``: a system, with your FMUs in its places, as an SSP file or as one FMU."""

import os
import shutil
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

from .common import UsageError, writable_file

NAME = "export"
HELP = "write a system, with your FMUs in its places (--use), as an SSP file or as one FMU"
DESCRIPTION = ("Write a built-in system or an SSP file, with the FMUs of --use in its instances' places and the "
               "values of --parameters and --set, as an SSP package (.ssp: OMSimulator, libcosim, Ecos, ...) or as "
               "one FMU (.fmu): one native FMU where every component is a built-in native one, else fmpy's "
               "container FMU of the system's FMUs.")
EXAMPLES = (
    "examples:\n"
    "  crane-fmu export --system transport --use controller=build/mine/PdSway.fmu --out mine.ssp\n"
    "  crane-fmu export --system lqr --use controller=build/mine/PdSway.fmu --out MyLoop.fmu   # a container\n"
    "  crane-fmu export --system lqr --set crane.l2=0.6 --out CraneLqr.fmu   # every component native: one native FMU\n"
    "  crane-fmu export --system transport --use controller=examples/my_controller/pd_sway.py --out mine.ssp"
)


def arguments(p):
    from crane_fmu import DEFAULT_FMU_DIR, DEFAULT_SYSTEM

    p.add_argument("--system", default=DEFAULT_SYSTEM,
                   help=f"a built-in system's name or an SSP file (default: {DEFAULT_SYSTEM})")
    p.add_argument("--fmu-dir", default=DEFAULT_FMU_DIR, help=f"folder of the built FMUs (default: {DEFAULT_FMU_DIR})")
    p.add_argument("--use", action="append", default=[], metavar="INSTANCE=FILE.fmu",
                   help="put this FMU in the instance's place (repeatable); the system's values for it are kept "
                        "where the FMU has them, and a controller is told the move as simulate tells it; a law "
                        "file's Component (controller=mylaw.py[:NAME]) is built as an FMU first")
    p.add_argument("--parameters", metavar="FILE.ssv", help="SSP parameter set (INSTANCE.VARIABLE), before --set")
    p.add_argument("--set", action="append", default=[], metavar="INSTANCE.VARIABLE=VALUE",
                   help="a parameter value written into the file (repeatable); crane.l2=0.6 sets the crane's")
    p.add_argument("--out", required=True, metavar="FILE.ssp|FILE.fmu",
                   help="the file to write: .ssp (an SSP package) or .fmu (one FMU)")


def run(args):
    from .simulate import on_system

    writable_file(args.out, "--out", (".ssp", ".fmu"))
    return on_system(args, _export)


def exported(args, system, built=None):
    """The system as the file carries it: ``--use``'s FMUs (told the move), then ``--parameters`` and ``--set``,
    every value checked by its component's rules. A law file is checked as itself, as simulate checks it, then its
    Component is built as an FMU into the folder ``built`` (a plain law function has none: refused in one line)."""
    from crane_fmu import crane_parameters, systems

    from .simulate import _keep_known, _parameter_file, parse_sets

    _no_plain_laws(system, built)
    fmus, _ = systems.resolve(system, args.fmu_dir)  # a law file as itself: its mistakes name it, not its build
    system = _keep_known(system, fmus, list(system.replaced))
    variables = systems.settable(system, fmus)
    values = [_parameter_file(args.parameters, variables)] if args.parameters else []
    values.append(parse_sets(args.set, variables))
    system, notes = systems.tell_controllers(system, args.fmu_dir, values)
    for note in notes:
        print(f"crane-fmu: note: {note}", file=sys.stderr)
    # the connections as checked (a controller's optional inputs left out), written out: the file's own
    fmus, connections = systems.resolve(system, args.fmu_dir)
    system = replace(system, connections=tuple(connections), match_names=False, replaced={},
                     tags=("yours",) if system.replaced else system.tags)
    for overrides in values:
        system = crane_parameters.with_values(system, overrides)
    systems.check_parameters(systems.bind(system))  # a law file's values by its own rules, as simulate checks them
    return _laws_built(system, built)


def _export(args, system):
    with tempfile.TemporaryDirectory(prefix="crane_export_") as built:
        return _write(args, exported(args, system, built))


def _no_plain_laws(system, folder):
    """Refuse a plain law function (``--use controller=mylaw.py:law``): it has no variables of its own to describe."""
    from crane_fmu import laws

    for name, source in system.instances.items():
        if laws.is_law(source) and (laws.is_plain(source) or folder is None):
            raise UsageError(f"--use {name}={source}: a plain law function runs only in this toolkit's master; "
                             f"write it as a Component (docs/reference/controller-interface.md) to export it")


def _laws_built(system, folder):
    """The system with each law file's Component (``--use controller=mylaw.py[:NAME]``) built as an FMU into
    ``folder`` and in its place."""
    from crane_fmu import laws

    from .build import _build_component

    built = {}
    for name, source in system.instances.items():
        if not laws.is_law(source):
            continue
        component = laws.component(source)
        _build_component(str(laws.law_file(source)), Path(folder) / name, log=lambda line: None)
        built[name] = str(Path(folder) / name / f"{component.model_identifier}.fmu")
    return replace(system, instances={**system.instances, **built})  # in the places the system was made for


def _write(args, system):
    from crane_fmu import systems

    out = Path(args.out)
    if out.suffix == ".ssp":
        systems.write_ssp(system, args.fmu_dir, out)
        print(f"wrote {out} (an SSP package of {', '.join(system.instances)})")
        return 0
    native, why = _native(system)
    if native:
        _one_fmu(system, out)
        print(f"wrote {out} (one native FMU: every component of {system.name} is native)")
    else:
        from crane_fmu.container import build_container

        build_container(system, args.fmu_dir, out)
        print(f"wrote {out} (fmpy's container FMU, FMI 3.0, of {', '.join(system.instances)}: {why})")
    return 0


def _native(system):
    """``(True, None)`` when the system can be one native FMU, else ``(False, why)``."""
    from crane_fmu.build_scripts.native import NativeUnavailable, compilers
    from crane_fmu.build_scripts.one_fmu import not_native

    if "yours" in system.tags:  # a user's FMU runs as itself, never as a native twin of its name
        return False, "your FMU runs as itself"
    missing = not_native(system)
    if missing:
        return False, f"{', '.join(missing)} has no native model"
    try:
        compilers()
    except NativeUnavailable as exc:
        return False, str(exc)
    return True, None


def _one_fmu(system, out):
    """The system as one native FMI 2.0 FMU at ``out`` (model identifier: the file's name, when it is one)."""
    from crane_fmu.build_scripts.one_fmu import build_one_fmu, one_fmu_name

    name = out.stem if out.stem.isidentifier() else one_fmu_name(system.name)
    with tempfile.TemporaryDirectory(prefix="crane_export_") as tmp:
        built = build_one_fmu(system, tmp, 2, name)
        out.parent.mkdir(parents=True, exist_ok=True)
        partial = out.with_name(f".{out.name}.partial")
        shutil.copyfile(built, partial)
        os.replace(partial, out)
