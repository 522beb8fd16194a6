"""The sensor profile (``sensor.json``): a measured sensor's noise terms and calibration.

``tiltbench noise`` writes it from a static log (Allan deviation, IEEE Std 952/1293 readings);
``generate --sensor`` simulates that sensor on the MuJoCo table; ``gap --sensor`` takes the
bias random walk's intensity from it instead of fitting it freely.

One JSON object (``format`` "tiltbench-sensor", ``format_version`` 1)::

    sample_rate          Hz
    axes                 ["x", "y"]   (the tilt plane's axes, course signs)
    white_noise_density  per axis: NoiseTerm, (m/s²)/√Hz  (Allan −½ line at τ = 1 s)
    bias_instability     per axis: NoiseTerm, m/s²        (flat minimum / 0.664), or null
    rate_random_walk     per axis: NoiseTerm, m/s²/√s     (Allan +½ line at τ = 3 s), or null;
                         the same q as the bias random walk b_k = b_{k-1} + q·√Δt·w_k
    quantization_step    per axis: m/s², or null
    calibration          {"param_names", "params", "cov"} (bias m/s², scale 1), or null
    source               {"name", "sha256"} of the static log, or null
    tool                 {"name": "tiltbench", "version": …}
    units                key → unit

A term that the log cannot resolve (no flat minimum, no +½ slope within the τ range) is null
for that axis, and a simulator leaves it out; its upper bound is kept in
``extra["unresolved_upper_bounds"][axis][term]`` (:meth:`SensorProfile.upper_bound`).
``extra`` also holds the interval ``level``, the significance ``alpha``, the sample count ``n``
and the lack-of-fit verdict per axis (:meth:`calib.noise.allan.NoiseCharacterization.to_profile`).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from calib.files.atomic import write_text
from calib.input_rules import DataError

FORMAT = "tiltbench-sensor"
FORMAT_VERSION = 1
UNITS = {
    "sample_rate": "Hz",
    "white_noise_density": "(m/s^2)/sqrt(Hz)",
    "bias_instability": "m/s^2",
    "rate_random_walk": "m/s^2/sqrt(s)",
    "quantization_step": "m/s^2",
    "calibration.params": "bias m/s^2, scale 1",
    "tau_range": "s",
}


@dataclass(frozen=True)
class NoiseTerm:
    """One noise coefficient of one axis: estimate, interval at ``level`` and the τ range
    (s) of the Allan deviation it was read from."""

    value: float
    interval: tuple[float, float]
    tau_range: tuple[float, float]
    level: float = 0.683

    def to_dict(self) -> dict:
        return {"value": float(self.value), "interval": [float(v) for v in self.interval],
                "tau_range": [float(v) for v in self.tau_range], "level": float(self.level)}

    @classmethod
    def from_dict(cls, d: dict) -> NoiseTerm:
        return cls(value=float(d["value"]), interval=tuple(float(v) for v in d["interval"]),
                   tau_range=tuple(float(v) for v in d["tau_range"]),
                   level=float(d.get("level", 0.683)))


def _terms_to(terms):
    return None if terms is None else [None if t is None else t.to_dict() for t in terms]


def _terms_from(d):
    return None if d is None else tuple(None if t is None else NoiseTerm.from_dict(t)
                                        for t in d)


@dataclass(frozen=True)
class SensorProfile:
    """A measured sensor (module docstring). Per-axis tuples hold (x, y)."""

    sample_rate: float
    white_noise_density: tuple[NoiseTerm | None, NoiseTerm | None]
    bias_instability: tuple[NoiseTerm | None, NoiseTerm | None] | None = None
    rate_random_walk: tuple[NoiseTerm | None, NoiseTerm | None] | None = None
    quantization_step: tuple[float | None, float | None] | None = None
    calibration: dict[str, Any] | None = None
    source: dict[str, str] | None = None
    tool_version: str = "unknown"
    axes: tuple[str, str] = ("x", "y")
    extra: dict[str, Any] = field(default_factory=dict)

    def white_sigma(self, axis: int) -> float:
        """Per-sample white-noise std (m/s²) at the profile's rate: σ = N·√fs."""
        term = self.white_noise_density[axis]
        return float("nan") if term is None else float(term.value * np.sqrt(self.sample_rate))

    def term(self, name: str, axis: int) -> NoiseTerm | None:
        """The :class:`NoiseTerm` ``name`` ("white_noise_density", "bias_instability",
        "rate_random_walk") of ``axis`` (0 = x, 1 = y), or None when the log did not resolve it.
        """
        terms = getattr(self, name)
        return None if terms is None else terms[axis]

    def upper_bound(self, name: str, axis: int) -> float | None:
        """For a term the log did not resolve: the upper end of its interval (same unit, at
        ``extra["level"]``), as ``tiltbench noise`` recorded it; None when resolved or unknown.
        A model that takes the term from the profile can bound it instead of leaving it free.
        """
        if self.term(name, axis) is not None:
            return None
        bounds = self.extra.get("unresolved_upper_bounds", {}).get(self.axes[axis], {})
        value = bounds.get(name)
        return None if value is None else float(value)

    def to_dict(self) -> dict:
        return {
            "format": FORMAT, "format_version": FORMAT_VERSION,
            "tool": {"name": "tiltbench", "version": self.tool_version},
            "sample_rate": float(self.sample_rate), "axes": list(self.axes),
            "white_noise_density": _terms_to(self.white_noise_density),
            "bias_instability": _terms_to(self.bias_instability),
            "rate_random_walk": _terms_to(self.rate_random_walk),
            "quantization_step": (None if self.quantization_step is None else
                                  [None if q is None else float(q)
                                   for q in self.quantization_step]),
            "calibration": self.calibration, "source": self.source, "extra": self.extra,
            "units": UNITS,
        }

    @classmethod
    def from_dict(cls, d: dict, where: str = "<memory>") -> SensorProfile:
        if d.get("format") != FORMAT:
            raise DataError(f"{where}: not a sensor profile (format {d.get('format')!r}, "
                            f"expected {FORMAT!r}; `tiltbench noise --save` writes one)")
        if d.get("format_version") != FORMAT_VERSION:
            raise DataError(f"{where}: sensor profile format_version "
                            f"{d.get('format_version')!r}; this tiltbench reads "
                            f"{FORMAT_VERSION} only")
        try:
            q = d.get("quantization_step")
            return cls(
                sample_rate=float(d["sample_rate"]),
                white_noise_density=_terms_from(d["white_noise_density"]),
                bias_instability=_terms_from(d.get("bias_instability")),
                rate_random_walk=_terms_from(d.get("rate_random_walk")),
                quantization_step=None if q is None else tuple(
                    None if v is None else float(v) for v in q),
                calibration=d.get("calibration"), source=d.get("source"),
                tool_version=d.get("tool", {}).get("version", "unknown"),
                axes=tuple(d.get("axes", ("x", "y"))), extra=d.get("extra", {}))
        except (KeyError, TypeError, ValueError) as exc:
            raise DataError(f"{where}: sensor profile field missing or malformed: {exc}"
                            ) from None


def save_profile(path: str | os.PathLike, profile: SensorProfile, force: bool = False) -> Path:
    """Write ``sensor.json`` atomically; refuses to overwrite without ``force``."""
    return write_text(path, json.dumps(profile.to_dict(), indent=2) + "\n", force=force)


def load_profile(path: str | os.PathLike) -> SensorProfile:
    """Read ``sensor.json`` (DataError naming the file on anything malformed)."""
    path = Path(path)
    try:
        doc = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise DataError(f"{path}: not JSON ({exc.msg}, line {exc.lineno})") from None
    return SensorProfile.from_dict(doc, str(path))


__all__ = ["FORMAT", "FORMAT_VERSION", "NoiseTerm", "SensorProfile", "UNITS", "load_profile",
           "save_profile"]
