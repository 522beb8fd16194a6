"""Batched Monte Carlo of "generate + calibrate" for one design (many runs, one factorization).

Model (course; :mod:`calib.calibration.ls`), per axis a ∈ {x, y} and run k::

    A_m,a = (1 + scale_a)·A_r,a(θ) + bias_a + σ_a v_a,k,      v_a,k ~ N(0, I_N)

with ``A_rx = -g sin θ``, ``A_ry = -g cos θ`` (m/s²). The per-axis OLS estimate is linear in
the data, so with the design factored once (:func:`calib.calibration.ls.axis_factor`,
``Hs = Q R``, ``p̂ = A Qᵀy``) a run costs its draws plus two matrix products::

    p̂_a,k  = p_a + σ_a · A_a (Q_aᵀ v_a,k)             (exact: A Qᵀ H = I)
    RSS_a,k = σ_a² · (‖v_a,k‖² − ‖Q_aᵀ v_a,k‖²)

A run's draws go into one reused (2, N) buffer and are reduced at once (while in cache) to
``Qᵀv`` and ``‖v‖²`` per axis; the chunk's estimates are then small matrix products.
Known σ² (``sigma2="given"``): covariance
``σ_a² A_a A_aᵀ``, the same for every run; estimated σ²: ``s_a² = RSS_a/(N − 2)`` per run and
covariance ``s_a² A_a A_aᵀ``. ``χ²_a = RSS_a / σ²_used``.

Seeds (:mod:`calib.stats.runs`): run k draws ``standard_normal`` of shape (2, N) (row x, then row y:
each axis' noise contiguous, so its reduction reads memory in order)
from ``Generator(PCG64(SeedSequence(seed, spawn_key=spawn_key + (k,))))`` — the k-th child of
``run_seeds(seed, runs, spawn_key)`` — so results depend on ``(seed, runs, spawn_key)`` only,
never on the chunk size, the mapper or the number of processes. ``calibrate()`` on the same
readings gives the same numbers to rounding (tested to 1e-12).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from calib.calibration.correct import apply_errors
from calib.calibration.ls import axis_factor
from calib.conventions import AXES, JOINT_PARAM_NAMES, G
from calib.results import ResultMixin
from calib.stats.consistency import nees
from calib.stats.runs import Mapper, chunk_ranges, serial_map

Sigma2Mode = Literal["given", "estimated"]

DEFAULT_CHUNK = 256
"""Runs per task. A task carries the factored design (≈ 0.64 MB at N = 20001), which costs
≈ 2 ms to ship to a local process (measured here), against ≈ 0.45 ms of work per run: 256 runs
keep that under 2 %, and still give a progress count every ≈ 0.1 s of a core. Memory per task
is one (2, N) buffer whatever the chunk."""


def _ro(a) -> np.ndarray:
    arr = np.array(a, dtype=float)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class BatchDesign:
    """A calibration design factored once, for many runs (module docstring for the equations).

    Use it directly to calibrate runs whose noise is drawn elsewhere (e.g. a run that also
    draws vehicle readings from the same stream): per run ``z, ss = design.reduce(v)`` on the
    (2, N) standard-normal draws, then ``design.estimates(Z, SS, truth, sd)`` for a batch.

    Attributes
    ----------
    qt : (2, 2, N) ``Q_xᵀ``, ``Q_yᵀ`` (Q: orthonormal columns of each axis' design; stored
        transposed and contiguous: ``Qᵀv`` is then the fastest matrix-vector product).
    maps : (2, 2, 2) ``A_x``, ``A_y`` (``p̂ = A Qᵀy``).  cov1 : (2, 2, 2) ``A Aᵀ`` (σ² = 1).
    n : samples N.  g : m/s².
    """

    qt: np.ndarray
    maps: np.ndarray
    cov1: np.ndarray
    n: int
    g: float

    def reduce(self, v: np.ndarray, z: np.ndarray | None = None,
               ss: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``(Qᵀv per axis (4,), ‖v_a‖² (2,))`` of one run's (2, N) draws (into z, ss)."""
        z = np.empty(4) if z is None else z
        ss = np.empty(2) if ss is None else ss
        vx, vy = v[0], v[1]
        z[0:2], z[2:4] = self.qt[0] @ vx, self.qt[1] @ vy
        ss[0], ss[1] = vx @ vx, vy @ vy
        return z, ss

    def estimates(self, z: np.ndarray, ss: np.ndarray, truth, sd
                  ) -> tuple[np.ndarray, np.ndarray]:
        """``(p̂ (r, 4), RSS (r, 2))`` from the reduced draws of r runs.

        ``truth`` (4,) ``[bias_x, scale_x, bias_y, scale_y]``; ``sd`` (2,) σ (m/s²).
        Element-wise (not a GEMM over the runs): a run's numbers must not depend on how many
        runs are computed with it, and BLAS kernels may round differently by matrix size.
        """
        z = np.atleast_2d(z)
        ss = np.atleast_2d(ss)
        truth = np.asarray(truth, dtype=float)
        sd = np.asarray(sd, dtype=float)
        params = np.empty((z.shape[0], 4))
        rss = np.empty((z.shape[0], 2))
        for a in range(2):
            z0, z1 = z[:, 2 * a], z[:, 2 * a + 1]
            A = self.maps[a]
            for i in range(2):
                params[:, 2 * a + i] = truth[2 * a + i] + sd[a] * (A[i, 0] * z0 + A[i, 1] * z1)
            rss[:, a] = sd[a] ** 2 * (ss[:, a] - (z0 * z0 + z1 * z1))
        return params, rss


