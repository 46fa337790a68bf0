"""The README and the documentation site (docs/) agree with the code and with CI; the site builds."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

from crane_fmu.cli import main

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
PAGES = [ROOT / "README.md"] + sorted(DOCS.rglob("*.md"))  # every page a user reads


def test_the_variable_tables_are_generated_from_the_tables(capsys):
    """docs/reference/variables.md holds what `crane-fmu info --markdown` prints (the one generator)."""
    main(["info", "--markdown"])
    generated = capsys.readouterr().out.strip()
    page = (DOCS / "reference" / "variables.md").read_text()
    section = re.search(r"<!-- variables:start -->\n(.*)\n<!-- variables:end -->", page, re.S).group(1)
    assert section.strip() == generated


def test_ci_runs_the_readme_test_command():
    readme = (ROOT / "README.md").read_text()
    command = re.search(r"## Run the tests\n\n```\n(.*?)\n```", readme, re.S).group(1)
    assert command in (ROOT / ".ci" / "run").read_text()


def test_the_quick_start_plot_says_what_it_compares():
    """The README's quick start ends with a titled plot that says only the LQR limits u (issue 29), and the
    tutorial runs the same plot command."""
    readme = (ROOT / "README.md").read_text()
    command = re.search(r"## Quick start.*?```\n(.*?)\n```", readme, re.S).group(1)
    plot = command.split(" && ")[-1]
    assert plot.startswith(".venv/bin/crane-fmu plot results/paper.csv results/lqr.csv --out results/section5.png")
    title = re.search(r'--title "(.*)"$', plot).group(1)
    assert "u unlimited" in title and "LQR (|u| <= 2 m/s2)" in title
    assert plot.removeprefix(".venv/bin/") in (DOCS / "tutorial.md").read_text()
    # after the .venv/bin/ quick start, bare crane-fmu and fmpy: the README says to activate the venv
    assert "activate the virtual environment first\n(`. .venv/bin/activate`)" in readme


def test_the_stop_times_the_docs_state_are_the_systems():
    """"Built-in systems run 20 s" was wrong (transport runs 10 s): the command line page names each exception."""
    from crane_fmu import systems

    page = " ".join((DOCS / "guide" / "command-line.md").read_text().split())  # lines joined
    assert "1 ms for every built-in one; 20 s, except" in page
    for system in systems.registered():
        assert system.step == 1e-3
        if system.stop_time != 20.0:
            assert f"{system.stop_time:g} s for `{system.name}`" in page, system.name


def test_the_readme_python_example_runs(fmu_dir, tmp_path):
    """The "From Python" block of the interoperability recipes, as a user runs it: in a folder with build/fmus.

    Its printed figures are not pinned to today's digits: the paper's swing must be the one the README
    states elsewhere (doc-sync), the LQR's residual must meet the LQR's settling target (requirement).
    """
    import subprocess
    import sys

    readme = "\n".join(page.read_text() for page in PAGES)
    recipes = (DOCS / "guide" / "interoperability.md").read_text()
    block = re.search(r"## From Python\n.*?```python\n(.*?)```", recipes, re.S).group(1)
    (tmp_path / "build").mkdir()
    (tmp_path / "build" / "fmus").symlink_to(fmu_dir)
    (tmp_path / "example.py").write_text(block)
    done = subprocess.run([sys.executable, "example.py"], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    lines = done.stdout.splitlines()
    # doc-sync: the paper's swing the example prints is the limit cycle the README's controller table states
    paper = re.fullmatch(r"paper: largest hook swing (\d+) deg", lines[0])
    assert paper and f"(+-{paper.group(1)} deg limit cycle)" in readme, lines[0]
    # requirement: the LQR's target is 0.1 deg within 4 s from 10 deg; from 15 deg it is well inside by 10 s
    lqr = re.fullmatch(r"lqr from 15 deg: (\d+\.\d{4}) deg at 10 s", lines[1])
    assert lqr and float(lqr.group(1)) < 0.1, lines[1]
    assert (tmp_path / "lqr_15deg.png").stat().st_size > 10_000


def _marked_blocks(text):
    """``(language, code)`` of each fenced block that follows a ``<!-- test: run -->`` line."""
    return re.findall(r"<!-- test: run -->\n```(\w*)\n(.*?)```", text, re.S)


def test_every_marked_block_runs_as_written(fmu_dir, tmp_path):
    """The marked blocks of the README and of every docs page, as a user runs them after `crane-fmu build`:
    shell blocks line by line with the installed commands on PATH (`set -e`: any failing line fails),
    Python blocks with this interpreter, in a folder whose build/ is this session's build."""
    import os

    blocks = [block for page in PAGES for block in _marked_blocks(page.read_text())]
    assert len(blocks) >= 8
    (tmp_path / "build").symlink_to(fmu_dir.parent)
    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}")
    for language, code in blocks:
        command = [sys.executable, "-c", code] if language == "python" else ["bash", "-e", "-c", code]
        done = subprocess.run(command, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=900)
        assert done.returncode == 0, f"{code}\n{done.stdout[-1000:]}{done.stderr[-2000:]}"
        if "libcosimpy" in code:
            assert done.stdout.startswith("20000 samples, theta1 = ") and done.stdout.endswith(" rad at 20.0 s\n")


