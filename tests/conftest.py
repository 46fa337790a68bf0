"""Shared fixtures: the FMUs of every registered component are built once per test session."""

import pytest

from crane_fmu import components, systems
from crane_fmu.build_scripts.build_fmus import build_all

pytest_plugins = ["required_checks"]  # CI=true: a skipped test fails the run


@pytest.fixture(scope="session")
def fmu_dir(tmp_path_factory):
    """Folder holding freshly built FMUs of every registered component (FMI 3.0 ones in ../fmi3)."""
    out = tmp_path_factory.mktemp("build") / "fmus"
    build_all(out, [c.model_identifier for c in components.registered()])
    return out


@pytest.fixture(scope="session")
def crane_fmus(fmu_dir):
    """``{instance: FMU path}`` of the built-in ``paper`` system."""
    return systems.get("paper").fmus(fmu_dir)


@pytest.fixture(scope="session")
def connections(fmu_dir):
    """The connections of the built-in ``paper`` system (plant state -> controller, u -> plant)."""
    return systems.get("paper").resolve(fmu_dir)[1]
