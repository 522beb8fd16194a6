"""The public Python API: exports, import cost, result round trips and notebook rendering.

Round trips (:mod:`calib.results`): for every result type ``T`` and object ``x`` built from the
course data and from a seeded synthetic run, ``T.from_dict(x.to_state()) == x`` (also through
JSON text), and the printed document survives ``from_dict``: ``T.from_dict(x.to_dict())`` is
``x`` where ``to_dict`` carries everything, else it prints the same ``to_dict()``. ``==`` is
checked to be a real comparison (a changed field compares unequal).
"""

from __future__ import annotations

import dataclasses
import doctest
import json
import subprocess
import sys
import types

import numpy as np
import pytest

import bench
import calib
import calib.calibration.calfile
import calib.calibration.montecarlo  # noqa: F401  (their docstring examples run below)
import calib.design.analysis
import calib.fusion.linear
from bench.validate import Validation, validate
from calib.calibration.ls import FitResult, fit_axis, fit_joint
from calib.calibration.tilt_plane import Calibration, calibrate
from calib.files.course import Acel, Ensayo
from calib.results import ResultMixin, same
from calib.vehicle.nmin import McRow, NminResult, PositionCovModel, SubsampleRow, analyze_nmin
from calib.vehicle.region import ArrivalRegion, Ellipse, arrival_region
from calib.vehicle.trajectory import Trajectory, compute_trajectory
from tests.reference import course_2009 as ref

CALIB_EXPORTS = {
    "calibrate", "Calibration", "fit_axis", "fit_joint", "FitResult", "read_ensayo",
    "read_acel", "read_puntos", "read_datos", "Ensayo", "Acel", "correct",
    "compute_trajectory", "Trajectory", "arrival_region", "ArrivalRegion", "analyze_nmin",
    "analyze_gap", "GapAnalysis", "fuse", "FusionResult", "save_calibration",
    "load_calibration", "simulate_calibrations", "MonteCarloResult", "analyze_design",
}
BENCH_EXPORTS = {
    "generate_calibration", "CalibrationConfig", "ThetaDesign", "SweepProfile",
    "SensorErrorModel", "make_vehicle_run", "VehicleConfig", "make_course_set", "run_gap",
    "GapReport", "record_calibration", "read_recording", "validate", "Validation",
}
HEAVY = ("mujoco", "matplotlib", "rerun", "scipy")
SEED = 20261122


# --- exports ----------------------------------------------------------------------------------

@pytest.mark.parametrize("pkg, names", [(calib, CALIB_EXPORTS), (bench, BENCH_EXPORTS)])
def test_every_export_resolves_and_is_listed(pkg, names):
    assert names <= set(pkg.__all__)
    listed = set(dir(pkg))
    for name in pkg.__all__:
        value = getattr(pkg, name)
        assert value is not None and name in listed, name
        if name in names:
            assert not isinstance(value, types.ModuleType), f"{pkg.__name__}.{name} is a module"
            mod, attr = pkg._EXPORTS[name].split(":")
            assert getattr(sys.modules[mod], attr) is value
    with pytest.raises(AttributeError):
        pkg.no_such_name  # noqa: B018


def test_a_function_named_like_its_module_stays_the_function():
    import bench.validate as _  # noqa: F401  (the import system sets the package attribute)

    assert callable(calib.correct) and not isinstance(calib.correct, types.ModuleType)
    assert bench.validate is sys.modules["bench.validate"].validate


