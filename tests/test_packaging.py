"""The installed package: one top-level module, crane_fmu, with the FMI sources and build scripts inside."""

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_wheel_adds_only_crane_fmu_to_site_packages(tmp_path):
    source = tmp_path / "src"
    source.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy2(ROOT / name, source)
    for name in ("crane_fmu", "fmu_src", "build_scripts"):
        shutil.copytree(ROOT / name, source / name, ignore=shutil.ignore_patterns("__pycache__"))
    subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(tmp_path / "wheel"),
                    str(source)], check=True, capture_output=True, timeout=600)
    (wheel,) = (tmp_path / "wheel").glob("*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    assert {n.split("/")[0] for n in names if ".dist-info/" not in n} == {"crane_fmu"}
    c_sources = [f"crane_fmu/{p.relative_to(ROOT).as_posix()}" for p in (ROOT / "fmu_src").rglob("*")
                 if p.suffix in (".c", ".h")]
    assert {path.split("/")[2] for path in c_sources} == {"framework", "models", "python", "system", "host"}
    for path in ("crane_fmu/fmu_src/python/slave2.py", *c_sources, "crane_fmu/build_scripts/build_fmus.py",
                 "crane_fmu/sweep/builtin/region_of_attraction.toml"):
        assert path in names
    packages = [p.parent.relative_to(ROOT).as_posix() for p in (ROOT / "crane_fmu").rglob("__init__.py")]
    assert all(f"{package}/__init__.py" in names for package in packages), packages  # crane_fmu/commands too
