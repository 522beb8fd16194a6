"""Nothing changes for users when code moves: every generated file kind and the ``--json``
output of every command match, by value, the reference in ``tests/reference/snapshot.json``
and ``snapshot.npz`` (made by ``tools/snapshot.py``; see that script for what is kept and the
tolerances). Numbers are compared with ``RTOL`` = 1e-8 and a floor of ``FLOOR`` = 1e-12 times
their array's (or section's) scale, text at its printed precision — so the suite passes on
any CPU, whatever BLAS kernels OpenBLAS picks (``.ci/run`` reruns the check under other
kernels and with numpy's SIMD dispatch reduced).

The comparator itself is tested first, on small synthetic outputs: each rule must both accept
rounding noise and reject a real change, and say what changed and by how much."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tools"))

import snapshot  # noqa: E402
from snapshot import FLOOR, RTOL, compare, flatten  # noqa: E402


def _diffs(ref: dict, got: dict) -> list[str]:
    return compare(flatten(ref), flatten(got))


def _roundtrip(ref: dict, tmp_path: Path) -> dict:
    snapshot.save(flatten(ref), tmp_path / "s.json", tmp_path / "s.npz")
    return snapshot.load(tmp_path / "s.json", tmp_path / "s.npz")


# ---- the comparator ---------------------------------------------------------------------------

def test_numbers_within_rtol_pass_and_a_larger_change_is_named_with_its_size():
    ref = {"out": {"params": [0.0767, -0.0301], "chi2": 1.03}}
    ok = {"out": {"params": [0.0767 * (1 + 0.5 * RTOL), -0.0301], "chi2": 1.03}}
    assert _diffs(ref, ok) == []
    bad = {"out": {"params": [0.0767 * (1 + 1e-6), -0.0301], "chi2": 1.03}}
    (msg,) = _diffs(ref, bad)
    assert msg.startswith("out::/params:") and "1 of 2 values differ" in msg
    assert "relative 1e-06" in msg and "0.0767" in msg


def test_worst_margin_says_how_close_a_run_came_to_the_tolerance():
    ref = {"o": {"v": [1.0, 2.0], "n": 3}}
    got = {"o": {"v": [1.0, 2.0 * (1 + 0.5 * RTOL)], "n": 3}}
    margin, where = snapshot.worst_margin(flatten(ref), flatten(got))
    assert where == "o::/v" and margin == pytest.approx(0.5, rel=1e-3)


def test_rounding_noise_below_the_floor_of_its_array_passes():
    """The issue's case: a covariance off-diagonal of −8.85e-19 beside variances of ~1e-5 is
    rounding noise; another machine's +3.1e-19 must pass, a real 1e-9 correlation not."""
    cov = np.array([[1.25e-5, -8.85e-19], [-8.85e-19, 3.2e-5]])
    noisy = cov.copy()
    noisy[0, 1] = noisy[1, 0] = 3.1e-19
    assert _diffs({"c": {"cov": cov}}, {"c": {"cov": noisy}}) == []
    real = cov.copy()
    real[0, 1] = real[1, 0] = 1e-9
    (msg,) = _diffs({"c": {"cov": cov}}, {"c": {"cov": real}})
    assert "2 of 4 values differ" in msg and f"{FLOOR:g}·3.2e-05" in msg


def test_a_lone_number_takes_the_scale_of_its_section():
    """``readings_change`` holds two values that are both rounding noise (a difference of two
    equal computations); their floor comes from the section two levels up (χ² ≈ 1)."""
    ref = {"shrink": {"x": {"chi2": 0.99, "change": {"max_abs": 1.8e-15, "norm": 2.0e-13}}}}
    got = {"shrink": {"x": {"chi2": 0.99, "change": {"max_abs": 1.9e-15, "norm": 2.3e-13}}}}
    assert _diffs(ref, got) == []
    got["shrink"]["x"]["change"]["norm"] = 1e-6  # a change that is not noise
    (msg,) = _diffs(ref, got)
    assert msg.startswith("shrink::/x/change/norm:")


def test_integers_booleans_words_nan_and_shape_must_be_equal():
    ref = {"o": {"n": 2001, "ok": True, "name": "wls", "v": [1.0, float("nan")],
                 "m": [[1.0, 2.0]]}}
    assert _diffs(ref, ref) == []
    for key, value, words in [("n", 2002, "integers differ"), ("ok", False, "differ"),
                              ("name", "ols", "'wls' -> 'ols'"),
                              ("v", [1.0, 2.0], "values differ"),
                              ("m", [[1.0], [2.0]], "shape (1, 2) -> (2, 1)")]:
        got = {"o": {**ref["o"], key: value}}
        (msg,) = _diffs(ref, got)
        assert f"o::/{key}" in msg and words in msg, msg
    (msg,) = _diffs(ref, {"o": {**ref["o"], "extra": 1.0}})
    assert msg == "new: o::/extra"


