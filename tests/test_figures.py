"""Figures: written as valid PNG / SVG, non-empty, also for the course data."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pytest

from bench.figures import (
    calibration_axis_figure,
    parameters_figure,
    save_calibration_plot,
    save_figure,
    write_calibration_figures,
    write_vehicle_figures,
)
from bench.figures.save import save_figure_as
from bench.tilt import CalibrationConfig, ThetaDesign, generate_calibration
from calib.calibration.tilt_plane import calibrate

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def assert_png(path: Path) -> None:
    data = path.read_bytes()
    assert data[:8] == PNG_MAGIC, path
    assert data[12:16] == b"IHDR"
    width, height = int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
    assert width >= 400 and height >= 300, (path, width, height)
    assert data.rstrip()[-8:-4] == b"IEND"


def assert_svg(path: Path) -> None:
    root = ET.parse(path).getroot()
    assert root.tag.endswith("svg")
    assert len(list(root.iter())) > 50  # something drawn, not an empty canvas


@pytest.fixture(scope="module")
def small_cal():
    run = generate_calibration(CalibrationConfig(theta=ThetaDesign(count=600)), 2)
    truth = {"sensor": run.config.sensor.to_dict()}
    return calibrate(run.ensayo(), [0.25, 0.64]), run.ensayo(), truth


def test_calibration_figures_png_and_svg(tmp_path, small_cal):
    """Both formats from one build of each figure (keys ``name.fmt``), every file whole."""
    cal, ensayo, truth = small_cal
    paths = write_calibration_figures(tmp_path, cal, ensayo, truth, fmt=("png", "svg"))
    assert set(paths) == {f"{n}.{f}" for n in ("calibration_x", "calibration_y", "parameters")
                          for f in ("png", "svg")}
    for key, p in paths.items():
        fmt = key.rsplit(".", 1)[1]
        assert p.suffix == f".{fmt}" and p.stat().st_size > 10_000
        (assert_png if fmt == "png" else assert_svg)(p)
    assert not list(tmp_path.glob(".*.tmp"))  # atomic writes leave nothing behind
    with pytest.raises(FileExistsError):  # every path checked before any is written
        write_calibration_figures(tmp_path, cal, ensayo, truth, fmt=("png", "svg"))
    assert plt.get_fignums() == []


def test_one_figure_in_two_formats_is_the_bytes_of_each_alone(tmp_path, small_cal):
    """``save_figure_as`` lays the figure out once for every path: each file is byte for byte
    what a single-format ``save_figure`` of the same figure writes."""
    cal, _, truth = small_cal
    both = save_figure_as(parameters_figure(cal, truth), [tmp_path / "b.png", tmp_path / "b.svg"])
    for p in both:
        alone = save_figure(parameters_figure(cal, truth), tmp_path / f"a{p.suffix}")
        assert alone.read_bytes() == p.read_bytes(), p.suffix


def test_save_figure_checks_extension_and_overwrite(tmp_path, small_cal):
    cal, ensayo, _ = small_cal
    with pytest.raises(ValueError, match="png or .svg"):
        save_figure(calibration_axis_figure(cal, ensayo, "x"), tmp_path / "f.pdf")
    p = save_figure(calibration_axis_figure(cal, ensayo, "x"), tmp_path / "f.png")
    before = p.read_bytes()
    with pytest.raises(FileExistsError):
        save_figure(calibration_axis_figure(cal, ensayo, "y"), p)
    assert p.read_bytes() == before
    save_figure(calibration_axis_figure(cal, ensayo, "y"), p, force=True)
    assert p.read_bytes() != before
    assert plt.get_fignums() == []  # figures are closed


def test_same_data_same_bytes(tmp_path, small_cal):
    cal, ensayo, truth = small_cal
    a = write_calibration_figures(tmp_path / "a", cal, ensayo, truth, fmt="svg")
    b = write_calibration_figures(tmp_path / "b", cal, ensayo, truth, fmt="svg")
    for k in a:
        assert a[k].read_bytes() == b[k].read_bytes()


def test_course_data_figures(tmp_path, course_dir):
    """All figures of the demo, produced from the real course files."""
    from bench.demo import analyze_course_dir

    ana = analyze_course_dir(course_dir)
    paths = write_calibration_figures(tmp_path, ana.cal, ana.ensayo)
    paths.update(write_vehicle_figures(tmp_path, ana.traj, ana.region, ana.cal, ana.ensayo.n))
    assert set(paths) == {"calibration_x", "calibration_y", "parameters", "trajectory",
                          "acceleration", "uncertainty_growth", "nmin"}
    for p in paths.values():
        assert_png(p)
        assert p.stat().st_size > 20_000
    # the trajectory figure is the one `tiltbench trajectory --plot` draws (shared code)
    svg = write_vehicle_figures(tmp_path / "svg", ana.traj, ana.region, ana.cal, ana.ensayo.n,
                                fmt="svg")
    for p in svg.values():
        assert_svg(p)
    assert np.isfinite(ana.region.std).all()


def test_calibrate_plot_figure(tmp_path, small_cal):
    """The one-file figure behind the proposed `tiltbench calibrate --plot FILE`."""
    cal, ensayo, truth = small_cal
    assert_png(save_calibration_plot(tmp_path / "cal.png", cal, ensayo, truth=truth))
    assert_svg(save_calibration_plot(tmp_path / "cal.svg", cal, ensayo))


# ---------------------------------------------------------------- what each figure must show
# Each test below fails when the figure's message is hidden: lines drawn on top of each other,
# the band under the samples, the course bound drawn as another shape, legend symbols that
# cannot be told apart, the true point under a candidate's marker.

def _px(ax, x, y) -> np.ndarray:
    """Display pixel coordinates of data points (x, y) of ``ax`` (after a draw)."""
    return ax.transData.transform(np.column_stack([np.atleast_1d(x), np.atleast_1d(y)]))


def _line(ax, prefix: str):
    found = [ln for ln in ax.get_lines() if ln.get_label().startswith(prefix)]
    assert len(found) == 1, (prefix, [ln.get_label() for ln in ax.get_lines()])
    return found[0]


def _lw_px(line) -> float:
    return line.get_linewidth() * line.figure.dpi / 72.0


@pytest.fixture(scope="module")
def large_errors():
    """A 3 % scale error and a 0.09 m/s² bias on x (course-like sizes), N = 600, and a
    truth that differs from the data's by 1 % of scale, so fit and truth must stand apart."""
    from bench.sensors import SensorErrorModel

    sensor = SensorErrorModel.from_pairs((0.09, -0.02), (-0.03, 0.02), (0.25, 0.64))
    run = generate_calibration(CalibrationConfig(theta=ThetaDesign(count=600), sensor=sensor),
                               3)
    truth = {"sensor": SensorErrorModel.from_pairs((0.09, -0.02), (-0.02, 0.02),
                                                   (0.25, 0.64)).to_dict()}
    return calibrate(run.ensayo(), [0.25, 0.64]), run.ensayo(), truth


