"""Numeric options and sizes (issue 11, parts 2 and 3): every reported bad value is one line on
stderr with exit code 2, naming the option, and writes nothing; property tests over the
numeric options of a few commands: a finite JSON result with exit code 0, or a one-line error
with exit code 2 — never a traceback, never NaN or Infinity on stdout."""

from __future__ import annotations

import contextlib
import io
import json
import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
import scipy.io
from hypothesis import HealthCheck, event, example, given, settings
from hypothesis import strategies as st

from bench import limits
from bench.cli import main
from bench.cli.output import NonFiniteError, check_finite, print_json
from tests.cli import unwrap


def _run(*argv) -> tuple[int, str, str]:
    """``tiltbench ARGV`` in this process: exit code, stdout, stderr (argparse exits too)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main([str(a) for a in argv])
        except SystemExit as exc:  # argparse: bad syntax or type
            rc = exc.code
    return rc, out.getvalue(), err.getvalue()


def _refuse_constant(name: str):
    raise AssertionError(f"non-finite number {name} in the JSON output")


def _assert_clean(rc: int, out: str, err: str) -> None:
    """Exit 0 with one finite JSON object, or exit 2 with one error message (wrapped at 100
    columns: :func:`tests.cli.unwrap` joins its continuation lines) and no output."""
    assert "Traceback" not in err
    event(f"exit code {rc}")  # counts shown by --hypothesis-show-statistics
    if rc == 0:
        obj = json.loads(out, parse_constant=_refuse_constant)
        assert isinstance(obj, dict)
    else:
        assert rc == 2, err
        assert out == ""
        errors = [ln for ln in unwrap(err).splitlines()
                  if not ln.startswith(("note:", "warning:", "["))]
        assert len(errors) == 1 and "error:" in errors[0], err


def _error(*argv) -> str:
    """Run a command that must be refused; return its one-line message."""
    rc, out, err = _run(*argv)
    assert rc == 2, err
    assert out == "" and "Traceback" not in err
    lines = [ln for ln in unwrap(err).splitlines() if not ln.startswith("note:")]
    assert len(lines) == 1, err
    assert lines[0].startswith("tiltbench ") and "error:" in lines[0]
    return lines[0]


@pytest.fixture(scope="module")
def course(tmp_path_factory):
    """A small course-format set: ensayo.mat (200 samples), acel.mat (300), puntos.mat."""
    d = tmp_path_factory.mktemp("course")
    rng = np.random.default_rng(3)
    tita = np.linspace(0.0, 2 * np.pi, 200)
    ref = np.column_stack([-9.8 * np.sin(tita), -9.8 * np.cos(tita)])
    scipy.io.savemat(d / "ensayo.mat", {"tita": tita[:, None],
                                        "datos": 1.01 * ref + 0.05 + rng.normal(0, 0.5, ref.shape)})
    t = np.arange(300) * 0.01
    scipy.io.savemat(d / "acel.mat", {"t": t[:, None], "Aerr": np.zeros((t.size, 2))})
    scipy.io.savemat(d / "puntos.mat", {"A": np.array([[3.0, 9.0]]),
                                        "B": np.array([[50.0, 50.0]])})
    return {k: d / f"{k}.mat" for k in ("ensayo", "acel", "puntos")}


def _course_argv(course) -> list:
    return ["--ensayo", course["ensayo"], "--acel", course["acel"], "--puntos", course["puntos"]]


# ---------------------------------------------------------------- the reported cases
SWEEP = ["generate", "calibration", "--mode", "sweep"]
REFUSED_GENERATE = [
    (["generate", "calibration", "--mode", "sweep", "--rate", "0"], "--rate"),
    (["generate", "vehicle", "--rate", "0"], "--rate"),
    (["generate", "vehicle", "--duration", "inf"], "--duration"),
    ([*SWEEP, "--duration", "inf"], "--duration"),
    (["generate", "vehicle", "--rate", "inf"], "--rate"),
    ([*SWEEP, "--rate", "inf"], "--rate"),
    (["generate", "course", "--min-separation", "nan"], "--min-separation"),
    ([*SWEEP, "--sweep-profile", "updown", "--cycles", "0"], "--cycles"),
    ([*SWEEP, "--sweep-profile", "sine", "--cycles", "nan"], "--cycles"),
    ([*SWEEP, "--sweep-profile", "sine", "--cycles", "inf"], "--cycles"),
    ([*SWEEP, "--duration", "1e-9"], "--duration"),
    ([*SWEEP, "--theta-range", "1,1"], "--theta-range"),
    ([*SWEEP, "--sweep-profile", "sine", "--cycles", "5000"], "--cycles"),
    (["generate", "vehicle", "--p0", "1e308,0"], "--p0"),
    (["generate", "vehicle", "--v0", "0,-1e300"], "--v0"),
    (["generate", "vehicle", "--profile", "inf:1,0"], "--profile"),
    (["generate", "calibration", "--bias", "1e300,0"], "--bias"),
    (["generate", "calibration", "--noise-var", "5e-324,0.5"], "--noise-var"),
    (["generate", "calibration", "--count", "2"], "--count"),
    (["generate", "calibration", "--positions", "0"], "--positions"),
    (["generate", "calibration", "--count", "1.5"], "--count"),
    (["generate", "calibration", "--g", "1e300"], "--g"),
    # sizes: refused with the estimate, before anything is allocated
    (["generate", "calibration", "--count", "100000000000"], "--count 100000000000"),
    (["generate", "calibration", "--count", "1e11"], "--count 100000000000"),
    ([*SWEEP, "--duration", "1e9"], "--duration"),
    (["generate", "vehicle", "--duration", "1e9"], "--duration"),
    (["generate", "course", "--duration", "1e9"], "--duration"),
    (["generate", "calibration", "--positions", "100000", "--per-position", "1000000"],
     "--positions 100000 --per-position 1000000"),
]


@pytest.mark.parametrize("argv, option", REFUSED_GENERATE, ids=lambda v: " ".join(v)
                         if isinstance(v, list) else None)
def test_reported_generate_inputs_are_refused(tmp_path, argv, option):
    out = tmp_path / "out"
    msg = _error(*argv, "--out", out)
    assert option in msg
    assert not out.exists()


@pytest.mark.parametrize("rate", ["0", "nan", "inf", "-3"])
def test_gap_rate_is_checked_before_reading(tmp_path, rate):
    msg = _error("gap", tmp_path / "missing.mat", "--noise-var", "0.25,0.64", "--rate", rate)
    assert "--rate" in msg


def test_sizes_are_stated_in_gib(tmp_path):
    msg = _error("generate", "calibration", "--count", "1e11", "--out", tmp_path / "o")
    assert "GiB of memory" in msg and "the machine has" in msg


def test_class_too_large_for_the_disk_is_refused_before_anything(tmp_path, monkeypatch):
    monkeypatch.setattr(limits, "free_disk", lambda path: 10**9)
    out = tmp_path / "class"
    msg = _error("generate", "class", "--students", "1000000", "--out", out)
    assert "--students 1000000" in msg and "disk" in msg
    assert not out.exists()


def test_demo_coverage_runs_too_many_is_refused(tmp_path):
    out = tmp_path / "demo"
    msg = _error("demo", "--out", out, "--coverage-runs", "1e11", "--quiet")
    assert "--coverage-runs 100000000000" in msg and "GiB" in msg
    assert not out.exists()


@pytest.mark.parametrize("extra, option", [
    (["--mc-n", "1e11"], "--mc-n 100000000000"),
    (["--mc-n", "abc"], "--mc-n"),
    (["--runs", "-1"], "--runs"),
    (["--level", "0.9999999999999999"], "--level"),
    (["--level", "nan"], "--level"),
    (["--p0", "1e308,0"], "--p0"),
])
def test_nmin_options_refused(course, extra, option):
    assert option in _error("nmin", *_course_argv(course), *extra)


@pytest.mark.parametrize("extra, option", [
    (["--level", "0.9999999999999999"], "--level"),
    (["--level", "inf"], "--level"),
    (["--p0", "1e308,0"], "--p0"),
    (["--v0", "nan,0"], "--v0"),
    (["--g", "1e300"], "--g"),
])
def test_trajectory_options_refused(course, tmp_path, extra, option):
    png = tmp_path / "t.png"
    assert option in _error("trajectory", *_course_argv(course), *extra, "--plot", png)
    assert not png.exists()


@pytest.mark.parametrize("nv", ["5e-324,0.5", "1e-310,0.5", "0.25,1e300", "0,0.5", "nan,1"])
def test_calibrate_noise_var_refused(course, nv):
    assert "--noise-var" in _error("calibrate", course["ensayo"], "--noise-var", nv, "--json")


def test_argparse_errors_are_one_line(tmp_path):
    msg = _error("generate", "calibration", "--count", "abc", "--out", tmp_path / "o")
    assert "--count" in msg


# ---------------------------------------------------------------- the output guard
def test_non_finite_output_names_the_field():
    with pytest.raises(NonFiniteError, match=r"axes\.x\.std\[1\]"):
        print_json({"axes": {"x": {"std": [1.0, float("inf")]}}})
    with pytest.raises(NonFiniteError, match=r"datos\[2, 1\]"):
        check_finite({"datos": np.array([[0.0, 1.0], [2.0, 3.0], [4.0, np.nan]])}, "run")
    check_finite({"note": "NaN is a word here", "x": [1.0, 2]}, "ok")  # strings are fine


def test_last_resort_errors_are_one_line(monkeypatch, course):
    """A fault that escapes the checks is still one line with exit code 2."""
    import calib.calibration.tilt_plane

    def boom(*a, **k):
        raise OverflowError("math range error")

    monkeypatch.setattr(calib.calibration.tilt_plane, "calibrate", boom)
    msg = _error("calibrate", course["ensayo"], "--noise-var", "0.25,0.64")
    assert "OverflowError" in msg and "calibrate" in msg


# ---------------------------------------------------------------- properties
ODD_FLOATS = st.one_of(
    st.sampled_from([0.0, -0.0, -1.0, 5e-324, 2.2e-308, 1e-300, 1e300, 1.7e308,
                     math.inf, -math.inf, math.nan, 1e-9, 1e9]),
    st.floats(allow_nan=True, allow_infinity=True),
)

def plausible(lo: float, hi: float) -> st.SearchStrategy[float]:
    """Odd values half of the time, values in [lo, hi] (which should work) otherwise."""
    return st.one_of(st.floats(lo, hi), ODD_FLOATS)


FUZZ = settings(derandomize=True, deadline=None, database=None,
                suppress_health_check=[HealthCheck.too_slow])


@settings(FUZZ, max_examples=25)
@given(rate=st.one_of(st.sampled_from([100.0, 200.0, 500.0]), ODD_FLOATS),
       duration=plausible(0.05, 5.0), cycles=plausible(0.1, 3.0),
       profile=st.sampled_from(["constant", "updown", "sine"]))
def test_generate_sweep_numbers(rate, duration, cycles, profile):
    # large valid durations are capped by the rate's grid check or the size check; keep the
    # runs that start small
    if math.isfinite(duration) and math.isfinite(rate) and duration * rate > 2000:
        duration = 2000 / rate
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "out"
        rc, so, se = _run(*SWEEP, "--sweep-profile", profile, f"--rate={rate!r}",
                          f"--duration={duration!r}", f"--cycles={cycles!r}", "--out", out,
                          "--json")
        _assert_clean(rc, so, se)
        assert out.exists() == (rc == 0)


@settings(FUZZ, max_examples=25)
@given(count=st.one_of(st.integers(-5, 40), st.sampled_from(["1e1", "3.5", "nan", "10**9"])),
       bias=plausible(-1, 1), nv=plausible(0, 1), g=plausible(1, 20))
def test_generate_static_numbers(count, bias, nv, g):
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "out"
        rc, so, se = _run("generate", "calibration", f"--count={count}",
                          f"--bias={bias!r},0.01", f"--noise-var={nv!r},0.5", f"--g={g!r}",
                          "--out", out, "--json")
        _assert_clean(rc, so, se)
        assert out.exists() == (rc == 0)


@settings(FUZZ, max_examples=30)
@given(nx=plausible(1e-3, 10), ny=plausible(1e-3, 10), level=plausible(0.01, 0.999))
def test_calibrate_numbers(course, nx, ny, level):
    _assert_clean(*_run("calibrate", course["ensayo"], f"--noise-var={nx!r},{ny!r}",
                        f"--level={level!r}", "--json"))


LEVELS = st.one_of(st.floats(0.0, 1.0), plausible(0.5, 0.999),
                   st.sampled_from([0.9999999999999999, 1 - 1e-12, 1 - 1e-13, 1e-300]))


@settings(FUZZ, max_examples=25)
@given(level=LEVELS, p0=plausible(-1e3, 1e3), v0=plausible(-50, 50))
def test_trajectory_numbers(course, level, p0, v0):
    _assert_clean(*_run("trajectory", *_course_argv(course), f"--level={level!r}",
                        f"--p0={p0!r},0", f"--v0=1,{v0!r}", "--json"))


@settings(FUZZ, max_examples=15)
@given(level=LEVELS, mc_n=st.one_of(st.sampled_from(["3", "50", "1e2"]),
                                    st.sampled_from(["2", "0", "1e11", "x", "nan", "-5"])),
       runs=st.one_of(st.sampled_from(["0", "2"]), st.sampled_from(["-1", "1e11", "2.5"])))
@example(level=0.95, mc_n="50", runs="2")
def test_nmin_numbers(course, level, mc_n, runs):
    _assert_clean(*_run("nmin", *_course_argv(course), f"--level={level!r}", "--steps", "1,2",
                        f"--mc-n={mc_n}", f"--runs={runs}", "--json"))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(n=st.one_of(st.integers(-10, 5000), st.sampled_from([10**9, 10**15])),
       rate=plausible(1e-6, 1e3), alpha=plausible(1e-9, 2.0),
       size=plausible(-1.0, 1.0))
def test_design_numbers(n, rate, alpha, size):
    """`design` (analytic effects only: fast): a finite JSON result or a one-line error."""
    _assert_clean(*_run("design", "--effects", "misalignment,tilt_offset", "--designs",
                        "uniform,sweep", "--count", str(n), "--sweep-rate", repr(rate), "--alpha",
                        repr(alpha), "--size", f"misalignment={size!r}", "--json",
                        "--workers", "1"))
