"""Step-like bias changes are said by their shape (issue 33, item 4): two-level switching
(random telegraph noise), a single step and a staircase — "the bias switches between two
levels …", "a step of … at t = …", "a staircase of …" —, never "1/f-like drift"
(:mod:`calib.gap.steps`, :func:`calib.gap.walk.step_drift`).

The logs are made here with numpy (course signs ``A_rx = −g sin θ``, ``A_ry = −g cos θ``) on
a stop-and-go θ(t) over three turns (:func:`tests.test_gap_drive_state.stop_and_go`), the
bias change added to x.
"""

from __future__ import annotations

import numpy as np
import pytest

from calib.files.course import validate_ensayo
from calib.gap import analyze_gap
from calib.gap.steps import (
    MIN_SEGMENT,
    describe,
    find_steps,
    optimal_steps,
    step_threshold,
    two_level,
    walk_unlike,
)
from calib.gap.walk import (
    CYCLE_MARGIN,
    NEAR_STEPS_MARGIN,
    NOTHING_BEYOND_LR,
    WALK_LEAN_MARGIN,
    steps_decision,
)
from tests.test_gap_drive_state import STATED, course_readings, stop_and_go

SIGMA_X = float(np.sqrt(STATED[0]))


def _run(kind: str, seed: int):
    n = 4001
    t, th, _ = stop_and_go(n, seed=seed, moves=24, turns=3.0)
    _, y = course_readings(th, seed)
    rng = np.random.default_rng([seed, 17])
    if kind == "telegraph":  # two levels 1 σ apart, exponential dwells of 5 s on average
        level, b, i = 0, np.zeros(n), 0
        while i < n:
            d = int(rng.exponential(500)) + 1
            b[i:i + d] = level
            level, i = 1 - level, i + d
        y[:, 0] += SIGMA_X * b
    elif kind == "step":
        y[int(0.43 * n):, 0] += SIGMA_X
    elif kind == "staircase":
        for c in (0.3, 0.55, 0.8):
            y[int(c * n):, 0] += SIGMA_X
    return analyze_gap(validate_ensayo(th, y, t), STATED)


def _said(res) -> str:
    return " | ".join(u["description"] for u in res.unexplained)


@pytest.mark.parametrize("seed", [2, 3])
def test_telegraph_noise_switches_between_two_levels_not_1_over_f(seed):
    res = _run("telegraph", seed)
    said = _said(res)
    assert res.verdict == "unexplained", res.summary()
    assert ("bias_random_walk", "x") not in res.named
    assert "the bias on x switches between two levels" in said, said
    assert "1/f" not in said
    walk = [w for w in res.adequacy["walk"] if w["axis"] == "x"][0]
    assert walk["steps"]["two_level"] and walk["steps"]["decision"] == "steps"


def test_a_single_step_is_a_step_at_its_time():
    res = _run("step", 0)
    said = _said(res)
    assert res.verdict == "unexplained", res.summary()
    assert "a step of +0.5" in said and "at t = 17" in said, said  # 0.43·4001 samples
    assert "two steps" not in said.split("(")[0] and "1/f" not in said


def test_a_staircase_is_a_staircase():
    res = _run("staircase", 1)
    said = _said(res)
    assert res.verdict == "unexplained", res.summary()
    assert ("bias_random_walk", "x") not in res.named
    assert "a staircase of 3 steps of about +0.5" in said or \
        "a staircase of 3 steps of about +0.49" in said, said


def test_find_steps_on_white_noise_rarely_finds_one():
    """The change-point search at its family level ``STEP_ALPHA`` = 0.01: on 40 white-noise
    paths of 4001 samples at most 2 show a step."""
    found = sum(find_steps(np.random.default_rng(s).standard_normal(4001), 1.0).count > 0
                for s in range(40))
    assert found <= 2
    assert 20 < step_threshold(4001) < 30


