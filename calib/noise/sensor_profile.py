"""The sensor profile (``sensor.json``): a measured sensor's noise terms and calibration, a
validated, versioned file like the calibration file (:mod:`calib.calibration.calfile`).

``tiltbench noise --save`` writes it from a static log (Allan deviation, IEEE Std 952/1293
readings) through :func:`save_profile`; ``generate --sensor`` simulates that sensor,
``gap --sensor`` takes the bias random walk's intensity from it, both through
:func:`load_profile`; :mod:`bench.sensor_twin` checks an in-memory profile with the same
checks (:func:`check_profile`). One set of checks, :func:`profile_from_document`, for all.

Format ``tiltbench-sensor``, version 2 (:data:`FORMAT_VERSION`), one JSON object::

    format, format_version  "tiltbench-sensor", 2                              defining
    tool                    {"name": "tiltbench", "version": …}   cosmetic (never checked)
    sample_rate             Hz, in SAMPLE_RATE_RANGE                           defining
    axes                    {axis name: axis block}, names from AXIS_NAMES,    defining
                            every name of REQUIRED_AXES present ("x", "y": the tilt plane,
                            course signs; "z" the third accelerometer axis; "gyro_x/y/z"
                            the gyro's, rad units); an axis block holds
        white_noise_density   NoiseTerm or null, (m/s²)/√Hz (Allan −½ line at τ = 1 s)
        bias_instability      NoiseTerm or null, m/s²      (flat minimum / 0.664)
        rate_random_walk      NoiseTerm or null, m/s²/√s   (Allan +½ line at τ = 3 s); the
                              q of the bias random walk b_k = b_{k-1} + q·√Δt·w_k
        quantization_step     m/s², or null (readings not on a lattice)
        unresolved_upper_bounds  {term: upper end of its interval} of the null terms
        fit_ok                true / false: a model of the rule of calib.noise.allan_fit
                              describes this axis's Allan curve on fit_tau_range or not
                              (false only with `noise --save-failed-fit`); null: not recorded
        quantization_noise    optional: NoiseTerm or null, m/s (Δv quantization, 3Q²/τ²)
        gauss_markov          optional: NoiseTerm + "correlation_time" (s), or null, m/s²
        fit_tau_range         optional: [τ0, τ1] s the model describes, or null
        export_filter         optional: the taps of the export's low-pass filter on lags
                              −L … L (odd count ≤ 2049, Σ = 1; calib.noise.shaping), or
                              null (readings not filtered)
        (gyro axes: rad/s for m/s², rad for m/s; GYRO_TERM_UNITS)
    fit                     {"level", "alpha", "n"} of the fit, or null          defining
    calibration             null, a cal.json's {"param_names", "params", "cov",  defining
                            "method", "g", "source"}, or {"bias": {axis: m/s²},
                            "scale": {axis: 1}}
    source                  {"name", "sha256"} of the static log, or null        defining
    units                   UNITS (must equal it)                                derived
    checksum                {"algorithm": "sha256", "covers": CHECKSUM_FIELDS, "value": hex}

A ``NoiseTerm`` is ``{"value", "interval": [lo, hi], "tau_range": [τ0, τ1] s, "level"}`` with
0 ≤ lo ≤ value ≤ hi (the Gauss–Markov one also ``"correlation_time"``, s). A term the log
cannot resolve (no flat minimum, no +½ slope in the τ range) is null for that axis and a
simulator leaves it out; its upper bound is kept in the axis block
(:meth:`SensorProfile.upper_bound`).

**Checks** (each failure one line, :class:`DataError` ``{file}: field '{dotted.path}' …``):
types and shapes, finite numbers, every value in the physical range stated below as a
module constant (with its reason), every axis of :data:`REQUIRED_AXES`, no unknown field, an
upper bound only for a null term, each term's level equal to ``fit.level``, a calibration's
parameters covering the tilt plane x, y with a symmetric positive-definite covariance,
``units`` equal to :data:`UNITS` (or :data:`UNITS_V2_0`, below), and the SHA-256 of the
canonical JSON of the defining fields (:func:`defining_checksum`): a hand edit that keeps
every range is refused too.

**Versions.** Version 1 files (written by ``tiltbench noise --save`` before the checksum; axes
as positional pairs) are refused with a one-line "re-run ``tiltbench noise … --save``": a
hand edit of a file without a checksum cannot be told from the original, as for ``cal.json``.
Version 2 grew without a new number, by a stated rule: the axes ``z`` and ``gyro_*`` are new
keys of :data:`AXIS_NAMES` (optional, like every axis but x and y), the axis keys of
:data:`OPTIONAL_AXIS_FIELDS` are optional (absent = null), and ``units`` is :data:`UNITS` or,
in a file that has none of these, the first version-2 object :data:`UNITS_V2_0`, and in a
file whose axis blocks have no ``export_filter`` key, :data:`UNITS_V2_1`. So every
version-2 file ever written loads; a file with the new keys is refused by an older tiltbench
("not part of format version 2").

**A failed fit.** ``fit_ok: false`` is written only on request (``noise
--save-failed-fit``); :func:`require_fit_ok` is the refusal every consumer runs
(``generate --sensor``, ``gap --sensor``; ``--allow-failed-fit`` accepts it).
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from calib.files.atomic import write_text
from calib.input_rules import (  # the value rules shared with cal.json: one home
    CORRELATION_EIG_MIN,
    G_RANGE,
    GAIN_RANGE,
    SIGMA2_RANGE,
    DataError,
    check_covariance,
    check_file,
)
from calib.input_rules import field_error as _fail
from calib.noise.allan_model import TERM_NAMES
from calib.noise.term_units import kind_of

FORMAT = "tiltbench-sensor"
"""The ``format`` value of every sensor profile."""
FORMAT_VERSION = 2
"""The only ``format_version`` this reader knows (version 1, before the checksum: re-run
``tiltbench noise --save``)."""

AXIS_NAMES: tuple[str, ...] = ("x", "y", "z", "gyro_x", "gyro_y", "gyro_z")
"""Axis names a profile may hold, in their canonical order: the accelerometer's tilt-plane
``x``, ``y`` (course signs after ``--axes``) and its third axis ``z`` (the one not in
``--axes``: the tilt axis), then the gyro's axes in the log's own frame (rad/s). Names starting
with ``gyro`` are gyro axes (:func:`calib.noise.term_units.kind_of`): their terms are in rad
units and ranges (:data:`GYRO_TERM_RANGES`)."""
CALIBRATION_AXES: tuple[str, ...] = ("x", "y")
"""The axes a profile's calibration covers: the tilt plane of ``cal.json``."""
REQUIRED_AXES: tuple[str, ...] = ("x", "y")
"""Axes every profile must hold: the tilt plane that ``generate --sensor`` simulates and
``gap --sensor`` reads (course signs)."""

