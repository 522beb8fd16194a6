"""A gain that differs for positive and negative specific force, and the weighted battery.

* Scale asymmetry (IEEE Std 1293's gain that differs by the sign of the input; not in the
  catalog): on a stop-and-go turn ``K2·A_r²`` follows ``|A_r|`` and a walk takes the rest, so
  the named pair mimics it. ``rival_shapes`` now tries ``max(A_r, 0)`` (1 parameter, no
  search) in place of the named effects: the run is called "unexplained", and the shape's
  size is the asymmetry's.
* A true K2 keeps its name: over R runs the asymmetry shape makes ``rival_shapes`` fail in
  at most the 0.999 quantile of Binomial(R, 0.005) (the battery's family α bounds every
  check's level).
* The weighted Bonferroni rule: the levels of the checks run sum to the family α, and
  ``walk_spectrum`` is judged at its weight times ``alpha_check``.
"""

from __future__ import annotations

import numpy as np
import pytest

from calib.conventions import G
from calib.files.course import Ensayo
from calib.gap import analyze_gap
from calib.gap.adequacy import CHECK_WEIGHTS
from calib.gap.confusions import AMBIGUITY_LR
from calib.gap.swaps import FITS, tier
from calib.gap.walk import LEAN_MARGIN
from calib.units import missing_units
from validation import designs
from validation.score import max_wrong

STATED = (0.25, 0.64)
FAMILY_ALPHA = 0.005


def _run(kind: str, size: float, seed: int, design: str = "stop_and_go"):
    rng = np.random.default_rng([7, seed])
    th, t = designs.design(design, None)
    a = np.column_stack([-G * np.sin(th), -G * np.cos(th)])
    y = a * np.array([1.01, 0.99]) + np.array([0.05, -0.02])
    if kind == "asymmetry":
        y[:, 1] += size * np.maximum(a[:, 1], 0.0)
    elif kind == "k2":
        y[:, 1] += size * a[:, 1] ** 2
    elif kind == "walk":
        y[:, 1] += np.cumsum(rng.normal(0.0, size, th.size))
    y += np.sqrt(STATED) * rng.standard_normal(a.shape)
    return analyze_gap(Ensayo(th, y, t), STATED)


def _rival_shapes(res, axis: str) -> dict:
    return next(c for c in res.adequacy["checks"]
                if c["name"] == "rival_shapes" and c["axis"] == axis)


def test_a_scale_asymmetry_is_unexplained_not_a_k2():
    kappa = 0.2
    res = _run("asymmetry", kappa, 0)
    assert res.verdict == "unexplained", res.summary()
    c = _rival_shapes(res, "y")
    assert not c["passed"], c
    assert "positive and negative" in c["description"]
    # size = |gain change| · max |A_r|; the estimate within 15 % of the truth (its std at
    # this noise is about 3 %)
    assert c["size"] == pytest.approx(kappa * G, rel=0.15)


def test_a_faint_asymmetry_ahead_of_k2_leaves_k2_unnamed():
    """κ = 0.11 on a stop-and-go run: below the ``rival_shapes`` check's Bonferroni level,
    but the asymmetry fits better than K2 by more than ``LEAN_MARGIN`` (one parameter each):
    K2 is not named, the verdict is "unexplained" with the asymmetry in words, and the pair
    is listed under ``not_identifiable``."""
    res = _run("asymmetry", 0.11, 1)
    assert _rival_shapes(res, "y")["passed"]
    found = [f for f in res.adequacy["asymmetry"] if f["axis"] == "y"]
    assert len(found) == 1 and found[0]["decision"] == "leans", res.adequacy["asymmetry"]
    assert found[0]["gain"] > LEAN_MARGIN
    # κ within 25 % of the truth (its spread over seeds 2–11 at this noise: 0.0094, 9 %)
    assert found[0]["asymmetry"] == pytest.approx(0.11, rel=0.25)
    assert res.verdict == "unexplained" and ("nonlinearity_k2", "y") not in res.named
    said = [u for u in res.unexplained if u["signature"] == "scale_asymmetry"]
    assert len(said) == 1 and "differs for positive and negative" in said[0]["description"]
    pair = [d for d in res.not_identifiable
            if d["names"] == ["nonlinearity_k2", "scale_asymmetry"]]
    assert len(pair) == 1 and pair[0]["reason"].startswith("cannot tell K2 from a scale")
    assert missing_units(res.to_dict()) == []


K2_LEAN_RATE = 0.01
"""Bound on how often a true K2 is left unnamed for the asymmetry (the whole-analysis study,
``python -m validation.asymmetry.score``, measured 1 of 181 named)."""


