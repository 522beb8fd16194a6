"""Final fit of the selected model and the catalog estimates (± std) of each named effect.

:class:`Reporter` refits the model with every linear parameter and the Gauss-Newton columns of
the nonlinear ones (τ, L: :meth:`calib.effects.Effect.gn_column`) in one whitened
least-squares system, gives the bias at t0 of a random-walk axis from the smoother, the mean
reading and the whitened residuals. Each effect object turns them into its catalog parameters
and units (:meth:`calib.effects.Effect.estimate`, ``interval``, ``nonlinear``).
"""

from __future__ import annotations

import numpy as np
from scipy import linalg as sla

from calib.calibration.ls import fit_linear
from calib.conventions import AXES
from calib.effects import CATALOG, Extensions, ModelState
from calib.filters import walk_filter
from calib.gap.quantization import quantized_moments
from calib.gap.random_walk import q_uncertainty
from calib.stats.diagnostics import Lattice


class Reporter:
    """Final fit of a model: parameters with covariance, effect estimates, residuals.

    The effect objects read it through ``value``, ``cov_of``, ``gn_std`` (Gauss-Newton std of
    τ and L), ``q_uncertainty`` (random walk), ``lattice`` (quantization), ``ext``, ``state``
    and ``run``.
    """

    def __init__(self, ext: Extensions, state: ModelState,
                 lattice: list[Lattice] | None = None) -> None:
        self.ext, self.state, self.run = ext, state, ext.run
        self.lattice = lattice
        self._q_unc: dict[int, tuple[float, tuple[float, float]]] = {}
        self._fit()

    @classmethod
    def from_params(cls, ext: Extensions, state: ModelState, names: list[str],
                    params: np.ndarray) -> Reporter:
        """A final fit given its parameters (no refit): enough for :meth:`mean` at the
        angles and times of ``ext.run`` (what :func:`calib.gap.predict` needs)."""
        rep = cls.__new__(cls)
        rep.ext, rep.state, rep.run = ext, state, ext.run
        rep.names, rep.params = list(names), np.asarray(params)
        return rep

    def q_uncertainty(self, k: int) -> tuple[float, tuple[float, float]]:
        """(std, 95 % interval) of the random-walk q of axis k (:func:`q_uncertainty`)."""
        if k not in self._q_unc:
            self._q_unc[k] = q_uncertainty(self.ext, self.state, k)
        return self._q_unc[k]

    def _axis_rows(self, k: int, gain: float) -> tuple[np.ndarray, np.ndarray, list[str],
                                                       np.ndarray | None]:
        ext, st = self.ext, self.state.axes[k]
        r = ext.reference(k, st.tau, st.limit)
        names, cols = ext.columns(k, st)
        parts = [self.run.datos[:, k] - r, np.ones_like(r), r, *cols]
        pnames = ["bias", "scale", *names]
        for e in CATALOG:  # Gauss-Newton columns d mean / d(nonlinear parameter)
            gn = e.gn_column(ext, k, st, gain) if e.present(st) else None
            if gn is not None:
                pnames.append(gn[0])
                parts.append(gn[1])
                self._gn_names.add(gn[0])
        if self.state.tilt:
            parts.append(ext.tilt_column(k, st))
        z = np.column_stack(parts)
        if st.q > 0:  # differenced and whitened: the bias drops out (smoother gives it)
            w = ext.whiten(st, z)
            w = np.delete(w, 1, axis=1)
            pnames = pnames[1:]
        else:
            w = z / np.sqrt(st.sigma2_eff)
        tilt = w[:, -1] if self.state.tilt else None
        h = w[:, 1:-1] if self.state.tilt else w[:, 1:]
        return w[:, 0], h, [f"{AXES[k]}.{n}" for n in pnames], tilt

    def _fit(self) -> None:
        ext, state = self.ext, self.state
        self._gn_names: set[str] = set()
        base = ext.fit(state).fit
        gains = [1.0 + float(base.params[base.param_names.index(f"{a}.scale")]) for a in AXES]
        rows = [self._axis_rows(k, gains[k]) for k in range(2)]
        ys = [r[0] for r in rows]
        hs = [r[1] for r in rows]
        names = rows[0][2] + rows[1][2]
        h = sla.block_diag(*hs)
        if state.tilt:
            h = np.column_stack([h, np.concatenate([rows[0][3], rows[1][3]])])
            names.append("sin_tilt")
        fit = fit_linear(h, np.concatenate(ys), tuple(names), sigma2=1.0, intercept=None)
        params, cov = np.array(fit.params), np.array(fit.cov)
        is_gn = [n.split(".", 1)[-1] in self._gn_names for n in names]
        self.gn_std = {n: float(np.sqrt(cov[i, i])) for i, n in enumerate(names) if is_gn[i]}
        keep = [i for i, n in enumerate(names) if not is_gn[i]]
        names = [names[i] for i in keep]
        params, cov = params[keep], cov[np.ix_(keep, keep)]
        self.innov: dict[int, np.ndarray] = {}
        for k in range(2):  # random-walk axes: bias at t0 from the smoother
            st = state.axes[k]
            if st.q <= 0:
                continue
            mean_nb = self._mean(k, names, params, with_bias=False)
            innov, b0, vb0 = walk_filter(self.run.datos[:, k] - mean_nb, st.sigma2_eff,
                                          st.q**2 * self.run.dt_walk)
            self.innov[k] = innov
            at = names.index(f"{AXES[k]}.scale")
            names.insert(at, f"{AXES[k]}.bias")
            params = np.insert(params, at, b0)
            cov = np.insert(np.insert(cov, at, 0.0, axis=0), at, 0.0, axis=1)
            cov[at, at] = vb0
        self.names, self.params, self.cov = names, params, cov

    def value(self, name: str) -> float:
        return float(self.params[self.names.index(name)]) if name in self.names else 0.0

    def _mean(self, k: int, names: list[str], params: np.ndarray, with_bias: bool = True
              ) -> np.ndarray:
        def val(n: str) -> float:
            return float(params[names.index(n)]) if n in names else 0.0

        ax = AXES[k]
        ext, st = self.ext, self.state.axes[k]
        r = ext.reference(k, st.tau, st.limit)
        cnames, cols = ext.columns(k, st)
        mean = r * (1.0 + val(f"{ax}.scale"))
        if with_bias:
            mean = mean + val(f"{ax}.bias")
        for n, c in zip(cnames, cols, strict=True):
            mean = mean + val(f"{ax}.{n}") * c
        if self.state.tilt:
            mean = mean + val("sin_tilt") * ext.tilt_column(k, st)
        return mean

    def walk_input(self, k: int) -> np.ndarray:
        """Readings of axis k minus the final model's mean without its bias, m/s² (what the
        random walk filter follows: ``e_k = b_k + v_k``)."""
        return self.run.datos[:, k] - self._mean(k, self.names, self.params, with_bias=False)

    def mean(self, k: int) -> np.ndarray:
        return self._mean(k, self.names, self.params)

    def residual_after(self, k: int) -> np.ndarray:
        """Whitened residual of axis k scaled to m/s² (variance σ²_eff under the model)."""
        st = self.state.axes[k]
        s2 = st.sigma2_eff
        if st.q > 0:
            return self.innov[k] * np.sqrt(s2)
        y, mu = self.run.datos[:, k], self.mean(k)
        if st.lsb > 2.0 * np.sqrt(st.sigma2):  # Sheppard no longer holds: exact moments
            m1, var = quantized_moments(mu, st.sigma2, st.lsb)
            return (y - m1) * np.sqrt(s2 / var)
        return y - mu

    def unclipped_mean(self, k: int) -> np.ndarray:
        """The mean reading of axis k with the saturation's clip of ``A_r`` undone (what the
        output would read before it rails), m/s²."""
        st = self.state.axes[k]
        mu = self.mean(k)
        if not np.isfinite(st.limit):
            return mu
        gain = 1.0 + self.value(f"{AXES[k]}.scale")
        a = self.run.a_ref[:, k]
        return mu + gain * (a - np.clip(a, -st.limit, st.limit))

    def cov_of(self, *names: str) -> np.ndarray:
        idx = [self.names.index(n) for n in names]
        return self.cov[np.ix_(idx, idx)]

