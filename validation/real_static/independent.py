"""Independent check of what ``tiltbench noise --json`` reports on a real long static log.

Written apart from the code under test: it imports numpy, scipy and allantools only — neither
``calib`` nor ``bench`` nor the rest of ``validation`` — and reads the tool's output JSON and the
log's CSV as plain files. It reports; it asserts nothing (exit 0).

    python -m validation.real_static.independent LOG.csv NOISE.json [--json OUT]

Per axis y (m/s² or rad/s, sampled every τ0 = 1/fs, fs = (n − 1)/(t_last − t_first)):

1. Overlapping Allan deviation of the raw readings, ``allantools.oadev(data_type="freq")`` at
   the JSON's τ = m·τ0 (rate-like data; σ²(τ) = ½⟨(ȳ_{k+m} − ȳ_k)²⟩ over all k, stride 1).
   Interval per τ at the JSON's ``level`` p: ν·s²/χ²_ν((1+p)/2) ≤ σ² ≤ ν·s²/χ²_ν((1−p)/2)
   (``allantools.confidence_interval``), ν = Greenhall's EDF (``allantools.edf_greenhall``,
   d = 2, overlapping, N = n + 1 phase points) for the power-law noise type α of that τ from
   allantools' lag-1 autocorrelation noise identification (``autocorr_noise_id``, Riley &
   Greenhall 2004) on the m-averaged readings; where fewer than 30 averages remain the last
   identified α is carried forward. α: 0 white FM (W), −1 flicker FM (F), −2 random-walk FM (R).
2. ``model_adev`` inside that interval for every τ of ``fit_range``; the ratio
   r = (model − s)/(hi − s) above s, (model − s)/(s − lo) below: |r| ≤ 1 is inside.
3. Bias instability (IEEE Std 952 C.1: flat floor σ = √(2 ln2/π)·B = 0.664·B, and every other
   term only adds): B ≤ hi(τ*)/0.664, τ* the argmin of the ADEV, hi its upper bound at p.
   σ_min/0.664 is the textbook (graphical) B, an over-estimate when other terms reach the floor.
4. White noise on the octaves of the JSON white term's ``tau_range`` — from two octaves past
   the ADEV's peak on when it rises first (a filtered export: the rise is the filter, not
   white noise) —: ln σ = ln N − ½ ln τ with
   the slope fixed, N from the weighted mean of ln(σ_i·√τ_i), weights w_i = 2ν_i (var ln σ_i ≈
   1/(2ν_i)); interval exp(ln N ± z·se), se = Σw_i·se_i/Σw_i (octaves taken as fully correlated:
   conservative; the independent-point se 1/√Σw is far narrower), z the normal quantile of p.
   A free-slope weighted fit (points independent) is shown beside it, and, as a diagnostic,
   N from σ² = N²/τ + c (a flat floor c, weighted LS on σ², var s² = 2σ⁴/ν).
5. Rate random walk (σ² = K²τ/3 on a +½ slope): the slope of ln σ vs ln τ on the last 3 octaves
   holding ≥ 8 non-overlapping clusters (n/m ≥ 8), weighted as in 4, with its independent-point
   standard error. A rise is a slope whose interval (±z·se) excludes 0 and holds +½; then
   K = σ·√(3/τ) from the fixed +½ fit as in 4. Always: the model-free bound
   K ≤ min_τ hi(τ)·√(3/τ) (every other term only adds to σ²).
6. Datasheet units: gyro N·(180/π)·60 °/√h, B·(180/π)·3600 °/h; accelerometer N/g0 µg/√Hz,
   B/g0 µg, g0 = 9.80665e-6 m/s² per µg.
7. The twin closure (``twin``) is only reported from the JSON.
"""

from __future__ import annotations

import argparse
import gzip
import json
import math
import sys

import allantools
import numpy as np
from scipy import stats

FLOOR = math.sqrt(2.0 * math.log(2.0) / math.pi)  # 0.6643: σ_A at the flicker floor per B
NOISE_ID_MIN = 30  # averages the lag-1 ACF noise identification needs
K_CLUSTERS = 8  # non-overlapping clusters n/m an octave of the rise fit must hold
K_OCTAVES = 3
MICRO_G = 9.80665e-6
ALPHA_CODE = {0: "W", -1: "F", -2: "R"}


