"""The README agrees with the code and with CI."""

import re
from pathlib import Path

from crane_fmu.cli import main

ROOT = Path(__file__).resolve().parent.parent


def test_readme_variable_tables_are_generated_from_the_tables(capsys):
    main(["info", "--markdown"])
    generated = capsys.readouterr().out.strip()
    readme = (ROOT / "README.md").read_text()
    section = re.search(r"<!-- variables:start -->\n(.*)\n<!-- variables:end -->", readme, re.S).group(1)
    assert section.strip() == generated


def test_ci_runs_the_readme_test_command():
    readme = (ROOT / "README.md").read_text()
    command = re.search(r"## Run the tests\n\n```\n(.*?)\n```", readme, re.S).group(1)
    assert command in (ROOT / ".ci" / "run").read_text()


def test_the_readme_python_example_runs(fmu_dir, tmp_path):
    """The README's "From Python" block, as a user runs it: in a folder with build/fmus."""
    import subprocess
    import sys

    readme = (ROOT / "README.md").read_text()
    block = re.search(r"\*\*From Python\*\*.*?```python\n(.*?)```", readme, re.S).group(1)
    (tmp_path / "build").mkdir()
    (tmp_path / "build" / "fmus").symlink_to(fmu_dir)
    (tmp_path / "example.py").write_text(block)
    done = subprocess.run([sys.executable, "example.py"], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    lines = done.stdout.splitlines()
    assert lines[0] == "paper: largest hook swing 63 deg" and lines[1] == "lqr from 15 deg: 0.0032 deg at 10 s"
    assert (tmp_path / "lqr_15deg.png").stat().st_size > 10_000


def test_the_readme_component_example_is_built_and_scored(fmu_dir, tmp_path, monkeypatch, capsys):
    """The README's PD component, its build and compare commands and its Python script, as a user runs them."""
    import shlex
    import subprocess
    import sys

    readme = (ROOT / "README.md").read_text()
    section = readme.split("## Components and systems: adding a controller")[1]
    module, script = re.findall(r"```python\n(.*?)```", section, re.S)[:2]
    commands = re.search(r"Build its FMUs.*?```\n(.*?)```", section, re.S).group(1).splitlines()
    assert [c.split()[:2] for c in commands] == [["crane-fmu", "build"], ["crane-fmu", "compare"]]
    monkeypatch.chdir(tmp_path)
    (tmp_path / "my_controller.py").write_text(module)
    (tmp_path / "build").mkdir()
    (tmp_path / "build" / "fmus").symlink_to(fmu_dir)  # the built-in FMUs, as `crane-fmu build` leaves them
    for command in commands:
        assert main(shlex.split(command)[1:]) == 0, capsys.readouterr().err
    board = (tmp_path / "results" / "mine" / "quick" / "scoreboard.md").read_text()
    assert "Controllers: `BacksteppingController`, `EnergyController`, `LqrController`, `PdController` (yours)" \
        in board
    assert all(f"| S{i} (QUICK" in board for i in range(1, 8))
    (tmp_path / "script.py").write_text(script)
    done = subprocess.run([sys.executable, "script.py"], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.splitlines()[-1] == "44 cases scored"  # 4 controllers x 11 quick cases, from the journal