def test_calibration_figure_separates_fit_truth_and_ideal(large_errors):
    """At the ends of A_r (where a scale error matters most) the LS fit, the truth and the
    ideal sensor lie more than a line width apart in display pixels — in the measured-vs-
    reference form (A_m against A_r over ±g) a 0.1 m/s² gap is about one pixel."""
    cal, ensayo, truth = large_errors
    fig = calibration_axis_figure(cal, ensayo, "x", truth)
    try:
        fig.canvas.draw()
        ax = next(a for a in fig.axes if a.get_xlabel().startswith("A_rx")
                  and a.get_ylabel().startswith("sensor error"))
        fit, true, ideal = (_line(ax, p) for p in ("LS fit", "truth", "ideal sensor"))
        x = fit.get_xdata()
        ends = [int(np.argmin(x)), int(np.argmax(x))]
        y_fit = _px(ax, x[ends], np.asarray(fit.get_ydata())[ends])[:, 1]
        y_true = _px(ax, x[ends], np.asarray(true.get_ydata())[ends])[:, 1]
        y_ideal = _px(ax, x[ends], np.zeros(2))[:, 1]
        width = max(_lw_px(fit), _lw_px(true), _lw_px(ideal))
        assert np.all(np.abs(y_fit - y_ideal) > width), (y_fit, y_ideal, width)
        assert np.all(np.abs(y_true - y_ideal) > width), (y_true, y_ideal, width)
        assert np.max(np.abs(y_fit - y_true)) > width, (y_fit, y_true, width)
        # the three are also told apart by style, not only by position
        styles = {(ln.get_color(), ln.get_linestyle()) for ln in (fit, true, ideal)}
        assert len(styles) == 3
    finally:
        plt.close(fig)