def test_find_steps_places_and_sizes_and_the_words():
    n = 3000
    e = np.zeros(n)
    e[1000:] += 1.0
    e[2000:] -= 1.0
    e[2500:] += 1.0
    noisy = e + 0.3 * np.random.default_rng(1).standard_normal(n)
    fit = find_steps(noisy, 0.09)
    assert fit.count == 3 and np.all(np.abs(fit.places - [1000, 2000, 2500]) <= 3)
    assert np.allclose(fit.sizes, [1, -1, 1], atol=0.1)
    assert two_level(fit)
    tcol = np.arange(n) / 100.0
    assert describe(fit, tcol, "s", "x").startswith("the bias on x switches between two")
    stair = find_steps(np.cumsum(np.isin(np.arange(n), [600, 1500, 2400])) * 1.0
                       + 0.3 * np.random.default_rng(2).standard_normal(n), 0.09)
    words = describe(stair, np.arange(n, dtype=float), "sample", "y")
    assert words.startswith("a staircase of 3 steps of about +1") and "samples 600" in words
    one = find_steps(np.r_[np.zeros(500), np.ones(500)]
                     + 0.3 * np.random.default_rng(3).standard_normal(1000), 0.09)
    words = describe(one, np.arange(1000) / 10.0, "s", "x")
    assert words.startswith("a step of +0.99 m/s² (+3.3 σ) in the bias on x at t = 50 s")


def _best_by_enumeration(e: np.ndarray, sigma2: float, penalty: float) -> float:
    """``max_K [LR_K − penalty·K]`` over every segmentation with up to 3 steps of at least
    MIN_SEGMENT samples, by brute force (an independent check of the recursion)."""
    from itertools import combinations

    n = e.size
    base = float(np.sum((e - e.mean()) ** 2))
    best = 0.0
    for k in (1, 2, 3):
        for places in combinations(range(MIN_SEGMENT, n - MIN_SEGMENT + 1), k):
            b = (0, *places, n)
            if min(np.diff(b)) < MIN_SEGMENT:
                continue
            rss = sum(float(np.sum((e[i:j] - e[i:j].mean()) ** 2))
                      for i, j in zip(b[:-1], b[1:], strict=True))
            best = max(best, (base - rss) / sigma2 - penalty * k)
    return best


@pytest.mark.parametrize("seed", range(4))
def test_optimal_steps_is_the_exact_optimum_of_the_penalised_gain(seed):
    rng = np.random.default_rng(seed)
    e = rng.standard_normal(36) + np.r_[np.zeros(11), np.full(14, 1.4), np.zeros(11)]
    fit = optimal_steps(e, 1.0, 6.0)
    assert fit.count <= 3  # the enumeration covers the optimum found
    assert fit.lr - 6.0 * fit.count == pytest.approx(_best_by_enumeration(e, 1.0, 6.0),
                                                     rel=1e-9, abs=1e-9)


def test_optimal_steps_finds_close_steps_that_binary_segmentation_merges():
    """Four steps of 0.41 σ, two of them 300 samples apart: the Bonferroni-thresholded
    binary segmentation merges the close pair into one step of twice the size; the
    penalised optimum at the walk review's charge finds all four within a few samples, and
    pure noise gives none (also on 60001 samples, searched on block means)."""
    n = 4001
    e = 0.3 * np.random.default_rng(1).standard_normal(n)
    e += 0.124 * np.cumsum(np.isin(np.arange(n), [1117, 1700, 2000, 3294]))
    penalty = 2.0 * (1.0 + np.log(n))
    assert find_steps(e, 0.09).count == 3
    fit = optimal_steps(e, 0.09, penalty)
    assert fit.count == 4 and np.all(np.abs(fit.places - [1117, 1700, 2000, 3294]) <= 20)
    assert np.allclose(fit.sizes, 0.124, atol=0.05)
    for m in (4001, 60001):
        noise = np.random.default_rng(m).standard_normal(m)
        assert optimal_steps(noise, 1.0, 2.0 * (1.0 + np.log(m))).count == 0