def load_log(path: str) -> tuple[np.ndarray, list[str]]:
    """The log's numbers and header cells (a ``.gz`` path is read through gzip)."""
    opener = gzip.open if str(path).endswith(".gz") else open
    with opener(path, "rt", encoding="utf-8") as f:
        header = [h.strip() for h in f.readline().split(",")]
    return np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2), header


def axis_columns(header: list[str], report: dict) -> dict[str, int]:
    mapping = report.get("provenance", {}).get("mapping") or {}
    if mapping:
        return {ax: header.index(col) for ax, col in mapping.items() if ax != "t" and col in header}
    names = ("x", "y", "z", "gyro_x", "gyro_y", "gyro_z")
    return {ax: i + 1 for i, ax in enumerate(names) if i + 1 < len(header)}


def noise_types(y: np.ndarray, ms: np.ndarray) -> tuple[list[int], str]:
    alphas, code, last = [], "", 0
    for m in ms:
        if len(y) // m >= NOISE_ID_MIN:
            last = int(allantools.autocorr_noise_id(y, int(m), data_type="freq", dmax=2)[0])
            last = max(-2, min(0, last))
            code += ALPHA_CODE[last]
        else:
            code += ALPHA_CODE[last].lower()
        alphas.append(last)
    return alphas, code


def weighted_line(lt: np.ndarray, ls: np.ndarray, w: np.ndarray) -> tuple[float, float]:
    """Slope and its standard error of a weighted LS line ln σ = a + b ln τ (independent)."""
    X = np.column_stack([np.ones_like(lt), lt])
    cov = np.linalg.inv(X.T @ (w[:, None] * X))
    b = (cov @ X.T @ (w * ls))[1]
    return float(b), float(math.sqrt(cov[1, 1]))


def fixed_slope(values: np.ndarray, w: np.ndarray, z: float) -> dict:
    """Weighted mean of ln values (one per octave); conservative (fully correlated) interval."""
    lv = np.log(values)
    mean = float(np.sum(w * lv) / np.sum(w))
    se = float(np.sum(w / np.sqrt(w)) / np.sum(w))
    chi2 = float(np.sum(w * (lv - mean) ** 2))
    return {"value": math.exp(mean), "interval": [math.exp(mean - z * se), math.exp(mean + z * se)],
            "se_log": se, "se_log_independent": float(1 / math.sqrt(np.sum(w))),
            "chi2_per_dof": chi2 / max(1, len(lv) - 1)}


def white_with_floor(taus: np.ndarray, s: np.ndarray, edf: np.ndarray) -> list[float]:
    """Diagnostic: N and its relative se from σ² = N²/τ + c (c a flat floor), weighted LS on
    σ², var(s²) = 2σ⁴/ν with σ² the fitted curve (iterated), points independent."""
    X = np.column_stack([1 / taus, np.ones_like(taus)])
    fit = s**2
    for _ in range(5):
        w = edf / (2 * fit**2)
        cov = np.linalg.inv(X.T @ (w[:, None] * X))
        th = cov @ X.T @ (w * s**2)
        fit = X @ th
    n = math.sqrt(max(th[0], 0.0))
    return [n, math.sqrt(cov[0, 0]) / (2 * n * n) if n > 0 else math.inf]


def in_range(taus: np.ndarray, lo: float, hi: float) -> np.ndarray:
    return (taus >= lo * (1 - 1e-9)) & (taus <= hi * (1 + 1e-9))


