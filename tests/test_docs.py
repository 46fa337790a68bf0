"""The README and the documentation site (docs/) agree with the code and with CI; the site builds."""

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from crane_fmu.cli import main

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
PAGES = [ROOT / "README.md"] + sorted(DOCS.rglob("*.md"))  # every page a user reads


@pytest.mark.quick
def test_the_variable_tables_are_generated_from_the_tables(capsys):
    """docs/reference/variables.md holds what `crane-fmu info --markdown` prints (the one generator)."""
    main(["info", "--markdown"])
    generated = capsys.readouterr().out.strip()
    page = (DOCS / "reference" / "variables.md").read_text()
    section = re.search(r"<!-- variables:start -->\n(.*)\n<!-- variables:end -->", page, re.S).group(1)
    assert section.strip() == generated


@pytest.mark.quick
def test_ci_runs_the_readme_test_command():
    readme = (ROOT / "README.md").read_text()
    command = re.search(r"## Run the tests\n\n(?:<!-- test: [^\n]*-->\n)?```\n(.*?)\n```", readme, re.S).group(1)
    assert command in (ROOT / ".ci" / "run").read_text()


@pytest.mark.quick
def test_the_quick_start_plot_says_what_it_compares():
    """The README's quick start, in short lines, installs what the five tasks need and ends with a titled plot
    that says only the LQR limits u; the tutorial runs the same simulate and plot commands."""
    readme = (ROOT / "README.md").read_text()
    block = re.search(r"## Quick start.*?```\n(.*?)\n```", readme, re.S).group(1)
    assert all(len(line) <= 100 for line in block.splitlines()), block
    assert ".venv/bin/pip install -e '.[plot,dask]'" in block  # plot: tasks 1 and 3; dask: compare and sweep
    commands = block.replace("\\\n", "").splitlines()
    plot = commands[-1]
    assert plot.startswith("crane-fmu plot results/paper.csv results/lqr.csv --out results/section5.png")
    title = re.search(r'--title "(.*)"$', plot).group(1)
    assert "u unlimited" in title and "LQR (|u| <= 2 m/s2)" in title
    tutorial = (DOCS / "tutorial.md").read_text()
    for command in commands[4:]:
        assert " ".join(command.split()) in tutorial, command
    assert ". .venv/bin/activate" in commands  # bare crane-fmu and fmpy from here on
    home = (DOCS / "index.md").read_text()
    assert re.search(r"## Quick start.*?```\n(.*?)\n```", home, re.S).group(1) == block  # the home page's too
    assert "](images/section5.png)" in home  # with the picture the plot command makes


def _command_lines(code):
    """The commands of a shell block: one per line, comments and repeated spaces dropped."""
    return {" ".join(line.split("  #")[0].split()) for line in code.splitlines() if line.strip()}


def test_every_command_of_the_readme_tasks_is_run():
    """The five tasks' commands, as written, are lines of blocks the suite runs (marked ``run``, or the
    controller example's), or named here with the reason they are not run."""
    not_run = {"crane-fmu sweep builtin:region-of-attraction --out results/roa":
               "240 runs of 20 s; tests/test_sweep.py runs studies of the same kind, smaller"}
    readme = (ROOT / "README.md").read_text()
    tasks = " ".join(readme.split("## The five commonest tasks")[1].split("\nAlso: ")[0].split())
    commands = re.findall(r"`((?:crane-fmu|fmpy) [^`]+)`", tasks)
    assert len(commands) >= 8, commands
    page = (DOCS / "reference" / "controller-interface.md").read_text()
    ran = set().union(*[_command_lines(code) for p in PAGES for language, code in _marked_blocks(p.read_text())
                        if language == ""],
                      _command_lines(re.search(r"Build it, run it.*?```\n(.*?)```", page, re.S).group(1)))
    for command in commands:
        assert command in ran or command in not_run, command


@pytest.mark.quick
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


MARKER = re.compile(r"<!-- test: (run|transcript|runs in (tests/\w+\.py)::(\w+)|not run: .+) -->")


def _blocks(text):
    """``(marker line or None, language, code)`` of each fenced block."""
    return re.findall(r"(?:(<!-- test: [^\n]*-->)\n)?```(\w*)\n(.*?)```", text, re.S)


def _marked_blocks(text, kind="run"):
    """``(language, code)`` of each fenced block that follows a ``<!-- test: run -->`` (or ``transcript``) line."""
    return [(language, code) for marker, language, code in _blocks(text) if marker == f"<!-- test: {kind} -->"]


