"""Shared fixtures: the FMUs are built once per test session into a temporary folder."""

import pytest

from build_scripts.build_fmus import BENCH_FMUS, CRANE_FMUS, build_all


@pytest.fixture(scope="session")
def fmu_dir(tmp_path_factory):
    """Folder holding freshly built CranePlant, BacksteppingController and the trivial FMUs."""
    out = tmp_path_factory.mktemp("fmus")
    build_all(out, CRANE_FMUS + BENCH_FMUS)
    return out


@pytest.fixture(scope="session")
def crane_fmus(fmu_dir):
    return {"plant": fmu_dir / "CranePlant.fmu", "controller": fmu_dir / "BacksteppingController.fmu"}