def test_text_is_compared_at_its_printed_precision():
    ref = "bias x = 0.0767 m/s² ± 3.5e-03 over 2001 samples\nchi2/dof 1.03\n"
    last_digit = "bias x = 0.0768 m/s² ± 3.4e-03 over 2001 samples\nchi2/dof 1.03\n"
    assert snapshot.compare_text(ref, last_digit) == []
    two_digits = "bias x = 0.0769 m/s² ± 3.5e-03 over 2001 samples\nchi2/dof 1.03\n"
    assert snapshot.compare_text(ref, two_digits) == ["line 1: 0.0767 -> 0.0769 (printed to "
                                                      "±0.0001)"]
    count = ref.replace("2001", "2000")
    (msg,) = snapshot.compare_text(ref, count)
    assert msg.startswith("line 1: 2001 -> 2000")  # an integer is exact (up to RTOL)
    words = ref.replace("samples", "runs")
    (msg,) = snapshot.compare_text(ref, words)
    assert msg.startswith("line 1:") and "runs" in msg
    # a printed noise value (a difference of equal computations) beside the line's numbers
    assert snapshot.compare_text("x 0.99 Δ 2e-13", "x 0.99 Δ 3.1e-13") == []


def test_recording_like_trees_sit_where_the_json_sits():
    """A recording mirrors a JSON report as entities ``/a/b`` with a one-row ``Scalars``
    column; ``rrd_content`` puts it at ``a["b|Scalars:scalars"]`` so the same section rule
    applies; an empty or text column compares as text."""
    tree = {"gap_report": {"x": {"chi2|Scalars:scalars": 0.99,
                                 "change": {"norm|Scalars:scalars": 2e-13,
                                            "norm|json_path": "/x/change/norm"}}}}
    got = {"gap_report": {"x": {"chi2|Scalars:scalars": 0.99,
                                "change": {"norm|Scalars:scalars": 2.5e-13,
                                           "norm|json_path": "/x/change/norm"}}}}
    assert _diffs({"r": tree}, {"r": got}) == []


def test_reference_roundtrip_keeps_values_and_fingerprints_long_arrays(tmp_path):
    rng = np.random.default_rng(5)
    long = rng.normal(size=(20001, 2))
    ref = {"mat": {"datos": long, "n": 2001, "t": np.arange(100.0)},
           "text": "a 1.5\nb 2", "names": ["x", "y"], "none": None}
    back = _roundtrip(ref, tmp_path)
    assert compare(back, flatten(ref)) == []
    assert isinstance(back["mat::/datos"].value, snapshot.Fingerprint)
    assert isinstance(back["mat::/t"].value, np.ndarray)  # 100 elements: kept whole
    noisy = long * (1 + 1e-12 * rng.standard_normal(long.shape))
    assert compare(back, flatten({**ref, "mat": {**ref["mat"], "datos": noisy}})) == []


@pytest.mark.parametrize("change", ["one kept", "many between", "order", "nan", "shape"])
def test_a_fingerprint_catches_changes_it_does_not_store(tmp_path, change):
    """Kept elements are compared one by one; the weighted sums catch a shift of many
    elements between them, a reordering and a NaN; the shape is compared."""
    rng = np.random.default_rng(6)
    long = rng.normal(loc=9.8, size=40002)
    back = _roundtrip({"r": {"col": long}}, tmp_path)
    fp = back["r::/col"].value
    got = long.copy()
    between = np.setdiff1d(np.arange(long.size), fp.index)
    if change == "one kept":
        got[fp.index[7]] += 1e-4
    elif change == "many between":
        got[between[::10]] += 1e-3  # 3,900 elements, none of them kept
    elif change == "order":
        got[between[:200]] = got[between[:200]][::-1]
    elif change == "nan":
        got[between[3]] = np.nan
    else:
        got = got[:-1]
    (msg,) = compare(back, flatten({"r": {"col": got}}))
    expected = {"one kept": "at the kept elements", "many between": "weighted sum",
                "order": "weighted sum", "nan": "non-finite", "shape": "shape"}[change]
    assert msg.startswith("r::/col:") and expected in msg, msg


# ---- the outputs ------------------------------------------------------------------------------

@pytest.mark.slow
def test_outputs_match_the_recorded_snapshot_by_value(tmp_path, course_dir):
    diffs = snapshot.check(tmp_path, course_dir)
    assert not diffs, ("outputs changed (rerun tools/snapshot.py only if meant):\n"
                       + "\n".join(diffs[:40]) + (f"\n… {len(diffs) - 40} more"
                                                  if len(diffs) > 40 else ""))
