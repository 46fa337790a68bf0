"""A control law as a plain Python file, run without building an FMU (``--use controller=mylaw.py``).

- The law file runs in ``simulate`` and ``compare`` and gives the same bits as the FMU built from it
  later (``crane-fmu build --component``): the same runtime runs the same Python code on the same doubles.
- A plain function ``law(config, state, inputs)`` runs too, as a stateless controller of the measured state.
- A mistake in the file (missing, an import that fails, no such name, a rule broken) is one line, exit 2.
"""

import shutil
from pathlib import Path

import numpy as np
import pytest

from crane_fmu.build_scripts.build_fmus import build_all
from crane_fmu.cli import main
from crane_fmu.cosim import read_csv

ROOT = Path(__file__).resolve().parents[1]
PD_SWAY = ROOT / "examples" / "my_controller" / "pd_sway.py"

PLAIN = '''
def law(config, state, inputs):
    """The PdSway example's law at its default gains, as a bare function."""
    x, dx, theta1, dtheta1, theta2, dtheta2 = inputs
    u = -1.0 * (x - 0.0) - 1.5 * dx + 2.0 * dtheta1
    return (max(-2.0, min(2.0, u)),)
'''


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    """The plant, planner and LQR (the systems' designs) and the PdSway example built as its user builds it."""
    out = tmp_path_factory.mktemp("laws")
    build_all(out / "fmus", ["CranePlant", "TrajectoryPlanner", "LqrController"], systems=[], containers=[],
              native=False, fmi3=False, log=lambda line: None)
    assert main(["build", "--component", str(PD_SWAY), "--out", str(out / "mine")]) == 0
    return out


def _run(capsys, fmus, tmp_path, system, use, *more):
    out = tmp_path / f"{len(list(tmp_path.iterdir()))}.csv"
    code = main(["simulate", "--system", system, "--fmu-dir", str(fmus / "fmus"), "--use", use, "--out", str(out),
                 *more])
    err = capsys.readouterr().err
    assert code == 0, err
    return read_csv(out), err


def _same_bits(a, b):
    assert list(a) == list(b)
    for name in a:
        assert np.array_equal(np.asarray(a[name]).view(np.uint64), np.asarray(b[name]).view(np.uint64)), name


@pytest.mark.parametrize("system", ["transport", "lqr"])
def test_the_law_file_gives_the_bits_of_the_fmu_built_from_it(fmus, tmp_path, capsys, system):
    law, law_err = _run(capsys, fmus, tmp_path, system, f"controller={PD_SWAY}", "--set", "controller.k_s=1.5")
    fmu, fmu_err = _run(capsys, fmus, tmp_path, system, f"controller={fmus / 'mine' / 'PdSway.fmu'}",
                        "--set", "controller.k_s=1.5")
    _same_bits(law, fmu)
    if system == "transport":  # told the move's target as its x_d, as the FMU is, and it takes the load there
        assert "x_d = 2 m" in law_err and "x_d = 2 m" in fmu_err
        assert abs(law["plant.x"][-1] - 2.0) < 0.05


def test_a_plain_function_runs_as_the_component_of_the_same_arithmetic(fmus, tmp_path, capsys):
    (tmp_path / "mylaw.py").write_text(PLAIN)
    law, _ = _run(capsys, fmus, tmp_path, "lqr", f"controller={tmp_path / 'mylaw.py'}:law")
    fmu, _ = _run(capsys, fmus, tmp_path, "lqr", f"controller={fmus / 'mine' / 'PdSway.fmu'}")
    _same_bits(law, fmu)
    assert abs(law["plant.theta1"][0]) > 0.1 and abs(law["plant.theta1"][-1]) < 0.5 * abs(law["plant.theta1"][0])


