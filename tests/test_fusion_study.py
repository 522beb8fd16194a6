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
from calib.runs import serial_map
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
