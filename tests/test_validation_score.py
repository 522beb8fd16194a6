"""Acceptance of the gap workflow on the independent validation set (``validation/``).

The set is made by code that shares nothing with the bench's effect code or the estimation
(tests/test_validation_generator.py checks its equations). Thresholds come from the stated
error rates, never from individual files:

* catalog cases: the right names and axes (ties count when the analysis lists the pair) and the
  verdict "explained" in ≥ 95 % (the issue's bar), and the gap after consistent with the
  stated noise in ≥ 95 %;
* every out-of-catalog case is called "unexplained";
* on every run the verdict agrees with the per-axis consistency (one verdict, issue 20 item 3;
  :func:`validation.score.contradictions`);
* clean runs: the selection names something with probability ≤ its family α
  (:data:`calib.gap.selection.FAMILY_ALPHA`, 0.001) and the adequacy battery fails with
  probability ≤ its own (:data:`calib.gap.adequacy.ADEQUACY_ALPHA`, 0.0025) (Bonferroni
  bounds), so the number of clean runs named must not exceed the 0.999 quantile of
  Binomial(R, 0.001), and of those called unexplained that of Binomial(R, 0.0035).
"""

from __future__ import annotations

import pytest

from calib.gap.adequacy import ADEQUACY_ALPHA
from calib.gap.selection import FAMILY_ALPHA
from tests.pools import process_pool
from validation.cases import clean_cases, validation_set
from validation.score import default_analyze, judge, max_wrong

NAMED_RATE = FAMILY_ALPHA
UNEXPLAINED_RATE = FAMILY_ALPHA + ADEQUACY_ALPHA
CLEAN_RUNS = 240


def _judge(case):
    return judge(case, default_analyze(case))


def _score(cases) -> list[dict]:
    with process_pool(2) as ex:
        return list(ex.map(_judge, cases, chunksize=4))


@pytest.fixture(scope="module")
def rows() -> list[dict]:
    return _score(validation_set(0))


def _kind(rows, kind):
    return [r for r in rows if r["kind"] == kind]


def test_catalog_effects_named_right(rows):
    cat = _kind(rows, "catalog")
    wrong = [(r["id"], r["named"], r["verdict"]) for r in cat if not r["right"]]
    assert len(cat) >= 40
    assert sum(r["right"] for r in cat) >= 0.95 * len(cat), wrong
    assert sum(r["gap_ok"] for r in cat) >= 0.95 * len(cat)


def test_verdict_and_consistency_agree_on_every_run_of_the_set(rows):
    """One verdict, never contradicting itself (issue 20, item 3): over every run of the set
    (:func:`validation.score.contradictions`)."""
    assert {r["kind"] for r in rows} == {"catalog", "clean", "out_of_catalog"}
    assert [line for r in rows for line in r["contradictions"]] == []


def test_every_out_of_catalog_case_is_unexplained(rows):
    ooc = _kind(rows, "out_of_catalog")
    assert len(ooc) >= 6
    assert [(r["id"], r["verdict"]) for r in ooc if r["verdict"] != "unexplained"] == []


def test_clean_runs_of_the_set(rows):
    clean = _kind(rows, "clean")
    named = [r["id"] for r in clean if r["named"]]
    unexplained = [r["id"] for r in clean if r["verdict"] == "unexplained"]
    assert len(named) <= max_wrong(len(clean), NAMED_RATE), named
    assert len(unexplained) <= max_wrong(len(clean), UNEXPLAINED_RATE), unexplained


def test_clean_false_alarms_over_many_runs():
    """≥ 200 clean runs over every design (static and timed)."""
    cases = clean_cases(CLEAN_RUNS, seed=1)
    assert len({c.design for c in cases}) >= 8 and any(c.t is None for c in cases)
    out = _score(cases)
    named = [r["id"] for r in out if r["named"]]
    unexplained = [r["id"] for r in out if r["verdict"] == "unexplained"]
    assert len(named) <= max_wrong(CLEAN_RUNS, NAMED_RATE), named
    assert len(unexplained) <= max_wrong(CLEAN_RUNS, UNEXPLAINED_RATE), unexplained