SAMPLE_RATE_RANGE = (1e-3, 1e5)
"""Sample rate of the static log, Hz: from one reading every ~17 min (a data logger) to
100 kHz, above the output data rate of any MEMS or navigation-grade accelerometer (vibration
parts reach tens of kHz); 1e9 Hz is a time-unit mistake (ns read as s)."""
WHITE_NOISE_DENSITY_RANGE = (1e-10, 10.0)
"""White-noise density N, (m/s²)/√Hz: from a tenth of the best superconducting gravimeters
(~1e-9 (m/s²)/√Hz) to 10 (m/s²)/√Hz, a per-sample σ of 10 m/s² ≈ 1 g at 1 Hz (N = σ/√fs:
a slow logger of a noisy part, e.g. the course's σ = 0.8 m/s² at 0.01 Hz, is N = 8; a phone
is ≈ 3e-3). A sensor noisier than that reads no tilt. Below the lower end the "noise" is
float rounding of a stuck axis (N ≈ 1e-28 from a constant reading)."""
BIAS_INSTABILITY_RANGE = (1e-10, 10.0)
"""Bias instability B, m/s²: down to the white-noise floor above, up to 10 m/s² ≈ 1 g (a
bias wandering by 1 g is a broken sensor; consumer MEMS parts are at 1e-3–1e-2 m/s²)."""
RATE_RANDOM_WALK_RANGE = (1e-12, 1.0)
"""Rate random walk K, m/s²/√s: up to 1 m/s²/√s, a bias walking by 1 g in 100 s (broken,
or not a static log); navigation-grade parts are near 1e-6."""
QUANTIZATION_STEP_RANGE = (1e-9, 2.0)
"""Quantization step Δ, m/s²: from below a 24-bit converter over ±2 g (2.3e-6 m/s²) to the
coarsest common mode (LIS3DH 8-bit at ±16 g: 0.188 g = 1.84 m/s²); a step of 5 m/s² cannot
resolve a tilt and is a unit mistake."""
QUANTIZATION_NOISE_RANGE = (1e-12, 1.0)
"""Quantization noise Q of an integrated output (``3Q²/τ²``), m/s (gyro: rad): Q = Δ/√12 of
the Δv (Δθ) step Δ; from far below a 32-bit counter's step to 1 m/s (a Δv step of 3.5 m/s per
sample is not an inertial sensor)."""
CORRELATION_TIME_RANGE = (1e-6, 1e9)
"""Gauss–Markov correlation time T_c, s: any τ of an Allan point (:data:`TAU_RANGE`)."""
TERM_RANGES: dict[str, tuple[float, float]] = {
    "white_noise_density": WHITE_NOISE_DENSITY_RANGE,
    "bias_instability": BIAS_INSTABILITY_RANGE,
    "rate_random_walk": RATE_RANDOM_WALK_RANGE,
    "quantization_noise": QUANTIZATION_NOISE_RANGE,
    "gauss_markov": BIAS_INSTABILITY_RANGE,
}
"""Range of each term's value of an accelerometer axis, in its unit (:data:`TERM_UNITS`); the
Gauss–Markov σ is a bias excursion like B and has its range."""
GYRO_TERM_RANGES: dict[str, tuple[float, float]] = {
    "white_noise_density": (1e-10, 1.0),
    "bias_instability": (1e-12, 1.0),
    "rate_random_walk": (1e-14, 1.0),
    "quantization_noise": QUANTIZATION_NOISE_RANGE,
    "gauss_markov": (1e-12, 1.0),
}
"""Range of each term's value of a gyro axis (rad units): angle random walk 1e-10 … 1
(rad/s)/√Hz (navigation grade ≈ 3e-7, 0.001 °/√h; 1 rad/s/√Hz ≈ 57 °/s/√Hz is no gyro); bias
instability and the GM σ 1e-12 … 1 rad/s (2e-7 °/h, below any gyro, to a bias wandering by
57 °/s, a broken part); rate random walk 1e-14 … 1 rad/s/√s; the quantization step of the
readings, :data:`GYRO_QUANTIZATION_STEP_RANGE`."""
GYRO_QUANTIZATION_STEP_RANGE = (1e-9, 1.0)
"""Quantization step of gyro readings, rad/s: a 16-bit converter at ±2000 °/s steps by
1.1e-3 rad/s, an 8-bit one by 0.27 rad/s; 1 rad/s cannot resolve a turn."""
TERM_UNITS: dict[str, str] = {"white_noise_density": "(m/s²)/√Hz",
                              "bias_instability": "m/s²", "rate_random_walk": "m/s²/√s",
                              "quantization_noise": "m/s", "gauss_markov": "m/s²"}
"""Unit of each term of an accelerometer axis (value, interval and upper bound), as messages
print it."""
GYRO_TERM_UNITS: dict[str, str] = {"white_noise_density": "(rad/s)/√Hz",
                                   "bias_instability": "rad/s",
                                   "rate_random_walk": "rad/s/√s", "quantization_noise": "rad",
                                   "gauss_markov": "rad/s"}
"""Unit of each term of a gyro axis, as messages print it."""
TAU_RANGE = (1e-6, 1e9)
"""τ of an Allan point, s: from one sample at 1 MHz to ~32 years, longer than any log."""
N_RANGE = (64, 10 ** 12)
"""Samples of the static log: at least ``calib.noise.allan.MIN_SAMPLES`` (64: five octave
points), at most 10¹² (≈ 3 years at 10 kHz)."""
MAX_ABS_CALIBRATION_BIAS = 1e4
"""Largest |bias| of the calibration, m/s² (≈ 1000 g): above the full scale of any MEMS
accelerometer one would tilt on a table (±400 g is the widest common part), so a larger
"bias" is a unit mistake (counts, mg), not a sensor; the twin adds it to ±1 g readings. This
is tighter than ``cal.json``'s reading limit (10⁹ m/s², any number a file may hold): the
profile describes a sensor to simulate."""
CALIBRATION_METHODS: tuple[str, ...] = ("ols", "wls", "multiposition")
"""``method`` of a calibration from a ``cal.json`` (=
``calib.calibration.tilt_plane.METHODS``)."""

DEFINING_FIELDS = ("format", "format_version", "sample_rate", "axes", "fit", "calibration",
                   "source")