def check_axis(y: np.ndarray, fs: float, a: dict, level: float) -> dict:
    n = len(y)
    z = float(stats.norm.ppf(0.5 + level / 2))
    taus = np.asarray(a["taus"], float)
    ms = np.rint(taus * fs).astype(int)
    out: dict = {"axis": a["axis"], "kind": a["kind"], "unit": a.get("unit"),
                 "tau_m_integer": bool(np.allclose(taus * fs, ms, rtol=1e-9)),
                 "tau_octaves": bool(np.allclose(taus, taus[0] * 2.0 ** np.arange(len(taus))))}
    t_at, s, _, _ = allantools.oadev(y, rate=fs, data_type="freq", taus=taus)
    if len(t_at) != len(taus) or not np.allclose(t_at, taus):
        raise SystemExit(f"{a['axis']}: allantools returned τ {t_at}, JSON has {taus}")
    jadev = np.asarray(a["adev"], float)
    out["max_rel_diff_adev"] = float(np.max(np.abs(s / jadev - 1)))
    blk = int(round(taus[0] * fs))  # the tool's block means (docs: long logs): same τ grid
    yb = y[: n // blk * blk].reshape(-1, blk).mean(axis=1)
    sb = allantools.oadev(yb, rate=fs / blk, data_type="freq", taus=taus)[1]
    out["max_rel_diff_adev_block_means"] = float(np.max(np.abs(sb / jadev - 1)))
    alphas, out["noise_types"] = noise_types(y, ms)
    edf = np.array([allantools.edf_greenhall(al, 2, int(m), n + 1, overlapping=True)
                    for al, m in zip(alphas, ms, strict=True)])
    ci = np.array([allantools.confidence_interval(si, e, ci=level) for si, e in zip(s, edf,
                                                                                       strict=True)])
    lo, hi = ci[:, 0], ci[:, 1]
    out.update(adev=s.tolist(), adev_ci=ci.tolist(), edf=edf.tolist())

    # 2. the fitted curve inside the measured intervals over fit_range
    model = np.asarray(a["model_adev"], float)
    sel = in_range(taus, *a["fit_range"])
    r = np.where(model >= s, (model - s) / (hi - s), (model - s) / (s - lo))
    k = int(np.argmax(np.where(sel, np.abs(r), -1)))
    out["model_inside"] = [int(np.sum(sel & (np.abs(r) <= 1))), int(np.sum(sel))]
    out["worst_ratio"], out["worst_ratio_tau"] = float(r[k]), float(taus[k])

    # 3. B against the Allan minimum
    terms = a["terms"]
    jb = terms["bias_instability"]
    i = int(np.argmin(s))
    bmax = hi[i] / FLOOR
    out["allan_min"] = {"tau": float(taus[i]), "adev": float(s[i]), "ci": [float(lo[i]),
                        float(hi[i])], "b_max": float(bmax), "b_graphical": float(s[i] / FLOOR),
                        "b_graphical_ci": [float(lo[i] / FLOOR), float(bmax)]}
    jbv = jb["value"] if jb["value"] is not None else jb["upper_bound"]
    out["b_value_ok"] = bool(jbv <= bmax)
    out["b_lower_ok"] = bool(jb["interval"][0] <= bmax)

    # 4. white noise, slope −½ fixed, on the white term's tau_range
    w = 2 * edf
    jn = terms["white_noise_density"]
    sw = in_range(taus, *jn["tau_range"])
    # a filtered export: its ADEV rises to a peak before white noise's −½ line; the line is
    # read from two octaves past that peak on (none for a log whose ADEV falls from the start)
    peak = int(np.argmax(np.where(sw, s, -np.inf)))
    if peak > 0:
        sw &= taus >= 4.0 * taus[peak]
    lt, ls = np.log(taus), np.log(s)
    white = fixed_slope(s[sw] * np.sqrt(taus[sw]), w[sw], z)
    white["tau_range"] = [float(taus[sw][0]), float(taus[sw][-1])]
    white["free_slope"] = weighted_line(lt[sw], ls[sw], w[sw]) if sw.sum() >= 3 else None
    white["n_with_floor"] = white_with_floor(taus[sw], s[sw], edf[sw])
    jlo, jhi = jn["interval"]
    white["overlaps_json"] = bool(white["interval"][0] <= jhi and jlo <= white["interval"][1])
    white["ratio_to_json"] = white["value"] / jn["value"] if jn["value"] else None
    out["white"] = white

    # 5. rate random walk: a +½ rise at the long-τ end?
    jk = terms["rate_random_walk"]
    ok = np.flatnonzero(n // ms >= K_CLUSTERS)
    kw = ok[-K_OCTAVES:]
    rrw: dict = {"taus": taus[kw].tolist(), "clusters": (n // ms[kw]).tolist()}
    rrw["slope"], rrw["slope_se"] = weighted_line(lt[kw], ls[kw], w[kw])
    last = np.arange(kw[0], len(taus))
    rrw["slope_with_last_taus"] = weighted_line(lt[last], ls[last], w[last])[0]
    rrw["rise"] = bool(rrw["slope"] - z * rrw["slope_se"] > 0
                       and abs(rrw["slope"] - 0.5) <= z * rrw["slope_se"])
    kb = hi * np.sqrt(3 / taus)
    rrw["k_bound"], rrw["k_bound_tau"] = float(kb.min()), float(taus[int(np.argmin(kb))])
    jku = jk["interval"][1]
    rrw["json_upper_within_bound"] = bool(jku <= rrw["k_bound"])
    if rrw["rise"]:
        kfit = fixed_slope(s[kw] * np.sqrt(3 / taus[kw]), w[kw], z)
        rrw["k"] = kfit
        rrw["consistent"] = bool(kfit["interval"][0] <= jku and jk["interval"][0]
                                 <= kfit["interval"][1])
        rrw["verdict"] = "+½ rise"
    else:
        rrw["k"] = None
        rrw["consistent"] = not jk["resolved"]
        rrw["verdict"] = "no +½ rise: K not measurable"
    out["rrw"] = rrw

    # 6. datasheet units
    if a["kind"] == "gyro":
        fn, fb = 180 / math.pi * 60, 180 / math.pi * 3600
        out["datasheet_units"] = ["°/√h", "°/h"]
    else:
        fn = fb = 1 / MICRO_G
        out["datasheet_units"] = ["µg/√Hz", "µg"]
    out["datasheet"] = {"N": white["value"] * fn, "N_ci": [v * fn for v in white["interval"]],
                        "B": out["allan_min"]["b_graphical"] * fb,
                        "B_ci": [v * fb for v in out["allan_min"]["b_graphical_ci"]],
                        "json_N": jn["datasheet"], "json_B": jb["datasheet"]}
    return out


def g(v: float | None) -> str:
    return "—" if v is None else f"{v:.4g}"


def iv(pair) -> str:
    return f"[{g(pair[0])}, {g(pair[1])}]"


def yes(b: bool) -> str:
    return "yes" if b else "**NO**"


def table(head: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in rows])


def render(res: dict) -> str:
    axes = res["axes"]
    parts = [f"**{res['log']}** vs **{res['json']}**: n = {res['n']}, fs = {res['fs']:.6g} Hz "
             f"(JSON {res['json_fs']:.6g}), {res['duration_h']:.3g} h, level {res['level']}; "
             f"τ = {res['taus'][0]:g}·2^k s, {len(res['taus'])} octaves (τ·fs integer and "
             f"octaves: {yes(res['tau_grid_ok'])}); largest time step "
             f"{res['max_step_ratio']:.3g}× median. Noise type per τ for the EDF (lag-1 ACF, "
             "lower case = carried forward): W white FM, F flicker FM, R random-walk FM."]
    parts.append(table(
        ["axis", "max rel Δ ADEV raw", "Δ on block means", "noise type per τ",
         "model in CI (fit range)", "worst r @ τ"],
        [[a["axis"], f"{a['max_rel_diff_adev']:.2e}", f"{a['max_rel_diff_adev_block_means']:.1e}",
          a["noise_types"], f"{a['model_inside'][0]}/{a['model_inside'][1]}",
          f"{a['worst_ratio']:+.2f} @ {a['worst_ratio_tau']:g} s"] for a in axes]))
    parts.append(table(
        ["axis", "τ_min s", "σ_min [CI]", "hi/0.664", "JSON B [interval]", "B ≤", "B_lo ≤"],
        [[a["axis"], f"{a['allan_min']['tau']:g}",
          f"{g(a['allan_min']['adev'])} {iv(a['allan_min']['ci'])}",
          g(a["allan_min"]["b_max"]),
          f"{g(a['json_terms']['bias_instability']['value'])} "
          f"{iv(a['json_terms']['bias_instability']['interval'])}",
          yes(a["b_value_ok"]), yes(a["b_lower_ok"])] for a in axes]))
    parts.append(table(
        ["axis", "τ range s", "free slope ± se", "N (−½ fixed) [CI]", "JSON N [interval]",
         "mine/JSON", "overlap", "N (−½ + floor) ± rel se", "/JSON"],
        [[a["axis"], f"{a['white']['tau_range'][0]:g}–{a['white']['tau_range'][1]:g}",
          ("—" if a["white"]["free_slope"] is None else
           f"{a['white']['free_slope'][0]:+.3f} ± {a['white']['free_slope'][1]:.3f}"),
          f"{g(a['white']['value'])} {iv(a['white']['interval'])}",
          f"{g(a['json_terms']['white_noise_density']['value'])} "
          f"{iv(a['json_terms']['white_noise_density']['interval'])}",
          f"{a['white']['ratio_to_json']:.3f}", yes(a["white"]["overlaps_json"]),
          f"{g(a['white']['n_with_floor'][0])} ± {a['white']['n_with_floor'][1]:.1%}",
          f"{a['white']['n_with_floor'][0] / a['json_terms']['white_noise_density']['value']:.3f}"]
         for a in axes]))
    rows = []
    for a in axes:
        r, jk = a["rrw"], a["json_terms"]["rate_random_walk"]
        kmine = "—" if r["k"] is None else f"{g(r['k']['value'])} {iv(r['k']['interval'])}"
        jtxt = (f"{g(jk['value'])} {iv(jk['interval'])}" if jk["resolved"]
                else f"not resolved, < {g(jk['interval'][1])}")
        rows.append([a["axis"], f"{r['taus'][0]:g}–{r['taus'][-1]:g} (n/m ≥ {min(r['clusters'])})",
                     f"{r['slope']:+.3f} ± {r['slope_se']:.3f}",
                     f"{r['slope_with_last_taus']:+.3f}",
                     r["verdict"], kmine, g(r["k_bound"]), jtxt, yes(r["consistent"]),
                     yes(r["json_upper_within_bound"])])
    parts.append(table(["axis", "rise window τ s", "slope ± se", "slope to τ_max", "verdict",
                        "K mine", "K ≤ (model-free)", "JSON K", "consistent",
                        "JSON upper ≤ bound"], rows))
    parts.append(table(
        ["axis", "N mine [CI]", "N JSON [interval]", "B = σ_min/0.664 [CI]", "B JSON [interval]",
         "units"],
        [[a["axis"], f"{g(d['N'])} {iv(d['N_ci'])}",
          f"{g(d['json_N']['value'])} {iv(d['json_N']['interval'])}",
          f"{g(d['B'])} {iv(d['B_ci'])}",
          f"{g(d['json_B']['value'])} {iv(d['json_B']['interval'])}",
          " , ".join(a["datasheet_units"])] for a in axes for d in [a["datasheet"]]]))
    rows = []
    for ax, tw in res["twin"].items():
        mr = tw.get("model_range") or {}
        oc = mr.get("octaves")
        rng = f"{res['taus'][oc[0]]:g}–{res['taus'][oc[1] - 1]:g} s" if oc else "—"
        rows.append([ax, f"{tw['statistic']:.4g}/{tw['dof']}", f"{tw['p']:.3g}",
                     str(tw["reject"]), rng,
                     f"{mr.get('statistic', float('nan')):.4g}/{mr.get('dof')}",
                     f"{mr.get('p', float('nan')):.3g}", str(mr.get("reject"))])
    parts.append("Twin closure (from the JSON):\n\n" + table(
        ["axis", "full χ²/dof", "p", "reject", "model range", "χ²/dof", "p", "reject"], rows))
    return "\n\n".join(parts)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m validation.real_static.independent",
                                description=__doc__.split("\n\n")[0])
    p.add_argument("log")
    p.add_argument("noise_json")
    p.add_argument("--json", dest="out", help="write the numbers to this file")
    args = p.parse_args(argv)
    with open(args.noise_json, encoding="utf-8") as f:
        report = json.load(f)
    data, header = load_log(args.log)
    t = data[:, header.index(report.get("provenance", {}).get("mapping", {}).get("t", header[0]))]
    steps = np.diff(t)
    fs = (len(t) - 1) / (t[-1] - t[0])
    level = float(report["level"])
    jaxes = report["axes"]
    jaxes = jaxes if isinstance(jaxes, dict) else {a["axis"]: a for a in jaxes}
    cols = axis_columns(header, report)
    axes = []
    for name, a in jaxes.items():
        res = check_axis(data[:, cols[name]], fs, a, level)
        res["json_terms"] = a["terms"]
        axes.append(res)
    taus = list(next(iter(jaxes.values()))["taus"])
    res = {"log": args.log, "json": args.noise_json, "n": len(t), "fs": fs,
           "json_fs": report.get("sample_rate"), "duration_h": (t[-1] - t[0]) / 3600,
           "max_step_ratio": float(steps.max() / np.median(steps)), "level": level,
           "taus": taus, "tau_grid_ok": all(a["tau_m_integer"] and a["tau_octaves"] for a in axes),
           "axes": axes, "twin": report.get("twin") or {}}
    print(render(res))
    if args.out:
        with open(args.out, "w", encoding="utf-8") as f:
            json.dump(res, f, indent=1, ensure_ascii=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())
