"""No silent skip in CI: with CI=true a skipped check fails the run and says why; locally it skips."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

SKIPPING = """
import pytest

def test_needs_a_compiler():
    pytest.skip("no C compiler")

def test_needs_libcosim():
    pytest.importorskip("no_such_module_libcosim")
"""


@pytest.mark.parametrize("ci, returncode", [("true", 1), (None, 0)])
def test_a_skip_fails_the_run_in_ci_only(tmp_path, ci, returncode):
    (tmp_path / "test_skipping.py").write_text(SKIPPING)
    env = {k: v for k, v in os.environ.items() if k != "CI"}
    env["PYTHONPATH"] = str(Path(__file__).parent)
    if ci:
        env["CI"] = ci
    proc = subprocess.run([sys.executable, "-m", "pytest", "-p", "required_checks", "-p", "no:cacheprovider",
                           "-rA", "test_skipping.py"], cwd=tmp_path, env=env, capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == returncode, proc.stdout[-3000:]
    if ci:
        assert "2 failed" in proc.stdout
        assert "skipped in CI (CI=true), where every check is required: Skipped: no C compiler" in proc.stdout
        assert "could not import 'no_such_module_libcosim'" in proc.stdout
    else:
        assert "2 skipped" in proc.stdout