"""The fields that define the profile; the ``checksum`` covers exactly these."""
CHECKSUM_FIELDS = DEFINING_FIELDS
"""The ``checksum.covers`` list of every version-2 file."""
COSMETIC_FIELDS = ("tool",)
"""Fields never checked nor used."""
REQUIRED_AXIS_FIELDS = (*TERM_NAMES, "quantization_step", "unresolved_upper_bounds", "fit_ok")
"""The keys every axis block holds (a null where there is nothing)."""
OPTIONAL_AXIS_FIELDS = ("quantization_noise", "gauss_markov", "fit_tau_range", "export_filter")
"""Keys added to version 2 after its first files were written: the extra terms of the model
(a NoiseTerm, the Gauss–Markov one with its ``correlation_time``) and the τ range the model
describes. **Rule:** absent means null (a profile written before them has no such term and no
stated range); the writer always writes them (null where there is nothing), in this order
after the required ones, and the checksum covers them like every key of ``axes``. An older
tiltbench refuses a file that has them ("is not part of format version 2"): re-run its
``noise --save`` to make one it reads."""
AXIS_FIELDS = REQUIRED_AXIS_FIELDS + OPTIONAL_AXIS_FIELDS
"""The keys of an axis block, in the order the writer writes them."""
EXTRA_KEYS = ("unresolved_upper_bounds", "level", "alpha", "n", "lack_of_fit")
"""What :attr:`SensorProfile.extra` may hold (the file's axis blocks and ``fit``)."""

UNITS = {
    "sample_rate": "Hz",
    "white_noise_density": "(m/s^2)/sqrt(Hz)",
    "bias_instability": "m/s^2",
    "rate_random_walk": "m/s^2/sqrt(s)",
    "quantization_step": "m/s^2",
    "unresolved_upper_bounds": "the unit of each term",
    "tau_range": "s",
    "level": "1", "fit.alpha": "1", "fit.n": "count",
    "calibration.params": "bias m/s^2, scale 1",
    "calibration.cov": "products of the params' units",
    "calibration.g": "m/s^2",
    "calibration.bias": "m/s^2", "calibration.scale": "1",
}
"""The ``units`` object of the first version-2 files (before :data:`OPTIONAL_AXIS_FIELDS`
and the ``z`` and gyro axes): still accepted from a file that holds none of them."""
UNITS_V2_0 = dict(UNITS)
UNITS = {
    **UNITS_V2_0,
    "quantization_noise": "m/s",
    "gauss_markov": "m/s^2",
    "correlation_time": "s",
    "fit_tau_range": "s",
    "gyro_*.white_noise_density": "(rad/s)/sqrt(Hz)",
    "gyro_*.bias_instability": "rad/s",
    "gyro_*.rate_random_walk": "rad/s/sqrt(s)",
    "gyro_*.quantization_step": "rad/s",
    "gyro_*.quantization_noise": "rad",
    "gyro_*.gauss_markov": "rad/s",
}
"""The ``units`` object of the version-2 files written before ``export_filter``: still
accepted from a file whose axis blocks have no ``export_filter`` key."""
UNITS_V2_1 = dict(UNITS)
UNITS = {**UNITS_V2_1, "export_filter": "1 (filter taps, sum 1)"}
"""The ``units`` object of every version-2 file this tiltbench writes: a term's unit applies
to its value, interval and upper bound; the ``gyro_*`` keys are the units of the gyro axes."""
EXPORT_FILTER_TAPS = (3, 2049)
"""Fewest and most taps of an ``export_filter`` (an odd count: lags −L … L;
:data:`calib.noise.shaping.MAX_TAPS`)."""
EXPORT_FILTER_SUM_TOL = 1e-6
"""|Σ taps − 1| allowed (the taps are written as the shortest round trip of each float)."""

_REQUIRED = ("format", "format_version", "sample_rate", "axes", "fit", "calibration",
             "source", "units", "checksum")
_TERM_KEYS = ("value", "interval", "tau_range", "level")
_FIT_KEYS = ("level", "alpha", "n")
_CAL_FILE_KEYS = ("param_names", "params", "cov", "method", "g", "source")
_RERUN = "re-run `tiltbench noise STATIC_LOG --save sensor.json`"


@dataclass(frozen=True)
class NoiseTerm:
    """One noise coefficient of one axis: estimate, interval at ``level`` and the τ range
    (s) of the Allan deviation it was read from (units: :data:`TERM_UNITS`, gyro axes
    :data:`GYRO_TERM_UNITS`); ``correlation_time`` (s) for the Gauss–Markov term only."""

    value: float
    interval: tuple[float, float]
    tau_range: tuple[float, float]
    level: float = 0.683
    correlation_time: float | None = None

    def to_dict(self) -> dict:
        d = {"value": float(self.value), "interval": [float(v) for v in self.interval],
             "tau_range": [float(v) for v in self.tau_range], "level": float(self.level)}
        if self.correlation_time is not None:
            d["correlation_time"] = float(self.correlation_time)
        return d

    @classmethod
    def from_dict(cls, d: dict) -> NoiseTerm:
        tc = d.get("correlation_time")
        return cls(value=float(d["value"]), interval=tuple(float(v) for v in d["interval"]),
                   tau_range=tuple(float(v) for v in d["tau_range"]),
                   level=float(d.get("level", 0.683)),
                   correlation_time=None if tc is None else float(tc))


