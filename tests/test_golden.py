"""The Section V runs against reference results written before the component registry (tests/data)."""

from pathlib import Path

import numpy as np
import pytest

from crane_fmu import systems
from crane_fmu.cosim import ArrayRecorder, read_csv, run

DATA = Path(__file__).parent / "data"


@pytest.mark.parametrize("case, system, parameters", [
    ("paper", "paper", {}),
    ("free", "free", {}),
    ("w110", "paper", {"controller": {"w_theta2": 0.0}}),
])
def test_section5_runs_equal_the_reference_results(fmu_dir, case, system, parameters):
    """Same equations, same integrator, same exchange order: equal to 1e-12 (measured: bit for bit)."""
    reference = read_csv(DATA / f"section5_{case}.csv")
    result = run(systems.get(system).with_parameters(parameters), fmu_dir, recorder=ArrayRecorder()).columns()
    for name, values in reference.items():
        got = result[name][::100]
        assert len(got) == len(values) == 201
        assert np.abs(got - values).max() <= 1e-12, name
