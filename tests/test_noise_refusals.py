"""``tiltbench noise`` refuses a stuck axis and a log that is not still
(:func:`calib.logs.static_log.check_static`), each in one line naming the file, the axis and
the fix, writing nothing; still logs — white noise of any level, short or long, quantized, with
flicker or a random walk — pass.

Bands: a still log is refused only if its excess scatter ``e² = var(y) − var(Δy)/2`` exceeds
``MAX_EXCESS_STD² + EXCESS_Z·σ_d²/√n``; for white noise e² has std σ²/√n, so each of the
R = 200 seeded logs below passes except with probability ≈ 1e-9 (six standard deviations):
any refusal is a failure.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.io

from calib.input_rules import DataError
from calib.logs.static_log import (
    EXCESS_Z,
    MAX_EXCESS_STD,
    STUCK_SPAN,
    check_static,
    excess_scatter,
    stuck_axis,
)
from calib.noise.allan import characterize_noise
from calib.noise.sensor_profile import WHITE_NOISE_DENSITY_RANGE, save_profile
from tests.cli import one_line_error, run

SEED = 20260311
RATE = 50.0
N = 6000


def still(rng: np.random.Generator, n: int = N, sigma=(0.5, 0.8)) -> np.ndarray:
    """A held sensor at θ = 0 with the course's noise (σ 0.5, 0.8 m/s²), (n, 2) m/s²."""
    return np.array(sigma) * rng.standard_normal((n, 2)) + [0.0, -9.8]


def mat(path, acc: np.ndarray, rate: float = RATE):
    scipy.io.savemat(path, {"t": (np.arange(acc.shape[0]) / rate)[:, None], "Aerr": acc})
    return path


def refused_by_noise(capsys, log, tmp_path) -> str:
    """The one-line refusal of ``noise LOG --save --plot``; neither output written."""
    save, plot = tmp_path / "sensor.json", tmp_path / "allan.png"
    line = one_line_error(capsys, "noise", log, "--save", save, "--plot", plot)
    assert str(log) in line
    assert not save.exists() and not plot.exists()
    return line


# ------------------------------------------------------------------ a stuck axis
@pytest.mark.parametrize("kind", ["constant", "ulp jitter", "zero", "x stuck"])
def test_a_stuck_axis_is_refused_in_one_line(kind, tmp_path, capsys):
    """Before this check a constant y gave N ≈ 1e-28 (m/s²)/√Hz and a "resolved" walk of
    5e-28 m/s²/√s; now: the file, the axis, its value and the fix."""
    rng = np.random.default_rng(SEED)
    acc = still(rng)
    axis = "x" if kind == "x stuck" else "y"
    k = "xy".index(axis)
    acc[:, k] = {"constant": -9.8, "ulp jitter": -9.8 * (1 + 4e-16 * rng.standard_normal(N)),
                 "zero": 0.0, "x stuck": 0.25}[kind]
    line = refused_by_noise(capsys, mat(tmp_path / "stuck.mat", acc), tmp_path)
    assert f"axis {axis} reads" in line and "in every sample" in line
    assert "stuck, dead or saturated" in line and "check the logger" in line


def test_stuck_axis_rule():
    y = np.full(100, 9.80665)
    assert stuck_axis(y) == pytest.approx(9.80665)
    assert stuck_axis(y + 1e-14 * np.arange(100)) is not None  # float rounding of a constant
    # the finest real quantizer (24 bits over ±2 g: 2.3e-6 m/s²) is far above the span
    lsb = 4 * 9.80665 / 2 ** 24
    assert lsb > 100 * STUCK_SPAN * 9.80665
    assert stuck_axis(y + lsb * (np.arange(100) % 2)) is None
    assert stuck_axis(np.zeros(10)) == 0.0 and stuck_axis(np.array([0.0, 1e-12])) == 5e-13
    assert stuck_axis(np.array([0.0, 1e-8])) is None  # the span is at least 1 m/s² × 1e-9


def test_without_the_check_the_saver_refuses_the_fit_of_a_stuck_axis(tmp_path):
    """The second line of defence: a library caller that skips :func:`check_static` gets a fit
    whose N is float rounding; ``sensor.json`` refuses it, naming the field, writing nothing."""
    rng = np.random.default_rng(SEED + 1)
    acc = still(rng, n=2048)
    acc[:, 1] = -9.8 * (1 + 4e-16 * rng.standard_normal(2048))  # a constant, to the last ulp
    with pytest.raises(DataError, match="axis y reads -9.8"):
        check_static(acc, RATE, "log.mat")
    res = characterize_noise(acc, RATE)
    assert res.axes[1].term("white_noise_density").value < WHITE_NOISE_DENSITY_RANGE[0]
    with pytest.raises(DataError, match=r"\(not written\): field 'axes\.y\.white_noise_density"):
        save_profile(tmp_path / "sensor.json", res.to_profile())
    assert not (tmp_path / "sensor.json").exists()


# ------------------------------------------------------------------ not still
def _shaken(rng, f_hz: float, amp: float) -> np.ndarray:
    acc = still(rng)
    t = np.arange(N) / RATE
    acc[:, 0] += amp * np.sin(2 * np.pi * f_hz * t)
    return acc


def _carried(rng) -> np.ndarray:
    """Walked around with: a smooth random motion of ≈ 1 m/s² on both axes (a moving
    stretch everywhere, slower than the 1-s windows)."""
    acc = still(rng)
    kern = np.hanning(51)
    for k in range(2):
        m = np.convolve(rng.standard_normal(N + 50), kern / kern.sum(), "valid")
        acc[:, k] += m / m.std()
    return acc