@dataclass(frozen=True)
class SensorProfile:
    """A measured sensor (module docstring). Per-axis tuples hold one entry per name of
    ``axes``, in that order (the file keys them by name).

    Attributes
    ----------
    sample_rate : Hz.
    white_noise_density, bias_instability, rate_random_walk : per axis a :class:`NoiseTerm`
        or None (not resolved); the whole tuple may be None for the last two.
    quantization_step : per axis m/s² (gyro: rad/s) or None; or None.
    quantization_noise, gauss_markov : per axis a :class:`NoiseTerm` (the GM one with its
        ``correlation_time``) or None (not in the model, or not resolved); or None.
    fit_tau_range : per axis (τ0, τ1) s, the τ range the model describes, or None; or None.
    export_filter : per axis the taps of the export's low-pass filter (lags −L … L, Σ = 1;
        :mod:`calib.noise.shaping`) or None; or None.
    calibration : a cal.json's ``{"param_names", "params", "cov", …}`` or
        ``{"bias", "scale"}`` of the tilt plane x, y (a list [x, y] or an object keyed by
        axis name), or None.
    source : ``{"name", "sha256"}`` of the static log, or None.
    axes : axis names (:data:`AXIS_NAMES`).
    extra : ``unresolved_upper_bounds`` {axis: {term: bound}}, ``level``, ``alpha``, ``n``,
        ``lack_of_fit`` {axis: bool} (:meth:`calib.noise.allan.NoiseCharacterization.
        to_profile`); nothing else (:data:`EXTRA_KEYS`).
    """

    sample_rate: float
    white_noise_density: tuple[NoiseTerm | None, ...]
    bias_instability: tuple[NoiseTerm | None, ...] | None = None
    rate_random_walk: tuple[NoiseTerm | None, ...] | None = None
    quantization_step: tuple[float | None, ...] | None = None
    calibration: dict[str, Any] | None = None
    source: dict[str, str] | None = None
    tool_version: str = "unknown"
    axes: tuple[str, ...] = ("x", "y")
    extra: dict[str, Any] = field(default_factory=dict)
    quantization_noise: tuple[NoiseTerm | None, ...] | None = None
    gauss_markov: tuple[NoiseTerm | None, ...] | None = None
    fit_tau_range: tuple[tuple[float, float] | None, ...] | None = None
    export_filter: tuple[tuple[float, ...] | None, ...] | None = None

    def fit_ok(self, axis: int | str) -> bool | None:
        """Whether the model described ``axis``'s Allan curve when the profile was written
        (None: not recorded)."""
        lof = self.extra.get("lack_of_fit") or {}
        bad = lof.get(self.axes[self.axis_index(axis)])
        return None if bad is None else not bad

    def axis_index(self, axis: int | str) -> int:
        """Position of ``axis`` (an index or a name of :attr:`axes`) in the per-axis tuples."""
        return self.axes.index(axis) if isinstance(axis, str) else int(axis)

    def white_sigma(self, axis: int | str) -> float:
        """Per-sample white-noise std (m/s²) at the profile's rate: σ = N·√fs."""
        term = self.white_noise_density[self.axis_index(axis)]
        return float("nan") if term is None else float(term.value * np.sqrt(self.sample_rate))

    def term(self, name: str, axis: int | str) -> NoiseTerm | None:
        """The :class:`NoiseTerm` ``name`` (:data:`TERM_NAMES` or an optional term:
        ``quantization_noise``, ``gauss_markov``) of ``axis`` (index or name), or None when
        the log did not resolve it."""
        terms = getattr(self, name)
        return None if terms is None else terms[self.axis_index(axis)]

    def upper_bound(self, name: str, axis: int | str) -> float | None:
        """For a term the log did not resolve: the upper end of its interval (same unit, at
        ``extra["level"]``), as ``tiltbench noise`` recorded it; None when resolved or unknown.
        A model that takes the term from the profile can bound it instead of leaving it free.
        """
        if self.term(name, axis) is not None:
            return None
        k = self.axis_index(axis)
        bounds = self.extra.get("unresolved_upper_bounds", {}).get(self.axes[k], {})
        value = bounds.get(name)
        return None if value is None else float(value)

    def to_dict(self) -> dict:
        """The ``sensor.json`` object (module docstring), checksum included. Raises
        :class:`DataError` when a per-axis tuple does not match :attr:`axes` or ``extra``
        holds a key outside :data:`EXTRA_KEYS`."""
        return profile_document(self)

    @classmethod
    def from_dict(cls, d: Any, where: Any = "<memory>") -> SensorProfile:
        """The profile of a ``sensor.json`` object, after every check
        (:func:`profile_from_document`)."""
        return profile_from_document(d, where)


# ------------------------------------------------------------------ writing
def _plain(obj: Any) -> Any:
    """``json.dumps`` hook: numpy arrays and scalars, tuples."""
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, tuple):
        return list(obj)
    raise TypeError(f"not JSON: {type(obj).__name__}")


def _num(v: Any) -> Any:
    """A number as a Python float (the canonical form the checksum is taken of); anything
    else unchanged, for the checks to name."""
    if isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool):
        return float(v)
    return v


def _per_axis(profile: SensorProfile, name: str, k: int, where: Any) -> Any:
    values = getattr(profile, name)
    if values is None:
        return None
    if not isinstance(values, (tuple, list)) or len(values) != len(profile.axes):
        n = len(values) if isinstance(values, (tuple, list)) else type(values).__name__
        raise DataError(f"{where}: field '{name}' has {n} entries for the {len(profile.axes)} "
                        f"axes {', '.join(profile.axes)} (one per axis, in that order)")
    return values[k]


def _term_out(t: Any) -> Any:
    """A :class:`NoiseTerm` as the file holds it; what is not a number stays as it is, for
    the checks to name (anything else is left to them too)."""
    if not isinstance(t, NoiseTerm):
        return t

    def seq(v: Any) -> Any:
        return [_num(x) for x in v] if isinstance(v, (tuple, list, np.ndarray)) else v

    out = {"value": _num(t.value), "interval": seq(t.interval),
           "tau_range": seq(t.tau_range), "level": _num(t.level)}
    if t.correlation_time is not None:
        out["correlation_time"] = _num(t.correlation_time)
    return out


def _calibration_out(cal: Any, axes: tuple[str, ...]) -> Any:
    """The calibration in the file's form: bias/scale lists become objects keyed by axis."""
    if not isinstance(cal, dict) or set(cal) != {"bias", "scale"}:
        return cal
    out = {}
    for key in ("bias", "scale"):
        v = cal[key]
        if isinstance(v, (list, tuple, np.ndarray)) and len(v) == len(axes):
            v = {a: _num(x) for a, x in zip(axes, v, strict=True)}
        elif isinstance(v, dict):
            v = {a: _num(x) for a, x in v.items()}
        out[key] = v
    return out


def profile_document(profile: SensorProfile, where: Any = "<memory>") -> dict:
    """The ``sensor.json`` object of ``profile`` (module docstring), its checksum computed.
    Not checked here: :func:`save_profile` and :func:`check_profile` check it."""
    axes = tuple(profile.axes)
    extra = profile.extra or {}
    unknown = [k for k in extra if k not in EXTRA_KEYS]
    if unknown:
        raise DataError(f"{where}: field 'extra.{unknown[0]}' is not part of format version "
                        f"{FORMAT_VERSION} (extra holds {', '.join(EXTRA_KEYS)})")
    bounds = extra.get("unresolved_upper_bounds") or {}
    lof = extra.get("lack_of_fit") or {}
    blocks = {}
    for k, a in enumerate(axes):
        block: dict[str, Any] = {
            name: _term_out(_per_axis(profile, name, k, where)) for name in TERM_NAMES}
        block["quantization_step"] = _num(_per_axis(profile, "quantization_step", k, where))
        own = bounds.get(a, {}) if isinstance(bounds, dict) else bounds
        block["unresolved_upper_bounds"] = ({t: _num(v) for t, v in own.items()}
                                            if isinstance(own, dict) else own)
        ok = lof.get(a) if isinstance(lof, dict) else lof
        block["fit_ok"] = None if ok is None else (not ok if isinstance(ok, bool) else ok)
        for name in ("quantization_noise", "gauss_markov"):
            block[name] = _term_out(_per_axis(profile, name, k, where))
        rng = _per_axis(profile, "fit_tau_range", k, where)
        block["fit_tau_range"] = ([_num(v) for v in rng]
                                  if isinstance(rng, (tuple, list, np.ndarray)) else rng)
        taps = _per_axis(profile, "export_filter", k, where)
        block["export_filter"] = ([_num(v) for v in taps]
                                  if isinstance(taps, (tuple, list, np.ndarray)) else taps)
        blocks[a] = block
    fit = ({k: (extra[k] if k == "n" else _num(extra[k])) for k in _FIT_KEYS if k in extra}
           or None)
    doc = {
        "format": FORMAT, "format_version": FORMAT_VERSION,
        "tool": {"name": "tiltbench", "version": str(profile.tool_version)},
        "sample_rate": _num(profile.sample_rate), "axes": blocks, "fit": fit,
        "calibration": _calibration_out(profile.calibration, CALIBRATION_AXES),
        "source": profile.source, "units": dict(UNITS), "checksum": None,
    }
    try:  # plain JSON: what a reader will see
        doc = json.loads(json.dumps(doc, default=_plain))
    except (TypeError, ValueError) as exc:
        raise DataError(f"{where}: the profile holds a value that is not JSON ({exc})") from None
    doc["checksum"] = {"algorithm": "sha256", "covers": list(CHECKSUM_FIELDS),
                       "value": defining_checksum(doc)}
    return doc


