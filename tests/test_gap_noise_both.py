"""The noise level of both axes tested at once (``calib.effects.noise``, the pooled test).

A stated σ² off by one factor ρ on both axes puts each axis' χ² a few σ above its mean; each
axis alone may fall short of the per-step level that a lone axis must pass, the two pooled
do not. Runs made in numpy (``tests/gap_synthetic.py``), not by the bench.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from calib.effects import Extensions, ModelState, RunData
from calib.files.course import Ensayo
from calib.gap import analyze_gap
from calib.gap.selection import JOINT_NOISE
from tests.gap_synthetic import STATED, synth

N = 4000
SEED = 2035


def _run(seed: int, z_x: float, z_y: float):
    """A uniform full-turn run whose true σ² is ``(1 + z·√(2/N))·σ²_stated`` per axis: each
    axis' χ² excess z standard deviations of χ²(N) on average."""
    rng = np.random.default_rng(np.random.SeedSequence([SEED, seed]))
    ratio = [1.0 + z * np.sqrt(2.0 / N) for z in (z_x, z_y)]
    effects = [("noise_level", a, {"sigma2": r * s}) for a, r, s in zip("xy", ratio, STATED,
                                                                         strict=True)
               if r != 1.0]
    th, y, t = synth("uniform", N, rng, effects)
    return Ensayo(th, y, t)


def _added(res) -> list:
    return [s.get("added") for s in res.steps if "added" in s]


COMMON_RUNS = 12
COMMON_Z = 3.6
COMMON_POWER = 0.75
"""A lower bound on the pooled test's power at two axes 3.6 σ above their χ² mean: its z is
near 3.6·√2 = 5.1 (sd ≈ 1.08 at ρ = 1.08) against a two-sided per-step level near 4.1 σ
(α = 0.001 over 23 tests): Φ(0.93) ≈ 0.82."""


COUNTS_LSB = 0.5 * float(np.sqrt(STATED[1]))
"""A counts log: readings rounded to 0.4 m/s² (half of y's σ, 0.8 of x's): quantization is
named on both axes, and the sponge review (``calib.gap.sponges``) reviews the pair."""


@pytest.mark.parametrize("counts", [False, True], ids=["float", "counts"])
def test_a_common_excess_below_each_axis_level_is_named_on_both(counts):
    """Each axis 3.6 σ above its χ² mean, below the per-step level a lone axis must pass
    (near 4.1 σ). Over 12 runs the noise level is named on both axes in at least
    ``binom.ppf(0.001, 12, 0.75)`` of them, always through the pooled test, with the pair kept
    by the backward pass (each axis alone would fail its drop-one test) and reported with the
    pooled test's statistic and p-value; more often than the lone tests of the first step
    would both pass; and never on one axis only. In counts, also beside quantization: the
    sponge review pools the two axes as the selection did (reviewed one axis at a time, 5 of
    the 9 pairs lost an axis)."""
    both = lone_both = 0
    for seed in range(COMMON_RUNS):
        run = _run(seed, COMMON_Z, COMMON_Z)
        if counts:
            run = Ensayo(run.tita, np.round(run.datos / COUNTS_LSB) * COUNTS_LSB, run.t)
        res = analyze_gap(run, STATED)
        first = {(n, a): p for n, a, _, p in res.steps[0]["candidates"]}
        alpha = res.criterion["alpha_step"]
        lone_both += all(first[("noise_level", a)] < alpha for a in "xy")
        named = sorted(n for n in res.named if n[0] == "noise_level")
        assert named in ([], [("noise_level", "x"), ("noise_level", "y")]), (seed, res.steps)
        if counts:
            assert {("quantization", a) for a in "xy"} <= set(res.named), res.named
            sponges = [n for n in res.adequacy["sponges"] if n["name"] == "noise_level"]
            assert len({n["statistic"] for n in sponges}) <= 1, sponges  # one pooled review
        if named:
            both += 1
            assert [*JOINT_NOISE] in _added(res), (seed, res.steps)
            assert not any("removed" in s for s in res.steps), (seed, res.steps)
            # each line states the test the pair was named and kept by: the pooled one
            noise = [e for e in res.effects if e.name == "noise_level"]
            assert all(e.p_value < alpha for e in noise), (seed, noise)
            assert noise[0].statistic == noise[1].statistic
            assert all(e.pooled and e.to_dict()["pooled"] for e in noise)
            assert "(both axes pooled)" in str(noise[0])
    assert both >= stats.binom.ppf(0.001, COMMON_RUNS, COMMON_POWER), both
    assert both > lone_both, (both, lone_both)


def test_the_pooled_test_is_the_per_axis_statistic_summed():
    """Its p-value is the two-sided χ² of the summed whitened RSS over the summed dof; it is
    not testable once an axis has a noise level of its own."""
    from calib.calibration.ls import NotIdentifiableError
    from calib.calibration.tilt_plane import calibrate
    from calib.stats.diagnostics import chi2_two_sided_logp

    e = _run(0, 3.6, 3.6)
    ext = Extensions(RunData.build(e.tita, e.datos, 9.8),
                     1.0 + calibrate(e, STATED, "ols", 9.8).scale)
    state = ModelState.nominal(STATED)
    fit = ext.fit(state)
    t = ext.test(state, *JOINT_NOISE)
    tx, ty = (ext.test(state, "noise_level", a) for a in "xy")
    dof = 2 * (N - 2)
    assert t.logp == pytest.approx(chi2_two_sided_logp(fit.rss[0] + fit.rss[1], dof),
                                   rel=1e-12)
    assert t.logp < min(tx.logp, ty.logp)
    assert t.state.has("noise_level", "x") and t.state.has("noise_level", "y")
    with pytest.raises(NotIdentifiableError):
        ext.test(tx.state, *JOINT_NOISE)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_an_excess_on_one_axis_is_named_there_only(seed):
    """y 10 σ above its χ² mean, x clean: the lone axis' test is the stronger, y is named
    alone, and the pooled test is not asked again once y has its σ²."""
    res = analyze_gap(_run(seed, 0.0, 10.0), STATED)
    assert res.named == [("noise_level", "y")], res.steps
    assert not res.effects[0].pooled and "pooled" not in res.effects[0].to_dict()
    assert [*JOINT_NOISE] not in _added(res)


def test_the_command_says_the_pair_was_tested_pooled(tmp_path, capsys):
    """``tiltbench gap`` on such a run (a course-format .mat): the text and ``gap.md`` say
    "(both axes pooled)" after each axis' statistic, the JSON has ``"pooled": true``."""
    import json

    import scipy.io

    from bench.cli import main
    from calib.units import missing_units

    run = _run(1, COMMON_Z, COMMON_Z)  # named on both in the test above
    path = tmp_path / "ensayo.mat"
    scipy.io.savemat(path, {"tita": run.tita[:, None], "datos": run.datos})
    noise = ",".join(f"{v:g}" for v in STATED)
    assert main(["gap", str(path), "--noise-var", noise, "--report", str(tmp_path / "r")]) == 0
    assert capsys.readouterr().out.count("(both axes pooled)") == 2
    doc = json.loads((tmp_path / "r" / "gap.json").read_text())
    assert [(e["axis"], e.get("pooled")) for e in doc["effects"]] == [("x", True), ("y", True)]
    assert missing_units(doc) == []
    assert (tmp_path / "r" / "gap.md").read_text().count("(both axes pooled)") == 2
