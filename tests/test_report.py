"""The verdict rules of REPORT.md, each applied to made-up summaries (no simulation)."""

import copy

import pytest

from crane_fmu.analysis.paper_cases import ALTERNATIVE, PAPER_LAW
from crane_fmu.analysis.report import CLAIMS

pytestmark = pytest.mark.quick  # no build: in the quick subset

FORMS = (*PAPER_LAW, ALTERNATIVE)
NOT, PARTLY, ONLY_ALTERNATIVE = "not reproduced", "partly", "partly (only without the theta2 row)"


def _loop(**over):
    return {"outcome": "converges", "completed": True, "end_time_s": 30.0, "settling_0.5deg_s": 8.0,
            "corr_theta1_theta2": 0.9, "residual_after_15s_deg": 0.1, **over}


def _good():
    """A summary in which every claim holds."""
    return {
        "fig4": [{"theta1_0_deg": 10.0, "max_theta1_deg": 10.0, "max_theta2_deg": 16.5, "freqs_theta1_hz": [0.5, 1.2],
                  "freqs_theta2_hz": [1.2, 0.5], "ratio_max_theta2_to_theta1_0": 1.65}],
        "fig5": [{"l2": 0.25, "max_theta2_deg": 20.0, "freqs_theta1_hz": [0.45], "rms_theta1_deg": 5.0},
                 {"l2": 0.5, "max_theta2_deg": 15.0, "freqs_theta1_hz": [0.5], "rms_theta1_deg": 6.0}],
        "fig7": {"open loop": _loop(), **{form: _loop() for form in FORMS}},
        "fig8": {form: [{"l1": l1, "outcome": "converges", "max_theta2_deg": t2, "rms_theta1_deg": rms,
                         "settling_0.5deg_s": ts, "trolley_excursion_m": ex}
                        for l1, t2, rms, ts, ex in ((0.5, 10, 1, 8, 1.0), (1.0, 13, 2, 9, 0.8), (1.5, 15, 3, 10, 0.6))]
                 for form in FORMS},
        "region_of_attraction": {form: {"largest_converging_deg": 20.0} for form in FORMS},
        "linear": {"closed_loop_poles": {form: [[-1.0, 2.0], [-1.0, -2.0]] for form in FORMS}},
    }


def _set(path, value, forms=PAPER_LAW):
    """A mutation setting ``summary[...path...] = value`` for each of ``forms`` (``{form}`` in the path)."""
    def mutate(s):
        for form in forms:
            node = s
            keys = [form if k == "{form}" else k for k in path]
            for k in keys[:-1]:
                node = node[k]
            node[keys[-1]] = value(node[keys[-1]]) if callable(value) else value
    return mutate


def _fig8(key, values, forms=PAPER_LAW):
    def mutate(s):
        for form in forms:
            for row, v in zip(s["fig8"][form], values):
                row[key] = v
    return mutate


CASES = [
    (0, lambda s: s["fig4"][0].update(max_theta2_deg=9.0), NOT),
    (0, lambda s: s["fig4"][0].update(freqs_theta2_hz=[0.4]), NOT),
    (1, lambda s: s["fig4"][0].update(ratio_max_theta2_to_theta1_0=1.79), PARTLY),
    (1, lambda s: s["fig4"][0].update(ratio_max_theta2_to_theta1_0=2.0), NOT),
    (2, lambda s: s["fig5"][1].update(max_theta2_deg=25.0), NOT),
    (3, lambda s: s["fig5"][1].update(freqs_theta1_hz=[0.45]), PARTLY),
    (3, lambda s: s["fig5"][1].update(freqs_theta1_hz=[0.45], rms_theta1_deg=5.0), NOT),
    (4, _set(("fig7", "{form}", "settling_0.5deg_s"), None), ONLY_ALTERNATIVE),
    (4, _set(("fig7", "{form}", "settling_0.5deg_s"), 16.0, FORMS), NOT),
    (5, _set(("fig7", "{form}", "outcome"), "sustained oscillation"), ONLY_ALTERNATIVE),
    (5, _set(("fig7", "{form}", "corr_theta1_theta2"), 0.2, FORMS), NOT),
    (6, _set(("fig7", "{form}", "residual_after_15s_deg"), 0.6), ONLY_ALTERNATIVE),
    (6, _set(("fig7", "{form}", "residual_after_15s_deg"), None, FORMS), NOT),
    (7, _fig8("max_theta2_deg", (15, 13, 10)), ONLY_ALTERNATIVE),
    (7, _fig8("outcome", ("converges", "diverges", "converges"), FORMS), NOT),
    (8, _fig8("max_theta2_deg", (10, 20, 30)), ONLY_ALTERNATIVE),
    (8, _fig8("max_theta2_deg", (5, 8, 11), FORMS), NOT),
    (9, _fig8("settling_0.5deg_s", (10, 9, 8)), ONLY_ALTERNATIVE),
    (9, _fig8("settling_0.5deg_s", (8, None, 10), FORMS), NOT),
    (10, _fig8("trolley_excursion_m", (1.0, 0.9, 0.85)), ONLY_ALTERNATIVE),
    (10, _fig8("trolley_excursion_m", (0.6, 0.8, 1.0), FORMS), NOT),
    (11, _set(("fig7", "{form}", "outcome"), "diverges"), ONLY_ALTERNATIVE),
    (11, _set(("fig7", "{form}", "outcome"), "sustained oscillation", FORMS), NOT),
    (12, _set(("region_of_attraction", "{form}", "largest_converging_deg"), 2.0), "partly (only locally)"),
    (12, _set(("linear", "closed_loop_poles", "{form}"), [[0.1, 1.0], [0.1, -1.0]]), NOT),
]


def test_there_are_thirteen_claims_and_all_hold_in_the_good_summary():
    s = _good()
    assert len(CLAIMS) == 13
    assert [c.verdict(s) for c in CLAIMS] == ["reproduced"] * 13
    assert all(c.measure(s) for c in CLAIMS)  # every measurement renders


@pytest.mark.parametrize("index, mutate, verdict", CASES)
def test_each_rule_gives_its_verdict(index, mutate, verdict):
    s = copy.deepcopy(_good())
    mutate(s)
    assert CLAIMS[index].verdict(s) == verdict


def test_every_claim_has_a_case_that_fails_it():
    assert sorted({index for index, _, _ in CASES}) == list(range(13))