def defining_checksum(doc: dict) -> str:
    """SHA-256 (hex) of the canonical JSON of the :data:`DEFINING_FIELDS` of ``doc``: keys
    sorted, no spaces, floats in ``repr`` (the shortest round trip), so the same numbers give
    the same hash whether ``doc`` was just built or read back from the file."""
    part = {f: doc.get(f) for f in DEFINING_FIELDS}
    text = json.dumps(part, sort_keys=True, separators=(",", ":"), ensure_ascii=True,
                      default=_plain)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


def _document_json(doc: dict) -> str:
    return json.dumps(doc, indent=2) + "\n"


def save_profile(path: str | os.PathLike, profile: SensorProfile, force: bool = False) -> Path:
    """Write ``sensor.json`` atomically (:func:`calib.files.atomic.write_text`).

    The document goes through JSON and every check of :func:`load_profile` first: a profile
    the loader would refuse raises :class:`DataError` (``{path} (not written): field …``) and
    nothing is written. An existing file is refused (``FileExistsError``) unless ``force``.

    Parameters
    ----------
    path : the file to write.
    profile : the profile (:meth:`calib.noise.allan.NoiseCharacterization.to_profile`).
    force : replace an existing file.
    """
    where = f"{path} (not written)"
    text = _document_json(profile_document(profile, where))
    profile_from_document(json.loads(text), where)
    return write_text(path, text, force=force)


def check_profile(profile: SensorProfile, where: Any = "<memory>") -> SensorProfile:
    """``profile`` after the checks of :func:`load_profile` (through its JSON document), as
    the loader would return it: what a consumer given a profile object (not a file) runs.

    Raises
    ------
    DataError : one line naming ``where`` and the field.
    """
    return profile_from_document(profile_document(profile, where), where)


# ------------------------------------------------------------------ reading
def _short(v: Any) -> str:
    text = json.dumps(v, default=repr) if not isinstance(v, float) else repr(v)
    return text if len(text) <= 40 else text[:37] + "..."


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _number(v: Any, name: str, where: Any, unit: str,
            limits: tuple[float, float] | None = None, what: str = "") -> float:
    """``v`` as a finite float (within ``limits``, closed, in ``unit``), else one line."""
    if not _is_number(v):
        raise _fail(where, name, f"must be a number ({unit}), got {_short(v)}")
    if not math.isfinite(v):
        raise _fail(where, name, f"must be a finite number ({unit}), got {_short(v)}")
    x = float(v)
    if limits is not None and not limits[0] <= x <= limits[1]:
        raise _fail(where, name, f"is {x:g} {unit}: {what or 'it'} must be in "
                    f"[{limits[0]:g}, {limits[1]:g}] {unit}")
    return x


def _pair(v: Any, name: str, where: Any, unit: str) -> tuple[float, float]:
    if not isinstance(v, list) or len(v) != 2:
        raise _fail(where, name, f"must be a list of 2 numbers ({unit}), got {_short(v)}")
    return (_number(v[0], f"{name}[0]", where, unit), _number(v[1], f"{name}[1]", where, unit))


def _keys(d: Any, name: str, where: Any, required: tuple[str, ...],
          optional: tuple[str, ...] = ()) -> dict:
    """``d`` as an object with every ``required`` key and nothing else."""
    if not isinstance(d, dict):
        raise _fail(where, name, f"must be an object with {', '.join(required)}, got "
                    f"{_short(d)}")
    for key in required:
        if key not in d:
            raise _fail(where, f"{name}.{key}".lstrip("."), f"missing; {_RERUN}")
    unknown = [k for k in d if k not in required and k not in optional]
    if unknown:
        raise _fail(where, f"{name}.{unknown[0]}".lstrip("."), "is not part of format version "
                    f"{FORMAT_VERSION} (the file was edited?); {_RERUN}")
    return d


def _level(v: Any, name: str, where: Any) -> float:
    x = _number(v, name, where, "1")
    if not 0.0 < x < 1.0:
        raise _fail(where, name, f"is {x:g}: a two-sided level must be in (0, 1)")
    return x


def _ranges(kind: str) -> tuple[dict[str, tuple[float, float]], dict[str, str]]:
    """(term ranges, term units) of an axis of ``kind``."""
    if kind == "gyro":
        return GYRO_TERM_RANGES, GYRO_TERM_UNITS
    return TERM_RANGES, TERM_UNITS


def _term_from(d: Any, term: str, name: str, where: Any, level: float | None,
               kind: str = "accelerometer") -> NoiseTerm:
    """One :class:`NoiseTerm` of the file, every number checked."""
    gm = term == "gauss_markov"
    _keys(d, name, where, _TERM_KEYS + (("correlation_time",) if gm else ()))
    ranges, units = _ranges(kind)
    unit = units[term]
    value = _number(d["value"], f"{name}.value", where, unit, ranges[term],
                    "the " + term.replace("_", " "))
    lo, hi = _pair(d["interval"], f"{name}.interval", where, unit)
    if not 0.0 <= lo <= value <= hi:
        raise _fail(where, f"{name}.interval", f"is [{lo:g}, {hi:g}] {unit}: it must hold the "
                    f"value {value:g} and not go below 0")
    t0, t1 = _pair(d["tau_range"], f"{name}.tau_range", where, "s")
    if not TAU_RANGE[0] <= t0 <= t1 <= TAU_RANGE[1]:
        raise _fail(where, f"{name}.tau_range", f"is [{t0:g}, {t1:g}] s: expected "
                    f"{TAU_RANGE[0]:g} ≤ τ0 ≤ τ1 ≤ {TAU_RANGE[1]:g} s")
    lev = _level(d["level"], f"{name}.level", where)
    if level is not None and lev != level:
        raise _fail(where, f"{name}.level", f"is {lev:g} but fit.level is {level:g} (every "
                    f"interval is at the fit's level); {_RERUN}")
    tc = None
    if gm:
        tc = _number(d["correlation_time"], f"{name}.correlation_time", where, "s",
                     CORRELATION_TIME_RANGE, "a correlation time")
    return NoiseTerm(value=value, interval=(lo, hi), tau_range=(t0, t1), level=lev,
                     correlation_time=tc)