def test_every_block_of_the_docs_says_how_it_is_tested():
    """Every fenced block of the README and the docs follows a marker: run here as written (``run``), a
    command and the start of its answer (``transcript``), run by a named test (``runs in tests/F.py::name``,
    which must exist), or ``not run:`` with the reason."""
    for page in PAGES:
        for marker, _, code in _blocks(page.read_text()):
            found = MARKER.fullmatch(marker or "")
            assert found, f"{page.relative_to(ROOT)}: a block without a test marker: {code[:80]!r}"
            if found.group(2):
                assert f"def {found.group(3)}(" in (ROOT / found.group(2)).read_text(), marker


def _clone(tmp_path, fmu_dir, copy=False):
    """A folder laid out as a user's clone after `crane-fmu build`: examples/, and build/ (this session's, or
    a copy of it when what runs there may write into build/)."""
    if copy:
        shutil.copytree(fmu_dir.parent, tmp_path / "build", symlinks=True)
    else:
        (tmp_path / "build").symlink_to(fmu_dir.parent)
    (tmp_path / "examples").symlink_to(ROOT / "examples")


def test_every_marked_block_runs_as_written(fmu_dir, tmp_path):
    """The marked blocks of the README and of every docs page, in page order, as a user runs them after
    `crane-fmu build`, in a folder laid out as a clone whose build/ is a copy of this session's (a block may
    write into build/; the session's build is shared by every test): ``run`` blocks (shell blocks line by line
    with the installed commands on PATH, `set -e`: any failing line fails; Python blocks with this interpreter),
    and ``transcript`` blocks: ``$ command`` and the first line of its answer, with ``...`` for what varies."""
    import os

    blocks = [(marker, language, code) for page in PAGES for marker, language, code in _blocks(page.read_text())
              if marker in ("<!-- test: run -->", "<!-- test: transcript -->")]
    assert sum(marker.endswith("run -->") for marker, _, _ in blocks) >= 8
    assert sum(marker.endswith("transcript -->") for marker, _, _ in blocks) >= 2
    _clone(tmp_path, fmu_dir, copy=True)
    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}")
    for marker, language, code in blocks:
        if marker.endswith("transcript -->"):
            command, expected = code.splitlines()[:2]
            assert command.startswith("$ "), code
            done = subprocess.run(["bash", "-c", command[2:]], cwd=tmp_path, env=env, capture_output=True,
                                  text=True, timeout=600)
            answer = (done.stderr or done.stdout).splitlines()[0]
            assert re.fullmatch(".*?".join(map(re.escape, expected.split("..."))), answer), f"{command}\n{answer}"
            continue
        command = [sys.executable, "-c", code] if language == "python" else ["bash", "-e", "-c", code]
        done = subprocess.run(command, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=900)
        assert done.returncode == 0, f"{code}\n{done.stdout[-1000:]}{done.stderr[-2000:]}"
        if "libcosimpy" in code:
            assert done.stdout.startswith("20000 samples, theta1 = ") and done.stdout.endswith(" rad at 20.0 s\n")