def test_calibration_binned_band_is_drawn_above_light_samples(large_errors):
    """In every panel with samples, the binned mean and its ±q·σ/√n band have a higher zorder
    than the scatter, and the scatter is light (alpha ≤ 0.3)."""
    cal, ensayo, truth = large_errors
    fig = calibration_axis_figure(cal, ensayo, "y", truth)
    try:
        panels = [a for a in fig.axes if any("per sample" in ln.get_label()
                                             or ln.get_label().startswith("residual")
                                             for ln in a.get_lines())]
        assert len(panels) == 4
        for ax in panels:
            scatter = next(ln for ln in ax.get_lines() if ln.get_linestyle() == "None")
            band = [c for c in ax.collections if c.get_label().startswith("95 % band")]
            binned = [ln for ln in ax.get_lines() if ln.get_label().startswith("binned mean")]
            assert len(band) == 1 and len(binned) == 1
            assert band[0].get_zorder() > scatter.get_zorder()
            assert binned[0].get_zorder() > band[0].get_zorder()
            assert scatter.get_alpha() <= 0.3
    finally:
        plt.close(fig)


def test_calibration_figure_states_one_level_everywhere(large_errors):
    """Every band and the box are at the one level asked (issue 22): the box gives ± q·std
    (the level-L half-width), the binned-mean band ± q·σ/√n with n defined, and the fitted
    line carries its own band, ± q·sqrt([A_r 1] Cov [A_r 1]ᵀ)."""
    cal, ensayo, truth = large_errors
    for level in (0.95, 0.99):
        fig = calibration_axis_figure(cal, ensayo, "x", truth, level=level)
        try:
            f = cal.fits["x"]
            q = f.quantile(level)
            half = dict(zip(f.param_names, q * f.std, strict=True))
            box = next(t.get_text() for a in fig.axes for t in a.texts
                       if "bias" in t.get_text())
            assert f"± {half['bias']:.2g} m/s²" in box and f"± {half['scale']:.2g}" in box
            assert f"{100 * level:g} % interval" in box
            labels = [h for a in fig.axes for h in a.get_legend_handles_labels()[1]]
            pct = f"{100 * level:g} %"
            bands = [lab for lab in labels if "band" in lab]
            assert bands and all(lab.startswith(pct) for lab in bands)
            assert any("n = " in lab and "per bin" in lab for lab in bands)
            ax = next(a for a in fig.axes if a.get_xlabel().startswith("A_rx"))
            fit_band = next(c for c in ax.collections if "band of the LS fit" in c.get_label())
            fit = _line(ax, "LS fit")
            x = np.asarray(fit.get_xdata())
            i, j = f.param_names.index("scale"), f.param_names.index("bias")
            c = f.cov
            want = q * np.sqrt(c[i, i] * x ** 2 + 2 * c[i, j] * x + c[j, j])
            top = fit_band.get_paths()[0].vertices[:, 1].max()
            assert top == pytest.approx(float(np.max(fit.get_ydata() + want)), rel=1e-9)
        finally:
            plt.close(fig)