def batch_design(theta: np.ndarray, g: float = G) -> BatchDesign:
    """Factor the per-axis course designs of ``theta`` (rad) once
    (:func:`calib.calibration.ls.axis_factor`; raises
    :class:`calib.calibration.ls.NotIdentifiableError` like ``calibrate``)."""
    theta = np.asarray(theta, dtype=float).ravel()
    qt = np.empty((2, 2, theta.size))
    maps = np.empty((2, 2, 2))
    cov1 = np.empty((2, 2, 2))
    for a, ax in enumerate(AXES):
        _, fac = axis_factor(theta, ax, g)
        qt[a], maps[a], cov1[a] = fac.q.T, fac.solve_map, fac.cov1
    return BatchDesign(qt, maps, cov1, int(theta.size), float(g))


def run_generator(seed: int, k: int, spawn_key: tuple[int, ...] = ()) -> np.random.Generator:
    """Run k's generator: the k-th child of ``run_seeds(seed, ·, spawn_key)`` (a child's
    state depends on ``(seed, spawn_key + (k,))`` only, so it is built directly)."""
    ss = np.random.SeedSequence(int(seed), spawn_key=(*spawn_key, int(k)))
    return np.random.Generator(np.random.PCG64(ss))


def draw_noise(seed: int, runs: range, n: int, spawn_key: tuple[int, ...] = ()) -> np.ndarray:
    """Standard normal draws (len(runs), 2, n) of the runs in ``runs`` (module docstring)."""
    buf = np.empty((len(runs), 2, n))
    key = tuple(int(k) for k in spawn_key)
    for j, k in enumerate(runs):
        run_generator(seed, k, key).standard_normal(out=buf[j])
    return buf


def _chunk(task: tuple) -> tuple[np.ndarray, np.ndarray]:
    """One chunk: ``(p̂ (r, 4), RSS (r, 2))`` of the runs in the range.

    Each run is drawn into one reused (2, N) buffer and reduced at once, while in cache, to
    ``Qᵀv`` and ``‖v‖²`` per axis (:meth:`BatchDesign.reduce`); the estimates of the chunk
    follow element-wise (:meth:`BatchDesign.estimates`).
    """
    design, truth, sd, seed, key, runs = task
    v = np.empty((2, design.n))
    z = np.empty((len(runs), 4))
    ss = np.empty((len(runs), 2))
    for j, k in enumerate(runs):
        run_generator(seed, k, key).standard_normal(out=v)
        design.reduce(v, z[j], ss[j])
    return design.estimates(z, ss, truth, sd)


