"""calib.stats.binning, calib.vehicle.propagation, calib.vehicle.report: the equations the
recordings and figures draw, in calib (numpy/scipy only)."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from calib.stats.binning import binned_mean
from calib.vehicle.propagation import position_cov_along
from calib.vehicle.region import arrival_region
from calib.vehicle.report import ELLIPSE_KEYS, trajectory_tree
from tests.reference import course_2009 as ref


def test_binned_mean_equal_counts_and_values():
    x = np.arange(10.0)[::-1]
    y = 2.0 * x
    cx, my, at = binned_mean(x, y, bins=5)
    np.testing.assert_array_equal(cx, [0.5, 2.5, 4.5, 6.5, 8.5])
    np.testing.assert_array_equal(my, 2.0 * cx)
    # at: the middle sample (in the original order) of each bin
    assert at.dtype == np.int64
    np.testing.assert_array_equal(x[at], [0.0, 2.0, 4.0, 6.0, 8.0])


def test_binned_mean_edges():
    cx, my, at = binned_mean([], [])
    assert cx.size == my.size == at.size == 0
    cx, my, at = binned_mean([3.0, 1.0], [1.0, 2.0], bins=100)  # at most n bins
    np.testing.assert_array_equal(cx, [1.0, 3.0])
    np.testing.assert_array_equal(my, [2.0, 1.0])


@settings(derandomize=True, max_examples=30, deadline=None)
@given(st.integers(1, 200), st.integers(1, 30), st.integers(0, 2**31 - 1))
def test_binned_mean_sample_order_is_irrelevant(n, bins, seed):
    rng = np.random.default_rng(seed)
    x, y = rng.permutation(n).astype(float), rng.normal(size=n)  # distinct x
    perm = rng.permutation(n)
    a, b = binned_mean(x, y, bins), binned_mean(x[perm], y[perm], bins)
    np.testing.assert_allclose(a[0], b[0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(a[1], b[1], rtol=0, atol=1e-12)
    sizes = [g.size for g in np.array_split(np.arange(n), min(bins, n))]
    assert max(sizes) - min(sizes) <= 1
    np.testing.assert_allclose(a[1] @ np.array(sizes), y.sum(), atol=1e-9)


@pytest.fixture(scope="module")
def run(course):
    _, _, puntos, cal, traj = course
    return traj, cal, arrival_region(traj, cal, puntos, ref.NOISE_VAR, 0.997)


def test_position_cov_along_ends_at_the_arrival_covariance(run):
    traj, cal, region = run
    m = traj.t.size
    covs = position_cov_along(traj, cal, region.noise_var, [0, 1, m // 2, m - 1])
    assert covs.shape == (4, 2, 2)
    assert not np.any(covs[:2])  # P0, V0 exact
    np.testing.assert_allclose(covs[-1], region.cov, rtol=1e-12, atol=0)
    np.testing.assert_array_equal(covs, np.swapaxes(covs, 1, 2))
    assert np.all(np.linalg.eigvalsh(covs[2:]) > 0)
    # calibration part only: smaller than the total on the diagonal
    cal_only = position_cov_along(traj, cal, np.zeros((2, 2)), [m - 1])
    assert np.all(np.diagonal(cal_only[0]) < np.diagonal(covs[-1]))


def test_trajectory_tree(run):
    traj, cal, region = run
    out = trajectory_tree(traj, region, cal, method="ols", noise_var_source="given")
    assert out["level"] == region.level and out["method"] == "ols"
    assert out["noise_var_source"] == "given"
    assert out["calibration"] == cal.to_dict()
    assert tuple(out["ellipse"]) == ELLIPSE_KEYS
    assert set(traj.to_dict()) | set(region.to_dict()) <= set(out)
    assert "calibration" not in trajectory_tree(traj, region)


def test_calib_helpers_import_no_bench_nor_drawing():
    code = ("import sys, calib.stats.binning, calib.vehicle.propagation, calib.vehicle.report; "
            "bad = sorted(m for m in sys.modules if m.split('.')[0] in "
            "{'bench', 'mujoco', 'rerun', 'matplotlib'}); print(bad); assert not bad")
    subprocess.run([sys.executable, "-c", code], check=True)
