"""``crane-fmu build``: build the FMUs of every component and the files of every built-in system."""

import argparse
import importlib.util
import sys
from pathlib import Path

from crane_fmu import DEFAULT_FMU_DIR

from .common import UsageError, writable_folder

NAME = "build"
HELP = "build the FMUs of every component and the files of every built-in system"
EXAMPLES = (
    "examples:\n"
    "  crane-fmu build                 # makes again only what changed since the last build\n"
    "  crane-fmu build --force         # makes everything again\n"
    "  crane-fmu build --out my/fmus --bench\n"
    "  crane-fmu build --container transport       # build/containers/CraneTransport.fmu\n"
    "  crane-fmu build --container my_system.ssp\n"
    "  crane-fmu build --one-fmu lqr transport      # build/native/CraneLqr.fmu (FMI 3.0: build/native/fmi3)\n"
    "  crane-fmu build --component pd_sway.py --out build/mine        # a component of your own: build/mine,\n"
    "                                                                  # FMI 3.0 in build/mine/fmi3"
)


def arguments(p):
    p.add_argument("--out", default=DEFAULT_FMU_DIR,
                   help=f"FMI 2.0 FMUs (default: {DEFAULT_FMU_DIR}); FMI 3.0 ones and systems/ go beside it")
    p.add_argument("--bench", action="store_true", help="also build the benchmark's trivial FMUs")
    p.add_argument("--force", action="store_true",
                   help="make every file again (by default a file is made again only when what it is made from "
                        "changed: sources, tables, the build's tools)")
    p.add_argument("--native", action=argparse.BooleanOptionalAction, default=None,
                   help="also build the native (C) FMUs into build/native (default: when a C compiler is found)")
    instead = p.add_mutually_exclusive_group()  # separate builds: argparse refuses two
    instead.add_argument("--container", metavar="SYSTEM|FILE.ssp",
                         help="instead: pack one system (a built-in one, or an SSP file) into one FMU in "
                              "build/containers")
    instead.add_argument("--one-fmu", action="extend", nargs="+", metavar="SYSTEM|FILE.ssp",
                         help="instead: write systems of native components (built-in names or SSP files) as one native "
                              "FMU each, FMI 2.0 into build/native and 3.0 into build/native/fmi3 (repeatable)")
    instead.add_argument("--component", metavar="MODULE.py",
                         help="instead: build the components (Component objects) defined in your Python module, "
                              "FMI 2.0 into --out and FMI 3.0 into its fmi3 folder")


def run(args):
    from crane_fmu import components, systems
    from crane_fmu.build_scripts.build_fmus import build_all, container_name, containers_dir
    from crane_fmu.container import build_container

    writable_folder(args.out, f"--out {args.out}")  # a file there: one line, before anything is built
    if args.one_fmu:
        for path in _build_one_fmus(args.one_fmu, args.out):
            print(path)
        return 0
    if args.component:
        _report(_build_component(args.component, args.out, args.force), args.out)
        return 0
    if args.container:
        try:
            with systems.open_system(args.container) as system:
                name = container_name(Path(args.container).stem if args.container.endswith((".ssp", ".ssd"))
                                      else system.name)
                path = build_container(system, args.out, containers_dir(args.out) / f"{name}.fmu")
        except ValueError as exc:
            raise UsageError(str(exc)) from None
        print(path)
        return 0
    kinds = [c.model_identifier for c in components.registered() if args.bench or c.role != "benchmark"]
    from crane_fmu.build_scripts.native import NativeUnavailable

    try:
        built = build_all(args.out, kinds, native=args.native, force=args.force)
    except NativeUnavailable as exc:
        raise UsageError(f"--native: {exc}") from None
    _report(built, Path(args.out).parent)
    return 0


def _report(built, folder):
    """Each file made now, then one line: how many were made and how many were up to date."""
    for path in built.made:
        print(path)
    print(f"{len(built.made)} made, {len(built.kept)} up to date in {folder}"
          + (" (--force makes every file again)" if built.kept else ""))


def _build_one_fmus(items, out):
    """Each system (a built-in name or an SSP file) as one native FMU, FMI 2.0 and 3.0; their paths."""
    from crane_fmu import systems
    from crane_fmu.build_scripts.native import NativeUnavailable, compilers, native_dir
    from crane_fmu.build_scripts.one_fmu import build_one_fmu, one_fmu_name, plan

    try:
        tools = compilers()
    except NativeUnavailable as exc:
        raise UsageError(f"--one-fmu: {exc}") from None
    paths = []
    for checking in (True, False):  # every system checked before any is written
        for item in items:
            try:
                with systems.open_system(item) as system:
                    if checking:
                        plan(system)
                        continue
                    name = one_fmu_name(Path(item).stem if item.endswith((".ssp", ".ssd")) else system.name)
                    for version in (2, 3):
                        paths.append(build_one_fmu(system, native_dir(out, version), version, name, tools))
            except ValueError as exc:
                raise UsageError(f"--one-fmu {item}: {exc}") from None
    return paths


def _build_component(module_path, out, force=False, log=print):
    """Import a user's module by its file and build the FMUs of the components it defines."""
    path = Path(module_path)
    if path.suffix != ".py" or not path.is_file():
        raise UsageError(f"--component {module_path}: expected a Python file (MODULE.py) that defines a Component")
    name = path.stem
    if not name.isidentifier():
        raise UsageError(f"--component {module_path}: {name!r} is not a Python module name; rename the file")
    if name in sys.stdlib_module_names:
        raise UsageError(f"--component {module_path}: {name!r} is a standard library module's name; rename the file")
    saved = sys.modules.get(name)  # another module of that name (e.g. a pythonfmu build's) comes back afterwards
    spec = importlib.util.spec_from_file_location(name, path.resolve())
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # where the build looks for the component's model module
    try:
        try:
            spec.loader.exec_module(module)
        except Exception as exc:  # the user's code: report it in one line
            raise UsageError(f"--component {module_path}: importing it failed: {type(exc).__name__}: {exc}") from None
        return _build_components(module, module_path, out, force, log)
    finally:
        if saved is None:
            sys.modules.pop(name, None)
        else:
            sys.modules[name] = saved


def _build_components(module, module_path, out, force=False, log=print):
    """Register the components a user's module defines, build their FMUs into ``out`` (FMI 3.0: ``out/fmi3``),
    unregister them."""
    from crane_fmu import components, laws
    from crane_fmu.build_scripts.build_fmus import build_all
    from crane_fmu.model.component import Component

    name = module.__name__
    found = [v for v in vars(module).values() if isinstance(v, Component) and v.module == name]
    if not found:
        raise UsageError(f"--component {module_path}: defines no Component (crane_fmu.model.component.Component)")
    for component in found:  # no built-in's name, no bug in configure: as a law file of it is checked
        try:
            laws.usable(component, module_path)
        except ValueError as exc:
            raise UsageError(f"--component {exc}") from None
    try:
        for component in found:
            components.register(component)
        return build_all(out, [c.model_identifier for c in found], systems=[], containers=[], force=force,
                         fmi3_out=Path(out) / "fmi3", log=log)
    except ValueError as exc:
        raise UsageError(f"--component {module_path}: {exc}") from None
    finally:
        for component in found:
            components.unregister(component.model_identifier)