def test_true_k2_keeps_its_name_beside_the_asymmetry_shape():
    """R = 8 K2 runs (two designs, strong K2): K2 named in all but at most the 0.999
    quantile of Binomial(8, K2_LEAN_RATE) left unnamed for the asymmetry, and the
    ``rival_shapes`` check fails in at most the 0.999 quantile of Binomial(8, 0.005)
    runs."""
    runs = [_run("k2", 0.01, s, d) for s in range(4) for d in ("stop_and_go", "full_turn")]
    leans = sum(f["decision"] == "leans" for r in runs
                for f in (*r.adequacy["asymmetry"], *r.adequacy["cubic"]))
    assert leans <= max_wrong(len(runs), K2_LEAN_RATE), leans
    named = sum(("nonlinearity_k2", "y") in r.named for r in runs)
    assert named + leans == len(runs), [r.named for r in runs]
    failed = sum(not _rival_shapes(r, "y")["passed"] for r in runs)
    assert failed <= max_wrong(len(runs), FAMILY_ALPHA), failed


def test_a_k3_that_k2_and_the_lever_arm_follow_leaves_them_unnamed():
    """K3 = 2e-4 (m/s²)⁻² on y of a back-and-forth oscillation (θ = 2.5 sin(2πt/10 s)),
    where the lever arm's ω² and α are functions of θ: K2 with the lever arm would take it
    with a consistent gap after; K3 alone fits better by more than ``LEAN_MARGIN`` after the
    charges, so neither is named, the verdict is "unexplained" with K3 in words and the
    pair is listed. (1.5e-4 until the selection's family α went from 0.005 to 0.001: K2 was
    then named at p = 1e-4, above the new per-step level.)"""
    rng = np.random.default_rng([33, 3])
    n = 4001
    t = np.arange(n) / 100.0
    th = 2.5 * np.sin(2.0 * np.pi * t / 10.0)
    a = np.column_stack([-G * np.sin(th), -G * np.cos(th)])
    y = a * np.array([1.01, 0.99]) + np.array([0.05, -0.02])
    y[:, 1] += 2e-4 * a[:, 1] ** 3
    y += rng.standard_normal((n, 2)) * 0.2
    res = analyze_gap(Ensayo(th, y, t), (0.04, 0.04))
    found = [f for f in res.adequacy["cubic"] if f["axis"] == "y"]
    assert len(found) == 1 and found[0]["decision"] == "leans", res.adequacy["cubic"]
    assert found[0]["gain"] > LEAN_MARGIN and "nonlinearity_k2" in found[0]["names"]
    assert found[0]["k3"] == pytest.approx(2e-4, rel=0.15)
    assert res.verdict == "unexplained" and not res.named, res.summary()
    said = [u for u in res.unexplained if u["signature"] == "nonlinearity_k3"]
    assert len(said) == 1 and "third-order term on y" in said[0]["description"]
    pair = [d for d in res.not_identifiable if d["names"][-1] == "nonlinearity_k3"]
    assert len(pair) == 1 and pair[0]["names"][:-1] == found[0]["names"]
    assert missing_units(res.to_dict()) == []


def test_the_asymmetry_study_counts_its_runs(capsys):
    """``python -m validation.asymmetry.score``: every run counted once under its kind."""
    from validation.asymmetry.score import main

    assert main(["--k2", "2", "--asymmetry", "2", "--k3", "1", "--lever", "1", "--speed", "1",
                 "--seed", "5", "--jobs", "1"]) == 0
    lines = capsys.readouterr().out.splitlines()
    for kind, runs in (("k2", 2), ("asymmetry", 2), ("k3", 1), ("lever", 1), ("speed", 1)):
        line = next(x for x in lines if x.startswith(kind + " "))
        assert int(line.split()[1]) == runs, line


def test_weighted_bonferroni_levels_sum_to_the_family_alpha():
    res = _run("walk", 0.01, 1, "several_turns")
    assert ("bias_random_walk", "y") in res.named, res.summary()
    checks = res.adequacy["checks"]
    names = [c["name"] for c in checks]
    assert "walk_spectrum" in names
    a = res.adequacy["alpha_check"]
    total = sum(CHECK_WEIGHTS.get(n, 1.0) for n in names) * a
    assert total == pytest.approx(res.adequacy["family_alpha"], rel=1e-12)
    # each check failed exactly when its p is below its own weighted level
    for c in checks:
        assert c["passed"] == (c["p_value"] >= CHECK_WEIGHTS.get(c["name"], 1.0) * a) or \
            np.isclose(c["p_value"], CHECK_WEIGHTS.get(c["name"], 1.0) * a), c


def test_the_swaps_tiers_share_the_catalog_pairs_rule():
    """``calib.gap.swaps.tier``: a one-column rival is said ("ties") when the named effects fit
    better by less than the catalog pairs' likelihood ratio of 10 (2 ln 10 after the charges),
    "describes" when it fits better, "leans" beyond ``LEAN_MARGIN``; nothing at or below
    −2 ln 10. Every tier has its words in the reason."""
    eps = 1e-9
    assert AMBIGUITY_LR == pytest.approx(2.0 * np.log(10.0))
    assert tier(-AMBIGUITY_LR) is None and tier(-AMBIGUITY_LR - 1.0) is None
    assert tier(-AMBIGUITY_LR + eps) == "ties" and tier(0.0) == "ties"
    assert tier(eps) == "describes" and tier(LEAN_MARGIN) == "describes"
    assert tier(LEAN_MARGIN + eps) == "leans"
    assert set(FITS) == {"ties", "describes", "leans"}