def test_importing_the_packages_is_cheap():
    code = ("import json, sys; import bench, calib; "
            f"print(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert json.loads(out.stdout) == []


@pytest.mark.parametrize("module", ["calib", "calib.calibration.ls", "calib.calibration.tilt_plane",
                                    "calib.files.course", "calib.vehicle.trajectory",
                                    "calib.vehicle.region", "calib.vehicle.nmin",
                                    "calib.fusion.linear", "calib.calibration.calfile",
                                    "calib.calibration.montecarlo", "calib.design.analysis",
                                    "bench.validate"])
def test_docstring_examples_run(module):
    mod = sys.modules[module]  # all imported above
    res = doctest.testmod(mod, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert res.failed == 0


@pytest.mark.parametrize("pkg, name", [(calib, n) for n in sorted(CALIB_EXPORTS)
                                       if n not in ("analyze_gap", "GapAnalysis", "correct")]
                         + [(bench, "validate"), (bench, "Validation")])
def test_exports_of_these_files_document_parameters_and_examples(pkg, name):
    doc = getattr(pkg, name).__doc__ or ""
    if isinstance(getattr(pkg, name), type):
        assert "Attributes" in doc or "Parameters" in doc or ":" in doc, name
        assert "from_dict" in dir(getattr(pkg, name)) or name in ("Ensayo", "Acel"), name
    else:
        assert "Parameters" in doc and "Examples" in doc, name


# --- objects to round-trip --------------------------------------------------------------------

def _synthetic():
    """A seeded synthetic calibration + vehicle run (course model, R = 1 draw)."""
    rng = np.random.default_rng(SEED)
    th = np.linspace(0.0, 2 * np.pi, 1001)
    a_r = np.column_stack([-9.8 * np.sin(th), -9.8 * np.cos(th)])
    sd = np.sqrt([0.25, 0.64])
    datos = a_r * [0.97, 1.01] + [0.08, -0.02] + rng.normal(size=a_r.shape) * sd
    t = np.arange(1500) * 0.01
    acc = np.column_stack([np.sin(t), 0.3 * np.ones_like(t)])
    aerr = acc * [0.97, 1.01] + [0.08, -0.02] + rng.normal(size=acc.shape) * sd
    puntos = {"A": np.array([25.0, 80.0]), "B": np.array([60.0, 75.0]),
              "C": np.array([20.0, 120.0])}
    return Ensayo(th, datos), Acel(t, aerr), puntos


def _objects(ensayo, acel, puntos, noise_var, truth):
    """Every result type, from one data set: name → object."""
    objs = {"fit_axis": fit_axis(ensayo.tita, ensayo.datos[:, 0], "x", noise_var[0]),
            "fit_axis estimated": fit_axis(ensayo.tita, ensayo.datos[:, 1], "y"),
            "fit_joint": fit_joint(ensayo.tita, ensayo.datos, noise_var)}
    for method in ("ols", "wls"):
        for nv in (noise_var, None):
            objs[f"calibration {method} {'given' if nv else 'estimated'}"] = calibrate(
                ensayo, nv, method)
    cal = objs["calibration ols given"]
    traj = compute_trajectory(acel, cal)
    region = arrival_region(traj, cal, puntos, noise_var)
    nmin = analyze_nmin(ensayo, acel, puntos, noise_var=noise_var, steps=(10,), mc_n=(201,),
                        runs=3, seed=SEED)
    est = cal.to_dict()
    objs.update({
        "trajectory": traj, "trajectory simpson": compute_trajectory(acel, cal,
                                                                     integrator="simpson"),
        "region": region, "region without noise": arrival_region(traj, cal, puntos, noise_var,
                                                                 include_noise=False),
        "ellipse": region.ellipse, "nmin": nmin, "subsample row": nmin.subsample[0],
        "monte carlo row": nmin.monte_carlo[0],
        "position cov model": PositionCovModel.from_region(region),
        "validation": validate(truth, est, 0.99, theta=ensayo.tita),
        "validation design": validate(truth, est, 0.99, "design", theta=ensayo.tita),
    })
    return objs


def _truth(bias, scale, noise_var):
    return {"sensor": {a: {"bias": bias[k], "scale": scale[k], "noise_var": noise_var[k]}
                       for k, a in enumerate("xy")}, "g": 9.8}


@pytest.fixture(scope="module")
def course_objects(course):
    ensayo, acel, puntos, _, _ = course
    est = {k: v for k, (v, _) in ref.ESTIMATES.items()}  # the course answer as a "truth"
    truth = _truth([est["bias_x"], est["bias_y"]], [est["scale_x"], est["scale_y"]],
                   ref.NOISE_VAR)
    return _objects(ensayo, acel, puntos, list(ref.NOISE_VAR), truth)


@pytest.fixture(scope="module")
def synthetic_objects():
    ensayo, acel, puntos = _synthetic()
    return _objects(ensayo, acel, puntos, [0.25, 0.64],
                    _truth([0.08, -0.02], [-0.03, 0.01], [0.25, 0.64]))


TYPES = {FitResult, Calibration, Trajectory, ArrivalRegion, Ellipse, NminResult, SubsampleRow,
         McRow, PositionCovModel, Validation}
COMPLETE_TO_DICT = {FitResult, NminResult, SubsampleRow, McRow, PositionCovModel}
"""Types whose printed ``to_dict`` carries everything (the others add keys in ``to_state``)."""
UNIT = {FitResult: "m/s²", Calibration: "m/s²", Trajectory: "m/s", ArrivalRegion: "m²",
        Ellipse: "m²", NminResult: " m", SubsampleRow: " m", McRow: "dimensionless",
        PositionCovModel: "m²", Validation: "m/s²"}


def _check_round_trip(objs):
    assert {type(x) for x in objs.values()} == TYPES
    for name, x in objs.items():
        T = type(x)
        assert issubclass(T, ResultMixin), name
        state = x.to_state()
        assert T.from_dict(state) == x, name
        back = T.from_dict(json.loads(json.dumps(state)))
        assert back == x and hash(back) == hash(x), name
        d = x.to_dict()
        if T in COMPLETE_TO_DICT:
            assert T.from_dict(d) == x, name
            assert T.from_dict(json.loads(json.dumps(d))) == x, name
        elif T is Trajectory:
            with pytest.raises(ValueError, match="to_state"):
                T.from_dict(d)
        else:
            assert same(T.from_dict(d).to_dict(), d), name
            assert same(T.from_dict(json.loads(json.dumps(d))).to_dict(), d), name
        assert set(d) <= set(state), name  # to_state only adds keys


def test_round_trip_course(course_objects):
    _check_round_trip(course_objects)


def test_round_trip_synthetic(synthetic_objects):
    _check_round_trip(synthetic_objects)


def test_equality_is_a_real_comparison(synthetic_objects):
    for name, x in synthetic_objects.items():
        assert x == x and not (x != x), name
        for f in dataclasses.fields(x):
            v = getattr(x, f.name)
            if f.compare and isinstance(v, np.ndarray) and v.size and v.dtype.kind == "f":
                changed = np.array(v, copy=True)
                changed.flat[0] += 1.0
                assert dataclasses.replace(x, **{f.name: changed}) != x, (name, f.name)
                break
    a = synthetic_objects["calibration ols given"]
    assert a != synthetic_objects["calibration wls given"]
    assert a != "not a calibration"


def test_nested_results_compare_field_by_field(synthetic_objects):
    cal = synthetic_objects["calibration ols given"]
    other = dataclasses.replace(cal, fits={**cal.fits, "y": synthetic_objects["fit_axis"]})
    assert other != cal
    assert Calibration.from_dict(json.loads(json.dumps(cal.to_state()))).fits == cal.fits


@pytest.mark.parametrize("which", ["course_objects", "synthetic_objects"])
def test_notebook_rendering_has_the_summary_and_units(which, request):
    for name, x in request.getfixturevalue(which).items():
        md = x._repr_markdown_()
        assert isinstance(md, str) and md.strip(), name
        assert x.summary() in md, name
        assert "Units:" in md and UNIT[type(x)] in md, name