MOVING = {
    "shaken at 2 Hz": lambda rng: _shaken(rng, 2.0, 3.0),
    "vibrating at 10 Hz": lambda rng: _shaken(rng, 10.0, 3.0),
    "carried": _carried,
}


@pytest.mark.parametrize("case", MOVING, ids=str)
def test_a_log_that_is_not_still_is_refused_in_one_line(case, tmp_path, capsys):
    """Every window alike: the window tests pass these logs (their refusal comes first and
    reads differently); the excess scatter refuses them."""
    acc = MOVING[case](np.random.default_rng(SEED + 2))
    line = refused_by_noise(capsys, mat(tmp_path / "moving.mat", acc), tmp_path)
    assert "not a static log" in line and "cut the log to a still stretch" in line
    if case == "carried":  # its 1-s window means wander: the window test names the place
        assert "axis x's mean is" in line and "above the lowest window mean" in line
        return
    assert "not a static log: axis x scatters by" in line
    assert "beyond its sample-to-sample noise" in line and "limit" in line
    assert "record it lying still" in line


def test_the_excess_scatter_of_a_sine():
    """e² = var(y) − var(Δy)/2: a sine of amplitude A at f adds A²/2 to var(y) and
    A²·sin²(πf/fs) to var(Δy)/2 (module docstring), to the sampling error of the noise and
    of its cross term with the sine (std ≈ √2·A·σ/√n = 1.7e-3 here; 6 of them allowed)."""
    rng = np.random.default_rng(SEED + 3)
    t = np.arange(60_000) / RATE
    for f in (0.5, 2.0, 10.0):
        y = 3.0 * np.sin(2 * np.pi * f * t) + 0.1 * rng.standard_normal(t.size)
        e2, limit = excess_scatter(y)
        want = 9.0 / 2 * (1 - 2 * np.sin(np.pi * f / RATE) ** 2)
        assert e2 == pytest.approx(want, abs=6 * np.sqrt(2) * 3.0 * 0.1 / np.sqrt(t.size)), f
        assert limit == pytest.approx(MAX_EXCESS_STD ** 2 + EXCESS_Z * (
            0.01 + 9.0 * np.sin(np.pi * f / RATE) ** 2) / np.sqrt(t.size), rel=0.01)


def test_the_refusal_names_the_axis_as_the_log_has_it(tmp_path, capsys):
    """``--axes x,-z``: the message says which axis of the log is stuck."""
    rng = np.random.default_rng(SEED + 4)
    n = 3000
    path = tmp_path / "still.csv"
    rows = np.column_stack([np.arange(n) / 100.0, 0.02 * rng.standard_normal((n, 2)),
                            np.full(n, 9.8)])
    path.write_text("time (s),ax (m/s^2),ay (m/s^2),az (m/s^2)\n"
                    + "".join(",".join(repr(float(v)) for v in r) + "\n" for r in rows))
    line = one_line_error(capsys, "noise", path, "--axes", "x,-z", "--allow-saturation",
                          ignore=("note:",))
    assert f"{path}: axis y (the log's -z) reads -9.8 m/s² in every sample" in line


# ------------------------------------------------------------------ still logs pass
def test_still_logs_pass(tmp_path):
    """R = 200 white logs (σ from 1 mm/s² to 1 m/s², 64 to 6000 samples), quantized and
    coarse logs, and the bench's flicker and random walk over an hour: none is refused."""
    from bench.sensors import AxisErrors, SensorErrorModel
    from bench.terms import BiasInstability, BiasRandomWalk, Quantization

    rng = np.random.default_rng(SEED + 5)
    worst = 0.0
    for r in range(200):
        n = int(rng.choice([64, 256, 1000, 6000]))
        sigma = 10 ** rng.uniform(-3, 0, 2)
        acc = still(rng, n, sigma)
        if r % 4 == 0:  # on a lattice, up to a step twice the noise (a much coarser one
            # reads one value: stuck, and refused as such)
            step = float(min(sigma) * rng.uniform(0.1, 2.0))
            acc = step * np.round(acc / step)
        info = check_static(acc, RATE, "log.mat")
        worst = max(worst, *(e / lim for e, lim in zip(info["excess_std"],
                                                         info["excess_limit"], strict=True)))
    assert worst < 1.0
    # a drifting sensor held still for an hour at 10 Hz (flicker on x, a walk on y)
    rate = 10.0
    sensor = SensorErrorModel(
        AxisErrors(noise_var=0.02 ** 2, terms=(BiasInstability(b=2e-3),)),
        AxisErrors(noise_var=0.02 ** 2, terms=(BiasRandomWalk(q_per_sample=5e-4 / np.sqrt(rate)),
                                              Quantization(lsb=0.0024))))
    n = 36_000
    acc = sensor.apply(np.tile([0.0, -9.8], (n, 1)), np.random.default_rng(SEED + 6),
                       np.arange(n) / rate)
    info = check_static(acc, rate, "hour.mat")
    assert max(info["excess_std"]) < 0.1 < MAX_EXCESS_STD


def test_a_still_log_prints_the_check_and_its_units(tmp_path, capsys):
    log = mat(tmp_path / "still.mat", still(np.random.default_rng(SEED + 7)))
    rc, out, err = run(capsys, "noise", log)
    assert rc == 0, err
    assert "scatter beyond the sample-to-sample noise x " in out.replace("\n    ", " ")
    rc, out, err = run(capsys, "noise", log, "--json")
    import json

    doc = json.loads(out)
    check = doc["static_check"]
    assert len(check["excess_std"]) == 2 and all(
        e < lim for e, lim in zip(check["excess_std"], check["excess_limit"], strict=True))
    assert doc["units"]["static_check.excess_std"] == "m/s^2"
