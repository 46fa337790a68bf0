"""The Section V runs against reference results written before the component registry (tests/data),
with the CSV recorder of that time (%.17g); the CSV written now must parse to the same doubles."""

from pathlib import Path

import numpy as np
import pytest

from crane_fmu import systems
from crane_fmu.cosim import ArrayRecorder, CsvRecorder, read_csv, run

DATA = Path(__file__).parent / "data"


@pytest.mark.parametrize("case, system, parameters", [
    ("paper", "paper", {}),
    ("free", "free", {}),
    ("w110", "paper", {"controller": {"w_theta2": 0.0}}),
])
def test_section5_runs_equal_the_reference_results(fmu_dir, case, system, parameters, tmp_path):
    """Same equations, same integrator, same exchange order: bit for bit, in memory and through the CSV."""
    reference = read_csv(DATA / f"section5_{case}.csv")
    chosen = systems.get(system).with_parameters(parameters)
    in_memory = run(chosen, fmu_dir, recorder=ArrayRecorder()).columns()
    run(chosen, fmu_dir, recorder=CsvRecorder(tmp_path / "run.csv"))
    for result in (in_memory, read_csv(tmp_path / "run.csv")):
        for name, values in reference.items():
            got = result[name][::100]
            assert len(got) == len(values) == 201
            assert np.array_equal(got, values), name  # every value parses to the same double