def _axis_from(d: Any, axis: str, where: Any, level: float | None) -> dict:
    """The checked contents of one axis block (optional keys absent: null,
    :data:`OPTIONAL_AXIS_FIELDS`)."""
    name = f"axes.{axis}"
    kind = kind_of(axis)
    ranges, units = _ranges(kind)
    _keys(d, name, where, REQUIRED_AXIS_FIELDS, OPTIONAL_AXIS_FIELDS)
    out: dict[str, Any] = {}
    for term in (*TERM_NAMES, "quantization_noise", "gauss_markov"):
        v = d.get(term)
        out[term] = None if v is None else _term_from(v, term, f"{name}.{term}", where, level,
                                                      kind)
    q = d["quantization_step"]
    step_range = GYRO_QUANTIZATION_STEP_RANGE if kind == "gyro" else QUANTIZATION_STEP_RANGE
    out["quantization_step"] = None if q is None else _number(
        q, f"{name}.quantization_step", where, "rad/s" if kind == "gyro" else "m/s²",
        step_range, "a quantization step")
    bounds = d["unresolved_upper_bounds"]
    if not isinstance(bounds, dict):
        raise _fail(where, f"{name}.unresolved_upper_bounds", "must be an object {term: upper "
                    f"bound}} (empty when every term is resolved), got {_short(bounds)}")
    checked = {}
    for term, v in bounds.items():
        where_b = f"{name}.unresolved_upper_bounds.{term}"
        if term not in TERM_NAMES:
            raise _fail(where, where_b, f"is not a noise term ({', '.join(TERM_NAMES)})")
        if out[term] is not None:
            raise _fail(where, where_b, f"is given but {name}.{term} is resolved (a bound is "
                        f"kept only for a null term); {_RERUN}")
        checked[term] = _number(v, where_b, where, units[term],
                                (0.0, ranges[term][1]), "an upper bound")
    out["unresolved_upper_bounds"] = checked
    ok = d["fit_ok"]
    if ok is not None and not isinstance(ok, bool):
        raise _fail(where, f"{name}.fit_ok", f"must be true, false or null, got {_short(ok)}")
    out["fit_ok"] = ok
    rng = d.get("fit_tau_range")
    if rng is not None:
        t0, t1 = _pair(rng, f"{name}.fit_tau_range", where, "s")
        if not TAU_RANGE[0] <= t0 <= t1 <= TAU_RANGE[1]:
            raise _fail(where, f"{name}.fit_tau_range", f"is [{t0:g}, {t1:g}] s: expected "
                        f"{TAU_RANGE[0]:g} ≤ τ0 ≤ τ1 ≤ {TAU_RANGE[1]:g} s")
        rng = (t0, t1)
    out["fit_tau_range"] = rng
    taps = d.get("export_filter")
    out["export_filter"] = None if taps is None else _taps(taps, f"{name}.export_filter", where)
    return out


def _taps(v: Any, name: str, where: Any) -> tuple[float, ...]:
    """An ``export_filter``: an odd number of finite taps (:data:`EXPORT_FILTER_TAPS`), each
    within ±1, summing to 1 (:data:`EXPORT_FILTER_SUM_TOL`)."""
    lo, hi = EXPORT_FILTER_TAPS
    if (not isinstance(v, list) or not lo <= len(v) <= hi or len(v) % 2 == 0
            or not all(_is_number(x) for x in v)):
        raise _fail(where, name, f"must be a list of an odd number ({lo}–{hi}) of filter taps "
                    f"(numbers) or null, got {_short(v)}")
    taps = tuple(float(x) for x in v)
    if not all(math.isfinite(x) and abs(x) <= 1.0 for x in taps):
        raise _fail(where, name, "holds a tap that is not a finite number within ±1")
    total = math.fsum(taps)
    if abs(total - 1.0) > EXPORT_FILTER_SUM_TOL:
        raise _fail(where, name, f"sums to {total:.9g}; a low-pass filter's taps sum to 1 "
                    f"(unit gain at zero frequency); {_RERUN}")
    return taps


def _fit_from(d: Any, where: Any) -> dict | None:
    if d is None:
        return None
    _keys(d, "fit", where, _FIT_KEYS)
    level = _level(d["level"], "fit.level", where)
    alpha = _number(d["alpha"], "fit.alpha", where, "1")
    if not 0.0 < alpha < 0.5:
        raise _fail(where, "fit.alpha", f"is {alpha:g}: a one-sided significance must be in "
                    "(0, 0.5)")
    n = d["n"]
    if not _is_int(n) or not N_RANGE[0] <= n <= N_RANGE[1]:
        raise _fail(where, "fit.n", f"is {_short(n)}: the samples of the static log must be "
                    f"an integer in [{N_RANGE[0]}, {N_RANGE[1]:g}]")
    return {"level": level, "alpha": alpha, "n": n}


def _ref(v: Any, name: str, where: Any) -> dict | None:
    """null or ``{"name": file name, "sha256": 64 hex digits}`` (sha256 may be absent)."""
    if v is None:
        return None
    ok = (isinstance(v, dict) and isinstance(v.get("name"), str) and v["name"]
          and set(v) <= {"name", "sha256"})
    sha = v.get("sha256") if isinstance(v, dict) else None
    if ok and sha is not None:
        ok = (isinstance(sha, str) and len(sha) == 64
              and all(c in "0123456789abcdef" for c in sha))
    if not ok:
        raise _fail(where, name, "must be null or {\"name\": file name, \"sha256\": 64 hex "
                    f"digits}}, got {_short(v)}")
    return dict(v)


def _check_gain_and_bias(kind: str, axis: str, v: float, name: str, where: Any) -> None:
    if kind == "bias" and abs(v) > MAX_ABS_CALIBRATION_BIAS:
        raise _fail(where, name, f"has bias_{axis} = {v:g} m/s²: |bias| must be at most "
                    f"{MAX_ABS_CALIBRATION_BIAS:g} m/s² (MAX_ABS_CALIBRATION_BIAS: a larger "
                    "bias is a unit mistake)")
    if kind == "scale" and not GAIN_RANGE[0] <= 1.0 + v <= GAIN_RANGE[1]:
        raise _fail(where, name, f"has scale_{axis} = {v:g}: the gain 1 + scale must be in "
                    f"[{GAIN_RANGE[0]:g}, {GAIN_RANGE[1]:g}]")


