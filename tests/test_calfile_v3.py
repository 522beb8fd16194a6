"""The calibration file, version 3 (issue 30 item 4, docs/calibration-file.md): the log's axes
and unit, the source of g, and the six-face calibration of three axes (bias, scale,
misalignment, the poses, the hold-to-hold variance) — exact round trips in ``.json`` and
``.mat``, version-2 files still read, edits refused in one line, and the one check of every
command (:func:`calib.calibration.calfile.check_applies`) refusing a file whose axes, unit or
kind do not fit the log.

The six-face holds are drawn here from the physics (a sensor whose axes lean from the case
axes, a bias that moves from hold to hold, white noise), not from the fit's own model; the
tilt-plane log is a θ sweep read on the log's y and z axes.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.io

from calib.calibration.calfile import (
    DEFINING_FIELDS_V2,
    FILE_UNITS_V2,
    FORMAT_VERSION,
    calibration_document,
    check_applies,
    defining_checksum,
    load_calibration,
    load_calibration_file,
    mat_variables,
    save_calibration,
)
from calib.calibration.calfile_fields import document_json
from calib.calibration.correct import correct
from calib.calibration.multiposition import pose_statistics
from calib.calibration.readings import (
    COURSE_READINGS,
    GRAVITY_UNITS,
    READINGS_UNITS,
    GravitySource,
    LogReadings,
)
from calib.calibration.sixface import fit_six_face
from calib.calibration.tilt_plane import calibrate
from calib.conventions import STANDARD_GRAVITY, G, normal_gravity
from calib.files.course import Ensayo
from calib.input_rules import DataError
from calib.logs.reader import ImuLog
from calib.units import missing_units
from tests.cli import one_line_error, run
from tests.test_sixface_cli import write_six_face_log

FACES = np.vstack([np.eye(3), -np.eye(3)])
G55 = normal_gravity(55.0, 5000.0)
CONSISTENCY = "checksum/consistency failed"


def six_face_poses(seed: int = 3, repeats=2, face_error: float = 0.0, g: float = G55):
    """Holds of 60 samples on the six faces, each ``repeats`` times (or a list: the count of
    each face +x, +y, +z, -x, -y, -z): readings
    ``b + β_h + (1 + s)·(d · g u) + φ_f + w`` with axes ``d_a`` tilted by ~5 mrad from the
    case axes, a hold-to-hold bias β (σ 0.005 m/s²), a per-face error φ (a face not flat) and
    white noise (σ 0.03 m/s²)."""
    rng = np.random.default_rng(seed)
    bias, scale = rng.normal(0, 0.1, 3), rng.normal(0, 0.02, 3)
    d = np.eye(3) + rng.normal(0, 0.005, (3, 3)) * (1 - np.eye(3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    phi = rng.normal(0, face_error, (6, 3))
    faces = np.repeat(np.arange(6), repeats)
    rng.shuffle(faces)
    acc, pose = [], []
    for h, f in enumerate(faces):
        true = bias + rng.normal(0, 0.005, 3) + (1 + scale) * (d @ (g * FACES[f])) + phi[f]
        acc.append(true + rng.normal(0, 0.03, (60, 3)))
        pose.append(np.full(60, h))
    return pose_statistics(np.vstack(acc), np.concatenate(pose))


def tilt_plane_cal(g: float = G):
    th = np.linspace(0, 2 * np.pi, 400)
    ref = np.column_stack([-g * np.sin(th), -g * np.cos(th)])
    rng = np.random.default_rng(8)
    datos = 1.01 * ref + 0.05 + rng.normal(0, 0.05, ref.shape)
    return calibrate(Ensayo(th, datos), noise_var=[0.0025, 0.0025], g=g)


def write_yz_log(path, g: float = G, n: int = 2000):
    """A θ sweep (course signs) read on the log's y (tilt-plane x) and z (tilt-plane y) axes,
    x across the plane; a θ column in rad."""
    rng = np.random.default_rng(1)
    th = np.linspace(0, 2 * np.pi, n)
    y = 0.98 * (-g * np.sin(th)) + 0.05 + rng.normal(0, 0.05, n)
    z = 1.01 * (-g * np.cos(th)) - 0.03 + rng.normal(0, 0.05, n)
    x = rng.normal(0, 0.05, n)
    with open(path, "w") as fh:
        fh.write("time (s),acc_x (m/s^2),acc_y (m/s^2),acc_z (m/s^2),theta (rad)\n")
        for row in zip(np.arange(n) * 0.01, x, y, z, th, strict=True):
            fh.write(",".join(f"{v:.9g}" for v in row) + "\n")
    return path


def _edit(src, dst, edit) -> str:
    doc = json.loads(src.read_text())
    edit(doc)
    dst.write_text(json.dumps(doc, indent=1))
    return str(dst)


def _v2(doc: dict) -> dict:
    """The version-2 file of the same tilt-plane calibration (what tiltbench 0.1 wrote): no
    gravity, readings or sensor_axes, their units gone, the version-2 checksum."""
    out = {k: v for k, v in doc.items() if k not in ("gravity", "readings", "sensor_axes")}
    out["format_version"] = 2
    out["units"] = {k: v for k, v in doc["units"].items()
                    if k not in GRAVITY_UNITS and k not in READINGS_UNITS}
    covers = [f for f in doc["checksum"]["covers"] if f not in ("gravity", "readings")]
    out["checksum"] = {"algorithm": "sha256", "covers": covers, "value": None}
    out["checksum"]["value"] = defining_checksum(out)
    return out


@pytest.fixture(scope="module")
def six(tmp_path_factory):
    """A six-face fit (g from latitude 55°, 5000 m) saved as JSON and .mat, log axes -y,z in g."""
    d = tmp_path_factory.mktemp("v3six")
    poses = six_face_poses()
    fit = fit_six_face(poses, g=G55, g_source="WGS84 latitude 55", source="six.csv")
    kw = dict(readings=LogReadings(("-y", "z"), "g"),
              gravity=GravitySource("latitude", 55.0, 5000.0), poses=poses,
              tool_version="0.1.0")
    for name in ("cal.json", "cal.mat"):
        save_calibration(d / name, fit, **kw)
    return d, fit, poses


# ------------------------------------------------------------------ round trips
def test_six_face_round_trips_exactly_in_json_and_mat(six):
    d, fit, poses = six
    for name in ("cal.json", "cal.mat"):
        cf = load_calibration_file(d / name)
        assert cf.kind == "six-face" and cf.version == FORMAT_VERSION == 3
        assert cf.calibration == fit
        assert np.array_equal(cf.hold_means, poses.means)
        assert cf.readings == LogReadings(("-y", "z"), "g")
        assert cf.gravity == GravitySource("latitude", 55.0, 5000.0)
        assert cf.log_axes == ("-y", "z", "-x")  # z = x̂ × ŷ of the log's -y, z


def test_six_face_file_holds_every_field_of_the_issue(six):
    d, fit, poses = six
    doc = json.loads((d / "cal.json").read_text())
    assert doc["method"] == "six-face" and doc["readings"]["axes"] == ["-y", "z"]
    assert doc["readings"]["unit"] == "g" and doc["readings"]["to_m_s2"] == STANDARD_GRAVITY
    assert doc["sensor_axes"] == {"x": "-y", "y": "z", "z": "-x"}
    assert doc["gravity"] == {"source": "latitude", "latitude": 55.0, "height": 5000.0}
    assert doc["g"] == G55
    assert np.array_equal(doc["misalignment"], fit.misalignment)
    assert np.array_equal(doc["cov"], fit.cov) and len(doc["params"]) == 12
    assert doc["hold_to_hold_variance"] == (fit.sigma_between**2).tolist()
    assert [p["face"] for p in doc["poses"]] == list(fit.faces)
    assert [p["n"] for p in doc["poses"]] == poses.n.tolist()
    assert np.array_equal([p["mean"] for p in doc["poses"]], poses.means)
    assert doc["n"] == int(poses.n.sum())
    assert missing_units(doc) == []
    m = scipy.io.loadmat(str(d / "cal.mat"))
    assert np.array_equal(m["k_matrix"], fit.k_matrix)
    assert np.array_equal(m["hold_means"], poses.means)
    assert str(m["faces"][0]).split(",") == list(fit.faces)
    assert str(m["axes"][0]) == "-y,z" and str(m["sensor_axes"][0]) == "-y,z,-x"


def test_six_face_with_misfit_in_its_intervals_round_trips(tmp_path):
    """Faces that are not flat (the lack-of-fit rule puts the misfit into the intervals): the
    file still reads back equal."""
    poses = six_face_poses(0, face_error=0.05)
    fit = fit_six_face(poses, g=G55)
    assert any(fit.misfit_in_intervals)
    path = save_calibration(tmp_path / "m.json", fit, poses=poses,
                            gravity=GravitySource("latitude", 55.0, 5000.0))
    assert load_calibration_file(path).calibration == fit


def test_six_face_without_reholds_round_trips(tmp_path):
    poses = six_face_poses(repeats=1)
    fit = fit_six_face(poses, g=G55)
    assert not fit.repeatability_measured
    path = save_calibration(tmp_path / "once.mat", fit, poses=poses,
                            gravity=GravitySource("latitude", 55.0, 5000.0))
    assert load_calibration_file(path).calibration == fit
    doc = json.loads(str(scipy.io.loadmat(str(path))["document"][0]))
    assert doc["hold_to_hold_variance"] == [[None, None]] * 3


def test_six_face_with_a_borrowed_class_round_trips_and_is_checked(tmp_path):
    """Only ±x held twice: x's level class and the vertical class of y and z have no re-held
    face and carry the other class' σ_B (hold_std re-derived per class); a file whose
    borrowed σ_B differs from the one it borrows is refused in one line."""
    poses = six_face_poses(5, repeats=[2, 1, 1, 2, 1, 1])
    fit = fit_six_face(poses, g=G55)
    assert fit.borrowed().tolist() == [[False, True], [True, False], [True, False]]
    path = save_calibration(tmp_path / "b.json", fit, poses=poses,
                            gravity=GravitySource("latitude", 55.0, 5000.0))
    assert load_calibration_file(path).calibration == fit
    bad = _edit(tmp_path / "b.json", tmp_path / "e.json",
                lambda d: d["calibration"]["sigma_between"][0].__setitem__(1, 0.5))
    with pytest.raises(DataError, match=r"calibration\.sigma_between\[0\]\[1\].*held twice"):
        load_calibration_file(bad)


def test_tilt_plane_v3_records_axes_unit_and_gravity(tmp_path):
    cal = tilt_plane_cal(G55)
    readings = LogReadings(("y", "z"), "counts", 1024.0)
    for name in ("c.json", "c.mat"):
        path = save_calibration(tmp_path / name, cal, sigma2_source="given",
                                readings=readings,
                                gravity=GravitySource("latitude", 55.0, 5000.0))
        assert load_calibration(path) == cal
        cf = load_calibration_file(path)
        assert (cf.kind, cf.version, cf.readings) == ("tilt-plane", 3, readings)
    doc = json.loads((tmp_path / "c.json").read_text())
    assert doc["readings"] == {"axes": ["y", "z"], "unit": "counts",
                               "sensitivity_counts_per_g": 1024.0,
                               "to_m_s2": STANDARD_GRAVITY / 1024.0}
    assert doc["sensor_axes"] == {"x": "y", "y": "z"} and missing_units(doc) == []


def test_save_refuses_a_g_its_source_does_not_give(tmp_path):
    """g = 9.8 recorded as the normal gravity of 55°, 5000 m (9.7997): nothing is written."""
    with pytest.raises(DataError, match="not written.*WGS84"):
        save_calibration(tmp_path / "c.json", tilt_plane_cal(G), sigma2_source="given",
                         gravity=GravitySource("latitude", 55.0, 5000.0))
    with pytest.raises(DataError, match="assumed"):
        save_calibration(tmp_path / "c.json", tilt_plane_cal(9.81), sigma2_source="given",
                         gravity=GravitySource("assumed"))
    assert not (tmp_path / "c.json").exists()


def test_a_six_face_file_is_saved_with_its_holds(tmp_path):
    poses = six_face_poses()
    fit = fit_six_face(poses, g=G55)
    with pytest.raises(ValueError, match="holds"):
        calibration_document(fit, None)
    save_calibration(tmp_path / "a.json", fit, poses=poses)
    with pytest.raises(FileExistsError):
        save_calibration(tmp_path / "a.json", fit, poses=poses)
    with pytest.raises(ValueError, match="six-face"):
        calibration_document(tilt_plane_cal(), None, poses=poses)


# ------------------------------------------------------------------ version 2
def test_version_2_files_still_load_and_mean_course_axes(tmp_path):
    cal = tilt_plane_cal()
    v3 = json.loads(document_json(calibration_document(cal, None, "given")))
    doc = _v2(v3)
    assert doc["checksum"]["covers"] == list(DEFINING_FIELDS_V2)
    assert doc["units"] == FILE_UNITS_V2  # a course fit: no optional keys
    (tmp_path / "v2.json").write_text(document_json(doc))
    buf = mat_variables(doc)
    scipy.io.savemat(str(tmp_path / "v2.mat"), buf, format="5", oned_as="row")
    for name in ("v2.json", "v2.mat"):
        cf = load_calibration_file(tmp_path / name)
        assert cf.version == 2 and cf.readings == COURSE_READINGS and cf.gravity is None
        assert cf.calibration == cal and load_calibration(tmp_path / name) == cal
        check_applies(cf, COURSE_READINGS)  # course axes x, y in m/s²: applies
        with pytest.raises(DataError, match="log axes x,y"):
            check_applies(cf, LogReadings(("y", "z")))
    bad = _edit(tmp_path / "v2.json", tmp_path / "bad.json",
                lambda d: d["params"].__setitem__(0, 0.5))
    with pytest.raises(DataError, match=CONSISTENCY):
        load_calibration_file(bad)


# ------------------------------------------------------------------ edits refused
SIX_EDITS = {
    "k_matrix entry": (lambda d: d["calibration"]["k_matrix"][0].__setitem__(1, 0.01),
                       "calibration.params"),
    "a pose mean": (lambda d: d["poses"][2]["mean"].__setitem__(0, d["poses"][2]["mean"][0]
                                                               + 0.01), "residuals"),
    "a pose's face": (lambda d: d["poses"][0].update(face="+q"), "poses[0].face"),
    "readings axes": (lambda d: d["readings"].update(axes=["x", "y"]), "checksum"),
    "readings unit": (lambda d: d["readings"].update(unit="mg"), "to_m_s2"),
    "sensitivity": (lambda d: d["readings"].update(sensitivity_counts_per_g=1000.0),
                    "sensitivity"),
    "latitude": (lambda d: d["gravity"].update(latitude=10.0), "WGS84"),
    "assumed g": (lambda d: d["gravity"].update(source="assumed", latitude=None, height=None),
                  "assumed"),
    "sensor_axes": (lambda d: d["sensor_axes"].update(z="x"), "sensor_axes.z"),
    "bias copy": (lambda d: d["bias"].__setitem__(0, 1.0), "bias[0]"),
    "hold_to_hold": (lambda d: d["hold_to_hold_variance"][1].__setitem__(1, 1.0),
                     "hold_to_hold_variance[1]"),
    "level": (lambda d: d["calibration"].update(level=0.9), "checksum"),
    "sigma_between null": (lambda d: d["calibration"]["sigma_between"][0].__setitem__(0, None),
                           "sigma_between"),
    "hold_std of the other class": (lambda d: d["calibration"]["hold_std"][0].__setitem__(
        0, d["calibration"]["hold_std"][0][0] * 1.5), "hold_std[0][0]"),
    "dof of one axis": (lambda d: d["calibration"].update(dof=d["calibration"]["dof"][:3]),
                        "calibration.dof"),
    "asymmetric cov": (lambda d: d["calibration"]["cov"][0].__setitem__(1, 1e-3),
                       "not symmetric"),
    "added field": (lambda d: d.update(bias_x=0.5), "bias_x"),
    "missing": (lambda d: d.pop("poses"), "poses"),
}


@pytest.mark.parametrize("label", sorted(SIX_EDITS))
def test_edited_six_face_files_are_refused_in_one_line(six, tmp_path, label):
    d, _, _ = six
    edit, words = SIX_EDITS[label]
    path = _edit(d / "cal.json", tmp_path / "e.json", edit)
    with pytest.raises(DataError) as exc:
        load_calibration_file(path)
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith(path) and words in msg, msg


def test_a_consistent_edit_only_the_checksum_sees(six, tmp_path):
    """bias_x changed in every readable copy (params, bias, the state): refused by the
    checksum of the defining fields."""
    d, _, _ = six

    def edit(doc):
        shift = 0.2 - doc["params"][0]
        for node in (doc["params"], doc["calibration"]["params"], doc["bias"]):
            node[0] = 0.2
        for pose in doc["poses"]:  # the means move with the bias: the residuals stay
            pose["mean"][0] += shift
    path = _edit(d / "cal.json", tmp_path / "c.json", edit)
    with pytest.raises(DataError, match=CONSISTENCY):
        load_calibration_file(path)
    path = _edit(d / "cal.json", tmp_path / "t.json", lambda doc: doc.pop("tool"))  # cosmetic
    assert load_calibration_file(path).calibration == six[1]


def test_edited_mat_variables_are_refused(six, tmp_path):
    d, _, _ = six
    m = {k: v for k, v in scipy.io.loadmat(str(d / "cal.mat")).items() if not k.startswith("__")}
    m["k_matrix"] = m["k_matrix"] * 1.01
    scipy.io.savemat(str(tmp_path / "e.mat"), m, format="5", oned_as="row")
    with pytest.raises(DataError, match=f"{CONSISTENCY}: 'k_matrix'"):
        load_calibration_file(tmp_path / "e.mat")


# ------------------------------------------------------------------ the correction
def test_correct_inverts_the_model_and_reduces_to_the_course_equation(six):
    _, fit, _ = six
    rng = np.random.default_rng(2)
    a = rng.normal(0, 9.8, (200, 3))
    assert np.allclose(fit.correct(fit.apply_errors(a)), a, rtol=0, atol=1e-12)
    assert np.allclose(fit.correct(fit.apply_errors(a[0])), a[0], rtol=0, atol=1e-12)
    # no misalignment: each axis is the course's (A_m − bias)/(1 + scale)
    diag = fit.__class__.from_dict({**fit.to_dict(),
                                    "k_matrix": np.diag(np.diag(fit.k_matrix)).tolist()})
    m = rng.normal(0, 9.8, (50, 3))
    assert np.allclose(diag.correct(m), correct(m, diag.bias, diag.scale), rtol=1e-15,
                       atol=1e-14)
    with pytest.raises(ValueError, match="shape"):
        fit.correct(np.zeros((4, 2)))


# ------------------------------------------------------------------ what applies to what
def test_check_applies_names_kind_axes_unit_and_the_third_axis(six):
    d, _, _ = six
    cf = load_calibration_file(d / "cal.json")
    with pytest.raises(DataError, match="tiltbench apply LOG --calibration cal.json"):
        check_applies(cf)
    check_applies(cf, LogReadings(("-y", "z"), "g"), tilt_plane=False)
    with pytest.raises(DataError, match="log axes -y,z.*--axes=-y,z"):
        check_applies(cf, ImuLog(acc=np.zeros((5, 2)), acc_normal=np.zeros(5),
                                 provenance={"axes": ["x", "y"], "units": {"acc": "g"}}),
                      tilt_plane=False)
    with pytest.raises(DataError, match="readings in g, but .* in mg"):
        check_applies(cf, LogReadings(("-y", "z"), "mg"), tilt_plane=False)
    with pytest.raises(DataError, match="corrects 3 axes"):
        check_applies(cf, ImuLog(acc=np.zeros((5, 2)), source="two.csv",
                                 provenance={"axes": ["-y", "z"], "units": {"acc": "g"}}),
                      tilt_plane=False)
    counts = load_calibration_file(save_calibration(
        d / "counts.json", tilt_plane_cal(), sigma2_source="given",
        readings=LogReadings(("x", "y"), "counts", 1000.0), force=True))
    with pytest.raises(DataError, match="1000 counts/g.*1024 counts/g"):
        check_applies(counts, LogReadings(("x", "y"), "counts", 1024.0))


# ------------------------------------------------------------------ from the command line
@pytest.fixture(scope="module")
def saved_logs(tmp_path_factory):
    d = tmp_path_factory.mktemp("v3cli")
    six_csv = write_six_face_log(d / "six.csv")
    yz_csv = write_yz_log(d / "yz.csv")
    return d, six_csv, yz_csv


def test_calibrate_saves_a_six_face_file(capsys, saved_logs):
    d, six_csv, _ = saved_logs
    rc, out, err = run(capsys, "calibrate", six_csv, "--latitude", 10, "--save", d / "s.json")
    assert rc == 0, err
    assert f"wrote: {d / 's.json'}" in out
    rc, _, err = run(capsys, "calibrate", six_csv, "--latitude", 10, "--save", d / "s.mat")
    assert rc == 0, err
    a, b = load_calibration_file(d / "s.json"), load_calibration_file(d / "s.mat")
    assert a.kind == "six-face" and a.calibration == b.calibration
    assert a.gravity == GravitySource("latitude", 10.0, 0.0)
    assert a.calibration.g == normal_gravity(10.0)
    rc, out, _ = run(capsys, "calibrate", six_csv, "--latitude", 10, "--json")
    assert json.loads(out)["fit"]["params"] == a.calibration.params.tolist()
    msg = one_line_error(capsys, "calibrate", six_csv, "--save", d / "s.json",
                         ignore=("note:",))
    assert "--force" in msg


def test_calibrate_saves_the_axis_mapping_of_a_planar_log(capsys, saved_logs):
    d, _, yz_csv = saved_logs
    rc, _, err = run(capsys, "calibrate", yz_csv, "--axes", "y,z", "--g", 9.81,
                     "--save", d / "yz.json")
    assert rc == 0, err
    cf = load_calibration_file(d / "yz.json")
    assert cf.readings == LogReadings(("y", "z"), "m/s2") and cf.gravity.source == "given"
    rc, _, err = run(capsys, "calibrate", yz_csv, "--axes", "y,z", "--save", d / "yz0.json")
    assert rc == 0, err
    assert load_calibration_file(d / "yz0.json").gravity.source == "assumed"


def test_commands_refuse_a_file_that_does_not_fit_their_log(capsys, saved_logs, course_dir):
    """A y,z calibration on the course's x,y acel.mat, and a six-face file where the tilt
    plane's calibration is needed: one line each, in trajectory, nmin, fuse and validate."""
    d, six_csv, yz_csv = saved_logs
    for name, argv in (("yz.json", ["calibrate", yz_csv, "--axes", "y,z"]),
                       ("six.json", ["calibrate", six_csv])):
        if not (d / name).exists():
            assert run(capsys, *argv, "--save", d / name)[0] == 0
    course = ["--acel", course_dir / "acel.mat", "--puntos", course_dir / "puntos.mat",
              "--datos", course_dir / "datos.txt"]
    for command in (["trajectory"], ["nmin", "--quiet"]):
        msg = one_line_error(capsys, *command, "--calibration", d / "yz.json", *course)
        assert "log axes y,z" in msg and "acel.mat reads the course's axes x,y" in msg
        msg = one_line_error(capsys, *command, "--calibration", d / "six.json", *course)
        assert "six-face" in msg and "tilt-plane calibration" in msg and "apply" in msg
    rc, _, _ = run(capsys, "generate", "course", "--seed", "3", "--duration", "6", "--rate",
                   "20", "--count", "200", "--gps", "--out", d / "run")
    assert rc == 0
    run_files = ["--acel", d / "run" / "acel.mat", "--puntos", d / "run" / "puntos.mat",
                 "--gps", d / "run" / "gps.mat"]
    msg = one_line_error(capsys, "fuse", "--calibration", d / "yz.json", *run_files)
    assert "log axes y,z" in msg
    msg = one_line_error(capsys, "validate", "--truth", d / "run" / "truth.json",
                         "--calibration", d / "six.json")
    assert "six-face" in msg