@dataclass(frozen=True, eq=False)
class MonteCarloResult(ResultMixin):
    """Many calibrations of one design (per-axis OLS), run by run.

    Attributes
    ----------
    params : (R, 4) estimates ``[bias_x, scale_x, bias_y, scale_y]`` (m/s², 1, m/s², 1).
    sigma2 : (R, 2) noise variance used per run and axis, (m/s²)² (the given one repeated,
        or ``RSS/(N − 2)``).
    chi2 : (R, 2) ``RSS_a / σ²_used`` (dimensionless; ``N − 2`` when σ² is estimated).
    cov1 : (2, 2, 2) unit covariance ``A_a A_aᵀ`` per axis: ``cov_a,k = sigma2[k, a] · cov1[a]``.
    truth : (4,) the true parameters.  n : samples per run.  sigma2_source : "given" or
    "estimated".  seed, spawn_key : the streams (module docstring).  g : m/s².
    """

    params: np.ndarray
    sigma2: np.ndarray
    chi2: np.ndarray
    cov1: np.ndarray
    truth: np.ndarray
    n: int
    sigma2_source: Sigma2Mode
    seed: int
    spawn_key: tuple[int, ...] = ()
    g: float = G
    extra: dict = field(default_factory=dict, compare=False)

    _TITLE = "Monte Carlo of calibrations"
    _UNITS = ("bias m/s²; scale dimensionless; σ² (m/s²)²; χ² dimensionless; runs count")

    def __post_init__(self) -> None:
        for name in ("params", "sigma2", "chi2", "cov1", "truth"):
            object.__setattr__(self, name, _ro(getattr(self, name)))
        object.__setattr__(self, "spawn_key", tuple(int(k) for k in self.spawn_key))

    @property
    def runs(self) -> int:
        return int(self.params.shape[0])

    @property
    def dof(self) -> int:
        return self.n - 2

    @property
    def std(self) -> np.ndarray:
        """(R, 4) standard deviations of each run's estimates (same units as ``params``)."""
        d = np.stack([np.diag(c) for c in self.cov1])                 # (2, 2)
        return np.sqrt(np.repeat(self.sigma2, 2, axis=1) * d.reshape(4))

    def covs(self) -> np.ndarray:
        """(R, 4, 4) block-diagonal covariance of every run (per-axis OLS: no cross terms),
        ``σ²_a,k · cov1[a]`` on each axis' block."""
        c = np.zeros((self.runs, 4, 4))
        for a in range(2):
            c[:, 2 * a:2 * a + 2, 2 * a:2 * a + 2] = self.sigma2[:, a, None, None] * self.cov1[a]
        return c

    def errors(self) -> np.ndarray:
        """(R, 4) estimate − truth."""
        return self.params - self.truth

    def nees(self) -> np.ndarray:
        """(R,) ``d² = eᵀ Σ_k⁻¹ e`` per run (χ²₄ for an honest estimator with known σ²;
        :func:`calib.stats.consistency.nees` on each run's block-diagonal covariance)."""
        return nees(self.errors(), self.covs())

    def interval_hits(self, level: float = 0.95) -> np.ndarray:
        """(R, 4) bool: truth inside each run's two-sided ``level`` interval (normal
        quantiles when σ² is given, Student t(N − 2) when estimated)."""
        from scipy import stats

        q = 0.5 + level / 2
        k = stats.norm.ppf(q) if self.sigma2_source == "given" else stats.t.ppf(q, self.dof)
        return np.abs(self.errors()) <= k * self.std

    def estimates(self, k: int) -> dict:
        """Run ``k`` as a ``calibrate --json``-like ``axes`` object (for validators)."""
        axes = {}
        std = self.std[k]
        for i, a in enumerate(AXES):
            axes[a] = {"bias": float(self.params[k, 2 * i]), "bias_std": float(std[2 * i]),
                       "scale": float(self.params[k, 2 * i + 1]),
                       "scale_std": float(std[2 * i + 1]),
                       "cov": (self.sigma2[k, i] * self.cov1[i]).tolist(),
                       "sigma2": float(self.sigma2[k, i]),
                       "sigma2_source": self.sigma2_source,
                       "chi2_dof": float(self.chi2[k, i] / self.dof), "n": self.n}
        return {"method": "ols", "g": self.g, "axes": axes}

    def summary(self, level: float = 0.95) -> str:
        hits = self.interval_hits(level).mean(axis=0)
        mean, sd = self.params.mean(axis=0), self.params.std(axis=0, ddof=1)
        rows = [f"{self.runs} runs, N = {self.n}, σ² {self.sigma2_source}, seed {self.seed}",
                f"{'param':<9}{'truth':>12}{'mean':>13}{'sd(runs)':>12}{'mean std':>12}"
                f"{'cover ' + format(level, 'g'):>12}"]
        for i, name in enumerate(JOINT_PARAM_NAMES):
            unit = "m/s²" if name.startswith("bias") else "1"
            rows.append(f"{name:<9}{self.truth[i]:>12.6g}{mean[i]:>13.6g}{sd[i]:>12.4g}"
                        f"{self.std[:, i].mean():>12.4g}{hits[i]:>12.4f}  ({unit})")
        return "\n".join(rows)

    def to_dict(self) -> dict:
        return {"params": self.params.tolist(), "sigma2": self.sigma2.tolist(),
                "chi2": self.chi2.tolist(), "cov1": self.cov1.tolist(),
                "truth": self.truth.tolist(), "n": self.n,
                "sigma2_source": self.sigma2_source, "seed": self.seed,
                "spawn_key": list(self.spawn_key), "g": self.g, "extra": self.extra}

    @classmethod
    def from_dict(cls, d: dict) -> MonteCarloResult:
        return cls(np.asarray(d["params"], dtype=float).reshape(-1, 4),
                   np.asarray(d["sigma2"], dtype=float).reshape(-1, 2),
                   np.asarray(d["chi2"], dtype=float).reshape(-1, 2), d["cov1"], d["truth"],
                   int(d["n"]), d["sigma2_source"], int(d["seed"]),
                   tuple(d.get("spawn_key", ())), float(d.get("g", G)),
                   dict(d.get("extra", {})))

    def __eq__(self, other) -> bool:
        if not isinstance(other, MonteCarloResult):
            return NotImplemented
        return self.to_dict() == other.to_dict()

    __hash__ = None  # type: ignore[assignment]


