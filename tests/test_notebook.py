"""The tutorial as a Jupyter notebook (examples/tutorial.ipynb), executed as a user runs it after `crane-fmu build`.

Every cell runs without an error in a folder laid out as a clone (build/fmus, examples/); the cells'
own assertions (each command's exit status) hold; the loop analysis it shows is of a stable loop and the
tuned law damps the swing better than no swing feedback.
"""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOK = ROOT / "examples" / "tutorial.ipynb"


def test_the_tutorial_notebook_runs_as_written(fmu_dir, tmp_path):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    (tmp_path / "build").mkdir()
    (tmp_path / "build" / "fmus").symlink_to(fmu_dir)
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    assert all(not cell.get("outputs") for cell in notebook.cells if cell.cell_type == "code")  # saved clean
    nbclient.NotebookClient(notebook, timeout=120, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    text = "\n".join(o.get("text", "") for cell in notebook.cells if cell.cell_type == "code"
                     for o in cell.outputs)
    assert "closed loop: stable" in text and (tmp_path / "results" / "nb-loop.png").is_file()
    left = {float(k): float(v) for k, v in re.findall(r"k_s = (\S+) m/s: \|theta1\| over the last second <= (\S+) rad",
                                                        text)}
    assert set(left) == {0.0, 2.0, 4.0} and left[2.0] < left[0.0] / 2 and left[4.0] < left[0.0] / 2