def test_multiposition_figure_states_one_level_everywhere():
    """The pose ellipses, the residual bars and the estimates box are at the one level asked
    (issue 29: the box said ± 1 std beside 95 % bars): the box gives ± q·std with q the fit's
    quantile at that level, the bars ± q·σ/√n."""
    from bench.figures.multiposition import multiposition_figure
    from calib.calibration.multiposition import fit_multiposition, pose_statistics
    from tests.test_multiposition import SIGMA2, samples

    rng = np.random.default_rng(8)
    fit = fit_multiposition(pose_statistics(*samples(rng, np.radians(np.arange(0, 360, 45)),
                                                     200)), SIGMA2)
    for level in (0.95, 0.99):
        fig = multiposition_figure(fit, level)
        try:
            q = fit.quantile(level)
            texts = [t.get_text() for a in fig.axes for t in a.texts]
            box = next(t for t in texts if "bias_x" in t)
            assert f"± {100 * level:g}% half-width = {q:.3g} std" in box
            assert "1 std" not in " ".join(texts)
            for name, value, std in zip(fit.param_names, fit.params, fit.std, strict=True):
                assert f"{name} = {value:.5g} ± {q * std:.2g}" in box
            labels = [h for a in fig.axes for h in a.get_legend_handles_labels()[1]
                      if "%" in h]
            assert labels and all(f"{100 * level:g}%" in h for h in labels)
            rx = fig.axes[1]
            bars = [c for c in rx.containers if getattr(c, "has_yerr", False)]
            segs = bars[0].lines[2][0].get_segments()
            half = q * np.sqrt(fit.sigma2[0] / fit.poses.n)
            assert np.allclose([s[1, 1] - s[0, 1] for s in segs], 2 * half, rtol=1e-9)
        finally:
            plt.close(fig)


@pytest.fixture(scope="module")
def course_analysis(course_dir):
    from bench.demo import analyze_course_dir

    return analyze_course_dir(course_dir)


def test_trajectory_box_bound_is_a_rectangle_and_truth_on_top(course_analysis):
    """The course's 3σ box bound is a rectangle c ± (δP_x, δP_y) around each candidate (no
    ellipse); every legend entry has its own symbol; the true arrival, placed on candidate C,
    is drawn above C's marker with a different marker."""
    from matplotlib.patches import Rectangle

    from bench.figures import trajectory_figure

    region = course_analysis.region
    truth = np.asarray(region.candidates["C"], float)
    fig = trajectory_figure(course_analysis.traj, region, truth=truth)
    try:
        ax = fig.axes[0]
        rects = [p for p in ax.patches if isinstance(p, Rectangle)]
        assert len(rects) == len(region.candidates)
        box = np.asarray(region.course_box_bound, float)
        for rect, c in zip(rects, region.candidates.values(), strict=True):
            assert rect.get_width() == pytest.approx(2 * box[0])
            assert rect.get_height() == pytest.approx(2 * box[1])
            assert np.asarray(rect.get_xy()) + box == pytest.approx(np.asarray(c, float))
        assert not any("box" in ln.get_label() for ln in ax.get_lines())  # no ellipse lines
        legend = ax.get_legend()
        keys = []
        for h in legend.legend_handles:
            if hasattr(h, "get_marker"):
                keys.append(("line", h.get_color(), h.get_linestyle(), h.get_marker()))
            else:
                keys.append(("patch", tuple(h.get_facecolor()), tuple(h.get_edgecolor()),
                             h.get_linestyle()))
        assert len(set(keys)) == len(keys), keys
        labels = [t.get_text() for t in legend.get_texts()]
        corrected = keys[labels.index("corrected path")]
        region_key = keys[next(i for i, t in enumerate(labels) if "% region" in t)]
        assert corrected != region_key
        true_mark = _line(ax, "true arrival")
        cand = next(ln for ln in ax.get_lines() if ln.get_marker() == "x"
                    and np.allclose(ln.get_xydata()[0], truth))
        assert true_mark.get_zorder() > cand.get_zorder()
        assert true_mark.get_marker() != cand.get_marker()
    finally:
        plt.close(fig)


def test_nmin_figure_says_why_the_distances_rise(course_analysis):
    """The distances rise with N because Σ_P(N) shrinks: the figure says so (title and axis
    label), and the calibration-only curve's unbounded rise is annotated."""
    from bench.figures import nmin_figure

    ana = course_analysis
    fig = nmin_figure(ana.region, ana.ensayo.n, ana.cal.g)
    try:
        ax = fig.axes[0]
        assert "rise" in ax.get_title() and "shrink" in ax.get_title()
        assert "rises with N" in ax.get_ylabel()
        notes = [t.get_text() for t in ax.texts]
        assert any("√N" in t and "crosses r" in t for t in notes), notes
    finally:
        plt.close(fig)


# A unit: SI units and their powers and products, or a quantity stated dimensionless (a
# probability, a count of degrees of freedom, "(1)", a z in std).
UNIT = re.compile(r"m/s²|m/s|m²|\bm\b|\(s\)|\bs\b|rad|Hz|deg|dimensionless|dof|count|\(1\)|\(std\)")


