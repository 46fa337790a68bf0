"""A misspelt name of a system, instance, variable or controller: the one-line error that lists the choices also
names the nearest one (difflib), and only a near one."""

import pytest

from crane_fmu.cli import main
from crane_fmu.cosim.suggest import did_you_mean

pytestmark = pytest.mark.quick  # no build: the names are checked before any FMU is read


@pytest.mark.parametrize("name, expected", [
    ("lqe", "; did you mean 'lqr'?"), ("LQR", "; did you mean 'lqr'?"), ("hoist_transport", "; did you mean "
                                                                         "'hoist-transport'?"),
    ("nowhere", ""), ("lqr", "")])
def test_the_nearest_name_is_suggested_and_a_far_one_is_not(name, expected):
    assert did_you_mean(name, ["paper", "free", "lqr", "energy", "transport", "hoist-transport"]) == expected


def test_case_aside_the_same_name_wins_over_a_nearer_spelling():
    assert did_you_mean("U_max", ["x_max", "u_max", "v_max"]) == "; did you mean 'u_max'?"


@pytest.mark.parametrize("argv, message", [
    (["simulate", "--system", "lqe"], "no system 'lqe'; systems: paper, free, lqr, "),
    (["info", "--system", "trasnport"], "no system 'trasnport'; systems: paper, free, lqr, "),
    (["compare", "--controller", "LqrControler", "--out", "{tmp}/board"], "no controller 'LqrControler'; "
                                                                          "controllers: BacksteppingController, "),
])
def test_a_misspelt_name_is_one_line_with_the_choices_and_the_nearest(argv, message, tmp_path, capsys):
    assert main([a.replace("{tmp}", str(tmp_path)) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err
    wanted = {"lqe": "lqr", "trasnport": "transport", "LqrControler": "LqrController"}
    assert err.endswith(f"; did you mean '{next(v for k, v in wanted.items() if k in argv)}'?\n")
    assert not (tmp_path / "board").exists()