@pytest.mark.parametrize("use, message", [
    ("controller={tmp}/none.py", "none.py not found"),
    ("controller={tmp}/broken.py", "importing broken.py failed: ZeroDivisionError"),
    ("controller={tmp}/plain.py:missing", "plain.py defines no component or function 'missing'"),
    ("controller={tmp}/two.py", "expected one Component in two.py"),
    ("controller={tmp}/law.txt", "is neither an FMU file (.fmu) nor a law file (.py, .py:NAME)"),
])
def test_a_bad_law_file_is_one_line(fmus, tmp_path, capsys, use, message):
    (tmp_path / "broken.py").write_text("1 / 0\n")
    (tmp_path / "plain.py").write_text(PLAIN)
    (tmp_path / "two.py").write_text(PD_SWAY.read_text() + "\nfrom dataclasses import replace\n"
                                     "OTHER = replace(COMPONENT, model_identifier='PdOther')\n")
    code = main(["simulate", "--system", "lqr", "--fmu-dir", str(fmus / "fmus"), "--use", use.format(tmp=tmp_path),
                 "--out", str(tmp_path / "x.csv")])
    err = capsys.readouterr().err
    assert code == 2 and message in err and err.count("\n") == 1, err
    assert not (tmp_path / "x.csv").exists()


def test_a_broken_rule_of_the_law_is_one_line_before_it_runs(fmus, tmp_path, capsys):
    code = main(["simulate", "--system", "lqr", "--fmu-dir", str(fmus / "fmus"), "--use", f"controller={PD_SWAY}",
                 "--set", "controller.k_x=-1", "--out", str(tmp_path / "x.csv")])
    err = capsys.readouterr().err
    assert code == 2 and "k_x must be > 0 and finite, got -1" in err and err.count("\n") == 1, err


def test_compare_scores_the_law_file_as_its_fmu(fmus, tmp_path, dask_scheduler):
    """The board's rows of the law file and of its FMU hold the same figures (the law runs in the workers)."""
    pytest.importorskip("distributed")
    from crane_fmu.compare import compare

    copied = tmp_path / "pd_law.py"  # another name than the FMU's: two contenders
    shutil.copy(PD_SWAY, copied)
    text = copied.read_text().replace('"PdSway", "controller"', '"PdLaw", "controller"')
    copied.write_text(text)
    rows = compare(tmp_path / "board", [str(copied), str(fmus / "mine" / "PdSway.fmu")], fmu_dir=fmus / "fmus",
                   quick=True, only=True, scenarios=("S1",), scheduler=dask_scheduler)
    by = {}
    for row in rows:
        by.setdefault(row["controller"], {})[row["case"]] = row
    assert set(by) == {"PdLaw", "PdSway"} and by["PdLaw"].keys() == by["PdSway"].keys()
    own = {"case_id", "controller", "fmus_sha256", "date", "duration_s", "versions"}
    for case, row in by["PdLaw"].items():
        assert row["status"] == "ok"
        figures = [k for k, v in row.items() if k not in own and isinstance(v, float)]
        assert len(figures) >= 5, sorted(row)
        assert {k: row[k] for k in set(row) - own} == {k: by["PdSway"][case][k] for k in set(row) - own}, case


def _law(tmp_path, name, body, identifier="MyLaw"):
    """A law file ``name`` of the PdSway example, its model identifier ``identifier``, ``body`` appended."""
    text = PD_SWAY.read_text().replace('"PdSway", "controller"', f'"{identifier}", "controller"')
    (tmp_path / name).write_text(text + body)
    return tmp_path / name


def _commands(fmus, tmp_path, law):
    """Each command that takes a law file, with the law in the controller's place, writing under ``tmp_path/out``."""
    fmu_dir, out = str(fmus / "fmus"), tmp_path / "out"
    (tmp_path / "study.toml").write_text('system = "lqr"\nstop_time = 1.0\nstep = 0.001\n[parameters]\n'
                                         '"controller.k_x" = [1.0, 2.0]\n')
    return {"simulate": ["simulate", "--system", "lqr", "--fmu-dir", fmu_dir, "--use", f"controller={law}",
                         "--stop-time", "1", "--out", str(out / "x.csv")],
            "compare": ["compare", "--fmu-dir", fmu_dir, "--controller", str(law), "--only", "--scenario", "S1",
                        "--out", str(out)],
            "sweep": ["sweep", str(tmp_path / "study.toml"), "--use", f"controller={law}", "--fmu-dir", fmu_dir,
                      "--out", str(out), "--workers", "1"],
            "linearize": ["linearize", "--loop", "--fmu-dir", fmu_dir, "--system", "lqr", "--use",
                          f"controller={law}"],
            "build": ["build", "--component", str(law), "--out", str(out)]}


