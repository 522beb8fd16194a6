"""One verdict, never contradicting itself (issue 20, item 3).

The analysis states a verdict and, per axis, whether the gap after is consistent with noise
(``adequacy["consistent"]``). Both come from the same battery (the gap after's χ² against the
stated noise and its signatures are checks of the battery), so on every run:

* "explained" or "nothing_detected" ⇒ every axis consistent, and the gap after's χ²/dof inside
  its two-sided band at the battery's per-check level (or a named noise level on that axis);
* "unexplained" ⇒ at least one axis not consistent, and every failed check names its axis.

Asserted over every run of the validation set (``validation.cases.validation_set``, 90 runs,
≈ 30 s on one core: slow) and, unmarked, over a spread subset of it.
"""

from __future__ import annotations

import os
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context

import pytest

from calib.conventions import AXES
from validation.cases import validation_set
from validation.score import default_analyze


def _contradictions(case) -> list[str]:
    a = default_analyze(case)
    out = []
    consistent = a.adequacy["consistent"]
    alpha = a.adequacy["alpha_check"]
    if a.verdict in ("explained", "nothing_detected"):
        if not all(consistent.values()):
            out.append(f"{case.id}: verdict {a.verdict} but consistent = {consistent}")
        for k, ax in enumerate(AXES):
            gm = a.gap_after_fit[ax]
            lo, hi = gm.chi2_band(alpha)
            if not a.final.state.axes[k].noise_free and not lo <= gm.chi2_dof <= hi:
                out.append(f"{case.id}: verdict {a.verdict} but χ²/dof {ax} = "
                           f"{gm.chi2_dof:.4g} outside [{lo:.4g}, {hi:.4g}]")
    if a.verdict == "explained" and not a.effects:
        out.append(f"{case.id}: explained with nothing named")
    if a.verdict == "nothing_detected" and a.effects:
        out.append(f"{case.id}: nothing detected but {a.named} named")
    if a.verdict == "unexplained":
        if all(consistent.values()):
            out.append(f"{case.id}: unexplained but every axis consistent")
        if not a.unexplained or any(u["axis"] not in (*AXES, "both") for u in a.unexplained):
            out.append(f"{case.id}: unexplained without an axis-named signature")
    return out


def _all(cases) -> list[str]:
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    with ProcessPoolExecutor(2, mp_context=get_context("spawn")) as ex:
        return [line for lines in ex.map(_contradictions, cases, chunksize=4) for line in lines]


@pytest.mark.slow
def test_verdict_and_consistency_agree_on_every_run_of_the_set():
    cases = validation_set(0)
    assert {c.kind for c in cases} == {"catalog", "clean", "out_of_catalog"}
    assert _all(cases) == []


def test_bench_never_states_explained_beside_an_inconsistent_resimulated_gap():
    """The bench's report downgrades "explained" when its own re-simulated gap after is not
    consistent (here made so by hand: χ²/dof three times the stated noise on x)."""
    from dataclasses import replace

    import numpy as np

    from bench.gap import run_gap
    from calib.io import Ensayo
    from validation.cases import build_case

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
