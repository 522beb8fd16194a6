"""Final fit of the selected model and the catalog estimates (± std) of each named effect.

:class:`_Reporter` refits the model with every linear parameter and the Gauss-Newton columns of
the nonlinear ones (τ, L) in one whitened least-squares system, gives the bias at t0 of a
random-walk axis from the smoother, the mean reading and the whitened residuals.
:func:`_estimate` turns its parameters into the catalog's parameters and units.
"""

from __future__ import annotations

import numpy as np
from scipy import linalg as sla

from calib.conventions import AXES
from calib.diagnostics import Lattice
from calib.effects import LINEAR_COLUMNS, Extensions, ModelState
from calib.filters import walk_filter
from calib.gap.quantization import quantized_moments
from calib.ls import fit_linear


def _ratio(c: float, s: float, cov2: np.ndarray) -> tuple[float, float]:
    """``c / (1 + s)`` and its delta-method std; ``cov2`` = cov of (s, c)."""
    v = c / (1.0 + s)
    grad = np.array([-c / (1.0 + s) ** 2, 1.0 / (1.0 + s)])
    return v, float(np.sqrt(max(grad @ cov2 @ grad, 0.0)))



class _Reporter:
    """Final fit of a model: parameters with covariance, effect estimates, residuals."""

    def __init__(self, ext: Extensions, state: ModelState) -> None:
        self.ext, self.state, self.run = ext, state, ext.run
        self._fit()

    def _axis_rows(self, k: int, gain: float) -> tuple[np.ndarray, np.ndarray, list[str],
                                                       np.ndarray | None]:
        ext, st = self.ext, self.state.axes[k]
        r = ext.reference(k, st.tau, st.limit)
        names, cols = ext.columns(k, st)
        parts = [self.run.datos[:, k] - r, np.ones_like(r), r, *cols]
        pnames = ["bias", "scale", *names]
        a = self.run.a_ref[:, k]
        if np.isfinite(st.limit):  # Gauss-Newton column: d mean / dL
            parts.append(gain * ext._filter(np.sign(a) * (np.abs(a) > st.limit), st.tau))
            pnames.append("d_limit")
        if st.tau > 0:
            eps = 1e-3
            d = (ext.reference(k, st.tau * (1 + eps), st.limit)
                 - ext.reference(k, st.tau * (1 - eps), st.limit)) / (2 * eps * st.tau)
            parts.append(gain * d)
            pnames.append("d_tau")
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
        self.gn_std = {n: float(np.sqrt(cov[i, i])) for i, n in enumerate(names)
                       if n.endswith(("d_limit", "d_tau"))}
        keep = [i for i, n in enumerate(names) if not n.endswith(("d_limit", "d_tau"))]
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

    def cov_of(self, *names: str) -> np.ndarray:
        idx = [self.names.index(n) for n in names]
        return self.cov[np.ix_(idx, idx)]


def _estimate(rep: _Reporter, name: str, axis: str, lattice: list[Lattice], q_unc: dict
              ) -> tuple[dict, dict]:
    """Catalog parameters (and std) of one named effect from the final fit.

    ``q_unc``: axis index → (std, interval) of the random-walk q (:func:`_q_uncertainty`).
    """
    run, state = rep.run, rep.state
    if name == "tilt_offset":
        s = rep.value("sin_tilt")
        sd = float(np.sqrt(rep.cov_of("sin_tilt")[0, 0]))
        d = float(np.arcsin(np.clip(s, -1, 1)))
        return {"delta": d}, {"delta": sd / np.cos(d)}
    k = AXES.index(axis)
    st = state.axes[k]
    sc = f"{axis}.scale"
    s = rep.value(sc)
    if name == "misalignment":
        cn = f"{axis}.c_mis"
        c = rep.value(cn)
        den = (1 + s) ** 2 + c * c
        grad = np.array([-c / den, (1 + s) / den])
        sd = float(np.sqrt(max(grad @ rep.cov_of(sc, cn) @ grad, 0.0)))
        return {"delta": float(np.arctan2(c, 1 + s))}, {"delta": sd}
    if name in ("nonlinearity_k2", "cross_axis"):
        cn = f"{axis}.{LINEAR_COLUMNS[name][0]}"
        key = "k2" if name == "nonlinearity_k2" else "k_ip"
        v, sd = _ratio(rep.value(cn), s, rep.cov_of(sc, cn))
        return {key: v}, {key: sd}
    if name == "bias_drift":
        cn = f"{axis}.c_drift"
        key = "rate" if run.time_unit == "s" else "rate_per_sample"
        return {key: rep.value(cn)}, {key: float(np.sqrt(rep.cov_of(cn)[0, 0]))}
    if name == "lever_arm":
        w2, al = f"{axis}.c_w2", f"{axis}.c_alpha"
        c = rep.cov_of(sc, w2, al)
        vw, sw = _ratio(rep.value(w2), s, c[np.ix_([0, 1], [0, 1])])
        va, sa = _ratio(rep.value(al), s, c[np.ix_([0, 2], [0, 2])])
        if axis == "x":  # x: -ω² pos_x + α pos_z
            return {"pos_x": -vw, "pos_z": va}, {"pos_x": sw, "pos_z": sa}
        return {"pos_x": va, "pos_z": vw}, {"pos_x": sa, "pos_z": sw}  # y: ω² pos_z + α pos_x
    if name == "lowpass_lag":
        return {"tau": st.tau}, {"tau": rep.gn_std[f"{axis}.d_tau"]}
    if name == "saturation":
        return {"limit": st.limit}, {"limit": rep.gn_std[f"{axis}.d_limit"]}
    if name == "bias_random_walk":
        key = "q" if run.time_unit == "s" else "q_per_sample"
        return {key: st.q}, {key: q_unc[k][0]}
    if name == "noise_level":
        dof = run.n - rep.ext.n_params(state, k)
        return {"sigma2": st.sigma2}, {"sigma2": st.sigma2 * float(np.sqrt(2.0 / dof))}
    if name == "quantization":
        lat = lattice[k]
        return {"lsb": lat.lsb}, {"lsb": lat.lsb_std}
    raise ValueError(name)