def _labels_carry_units(fig) -> list[str]:
    """Every non-empty x/y label of every axes (subfigures too) names a unit; returns the
    labels that do not."""
    axes = list(fig.axes) + [a for sub in getattr(fig, "subfigs", []) for a in sub.axes]
    labels = [lab for a in axes for lab in (a.get_xlabel(), a.get_ylabel()) if lab.strip()]
    assert labels, "a figure without axis labels"
    return [lab for lab in labels if not UNIT.search(lab)]


@pytest.fixture(scope="module")
def every_figure(course_analysis, small_cal):
    """Each public figure function rendered from a result object (issue 22, part 4)."""
    import bench.figures as figs
    from bench import fusion_study
    from calib.calibration.multiposition import fit_multiposition, pose_statistics
    from calib.design import Experiment, analyze_design
    from calib.fusion.linear import fuse
    from calib.noise.allan import characterize_noise
    from calib.stats.runs import serial_map
    from tests.test_multiposition import SIGMA2, samples

    ana = course_analysis
    cal, ensayo, truth = small_cal
    tr = ana.traj
    rng = np.random.default_rng(5)
    fix_t = tr.t[::100]
    fix_pos = tr.pos_corrected[::100] + 3.0 * rng.standard_normal((fix_t.size, 2))
    acel = ana.acel
    fused = fuse(acel.t, acel.aerr, fix_t, fix_pos, bias=ana.cal.bias, scale=ana.cal.scale,
                 cal_cov=ana.cal.cov, noise_var=[0.25, 0.64], sigma_pos=3.0, p0=tr.p0,
                 v0=tr.v0, p0_cov=0.0, v0_cov=0.0, smoother=True)
    study = fusion_study.run_study(fusion_study.StudyConfig(
        runs=2, seed=0, scenarios=fusion_study.SCENARIOS[:1]), serial_map)
    design = analyze_design([Experiment("uniform", 401, 0.314)], ["tilt_offset", "saturation"],
                            runs=4, mapper=serial_map)
    noise = characterize_noise(rng.standard_normal((4096, 2)) * 0.01, 50.0)
    mp = fit_multiposition(pose_statistics(*samples(rng, np.radians(np.arange(0, 360, 45)),
                                                    200)), SIGMA2)
    made = {
        "calibration_axis_figure": lambda: figs.calibration_axis_figure(cal, ensayo, "x",
                                                                        truth),
        "calibration_figure": lambda: figs.calibration_figure(cal, ensayo, truth),
        "parameters_figure": lambda: figs.parameters_figure(cal, truth),
        "acceleration_figure": lambda: figs.acceleration_figure(tr),
        "trajectory_figure": lambda: figs.trajectory_figure(tr, ana.region),
        "uncertainty_growth_figure": lambda: figs.uncertainty_growth_figure(tr, ana.region,
                                                                            ana.cal),
        "nmin_figure": lambda: figs.nmin_figure(ana.region, ana.ensayo.n, ana.cal.g),
        "fusion_figure": lambda: figs.fusion_figure(tr, ana.region, fused, fix_pos, 0.997,
                                                    ana.region.decision,
                                                    true_path=tr.pos_corrected),
        "fusion_study_figure": lambda: figs.fusion_study_figure(study),
        "design_figure": lambda: figs.design_figure(design),
        "allan_figure": lambda: figs.allan_figure(noise),
        "multiposition_figure": lambda: figs.multiposition_figure(mp),
    }
    return made


def test_every_public_figure_renders_from_a_result_with_units(every_figure):
    """Each function of ``bench.figures.FIGURES`` returns a Figure whose axis labels carry
    their units."""
    from matplotlib.figure import Figure

    import bench.figures as figs

    assert set(every_figure) == set(figs.FIGURES)
    for name, make in every_figure.items():
        fig = make()
        try:
            assert isinstance(fig, Figure), name
            assert _labels_carry_units(fig) == [], name
        finally:
            plt.close(fig)