def _calibration_from(d: Any, axes: tuple[str, ...], where: Any) -> dict | None:
    """null, the cal.json form or the bias/scale form (module docstring), checked."""
    if d is None:
        return None
    if isinstance(d, dict) and set(d) == {"bias", "scale"}:
        out: dict[str, Any] = {}
        for kind, unit in (("bias", "m/s²"), ("scale", "1")):
            v = d[kind]
            name = f"calibration.{kind}"
            if not isinstance(v, dict) or set(v) != set(axes):
                raise _fail(where, name, f"must be an object with one number per axis "
                            f"({', '.join(axes)}), got {_short(v)}")
            out[kind] = {}
            for a in axes:
                x = _number(v[a], f"{name}.{a}", where, unit)
                _check_gain_and_bias(kind, a, x, f"{name}.{a}", where)
                out[kind][a] = x
        return out
    _keys(d, "calibration", where, ("param_names", "params", "cov"), _CAL_FILE_KEYS[3:])
    names = d["param_names"]
    want = [f"{kind}_{a}" for a in axes for kind in ("bias", "scale")]
    if (not isinstance(names, list) or not all(isinstance(n, str) for n in names)
            or sorted(names) != sorted(want)):
        raise _fail(where, "calibration.param_names", f"must name {', '.join(want)} (any "
                    f"order, each once), got {_short(names)}")
    params = d["params"]
    if not isinstance(params, list) or len(params) != len(names):
        raise _fail(where, "calibration.params", f"must be a list of {len(names)} numbers (one "
                    f"per param_names), got {_short(params)}")
    values = [_number(v, f"calibration.params[{i}]", where, "bias m/s², scale 1")
              for i, v in enumerate(params)]
    for n, v in zip(names, values, strict=True):
        kind, axis = n.split("_", 1)
        _check_gain_and_bias(kind, axis, v, "calibration.params", where)
    cov = d["cov"]
    p = len(names)
    if (not isinstance(cov, list) or len(cov) != p
            or not all(isinstance(r, list) and len(r) == p for r in cov)):
        raise _fail(where, "calibration.cov", f"must be a {p}×{p} list of lists, got "
                    f"{_short(cov)}")
    for i, row in enumerate(cov):
        for j, v in enumerate(row):
            _number(v, f"calibration.cov[{i}][{j}]", where, "products of the params' units")
    check_covariance(np.asarray(cov, dtype=float), tuple(names), "calibration.cov", where)
    out = {"param_names": list(names), "params": values,
           "cov": [[float(v) for v in row] for row in cov]}
    if "method" in d:
        if d["method"] not in CALIBRATION_METHODS:
            raise _fail(where, "calibration.method", f"is {_short(d['method'])}, expected one "
                        f"of {', '.join(CALIBRATION_METHODS)}")
        out["method"] = d["method"]
    if "g" in d:
        out["g"] = _number(d["g"], "calibration.g", where, "m/s²", G_RANGE, "gravity")
    if "source" in d:
        out["source"] = _ref(d["source"], "calibration.source", where)
    return out


def _header(doc: Any, where: Any) -> None:
    """``format`` and ``format_version``: another file, or another version, in one line."""
    if not isinstance(doc, dict):
        kind = {list: "a JSON list", str: "a JSON string"}.get(type(doc), "not a JSON object")
        raise DataError(f"{where}: not a sensor profile: the top level is {kind}, expected an "
                        f"object with 'format': '{FORMAT}' (`tiltbench noise --save` writes one)")
    if doc.get("format") != FORMAT:
        got = "missing" if "format" not in doc else f"is {_short(doc['format'])}"
        raise DataError(f"{where}: not a sensor profile: field 'format' {got}, expected "
                        f"{FORMAT!r} (`tiltbench noise --save` writes one)")
    if "format_version" not in doc:
        raise _fail(where, "format_version", f"missing; {_RERUN}")
    version = doc["format_version"]
    if version != FORMAT_VERSION or not _is_int(version):
        old = _is_int(version) and 1 <= version < FORMAT_VERSION
        raise _fail(where, "format_version", f"is {_short(version)}; this tiltbench reads "
                    f"version {FORMAT_VERSION} only ("
                    + ("a version-1 profile, without a checksum: " if old else
                       "written by a newer tiltbench? upgrade, or ") + f"{_RERUN})")


def profile_from_document(doc: Any, where: Any = "<memory>") -> SensorProfile:
    """Check a ``sensor.json`` object completely and build its :class:`SensorProfile`.

    In order: the header (``format``, ``format_version``); every field present and no
    unknown one; ``sample_rate``; ``fit``; every axis block (terms, ranges, bounds,
    ``fit_ok``), every axis of :data:`REQUIRED_AXES`; ``calibration``; ``source``;
    ``units``; the ``checksum`` of the defining fields.

    Parameters
    ----------
    doc : the parsed JSON.
    where : the file name (or what stands for it) for the messages.

    Raises
    ------
    DataError : one line, ``{where}: field '{dotted.path}' {what is wrong}``; a hand edit that
        keeps every check says "checksum/consistency failed".
    """
    _header(doc, where)
    _keys(doc, "", where, _REQUIRED, COSMETIC_FIELDS)
    rate = _number(doc["sample_rate"], "sample_rate", where, "Hz", SAMPLE_RATE_RANGE,
                   "the sample rate")
    fit = _fit_from(doc["fit"], where)
    blocks = doc["axes"]
    if not isinstance(blocks, dict):
        raise _fail(where, "axes", "must be an object {axis name: axis block} (e.g. "
                    f"{{\"x\": …, \"y\": …}}), got {_short(blocks)}")
    unknown = [a for a in blocks if a not in AXIS_NAMES]
    if unknown:
        raise _fail(where, f"axes.{unknown[0]}", f"is not an axis of format version "
                    f"{FORMAT_VERSION} ({', '.join(AXIS_NAMES)})")
    missing = [a for a in REQUIRED_AXES if a not in blocks]
    if missing:
        has = ", ".join(blocks) if blocks else "no axis"
        raise _fail(where, f"axes.{missing[0]}", f"missing: the profile has {has}; it needs "
                    f"the tilt plane's axes {' and '.join(REQUIRED_AXES)}; {_RERUN}")
    axes = tuple(a for a in AXIS_NAMES if a in blocks)
    level = None if fit is None else fit["level"]
    checked = {a: _axis_from(blocks[a], a, where, level) for a in axes}
    calibration = _calibration_from(doc["calibration"], CALIBRATION_AXES, where)
    source = _ref(doc["source"], "source", where)
    tool = doc.get("tool")
    first = (set(axes) <= {"x", "y"}
             and not any(k in blocks[a] for a in axes for k in OPTIONAL_AXIS_FIELDS))
    before_filter = not any("export_filter" in blocks[a] for a in axes)
    if (doc["units"] != UNITS and not (before_filter and doc["units"] == UNITS_V2_1)
            and not (first and doc["units"] == UNITS_V2_0)):
        raise DataError(f"{where}: checksum/consistency failed: field 'units' differs from "
                        f"this format's units (the file was edited); {_RERUN}")
    stored = doc["checksum"]
    value = defining_checksum(doc)
    if (not isinstance(stored, dict) or stored.get("algorithm") != "sha256"
            or stored.get("covers") != list(CHECKSUM_FIELDS) or stored.get("value") != value
            or set(stored) != {"algorithm", "covers", "value"}):
        raise DataError(f"{where}: checksum/consistency failed: field 'checksum' does not "
                        f"match the fields it covers ({', '.join(CHECKSUM_FIELDS)}): the file "
                        f"was edited; {_RERUN}")

    def per_axis(name: str, optional: bool = True) -> tuple | None:
        values = tuple(checked[a][name] for a in axes)
        return None if optional and all(v is None for v in values) else values

    extra: dict[str, Any] = {"unresolved_upper_bounds": {
        a: checked[a]["unresolved_upper_bounds"] for a in axes}}
    if fit is not None:
        extra.update(fit)
    if any(checked[a]["fit_ok"] is not None for a in axes):
        extra["lack_of_fit"] = {a: not checked[a]["fit_ok"] for a in axes
                                if checked[a]["fit_ok"] is not None}
    version = tool.get("version") if isinstance(tool, dict) else None
    return SensorProfile(
        sample_rate=rate, white_noise_density=per_axis("white_noise_density", False),
        bias_instability=per_axis("bias_instability"),
        rate_random_walk=per_axis("rate_random_walk"),
        quantization_step=per_axis("quantization_step"), calibration=calibration,
        source=source, tool_version=str(version) if version is not None else "unknown",
        axes=axes, extra=extra, quantization_noise=per_axis("quantization_noise"),
        gauss_markov=per_axis("gauss_markov"), fit_tau_range=per_axis("fit_tau_range"),
        export_filter=per_axis("export_filter"))


