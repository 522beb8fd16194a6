"""calib.calibration.montecarlo: the batched engine equals calibrate() run by run, its results do
not depend on the chunk size, the process pool or a Dask cluster, and its intervals cover."""

from __future__ import annotations

import json

import numpy as np
import pytest

from bench.sweep import dask_map, process_map
from calib import Ensayo, calibrate
from calib.calibration.montecarlo import (
    MonteCarloResult,
    draw_noise,
    simulate_calibrations,
    synthetic_readings,
)
from calib.stats.runs import run_seeds

THETA = np.linspace(0.0, 2 * np.pi, 2001)
BIAS, SCALE, NV = [0.0767, -0.0175], [-0.0301, 0.0100], [0.25, 0.64]


def _sim(runs=23, seed=5, **kw):
    return simulate_calibrations(THETA, BIAS, SCALE, NV, runs, seed, **kw)


@pytest.mark.parametrize("mode", ["given", "estimated"])
def test_equals_calibrate_run_by_run(mode):
    """Estimates, std, σ² and χ² of runs 0, 7, 22 equal calibrate() on the same readings."""
    res = _sim(sigma2=mode, chunk=5)
    for k in (0, 7, 22):
        datos = synthetic_readings(THETA, BIAS, SCALE, NV, 5, k)
        cal = calibrate(Ensayo(THETA, datos), NV if mode == "given" else None, "ols")
        np.testing.assert_allclose(res.params[k], cal.params, rtol=0, atol=1e-12)
        np.testing.assert_allclose(res.std[k], cal.std, rtol=1e-12, atol=0)
        for i, a in enumerate("xy"):
            f = cal.fits[a]
            assert f.sigma2_source == res.sigma2_source == mode
            np.testing.assert_allclose(res.sigma2[k, i], f.sigma2.item(), rtol=1e-12)
            np.testing.assert_allclose(res.chi2[k, i], f.chi2, rtol=1e-12)
            np.testing.assert_allclose(res.sigma2[k, i] * res.cov1[i], f.cov, rtol=1e-12,
                                       atol=1e-20)


def test_stream_of_run_k_is_the_kth_spawned_child():
    """The seed contract of calib.stats.runs: run k draws from run_seeds(seed, runs, key)[k]."""
    ss = run_seeds(5, 23, (7,))[11]
    want = np.random.default_rng(ss).standard_normal((2, THETA.size))
    np.testing.assert_array_equal(draw_noise(5, range(11, 12), THETA.size, (7,))[0], want)
    readings = synthetic_readings(THETA, BIAS, SCALE, NV, 5, 11, spawn_key=(7,))
    np.testing.assert_allclose(readings, synthetic_readings(THETA, BIAS, SCALE, NV, 5, 11,
                                                            spawn_key=(7,)), rtol=0, atol=0)
    assert not np.array_equal(readings, synthetic_readings(THETA, BIAS, SCALE, NV, 5, 12,
                                                           spawn_key=(7,)))


def test_independent_of_chunk_size_and_processes():
    ref = _sim(chunk=1)
    for other in (_sim(chunk=7), _sim(chunk=23), _sim(chunk=4, mapper=process_map(2))):
        np.testing.assert_array_equal(other.params, ref.params)
        np.testing.assert_array_equal(other.chi2, ref.chi2)
    assert _sim(seed=6).params[0, 0] != ref.params[0, 0]


@pytest.fixture(scope="module")
def cluster():
    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as c:
        yield c


def test_dask_cluster_equals_serial(cluster):
    ref = _sim(chunk=3)
    seen = []
    got = _sim(chunk=3, mapper=dask_map(cluster.scheduler_address),
               progress=lambda d, t: seen.append((d, t)))
    np.testing.assert_array_equal(got.params, ref.params)
    np.testing.assert_array_equal(got.sigma2, ref.sigma2)
    assert seen[-1] == (8, 8) and len(seen) == 8


def test_cli_generate_class_on_cluster_equals_one_process(cluster, tmp_path, capsys):
    """`generate class` writes the same bytes with --workers 1 and --scheduler ADDR."""
    from bench.cli import main

    outs = {}
    for name, extra in (("one", ["--workers", "1"]),
                        ("dask", ["--scheduler", cluster.scheduler_address])):
        outs[name] = tmp_path / name
        assert main(["generate", "class", "--students", "2", "--seed", "4", "--out",
                     str(outs[name]), "--json", *extra]) == 0
        capsys.readouterr()
    files = sorted(p.relative_to(outs["one"]) for p in outs["one"].rglob("*") if p.is_file())
    assert len(files) == 2 + 2 * 4
    for f in files:
        assert (outs["one"] / f).read_bytes() == (outs["dask"] / f).read_bytes(), f