def test_monte_carlo_figures_carry_their_95_percent_bars(every_figure):
    """nmin: both probability curves have error bars, on a logit axis (nothing cut);
    fusion-study: the RMS bars have error bars and the legend/title says 95 %; the fusion
    figure draws the smoothed path and the truth."""
    from matplotlib.container import BarContainer, ErrorbarContainer

    fig = every_figure["nmin_figure"]()
    try:
        top, prob = fig.axes[:2]
        assert "\n" not in top.get_title() and not top.patches  # one line, no shading
        assert prob.get_yscale() == "logit"
        bars = [c for c in prob.containers if isinstance(c, ErrorbarContainer)]
        drawn = [c for c in bars if c.lines[0] is not None and len(c.lines[0].get_xdata())]
        assert len(drawn) == 2 and all(c.has_yerr for c in drawn)
        assert any("95 %" in lab for lab in prob.get_legend_handles_labels()[1])
    finally:
        plt.close(fig)
    fig = every_figure["fusion_study_figure"]()
    try:
        rms = fig.axes[0]
        assert "95 %" in rms.get_title()
        assert [c for c in rms.containers if isinstance(c, BarContainer) and c.errorbar]
    finally:
        plt.close(fig)
    fig = every_figure["fusion_figure"]()
    try:
        labels = fig.axes[0].get_legend_handles_labels()[1]
        assert "RTS smoother" in labels and any("true path" in lab for lab in labels)
    finally:
        plt.close(fig)


def test_fuse_plot_gets_the_smoothed_path_and_the_truth_beside_the_data(tmp_path, capsys,
                                                                       monkeypatch):
    """``fuse --smoother --plot`` on a generated course set (truth.json beside acel.mat)
    hands the figure the smoothed estimates and the true path, not only on turning runs."""
    import bench.figures.fusion as fusion_fig
    from tests.cli import run

    seen = {}

    def spy(path, *args, force=False, **kwargs):
        seen["fused"], seen["kwargs"] = args[2], kwargs
        return fusion_fig.save_figure(fusion_fig.fusion_figure(*args, **kwargs), path,
                                      force=force)

    monkeypatch.setattr(fusion_fig, "save_fusion_plot", spy)
    d = tmp_path / "cs"
    assert run(capsys, "generate", "course", "--seed", "3", "--out", d, "--gps")[0] == 0
    rc, out, err = run(capsys, "fuse", "--acel", d / "acel.mat", "--gps", d / "gps.mat",
                       "--puntos", d / "puntos.mat", "--datos", d / "datos.txt",
                       "--ensayo", d / "ensayo.mat", "--smoother", "--plot", tmp_path / "f.png")
    assert rc == 0, err
    assert np.asarray(seen["fused"].smoothed).size > 0
    true_path = seen["kwargs"]["true_path"]
    assert true_path is not None and np.asarray(true_path).shape[1] == 2
    assert_png(tmp_path / "f.png")


def test_fit_quality_says_when_no_degree_of_freedom_is_left():
    """A figure title never prints "nan" for χ²/dof: with no dof left it says so."""
    from bench.figures.fit_quality import fit_quality

    assert fit_quality(1.02345, 6) == "χ²/dof = 1.02 (dof 6)"
    for chi2_dof, dof in ((float("nan"), 0), (0.0, 0), (float("inf"), 3)):
        text = fit_quality(chi2_dof, dof)
        assert "nan" not in text and "no degrees of freedom left" in text


def test_one_figure_module_imports_without_the_others():
    """Importing ``bench.figures.save`` (what ``gap --report`` draws with) leaves the other
    figure modules, calib.design and scipy.stats unimported; every name the package exports
    still resolves, to the object its module defines."""
    import subprocess
    import sys

    code = ("import sys, bench.figures.save; "
            "print(sorted(m for m in ('bench.figures.design', 'bench.figures.nmin', "
            "'bench.figures.write', 'calib.design', 'scipy.stats') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=Path(__file__).resolve().parents[1])
    assert out.stdout.strip() == "[]", out.stdout
    import bench.figures as figs
    from bench.figures import nmin, save

    assert set(figs.__all__) >= set(figs.FIGURES) | {"save_figure", "DPI"}
    assert figs.nmin_figure is nmin.nmin_figure and figs.FORMATS is save.FORMATS
    assert all(callable(getattr(figs, n)) for n in figs.FIGURES)
    with pytest.raises(AttributeError, match="no attribute 'not_a_figure'"):
        figs.not_a_figure  # noqa: B018
