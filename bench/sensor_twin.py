"""The twin of a measured sensor: a :class:`calib.noise.sensor_profile.SensorProfile`
(``sensor.json``) turned into the bench's sensor error model, and static logs of it on the MuJoCo
table.

Per axis, the profile's terms become (docs/noise.md):

=========================  ===============================================================
profile term               bench model at the run's sample rate fs
=========================  ===============================================================
white_noise_density N      ``AxisErrors.noise_var = (N·√fs)²`` (per-sample white noise)
bias_instability B         :class:`bench.terms.BiasInstability` ``b = B`` (Kasdin flicker;
                           ADEV floor 0.664·B, independent of fs)
rate_random_walk K         :class:`bench.terms.BiasRandomWalk` ``q_per_sample = K/√fs``
                           (the same walk as ``q = K`` with Δt = 1/fs)
quantization_step Δ        :class:`bench.terms.Quantization` ``lsb = Δ``
calibration bias, scale    ``AxisErrors.bias`` / ``scale`` (the profile's estimates)
=========================  ===============================================================

A term the profile leaves null (not resolved by its log) is left out. The walk and the
flicker are per sample, so a static run without sample times is simulated as consecutive
samples at fs (``generate calibration --sensor``: the profile's own rate; a sweep: ``--rate``).

Every function here takes a profile object and runs the checks of the one loader first
(:func:`calib.noise.sensor_profile.check_profile`, the checks of ``load_profile``): a profile
built in Python with a negative N, one axis or a calibration that does not cover x and y is
refused in one line (:class:`calib.input_rules.DataError`), never an IndexError.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bench.sensors import AxisErrors, SensorErrorModel
from bench.terms import BiasInstability, BiasRandomWalk, Quantization
from calib.conventions import AXES
from calib.noise.sensor_profile import NoiseTerm, SensorProfile, check_profile


def _value(terms: tuple[NoiseTerm | None, ...] | None, k: int) -> float | None:
    if terms is None or terms[k] is None:
        return None
    return float(terms[k].value)


def calibration_pairs(profile: SensorProfile) -> tuple[tuple[float, float], tuple[float, float]
                                                       ] | None:
    """(bias (x, y) m/s², scale (x, y)) from the profile's calibration, or None if it has none.

    The calibration is ``{"param_names", "params", ...}`` of a calibration file
    (``scale_x, bias_x, scale_y, bias_y`` in any order) or ``{"bias", "scale"}``, each an
    object keyed by axis name (the file's form) or a list in the order of ``profile.axes``.
    The profile is checked first (:func:`calib.noise.sensor_profile.check_profile`).
    """
    profile = check_profile(profile)
    cal = profile.calibration
    if not cal:
        return None
    if "bias" in cal and "scale" in cal:
        bias, scale = cal["bias"], cal["scale"]
        return (tuple(float(bias[a]) for a in AXES), tuple(float(scale[a]) for a in AXES))
    named = dict(zip(cal["param_names"], cal["params"], strict=True))
    return (tuple(float(named[f"bias_{a}"]) for a in AXES),
            tuple(float(named[f"scale_{a}"]) for a in AXES))


def twin_axis(profile: SensorProfile, k: int, rate: float, bias: float = 0.0,
              scale: float = 0.0) -> AxisErrors:
    """The bench's :class:`AxisErrors` of axis ``k`` (0 = x, 1 = y) of ``profile`` at
    ``rate`` Hz (table in the module docstring); bias m/s², scale 1."""
    profile = check_profile(profile)
    k = profile.axis_index(AXES[k])
    n_d = _value(profile.white_noise_density, k)
    b = _value(profile.bias_instability, k)
    q = _value(profile.rate_random_walk, k)
    lsb = None if profile.quantization_step is None else profile.quantization_step[k]
    terms = []
    if b is not None and b > 0:
        terms.append(BiasInstability(b=b))
    if q is not None and q > 0:
        terms.append(BiasRandomWalk(q_per_sample=q / np.sqrt(rate)))
    if lsb is not None:
        terms.append(Quantization(lsb=float(lsb)))
    return AxisErrors(bias=float(bias), scale=float(scale),
                      noise_var=0.0 if n_d is None else (n_d * np.sqrt(rate)) ** 2,
                      terms=tuple(terms))


def twin_sensor(profile: SensorProfile, rate: float | None = None,
                bias: tuple[float, float] = (0.0, 0.0),
                scale: tuple[float, float] = (0.0, 0.0)) -> SensorErrorModel:
    """The :class:`SensorErrorModel` of ``profile`` at ``rate`` Hz (default: the profile's).
    Bias (m/s²) and scale come from the profile's calibration when it has one, else from the
    arguments (x, y). Raises :class:`calib.input_rules.DataError` on a profile the loader
    would refuse."""
    profile = check_profile(profile)
    rate = float(profile.sample_rate if rate is None else rate)
    if not (np.isfinite(rate) and rate > 0):
        raise ValueError(f"sample rate must be a positive number of Hz, got {rate}")
    cal = calibration_pairs(profile)
    if cal is not None:
        bias, scale = cal
    return SensorErrorModel(*(twin_axis(profile, k, rate, bias[k], scale[k])
                              for k in range(len(AXES))))


def twin_truth(profile: SensorProfile, rate: float, source: str | None = None) -> dict:
    """What ``truth.json`` records of the twin: the profile's values (per axis x, y; units
    as :data:`calib.noise.sensor_profile.TERM_UNITS`), the run's rate (Hz) and the profile's
    file name."""
    profile = check_profile(profile)
    cal = calibration_pairs(profile)
    idx = [profile.axis_index(a) for a in AXES]
    q = profile.quantization_step
    return {
        "source": source, "sample_rate": float(profile.sample_rate), "run_rate": float(rate),
        "white_noise_density": [_value(profile.white_noise_density, k) for k in idx],
        "bias_instability": [_value(profile.bias_instability, k) for k in idx],
        "rate_random_walk": [_value(profile.rate_random_walk, k) for k in idx],
        "quantization_step": None if q is None else [q[k] for k in idx],
        "calibration": None if cal is None else {"bias": list(cal[0]), "scale": list(cal[1])},
    }


@dataclass(frozen=True)
class StaticRun:
    """A static log on the MuJoCo table: t (N,) s, tita (N,) rad (constant), datos (N, 2)
    m/s², a_true (N, 2) m/s², and what made it."""

    t: np.ndarray
    tita: np.ndarray
    datos: np.ndarray
    a_true: np.ndarray
    sensor: SensorErrorModel
    rate: float
    seed: int
    g: float
    twin: dict | None = None

    def truth(self) -> dict:
        d = {"kind": "static", "n": int(self.t.size), "duration": float(self.t.size / self.rate),
             "rate": float(self.rate), "theta": float(self.tita[0]), "g": float(self.g),
             "sensor": self.sensor.to_dict(), "model": "models/tilt_table.xml"}
        if self.twin is not None:
            d["sensor_profile"] = self.twin
        return d


def static_samples(duration: float, rate: float) -> int:
    """Number of samples of a static log: ⌊duration·rate⌋ (at least 1)."""
    return max(1, int(np.floor(duration * rate + 1e-9)))


def make_static_run(sensor: SensorErrorModel, duration: float, rate: float, theta: float,
                    seed: int, g: float | None = None, twin: dict | None = None) -> StaticRun:
    """Hold the table at ``theta`` (rad) for ``duration`` s sampled at ``rate`` Hz: MuJoCo
    evaluates the pose once (:func:`bench.tilt.static_readings`), the sensor model adds its
    errors over the run's sample times (same seed → same bytes)."""
    from bench.model import TableEdits
    from bench.tilt import static_readings

    table = TableEdits() if g is None else TableEdits(g=g)
    n = static_samples(duration, rate)
    a_pose, enc = static_readings(np.array([float(theta)]), table)
    a_true = np.repeat(a_pose, n, axis=0)
    t = np.arange(n) / float(rate)
    rng = np.random.default_rng(np.random.SeedSequence(int(seed)))
    datos = sensor.apply(a_true, rng, t)
    return StaticRun(t=t, tita=np.full(n, float(enc[0])), datos=datos, a_true=a_true,
                     sensor=sensor, rate=float(rate), seed=int(seed), g=table.g, twin=twin)


def write_static(run: StaticRun, out, force: bool = False) -> dict[str, str]:
    """Write ``static.mat`` (the course ``acel.mat`` layout: t N×1 s, Aerr N×2 m/s², which every
    log reader reads; one pose is no calibration run, so not the ensayo layout) and
    ``truth.json`` (θ, the sensor, the profile) into ``out``."""
    from bench.dataset import prepare_out_dir, save_mat, write_truth

    out = prepare_out_dir(out, ["static.mat", "truth.json"], force)
    paths = {"static": save_mat(out / "static.mat",
                                {"t": run.t, "Aerr": run.datos}, force=True),
             "truth": write_truth(out / "truth.json", run.truth(), run.seed, force=True)}
    return {k: str(v) for k, v in paths.items()}


__all__ = ["StaticRun", "calibration_pairs", "make_static_run", "static_samples",
           "twin_axis", "twin_sensor", "twin_truth", "write_static"]