def test_the_readme_component_example_is_built_and_scored(fmu_dir, tmp_path, monkeypatch, capsys):
    """The PD component of the controller interface page, its build and compare commands and its Python
    script, as a user runs them."""
    import shlex

    page = (DOCS / "reference" / "controller-interface.md").read_text()
    section = page.split("## Components and systems: adding a controller")[1]
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
    assert "Controllers: `BacksteppingController`, `EnergyController`, `HardHitController`, `LqrController`, " \
        "`PdController` (yours)" \
        in board
    assert all(f"| S{i} (QUICK" in board for i in range(1, 4)) and "| S3 (QUICK: 16 cases)" in board
    (tmp_path / "script.py").write_text(script)
    done = subprocess.run([sys.executable, "script.py"], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.splitlines()[-1] == "90 cases scored"  # 5 controllers x (1 + 1 + 16) cases, from the journal


def test_the_site_builds_strictly(tmp_path):
    """`mkdocs build --strict`: a broken link, a missing page or an API docstring that does not render fails."""
    pytest.importorskip("mkdocs")
    pytest.importorskip("mkdocstrings")
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-d", str(tmp_path / "site")],
                          cwd=ROOT, capture_output=True, text=True, timeout=600,
                          env={**__import__("os").environ, "NO_MKDOCS_2_WARNING": "1"})
    assert done.returncode == 0, done.stderr[-3000:]
    api = (tmp_path / "site" / "reference" / "api" / "index.html").read_text()
    assert "crane_fmu.cosim.system.simulate" in api and "recorder_for" in api  # generated from the docstrings
    nav = re.findall(r"^\s+- [^:]+: (\S+\.md)$", (ROOT / "mkdocs.yml").read_text(), re.M)
    assert set(nav) == {str(p.relative_to(DOCS)) for p in DOCS.rglob("*.md")}  # every page is in the navigation


def test_readme_and_docs_link_only_to_files_that_exist():
    """The README's links (into docs/) and the docs' relative links resolve."""
    for page in PAGES:
        for target in re.findall(r"\]\(([^)#:]+)(?:#[^)]*)?\)", page.read_text()):
            assert (page.parent / target).exists(), f"{page.name}: {target}"


def test_license_and_ignored_outputs():
    """The LICENSE is the MIT text pyproject names; every output the README and the docs make is ignored by git."""
    import shutil

    assert 'license = { text = "MIT" }' in (ROOT / "pyproject.toml").read_text()
    assert (ROOT / "LICENSE").read_text().startswith("MIT License\n")
    if not shutil.which("git") or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    text = "\n".join("\n".join(re.findall(r"```\w*\n(.*?)```", page.read_text(), re.S)) for page in PAGES)
    outputs = set(re.findall(r"(?:--out|--output-file|--plot|--dest)[ =](\S+)", text)) | {"lqr_15deg.png"}
    outputs = {o for o in outputs if not o.startswith(("DIR", "FILE", "x."))}
    assert len(outputs) >= 15, outputs
    for output in outputs:
        done = subprocess.run(["git", "check-ignore", "-q", "--no-index", output], cwd=ROOT)
        assert done.returncode == 0, f"{output} is not in .gitignore"