@pytest.mark.parametrize("command", ["simulate", "compare", "sweep", "linearize", "build"])
def test_a_bug_in_configure_is_one_line_naming_the_file_and_function(fmus, tmp_path, capsys, command):
    """Anything but a ValueError that ``configure`` raises (a bug, not a rule) is refused before the run, no folder."""
    law = _law(tmp_path, "cfgbug.py", "\nfrom dataclasses import replace\n\n\ndef configure(values):\n"
               "    return values['k_xx']\n\n\nCOMPONENT = replace(COMPONENT, configure=configure)\n")
    code = main(_commands(fmus, tmp_path, law)[command])
    err = capsys.readouterr().err
    assert code == 2 and f"{law}: configure raised KeyError: 'k_xx'" in err and err.count("\n") == 1, err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("command", ["simulate", "compare", "sweep", "linearize", "export", "info", "build"])
def test_a_law_with_a_built_in_components_name_is_refused_in_one_line(fmus, tmp_path, capsys, command):
    """A law's model identifier is never a registered component's: the law would be taken for it (its rules, its
    variables), so every command that loads the file refuses it as ``build --component`` does."""
    law = _law(tmp_path, "impostor.py", "", identifier="LqrController")
    commands = _commands(fmus, tmp_path, law)
    commands["export"] = ["export", "--system", "lqr", "--fmu-dir", str(fmus / "fmus"), "--use", f"controller={law}",
                          "--out", str(tmp_path / "out" / "x.ssp")]
    commands["info"] = ["info", "--system", "lqr", "--use", f"controller={law}"]
    code = main(commands[command])
    err = capsys.readouterr().err
    assert code == 2 and "LqrController is already a component's name; choose another model identifier" in err, err
    assert err.count("\n") == 1 and not (tmp_path / "out").exists(), err


@pytest.mark.parametrize("returned", ["(0.0, 1.0)", "()", "0.0", "(None,)", "('fast',)"])
def test_a_law_that_returns_other_than_its_outputs_is_refused_by_the_runtime(fmus, tmp_path, capsys, returned):
    """The law's value is checked against its outputs where it is computed (the runtime its FMU runs too): the law
    file and the FMU built from it fail with the same line, where two values for one output used to pass."""
    law = _law(tmp_path, "wrong.py", f"\nfrom dataclasses import replace\n\n\ndef law(config, state, inputs):\n"
               f"    return {returned}\n\n\nCOMPONENT = replace(COMPONENT, output=law)\n", identifier="WrongLaw")
    assert main(["build", "--component", str(law), "--out", str(tmp_path / "built")]) == 0
    capsys.readouterr()
    for used in (law, tmp_path / "built" / "WrongLaw.fmu"):
        code = main(["simulate", "--system", "lqr", "--fmu-dir", str(fmus / "fmus"), "--use", f"controller={used}",
                     "--stop-time", "0.1", "--out", str(tmp_path / "x.csv")])
        err = capsys.readouterr().err
        assert code == 1 and f"law must return a tuple of 1 number (u), got {returned}" in err, (used, err)
        assert err.count("\n") == 1 and not (tmp_path / "x.csv").exists(), err


