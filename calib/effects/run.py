"""A measured calibration run prepared for the extensions (:class:`RunData`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from calib.conventions import reference_accel
from calib.filters import uniform_step
from calib.stats.diagnostics import angular_rates


@dataclass(frozen=True, eq=False)
class RunData:
    """A measured calibration run prepared for the extensions (read-only arrays).

    tita : (N,) rad.  datos : (N, 2) m/s².  a_ref : (N, 2) ``[-g sin θ, -g cos θ]``.
    g : m/s².  The stated noise is not part of the run: it is a statement about the sensor,
    kept in the model state (:attr:`calib.effects.AxisState.sigma2_stated`).
    t : (N,) sample times, s (the file's ``t`` or ``k/rate``), or None.
    tcol : (N,) ``t - t0`` (s) or the sample index k.  time_unit : "s" or "sample".
    dt_walk : (N-1,) Δt of the random walk (s, or 1 per sample).
    omega, alpha : (N,) dθ/dt (rad/s), d²θ/dt² (rad/s²) when timed, else None.
    h_uniform : the sampling period when ``t`` is uniform, else None.
    """

    tita: np.ndarray
    datos: np.ndarray
    a_ref: np.ndarray
    g: float
    t: np.ndarray | None
    tcol: np.ndarray
    time_unit: str
    dt_walk: np.ndarray
    omega: np.ndarray | None
    alpha: np.ndarray | None
    h_uniform: float | None

    @property
    def n(self) -> int:
        return int(self.tita.shape[0])

    @property
    def timed(self) -> bool:
        return self.t is not None

    @classmethod
    def build(cls, tita, datos, g: float, t=None, rate: float | None = None) -> RunData:
        """Prepare a run. ``t`` (s) wins over ``rate`` (Hz, samples in time order)."""
        tita = np.asarray(tita, dtype=float)
        datos = np.asarray(datos, dtype=float)
        n = tita.shape[0]
        if datos.shape != (n, 2):
            raise ValueError(f"datos must be ({n}, 2), got {datos.shape}")
        if t is None and rate is not None:
            if not (np.isfinite(rate) and rate > 0):
                raise ValueError(f"rate must be a positive sample rate (Hz), got {rate}")
            t = np.arange(n, dtype=float) / float(rate)
        omega = alpha = None
        h_uniform = None
        if t is not None:
            t = np.asarray(t, dtype=float)
            if t.shape != (n,) or np.any(np.diff(t) <= 0):
                raise ValueError("t must be (N,) and strictly increasing")
            tcol = t - t[0]
            dt = np.diff(t)
            h_uniform = uniform_step(t)
            omega, alpha = angular_rates(tita, t)
            unit = "s"
        else:
            tcol = np.arange(n, dtype=float)
            dt = np.ones(n - 1)
            unit = "sample"
        arrays = dict(tita=tita, datos=datos, a_ref=reference_accel(tita, g),
                      t=t, tcol=tcol, dt_walk=dt, omega=omega, alpha=alpha)
        for v in arrays.values():
            if v is not None:
                v.setflags(write=False)
        return cls(g=float(g), time_unit=unit, h_uniform=h_uniform, **arrays)