def test_demo_coverage_check_mapper_independent(cluster):
    """The demo's coverage check (batched engine) gives the same dict serially and on the
    cluster, and matches a plain loop of calibrate() + validate() on the same streams."""
    from bench.demo import coverage_check
    from bench.validate import validate

    truth = {"sensor": {"x": {"bias": 0.0767, "scale": -0.0301, "noise_var": 0.25},
                        "y": {"bias": -0.0175, "scale": 0.0100, "noise_var": 0.64}},
             "theta_design": {"kind": "range", "start": 0.0, "stop": 6.283185307179586,
                              "count": 2001}}
    one = coverage_check(truth, 60, 0.95, seed=3)
    assert coverage_check(truth, 60, 0.95, seed=3,
                          mapper=dask_map(cluster.scheduler_address)) == one
    from bench.validate import design_theta
    th = design_theta(truth)
    passed = 0
    for k in range(60):
        datos = synthetic_readings(th, [0.0767, -0.0175], [-0.0301, 0.0100], [0.25, 0.64], 3,
                                   k, spawn_key=(7,))
        passed += validate(truth, calibrate(Ensayo(th, datos), [0.25, 0.64]).to_dict(),
                           0.95).passed
    assert one["pass_rate"] == passed / 60


def test_interval_coverage_and_nees_in_binomial_band():
    """R = 2000 runs, known σ²: each 95 % interval covers with probability 0.95, so the hit
    count is Binomial(R, 0.95) and |hits/R − 0.95| ≤ 4·sqrt(0.95·0.05/R) = 0.0195 fails by
    chance with probability < 1e-4; the mean NEES of the 4 parameters is χ²₄/R-averaged:
    mean 4, sd sqrt(2·4/R) = 0.063, band ±4 sd. (R = 2000 supports only claims at this
    resolution: coverage to ±0.02.)"""
    R = 2000
    res = simulate_calibrations(THETA, BIAS, SCALE, NV, R, 2026, chunk=250)
    hits = res.interval_hits(0.95).mean(axis=0)
    tol = 4 * np.sqrt(0.95 * 0.05 / R)
    assert np.all(np.abs(hits - 0.95) <= tol), hits
    assert abs(res.nees().mean() - 4) <= 4 * np.sqrt(8 / R)
    # estimated σ²: chi2 is N − 2 by construction, σ² is unbiased within its χ² spread
    est = simulate_calibrations(THETA, BIAS, SCALE, NV, 400, 9, sigma2="estimated")
    np.testing.assert_allclose(est.chi2, THETA.size - 2, rtol=1e-12)
    rel = est.sigma2.mean(axis=0) / np.array(NV) - 1
    assert np.all(np.abs(rel) <= 4 * np.sqrt(2 / (THETA.size - 2) / 400))


def test_result_round_trip_and_summary():
    res = _sim(runs=4)
    back = MonteCarloResult.from_dict(json.loads(json.dumps(res.to_dict())))
    assert back == res
    assert "bias_x" in res.summary() and "m/s²" in res.summary()
    est = res.estimates(2)
    assert est["axes"]["y"]["scale"] == res.params[2, 3]


def test_bad_input():
    with pytest.raises(ValueError, match="noise variances"):
        simulate_calibrations(THETA, BIAS, SCALE, [0.25, -1], 3, 0)
    with pytest.raises(ValueError, match="runs"):
        simulate_calibrations(THETA, BIAS, SCALE, NV, 0, 0)
    from calib.calibration.ls import NotIdentifiableError
    with pytest.raises(NotIdentifiableError, match="scale_x"):
        simulate_calibrations(np.zeros(10), BIAS, SCALE, NV, 3, 0)


def test_batch_design_on_noise_drawn_elsewhere():
    """The engine's pieces on draws made by the caller (e.g. a run that also draws vehicle
    readings from the same generator, as calib.vehicle.nmin does) equal calibrate()."""
    from calib.calibration.correct import apply_errors
    from calib.calibration.montecarlo import batch_design
    from calib.conventions import reference_accel

    design = batch_design(THETA)
    v = np.random.default_rng(4).standard_normal((2, THETA.size))
    z, ss = design.reduce(v)
    truth = [BIAS[0], SCALE[0], BIAS[1], SCALE[1]]
    params, rss = design.estimates(z, ss, truth, np.sqrt(NV))
    datos = apply_errors(reference_accel(THETA), BIAS, SCALE) + np.sqrt(NV) * v.T
    cal = calibrate(Ensayo(THETA, datos), NV)
    np.testing.assert_allclose(params[0], cal.params, rtol=0, atol=1e-12)
    np.testing.assert_allclose(rss[0] / np.array(NV), [cal.fits[a].chi2 for a in "xy"],
                               rtol=1e-12)


def test_single_fit_design_cache_is_exact():
    """calibrate()/fit_axis cache what depends on θ alone: a warm fit is bit-identical to a
    cold one, and a θ with the same fingerprint (first, middle, last sample) but another
    value elsewhere is not served the cached design."""
    from calib.calibration.ls import _DESIGN_CACHE, fit_axis

    y = synthetic_readings(THETA, BIAS, SCALE, NV, 1, 0)[:, 0]
    _DESIGN_CACHE.clear()
    cold = fit_axis(THETA, y, "x", 0.25)
    warm = fit_axis(THETA, y, "x", 0.25)
    for name in ("params", "cov", "residuals"):
        assert np.array_equal(getattr(cold, name), getattr(warm, name))
    assert cold.cond == warm.cond and cold.chi2 == warm.chi2
    other = THETA.copy()
    other[5] += 1e-3
    served = fit_axis(other, y, "x", 0.25)
    _DESIGN_CACHE.clear()
    fresh = fit_axis(other, y, "x", 0.25)
    assert np.array_equal(served.params, fresh.params)
    assert not np.array_equal(served.params, cold.params)