def test_the_controller_example_is_built_simulated_and_scored(native, tmp_path, monkeypatch, capsys):
    """The controller example of the controller interface page (the README's task 3 and the tutorial's section 6
    name the same commands), as a user runs it in a clone: build, simulate, compare, and the Python script. The
    built-in FMUs in its build/fmus are the native ones (held to the Python FMUs' board to 1e-9 by
    test_native_board.py): the example's own controller is a Python FMU as the page builds it, the built-in LQR
    beside it runs its 58 quick cases in C instead of Python."""
    import shlex

    from crane_fmu.cosim import read_csv

    page = (DOCS / "reference" / "controller-interface.md").read_text()
    section = page.split("## Your own controller, step by step")[1].split("\n## ")[0]
    module, script = re.findall(r"```python\n(.*?)```", section, re.S)
    assert module == (ROOT / "examples" / "my_controller" / "pd_sway.py").read_text()
    commands = re.search(r"Build it, run it.*?```\n(.*?)```", section, re.S).group(1).splitlines()
    assert [c.split()[:2] for c in commands] == [["crane-fmu", "build"], ["crane-fmu", "simulate"],
                                                 ["crane-fmu", "compare"]]
    tutorial = (DOCS / "tutorial.md").read_text().split("## 6. Your own controller")[1]
    readme = " ".join((ROOT / "README.md").read_text().split("3. **Try your own controller**")[1]
                      .split("4. **")[0].split())
    for command in commands:
        assert command in tutorial and f"`{command}`" in readme, command
    monkeypatch.chdir(tmp_path)
    (tmp_path / "examples" / "my_controller").mkdir(parents=True)
    (tmp_path / "examples" / "my_controller" / "pd_sway.py").write_text(module)
    (tmp_path / "build").mkdir()
    (tmp_path / "build" / "fmus").symlink_to(native[2])  # every built-in component, as a build leaves them
    for command in commands:
        assert main(shlex.split(command)[1:]) == 0, capsys.readouterr().err
    written = sorted(str(p.relative_to(tmp_path / "build")) for p in (tmp_path / "build").rglob("*.fmu")
                     if not p.is_relative_to(tmp_path / "build" / "fmus"))
    assert written == ["mine/PdSway.fmu", "mine/fmi3/PdSway.fmu"]  # everything under --out, nothing else
    assert "it is told the move's target, controller.x_d = 2 m" in capsys.readouterr().err
    run = read_csv(tmp_path / "results" / "mine.csv")
    assert abs(run["plant.x"][-1] - 2.0) <= 0.005  # the page: within 5 mm of the 2 m at the end of the run
    board = (tmp_path / "results" / "mine" / "quick" / "scoreboard.md").read_text()
    assert "Controllers: `LqrController`, `PdSway` (yours)" in board
    assert all(f"| S{i} (QUICK" in board for i in range(1, 4)) and "| S3 (QUICK: 16 cases)" in board
    (tmp_path / "script.py").write_text(script)
    done = subprocess.run([sys.executable, "script.py"], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.splitlines()[-1] == "36 cases scored"  # 2 controllers x (1 + 1 + 16) cases, from the journal


def test_the_site_builds_strictly(tmp_path):
    """`mkdocs build --strict`: a broken link, a missing page or an API docstring that does not render fails."""
    pytest.importorskip("mkdocs")
    pytest.importorskip("mkdocstrings")
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-d", str(tmp_path / "site")],
                          cwd=ROOT, capture_output=True, text=True, timeout=600,
                          env={**__import__("os").environ, "NO_MKDOCS_2_WARNING": "1"})
    assert done.returncode == 0, done.stderr[-3000:]
    home = (tmp_path / "site" / "index.html").read_text()
    assert "stylesheets/extra.css" in home and "images/section5.png" in home
    css = (DOCS / "stylesheets" / "extra.css").read_text()  # long command lines wrap; names in tables do not break
    assert re.search(r"\.md-typeset pre > code \{[^}]*white-space: pre-wrap", css)
    assert re.search(r"\.md-typeset table:not\(\[class\]\) code \{[^}]*white-space: nowrap", css)
    api = (tmp_path / "site" / "reference" / "api" / "index.html").read_text()
    assert "crane_fmu.cosim.system.simulate" in api and "recorder_for" in api  # generated from the docstrings
    nav = re.findall(r"^\s+- [^:]+: (\S+\.md)$", (ROOT / "mkdocs.yml").read_text(), re.M)
    assert set(nav) == {str(p.relative_to(DOCS)) for p in DOCS.rglob("*.md")}  # every page is in the navigation


@pytest.mark.quick
def test_readme_and_docs_link_only_to_files_that_exist():
    """The README's links (into docs/) and the docs' relative links resolve."""
    for page in PAGES:
        for target in re.findall(r"\]\(([^)#:]+)(?:#[^)]*)?\)", page.read_text()):
            assert (page.parent / target).exists(), f"{page.name}: {target}"


@pytest.mark.quick
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


@pytest.mark.quick
def test_the_docs_name_every_built_in_one_fmu():
    """The lists of the one-FMUs `crane-fmu build` writes named `CraneOpenLoop3d.fmu` but not `CraneLqr3d.fmu`,
    `CraneLqr3dMove.fmu` and `CraneLqr3dPath.fmu`, which it writes too: each page lists every one of them."""
    from crane_fmu import systems
    from crane_fmu.build_scripts.one_fmu import not_native, one_fmu_name

    built = [name for name in systems.tagged("one-fmu") if not not_native(systems.get(name))]
    assert "lqr3d-path" in built
    interoperability = (DOCS / "guide" / "interoperability.md").read_text()
    assert [name for name in built if f"`{one_fmu_name(name)}.fmu`" not in interoperability] == []
    readme = (ROOT / "README.md").read_text()
    one_fmu_section = readme[readme.index("## One FMU for your tool"):readme.index("## Where it runs")]
    assert [name for name in built if f"`{name}`" not in one_fmu_section] == []