FAILED_FIT_FLAG = "--allow-failed-fit"
"""The option of ``generate`` and ``gap`` that accepts a profile saved from a failed fit."""


def require_fit_ok(profile: SensorProfile, where: Any, allow: bool = False,
                   axes: tuple[str, ...] | None = None) -> list[str]:
    """Refuse a profile written from a fit that did not describe the curve.

    ``tiltbench noise --save`` refuses such a profile unless ``--save-failed-fit``, which
    writes ``fit_ok: false`` on the axes no model of the rule described; a consumer of the
    profile (``generate --sensor``, ``gap --sensor``) refuses it too unless told
    (:data:`FAILED_FIT_FLAG`): a twin of terms that do not describe the sensor would be
    another sensor.

    Parameters
    ----------
    profile : the loaded profile.
    where : its file name, for the message.
    allow : accept it (the consumer's ``--allow-failed-fit``): the axes are returned.
    axes : the axes the consumer uses (default every axis of the profile).

    Returns
    -------
    list[str] : the used axes saved with ``fit_ok: false`` (empty when none, or refused).

    Raises
    ------
    DataError : one line naming the file, the axes and the flag.
    """
    names = [a for a in (axes or profile.axes) if a in profile.axes]
    bad = [a for a in names if profile.fit_ok(a) is False]
    if bad and not allow:
        raise DataError(f"{where}: field 'axes.{bad[0]}.fit_ok' is false: the profile was saved "
                        f"from a fit that does not describe the Allan curve of axis "
                        f"{', '.join(bad)} (`noise --save-failed-fit`); a twin of it is not "
                        f"that sensor — re-run `tiltbench noise` on a better log or τ range, "
                        f"or give {FAILED_FIT_FLAG} to use it anyway")
    return bad


def load_profile(path: str | os.PathLike) -> SensorProfile:
    """Read and check ``sensor.json``: the one reader of every command (``generate
    --sensor``, ``gap --sensor``).

    Parameters
    ----------
    path : the profile, as :func:`save_profile` wrote it.

    Returns
    -------
    SensorProfile : its terms (units in :data:`TERM_UNITS`), calibration and provenance.

    Raises
    ------
    DataError : file missing, empty, not UTF-8 JSON, another format or version, or any check
        of :func:`profile_from_document` (one line naming the file and the field).
    """
    path = Path(path)
    check_file(path, "a sensor profile (sensor.json)", "sensor profile")
    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as exc:
        raise DataError(f"{path}: not a sensor profile (not UTF-8 text: {exc.reason} at byte "
                        f"{exc.start}); {_RERUN}") from None
    if not text.strip():
        raise DataError(f"{path}: empty file, not a sensor profile; {_RERUN}")
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise DataError(f"{path}: not JSON ({exc.msg}, line {exc.lineno}); {_RERUN}") from None
    except (ValueError, RecursionError) as exc:
        raise DataError(f"{path}: not JSON ({str(exc)[:80]}); {_RERUN}") from None
    return profile_from_document(doc, path)


__all__ = ["AXIS_FIELDS", "AXIS_NAMES", "BIAS_INSTABILITY_RANGE", "CALIBRATION_AXES",
           "CALIBRATION_METHODS", "CHECKSUM_FIELDS", "CORRELATION_EIG_MIN",
           "CORRELATION_TIME_RANGE", "COSMETIC_FIELDS", "DEFINING_FIELDS", "EXPORT_FILTER_SUM_TOL",
           "EXPORT_FILTER_TAPS", "EXTRA_KEYS", "FAILED_FIT_FLAG", "FORMAT", "FORMAT_VERSION",
           "GAIN_RANGE", "GYRO_QUANTIZATION_STEP_RANGE", "GYRO_TERM_RANGES", "GYRO_TERM_UNITS",
           "G_RANGE", "MAX_ABS_CALIBRATION_BIAS", "N_RANGE", "OPTIONAL_AXIS_FIELDS",
           "QUANTIZATION_NOISE_RANGE", "QUANTIZATION_STEP_RANGE", "RATE_RANDOM_WALK_RANGE",
           "REQUIRED_AXES", "REQUIRED_AXIS_FIELDS", "SAMPLE_RATE_RANGE", "SIGMA2_RANGE",
           "TAU_RANGE", "TERM_NAMES", "TERM_RANGES", "TERM_UNITS", "UNITS", "UNITS_V2_0",
           "UNITS_V2_1", "WHITE_NOISE_DENSITY_RANGE", "NoiseTerm", "SensorProfile", "check_profile",
           "defining_checksum", "load_profile", "profile_document", "profile_from_document",
           "require_fit_ok", "save_profile"]
