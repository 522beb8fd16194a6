"""Figures: written as valid PNG / SVG, non-empty, also for the course data."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pytest

from bench.figures import (
    calibration_axis_figure,
    save_calibration_plot,
    save_figure,
    write_calibration_figures,
    write_vehicle_figures,
)
from bench.tilt import CalibrationConfig, ThetaDesign, generate_calibration
from calib.calibration import calibrate

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


@pytest.mark.parametrize("fmt", ["png", "svg"])
def test_calibration_figures_png_and_svg(tmp_path, small_cal, fmt):
    cal, ensayo, truth = small_cal
    paths = write_calibration_figures(tmp_path, cal, ensayo, truth, fmt=fmt)
    assert set(paths) == {"calibration_x", "calibration_y", "parameters"}
    for p in paths.values():
        assert p.suffix == f".{fmt}" and p.stat().st_size > 10_000
        (assert_png if fmt == "png" else assert_svg)(p)
    assert not list(tmp_path.glob(".*.tmp"))  # atomic writes leave nothing behind


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
