"""The safety envelope's requirement counted on a board's rows (crane_fmu/analysis/envelope.py), on made-up rows."""

import pytest

from crane_fmu.analysis import envelope


def _row(controller, scenario, case, residual, peak):
    return {"controller": controller, "scenario": scenario, "case": case, "status": "ok", "residual_deg": residual,
            "peak_swing_deg": peak}


def test_the_cases_worse_than_the_lqr_and_above_the_nominal_peak_are_counted():
    """S2's MPC peak 15 deg: the bound 17 deg. Of three S9 cases, one is worse than the LQR by 0.06 deg (> 0.05),
    one by 0.04 (not counted), and one peaks at 17.5 deg."""
    rows = [_row("MpcController", "S2", "nominal", 0.003, 15.0), _row("LqrController", "S2", "nominal", 0.01, 9.0),
            _row("MpcController", "S9", "#1", 0.16, 12.0), _row("LqrController", "S9", "#1", 0.10, 8.0),
            _row("MpcController", "S9", "#2", 0.14, 16.9), _row("LqrController", "S9", "#2", 0.10, 8.0),
            _row("MpcController", "S9", "#3", 0.05, 17.5), _row("LqrController", "S9", "#3", 0.10, 8.0)]
    found, bound = envelope.violations(rows)
    assert bound == 17.0
    cases, worse, higher, excess = found["S9"]
    assert (cases, worse, higher) == (3, 1, 1) and excess == pytest.approx(0.06)
    assert found["S2"][:3] == (1, 0, 0)


def test_without_the_nominal_move_the_peak_is_not_judged():
    rows = [_row("MpcController", "S9", "#1", 0.2, 30.0), _row("LqrController", "S9", "#1", 0.1, 8.0)]
    found, bound = envelope.violations(rows)
    assert bound is None and found["S9"] == (1, 1, None, pytest.approx(0.1))