@pytest.mark.quick
@pytest.mark.parametrize("under", ["", "sub"])
def test_build_component_out_at_a_file_is_one_line(tmp_path, capsys, under):
    """``build --component --out`` where a file is (or is on the way) refuses in one line, as the other commands'
    --out does, and leaves the file as it was."""
    blocker = tmp_path / "file.txt"
    blocker.write_text("precious")
    out = blocker / under if under else blocker
    code = main(["build", "--component", str(PD_SWAY), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and f"--out {out}: cannot create folder" in err and f"({blocker} is a file)" in err, err
    assert err.count("\n") == 1 and blocker.read_text() == "precious"


@pytest.mark.parametrize("value, written", [("-1", False), ("2", True)])
def test_export_checks_the_law_files_rules_as_simulate_does(fmus, tmp_path, capsys, value, written):
    """``export --use controller=mylaw.py --set``: the law file's rules refuse a value before anything is written,
    in the line simulate gives (the FMU built from the file used to stand in its place unchecked)."""
    out = tmp_path / "x.ssp"
    code = main(["export", "--system", "lqr", "--fmu-dir", str(fmus / "fmus"), "--use", f"controller={PD_SWAY}",
                 "--set", f"controller.k_x={value}", "--out", str(out)])
    err = capsys.readouterr().err
    if written:
        assert code == 0 and out.is_file(), err
    else:
        assert code == 2 and err == "crane-fmu: error: controller: k_x must be > 0 and finite, got -1.0\n", err
        assert not out.exists()


def test_file_colon_name_takes_a_components_model_identifier_or_its_variable(fmus, tmp_path, capsys):
    """``mylaw.py:NAME``: NAME is the component's model identifier (as the docs and the choice's message name it)
    or the Python variable that holds it; both run the same component, and a NAME of neither lists the choices."""
    law = _law(tmp_path, "two.py", "\nfrom dataclasses import replace\n\n"
               "SOFT = replace(COMPONENT, model_identifier='PdSoft', variables=(parameter('k_x', 0.5, '1/s2', 'soft'),)"
               " + COMPONENT.variables[1:])\n")
    runs = [_run(capsys, fmus, tmp_path, "lqr", f"controller={law}:{name}")[0] for name in ("PdSoft", "SOFT")]
    _same_bits(*runs)
    other, _ = _run(capsys, fmus, tmp_path, "lqr", f"controller={law}:MyLaw")
    assert not np.array_equal(other["plant.x"], runs[0]["plant.x"])  # the other component: k_x 1.0, not 0.5
    code = main(["simulate", "--system", "lqr", "--fmu-dir", str(fmus / "fmus"), "--use", f"controller={law}:Nope",
                 "--out", str(tmp_path / "x.csv")])
    err = capsys.readouterr().err
    assert code == 2 and "two.py defines no component or function 'Nope' (its components: MyLaw, PdSoft)" in err, err


def test_export_names_the_law_file_not_the_fmu_it_builds(fmus, tmp_path, capsys):
    """A law file that does not fit the system's place is named in export's line as simulate names it (its FMU,
    built into a temporary folder, is made only once everything is checked)."""
    law = _law(tmp_path, "wrongout.py", "\nfrom dataclasses import replace\n\n"
               "COMPONENT = replace(COMPONENT, variables=COMPONENT.variables[:-1] + (output('acc', 'm/s2', 'a'),))\n")
    code = main(["export", "--system", "lqr", "--fmu-dir", str(fmus / "fmus"), "--use", f"controller={law}",
                 "--out", str(tmp_path / "x.ssp")])
    err = capsys.readouterr().err
    assert code == 2 and err == f"crane-fmu: error: controller: {law} has no output u, which the system connects to " \
                                "plant.u\n", err
    assert not (tmp_path / "x.ssp").exists()


def test_compare_says_what_to_rename_of_two_laws_of_one_name(tmp_path):
    """Two law functions both called ``law``: rename one of the functions; two law files of one component name:
    give one another model identifier (neither has an FMU file to rename)."""
    from crane_fmu.compare import contenders

    for name in ("a", "b"):
        (tmp_path / f"{name}.py").write_text(PLAIN)
        _law(tmp_path, f"pd_{name}.py", "")
    for chosen, advice in ((["a.py:law", "b.py:law"], "; rename one of the functions"),
                           (["pd_a.py", "pd_b.py"], "; give one of the components another model identifier")):
        with pytest.raises(ValueError) as refused:
            contenders([str(tmp_path / c) for c in chosen], only=True)
        assert str(refused.value).endswith(advice) and "FMU" not in str(refused.value), refused.value
    with pytest.raises(ValueError, match=r"or a law file FILE\.py\[:NAME\]\)"):  # the choices name law files too
        contenders(["NoSuchController"], only=True)