def test_a_faint_staircase_ahead_of_the_walk_is_not_told_apart_and_the_walk_not_named():
    """Three steps of 0.33 σ (two of them 1.2 s apart) beat a walk after their charges by
    more than ``WALK_LEAN_MARGIN`` but within ``CYCLE_MARGIN``, and a walk adds nothing beyond
    them: this run cannot tell them apart, so the pair is listed under ``not_identifiable``
    with the steps' shape in words, the walk is not presented as the explanation and the
    verdict is "unexplained" — never a silent walk."""
    n = 4001
    t, th, _ = stop_and_go(n, seed=0, moves=24, turns=3.0)
    _, y = course_readings(th, 0)
    for c in (0.2, 0.6, 0.63):
        y[int(c * n):, 0] += 0.33 * SIGMA_X
    res = analyze_gap(validate_ensayo(th, y, t), STATED)
    walk = [w for w in res.adequacy["walk"] if w["axis"] == "x"][0]
    assert walk["steps"]["decision"] == "leans", walk["steps"]
    assert WALK_LEAN_MARGIN < walk["steps"]["gain"] <= CYCLE_MARGIN
    pair = [d for d in res.not_identifiable if d["names"] == ["bias_random_walk", "bias_steps"]]
    assert len(pair) == 1 and pair[0]["axis"] == "x", res.not_identifiable
    assert pair[0]["reason"].startswith("cannot tell a walk from steps on x: a staircase of")
    assert ("bias_random_walk", "x") not in res.named and res.verdict == "unexplained"
    said = _said(res)
    assert "a staircase of" in said and "cannot tell them apart" in said, said


def test_steps_just_short_of_the_walk_with_nothing_beyond_them_are_not_told_apart():
    """Four 0.3 σ steps, three of them close: after their place charges the steps fall short
    of the walk (gain ≤ 0, within ``NEAR_STEPS_MARGIN``), but a walk adds nothing at all beyond
    them (its q fits 0). The near tier: the walk is not named, the verdict is "unexplained"
    and the words say the steps and that the run cannot tell them from a walk."""
    n = 4001
    t, th, _ = stop_and_go(n, seed=0, moves=24, turns=3.0)
    _, y = course_readings(th, 0)
    for c in (0.3, 0.5, 0.55, 0.6):
        y[int(c * n):, 0] += 0.3 * SIGMA_X
    res = analyze_gap(validate_ensayo(th, y, t), STATED)
    steps = [w for w in res.adequacy["walk"] if w["axis"] == "x"][0]["steps"]
    assert -NEAR_STEPS_MARGIN < steps["gain"] <= 0.0, steps
    assert steps["walk_beyond_lr"] <= NOTHING_BEYOND_LR
    assert steps["decision"] == "leans" and steps["near"] is True
    assert ("bias_random_walk", "x") not in res.named and res.verdict == "unexplained"
    said = _said(res)
    assert "a staircase of" in said and "cannot tell them apart" in said, said
    assert "adds nothing at all beyond them" in said, said


def test_a_walk_unlike_shape_is_a_one_signed_staircase_of_three_or_switching():
    """``walk_unlike``: three or more steps of one sign, or two levels revisited; not one or
    two steps, nor steps of both signs that wander (what a walk's path is cut into)."""
    def fit(levels):
        return optimal_steps(np.repeat(np.asarray(levels, dtype=float), 100), 1e-6, 1.0)

    assert walk_unlike(fit([0.0, 1.0, 2.0, 3.0]))
    assert walk_unlike(fit([0.0, -1.0, -1.5, -3.0]))
    assert walk_unlike(fit([0.0, 1.0, 0.0, 1.0, 0.0]))  # two levels: switching
    assert not walk_unlike(fit([0.0, 1.0]))
    assert not walk_unlike(fit([0.0, 1.0, 2.0]))  # two steps
    assert not walk_unlike(fit([0.0, 1.0, 2.5, 1.2]))  # both signs, no two levels


def test_the_tiers_of_steps_against_the_walk():
    """``steps_decision``: replaced beyond the margin, not named beyond
    ``WALK_LEAN_MARGIN`` (2: beyond "about as well supported"), named with the pair listed
    below it."""
    assert WALK_LEAN_MARGIN == 2.0
    assert steps_decision(CYCLE_MARGIN + 0.1, CYCLE_MARGIN) == "steps"
    assert steps_decision(CYCLE_MARGIN, CYCLE_MARGIN) == "leans"
    assert steps_decision(WALK_LEAN_MARGIN + 0.1, CYCLE_MARGIN) == "leans"
    assert steps_decision(WALK_LEAN_MARGIN, CYCLE_MARGIN) == "describes"
    assert steps_decision(0.5, CYCLE_MARGIN) == "describes"
