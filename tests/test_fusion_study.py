"""The fusion comparison (:mod:`bench.fusion_study`, ``tiltbench fusion-study``) on a few
scenarios and a handful of runs (the full study is ``tiltbench fusion-study``, docs/fusion.md).

With R = 6 runs the bands are wide: the assertions are the orderings the physics fixes (the
fused path is metres, dead reckoning tens of metres) and gross inconsistencies (R told 10×
too small gives a mean NEES several times 2) — what 6 runs can show."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.stats import chi2

from bench import fusion_study
from bench.cli import main
from bench.fusion_study import Scenario, StudyConfig, StudyResult, run_study
from calib.stats.consistency import mean_nees_band
from calib.stats.runs import serial_map
from calib.units import missing_units

FEW = (Scenario("base"), Scenario("outage", outage_s=20.0), Scenario("R /10", r_factor=0.1))


@pytest.fixture(scope="module")
def study():
    return run_study(StudyConfig(runs=6, chunk=3, scenarios=FEW))


def test_fused_final_std_is_metres_against_dead_reckonings_tens(study):
    dr, fx = study.row("base", "dead_reckoning"), study.row("base", "fixes")
    kf, rts = study.row("base", "filter"), study.row("base", "smoother")
    assert dr.final_std_m > 10.0 and kf.final_std_m < 3.0
    assert kf.area_m2 < dr.area_m2 / 50
    assert rts.rms_m < kf.rms_m < fx.rms_m < dr.rms_m
    # the smoother's last node is the filter's
    assert rts.final_std_m == kf.final_std_m


def test_mis_set_r_is_caught_by_the_nees(study):
    good, bad = study.row("base", "filter"), study.row("R /10", "filter")
    assert good.nees_band[0] < 2.0 < good.nees_band[1]
    assert bad.nees > bad.nees_band[1] and not bad.nees_ok
    assert bad.final_std_m < good.final_std_m  # it claims more than it knows


def test_outage_region_grows_as_predicted(study):
    t, std, rms = study.outage_t, study.outage_std, study.outage_rms
    before = t < study.outage_start
    assert std[-1] > 3 * std[before][-1]  # the region grows without fixes
    # the stated std follows the error of the runs: 6 runs × 2 axes of squared errors over
    # the stated variance is χ²(12)/12 if consistent; its 0.05 %–99.95 % quantiles
    lo, hi = chi2.ppf([5e-4, 1 - 5e-4], 12) / 12
    ratio = (rms[-1] / std[-1]) ** 2
    assert lo < ratio < hi
    assert study.row("outage", "filter").final_std_m > study.row("base", "filter").final_std_m


def test_same_seed_same_numbers_whatever_the_chunks(study):
    again = run_study(StudyConfig(runs=6, chunk=6, scenarios=FEW[:1]), mapper=serial_map)
    a, b = study.row("base", "filter"), again.row("base", "filter")
    assert a.rms_m == pytest.approx(b.rms_m, rel=1e-12) and a.nees == pytest.approx(b.nees,
                                                                                    rel=1e-12)


def test_result_round_trips_and_has_units(study):
    d = study.to_dict()
    assert missing_units(d) == []
    back = StudyResult.from_dict(json.loads(json.dumps(d)))
    assert back.rows == study.rows and np.array_equal(back.outage_std, study.outage_std)
    assert back.paths == study.paths and len(study.paths) == 2 * len(FEW)
    assert "| base | filter |" in study.markdown() and "(m)" in study.summary()


def test_command_writes_table_and_figure_and_refuses_overwrite(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(fusion_study, "SCENARIOS", FEW[:1])
    out = tmp_path / "fs"
    argv = ["fusion-study", "--out", str(out), "--runs", "2", "--workers", "1", "--quiet"]
    assert main([*argv, "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert missing_units(d) == [] and d["config"]["runs"] == 2
    assert (out / "fusion-study.png").stat().st_size > 0
    assert "dead reckoning" in (out / "fusion-study.md").read_text()
    assert main(argv) == 2
    assert "--force" in capsys.readouterr().err
    assert main([*argv, "--force"]) == 0
    assert "RMS error (m)" in capsys.readouterr().out


# ------------------------------------------------------------------ NEES along the path
PATH_RUNS = 30
PATH_SCN = (Scenario("nominal"), Scenario("P0 /10", p0_factor=0.1),
            Scenario("Q /10", q_factor=0.1), Scenario("R /10", r_factor=0.1))


@pytest.fixture(scope="module")
def path_study():
    return run_study(StudyConfig(runs=PATH_RUNS, chunk=PATH_RUNS, scenarios=PATH_SCN))


def test_path_band_is_bonferroni_and_ranges_are_described():
    lo, hi = fusion_study.path_band(2, 200, 1)
    assert (lo, hi) == pytest.approx(mean_nees_band(2, 200))
    lo60, hi60 = fusion_study.path_band(2, 200, 60)
    assert lo60 < lo and hi60 > hi  # wider per epoch: the family level stays NEES_ALPHA
    t = np.arange(6.0)
    out = np.array([True, True, False, False, True, True])
    assert fusion_study.out_ranges(t, out) == [(0.0, 1.0), (4.0, 5.0)]
    assert fusion_study.describe_ranges([(0.0, 1.0), (4.0, 5.0)], 0.0, 5.0) == \
        "t ≤ 1 s, t ≥ 4 s"
    assert fusion_study.describe_ranges([], 0.0, 5.0) == "—"
    assert fusion_study.describe_ranges([(0.0, 5.0)], 0.0, 5.0) == "all t"


def test_nominal_filter_and_smoother_are_consistent_along_the_path(path_study):
    # If the stated covariances are right, every epoch (position and position+velocity) is
    # inside its band with probability ≥ 1 − NEES_ALPHA (Bonferroni): a failure here is a
    # 6e-5 event or a real inconsistency.
    for m in ("filter", "smoother", "fixes"):
        r = path_study.row("nominal", m)
        assert r.path_ok and r.path_out_frac == 0.0 and r.path_where == "—"
    p = path_study.path("nominal")
    assert len(p.t) == 60 and len(p.nees4) == 60  # 1 Hz fixes over 60 s
    assert path_study.row("nominal", "dead_reckoning").path_ok is None


def test_q_and_r_told_ten_times_too_small_are_inconsistent_along_the_path(path_study):
    q, r = path_study.row("Q /10", "filter"), path_study.row("R /10", "filter")
    assert not q.path_ok and not r.path_ok
    assert r.path_out_frac > 0.9  # over-confident at (nearly) every fix
    assert q.path4_out_frac > 0.5  # the velocity part shows Q mis-set most


def test_p0_told_ten_times_too_small_is_out_early_and_forgotten_later(path_study):
    from scipy.stats import chi2

    p = path_study.path("P0 /10")
    cfg = path_study.config
    assert p.t[0] == 0.0
    # First fix (t = 0): per axis, stated prior 0.1 σ_p0², true σ_p0²; after the update with
    # a fix of variance σ² the stated variance is 1/(1/(0.1σ_p0²) + 1/σ²) and the true one
    # (1−K)² σ_p0² + K² σ², K = 0.1σ_p0²/(0.1σ_p0² + σ²) (P0 block-diagonal: the position is
    # uncorrelated with the rest at t = 0). Then R·mean NEES = ratio · χ²(2R) exactly, and the
    # chance that this first epoch falls inside the band is chi2.cdf(R·hi/ratio, 2R):
    s0, s2 = cfg["p0_std"] ** 2, cfg["gps_sigma"] ** 2
    stated = 1.0 / (1.0 / (0.1 * s0) + 1.0 / s2)
    k = 0.1 * s0 / (0.1 * s0 + s2)
    ratio = ((1 - k) ** 2 * s0 + k * k * s2) / stated
    assert chi2.cdf(PATH_RUNS * p.band[1] / ratio, 2 * PATH_RUNS) < 1e-9
    out = p.out(2)
    assert out[0]
    # once the fixes have replaced the prior (after ≈ 20 s, docs/fusion.md) the filter is the
    # nominal one: every later epoch is inside with probability ≥ 1 − NEES_ALPHA
    late = np.asarray(p.t) >= 30.0
    assert not out[late].any() and not p.out(4)[late].any()
    row = path_study.row("P0 /10", "filter")
    assert not row.path_ok and row.path_where.startswith("t ≤ ")
    assert len(row.path_out_ranges) == 1 and row.path_out_ranges[0][1] < 30.0
    # the final-position NEES cannot see it (the ≈ 10× early excess is forgotten)
    assert row.nees_ok
