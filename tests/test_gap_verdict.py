"""One verdict, never contradicting itself (issue 20, item 3).

The analysis states a verdict and, per axis, whether the gap after is consistent with noise
(``adequacy["consistent"]``). Both come from the same battery, so on every run they must agree
(:func:`validation.score.contradictions` says how). That is asserted over every run of the
validation set in ``tests/test_validation_score.py`` (on the one analysis of the set the
score tests share); here: that the rule sees a contradiction when there is one, on a real
analysis, and that the bench's report never states "explained" beside an inconsistent
re-simulated gap.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from calib.files.course import Ensayo
from validation.cases import build_case
from validation.score import contradictions


def test_the_rule_finds_each_kind_of_contradiction_on_a_real_analysis():
    from calib.gap import analyze_gap

    case = build_case("catalog", "overshoot", [("misalignment", "x")],
                      np.random.default_rng(7), n=1200)
    a = analyze_gap(Ensayo(case.tita, case.datos, case.t, source="m"), case.noise_var)
    assert a.verdict == "explained" and contradictions("m", a) == []
    flagged = {**a.adequacy, "consistent": {"x": False, "y": True}}
    assert "consistent" in contradictions("m", replace(a, adequacy=flagged))[0]
    assert "nothing named" in contradictions("m", replace(a, effects=()))[0]
    calm = {**a.adequacy, "consistent": {"x": True, "y": True}}
    lines = contradictions("m", replace(a, verdict="unexplained", adequacy=calm))
    assert any("every axis consistent" in line for line in lines)
    assert any("axis-named" in line for line in lines)  # nothing listed as unexplained


def test_bench_never_states_explained_beside_an_inconsistent_resimulated_gap():
    """The bench's report downgrades "explained" when its own re-simulated gap after is not
    consistent (here made so by hand: χ²/dof three times the stated noise on x)."""
    from bench.gap import run_gap

    case = build_case("catalog", "overshoot", [("misalignment", "x")],
                      np.random.default_rng(7), n=1200)
    report = run_gap(Ensayo(case.tita, case.datos, case.t, source="m"), case.noise_var)
    assert report.analysis.verdict == "explained"
    assert report.verdict == "explained" and report.to_dict()["consistent_after"]
    bad = replace(report.gap_after["x"], chi2_dof=3.0)
    worse = replace(report, gap_after={**report.gap_after, "x": bad},
                    chi2_after_stated={**report.chi2_after_stated, "x": 3.0})
    d = worse.to_dict()
    assert d["verdict"] == "unexplained" and not d["consistent_after"]
    assert not d["gap_after"]["x"]["consistent"]
    assert [u["signature"] for u in d["unexplained"]] == ["gap_after"]
    assert all(e["tentative"] for e in d["effects"])
    assert worse.verdict_lines()[0].startswith("verdict: UNEXPLAINED")