def simulate_calibrations(
    theta: np.ndarray, bias, scale, noise_var, runs: int, seed: int,
    sigma2: Sigma2Mode = "given", g: float = G, spawn_key: tuple[int, ...] = (),
    chunk: int = DEFAULT_CHUNK, mapper: Mapper = serial_map,
    progress: Callable[[int, int], None] | None = None,
) -> MonteCarloResult:
    """``runs`` fresh calibrations (per-axis OLS, the course method) of the design ``theta``.

    Parameters
    ----------
    theta : (N,) table angles, rad.  bias : (2,) true bias [x, y], m/s².  scale : (2,) true
        scale errors [x, y] (dimensionless).  noise_var : (2,) σ² [x, y], (m/s²)².
    runs : number of runs R.  seed, spawn_key : the streams (module docstring).
    sigma2 : "given" (the fit uses the true σ², as ``calibrate(e, noise_var)``) or
        "estimated" (``calibrate(e, None)``: σ² = RSS/(N − 2) per run).
    g : gravity, m/s².  chunk : runs per task (results do not depend on it).
    mapper : :class:`calib.stats.runs.Mapper` (serial by default; ``bench.sweep`` for processes or a
        Dask cluster).  progress : ``progress(done, total)`` in chunks.

    Returns
    -------
    MonteCarloResult

    Examples
    --------
    >>> import numpy as np
    >>> th = np.linspace(0.0, 2 * np.pi, 2001)
    >>> mc = simulate_calibrations(th, [0.08, -0.02], [-0.03, 0.01], [0.25, 0.64], runs=400,
    ...                            seed=0)
    >>> mc.params.shape                        # [bias_x, scale_x, bias_y, scale_y] per run
    (400, 4)
    >>> bool(0.9 < mc.interval_hits(0.95).mean() < 1.0)   # 95 % intervals cover ≈ 95 %
    True
    """
    theta = np.asarray(theta, dtype=float).ravel()
    if sigma2 not in ("given", "estimated"):
        raise ValueError(f"sigma2 must be 'given' or 'estimated', got {sigma2!r}")
    nv = np.asarray(noise_var, dtype=float).reshape(2)
    if not np.all(np.isfinite(nv)) or np.any(nv <= 0):
        raise ValueError(f"noise variances must be positive and finite, got {nv.tolist()}")
    if int(runs) < 1:
        raise ValueError(f"runs must be >= 1, got {runs}")
    bias = np.asarray(bias, dtype=float).reshape(2)
    scale = np.asarray(scale, dtype=float).reshape(2)
    n = theta.size
    design = batch_design(theta, g)
    truth = np.array([bias[0], scale[0], bias[1], scale[1]])
    tasks = [(design, truth, np.sqrt(nv), int(seed), tuple(int(k) for k in spawn_key), r)
             for r in chunk_ranges(int(runs), int(chunk))]
    parts = mapper(_chunk, tasks, progress)
    params = np.concatenate([p for p, _ in parts])
    rss = np.concatenate([r for _, r in parts])
    if sigma2 == "given":
        s2 = np.broadcast_to(nv, rss.shape).copy()
    else:
        s2 = rss / (n - 2)
    return MonteCarloResult(params, s2, rss / s2, design.cov1, truth, n, sigma2, int(seed),
                            tuple(spawn_key), float(g))


def synthetic_readings(theta: np.ndarray, bias, scale, noise_var, seed: int, k: int,
                       spawn_key: tuple[int, ...] = (), g: float = G) -> np.ndarray:
    """(N, 2) readings of run ``k`` exactly as the engine draws them (for checks and plots):
    ``apply_errors(A_r, bias, scale) + sqrt(σ²) · v_k`` (m/s²)."""
    from calib.conventions import reference_accel

    theta = np.asarray(theta, dtype=float).ravel()
    v = draw_noise(seed, range(k, k + 1), theta.size, spawn_key)[0]
    clean = apply_errors(reference_accel(theta, g), bias, scale)
    return clean + np.sqrt(np.asarray(noise_var, dtype=float)) * v.T


__all__ = ["BatchDesign", "MonteCarloResult", "batch_design", "draw_noise", "run_generator",
           "simulate_calibrations", "synthetic_readings"]
