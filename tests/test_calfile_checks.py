"""One calibration, checked on load (issue 23 part 1, docs/calibration-file.md).

Every command reads a calibration file through
:func:`calib.calibration.calfile.load_calibration_file` and sees the same numbers; an edit of any
readable block is refused ("checksum/consistency failed"), never graded; impossible numbers (|ρ| >
1, n = 0, σ² ≤ 0, a gain of 0 …) and empty or garbage files are one line naming the file and the
field.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import scipy.io

import calib.calibration.calfile as calfile
from bench.cli import main
from calib.calibration.calfile import FORMAT_VERSION, load_calibration, save_calibration
from calib.calibration.tilt_plane import calibrate
from calib.files.course import Ensayo
from calib.input_rules import DataError
from tests.cli import one_line_error as _error
from tests.cli import run as _run

CONSISTENCY = "checksum/consistency failed"


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    """A 300-sample calibration set (truth.json) calibrated to cal.json / cal.mat (σ²
    estimated) and wls.json (WLS, σ² given); a short vehicle run with a receiver (10 s at
    20 Hz) for trajectory, nmin and fuse."""
    d = tmp_path_factory.mktemp("calchk")
    for argv in (["generate", "calibration", "--count", "300", "--seed", "3", "--out",
                  d / "set"],
                 ["generate", "course", "--seed", "3", "--duration", "10", "--rate", "20",
                  "--count", "300", "--gps", "--out", d / "run"],
                 ["calibrate", d / "set" / "ensayo.mat", "--save", d / "cal.json"],
                 ["calibrate", d / "set" / "ensayo.mat", "--save", d / "cal.mat"],
                 ["calibrate", d / "set" / "ensayo.mat", "--method", "wls", "--noise-var",
                  "0.25,0.64", "--save", d / "wls.json"]):
        assert main([str(a) for a in argv]) == 0
    return d


def _vehicle(d) -> list:
    return ["--acel", d / "run" / "acel.mat", "--puntos", d / "run" / "puntos.mat",
            "--datos", d / "run" / "datos.txt"]


def _consumers(d, cal) -> dict[str, list]:
    """The argv of every command that reads a calibration file."""
    return {
        "validate": ["validate", "--truth", d / "set" / "truth.json", "--calibration", cal,
                     "--json"],
        "trajectory": ["trajectory", "--calibration", cal, *_vehicle(d), "--json"],
        "nmin": ["nmin", "--calibration", cal, *_vehicle(d), "--json", "--workers", "1",
                 "--confirm-runs", "0", "--draws", "0", "--quiet"],
        "fuse": ["fuse", "--calibration", cal, *_vehicle(d), "--gps", d / "run" / "gps.mat",
                 "--json"],
    }


def _edit_json(src, dst, edit) -> str:
    doc = json.loads(src.read_text())
    edit(doc)
    dst.write_text(json.dumps(doc, indent=1))
    return str(dst)


def _mat_vars(path) -> dict:
    m = scipy.io.loadmat(str(path))
    return {k: v for k, v in m.items() if not k.startswith("__")}


def _edit_mat(src, dst, edit) -> str:
    m = _mat_vars(src)
    edit(m)
    scipy.io.savemat(str(dst), m, format="5", oned_as="row")
    return str(dst)


def _edit_mat_document(edit):
    """A .mat edit that changes the JSON object inside the ``document`` variable."""
    def run(m):
        doc = json.loads(str(m["document"][0]))
        edit(doc)
        m["document"] = json.dumps(doc, indent=2) + "\n"
    return run


# ------------------------------------------------------------------ one reader
@pytest.mark.parametrize("name", ["cal.json", "cal.mat", "wls.json"])
def test_every_consumer_reads_the_same_calibration(small, capsys, monkeypatch, name):
    """validate, trajectory, nmin and fuse each call the one reader once and get equal
    calibrations; validate grades exactly that calibration's ``calibrate --json`` object."""
    import importlib

    validate_module = importlib.import_module("bench.validate")  # `bench.validate` is the function
    seen: list[tuple[str, calfile.CalibrationFile]] = []
    graded: list[dict] = []
    real_load, real_validate = calfile.load_calibration_file, validate_module.validate

    def spy_load(path):
        cf = real_load(path)
        seen.append((command, cf))
        return cf

    def spy_validate(truth, est, *args, **kwargs):
        graded.append(est)
        return real_validate(truth, est, *args, **kwargs)

    monkeypatch.setattr(calfile, "load_calibration_file", spy_load)
    monkeypatch.setattr(validate_module, "validate", spy_validate)
    for command, argv in _consumers(small, small / name).items():
        rc, out, err = _run(capsys, *argv)
        assert rc in (0, 1) if command == "validate" else rc == 0, (command, err)
        assert json.loads(out)
        assert [c for c, _ in seen].count(command) == 1, command
    ref = seen[0][1].calibration
    for command, cf in seen:
        assert cf.calibration == ref, command
        assert np.array_equal(cf.calibration.params, ref.params), command
        assert np.array_equal(cf.calibration.cov, ref.cov), command
    assert graded == [ref.to_dict()]
    if name != "wls.json":
        assert ref == load_calibration(small / "cal.json")


def test_the_cli_has_no_other_calibration_reader():
    """No command module opens a calibration file by itself: they name only the one reader
    (``load_calibration`` / ``load_calibration_file``) of :mod:`calib.calibration.calfile`."""
    from pathlib import Path

    import bench

    root = Path(bench.__file__).parent
    for path in root.rglob("*.py"):
        text = path.read_text(encoding="utf-8")
        assert "read_calibration_document" not in text, path
        assert "calibration_from_document" not in text, path


# ------------------------------------------------------------------ edited files
def _bump(doc, keys, factor=1.5, add=0.0):
    """Multiply (and shift) the number at ``keys`` (a path of keys and indices)."""
    node = doc
    for k in keys[:-1]:
        node = node[k]
    node[keys[-1]] = node[keys[-1]] * factor + add


JSON_EDITS = {  # one readable number changed in each block (plausible values: no range check)
    "params": lambda d: _bump(d, ["params", 0], add=0.1),
    "std": lambda d: _bump(d, ["std", 1]),
    "cov": lambda d: _bump(d, ["cov", 0, 0]),
    "cov offdiag": lambda d: (_bump(d, ["cov", 0, 1], 0.5), _bump(d, ["cov", 1, 0], 0.5)),
    "sigma2": lambda d: _bump(d, ["sigma2", 0]),
    "units": lambda d: d["units"].update(g="km/s²"),
    "g": lambda d: d.update(g=9.81),
    "calibration.g": lambda d: d["calibration"].update(g=9.81),
    "calibration.method": lambda d: d["calibration"].update(method="wls"),
    "axes.bias": lambda d: _bump(d, ["calibration", "axes", "x", "bias"], add=0.2),
    "axes.scale": lambda d: _bump(d, ["calibration", "axes", "y", "scale"], add=0.02),
    "axes.bias_std": lambda d: _bump(d, ["calibration", "axes", "x", "bias_std"]),
    "axes.cov": lambda d: _bump(d, ["calibration", "axes", "x", "cov", 1, 1]),
    "axes.sigma2": lambda d: _bump(d, ["calibration", "axes", "y", "sigma2"]),
    "axes.chi2_dof": lambda d: _bump(d, ["calibration", "axes", "x", "chi2_dof"]),
    "axes.n": lambda d: d["calibration"]["axes"]["x"].update(n=20001),
    "axes.units": lambda d: d["calibration"]["units"].update(g="1"),
    "fits.params": lambda d: _bump(d, ["calibration", "fits", "x", "params", 0], add=0.2),
    "fits.std": lambda d: _bump(d, ["calibration", "fits", "x", "std", 0]),
    "fits.chi2_dof": lambda d: _bump(d, ["calibration", "fits", "y", "chi2_dof"]),
    "fits.cond": lambda d: _bump(d, ["calibration", "fits", "y", "cond"]),
    "fits.residual sign": lambda d: _bump(d, ["calibration", "fits", "x", "residuals", 5],
                                          -1.0),
    "fits.extra": lambda d: d["calibration"]["fits"]["x"]["extra"].update(note=1),
    "source": lambda d: d["source"].update(sha256="0" * 64),
    "noise_file": lambda d: d.update(noise_file={"name": "datos.txt", "sha256": "1" * 64}),
    "sigma2_source": lambda d: d.update(sigma2_source="given"),
    "checksum": lambda d: d["checksum"].update(value="f" * 64),
    "added field": lambda d: d.update(bias_x=0.5),
}


def _every_copy_of_bias_x(value):
    """Set bias_x in every place it is readable: a consistent edit only the checksum sees."""
    def edit(d):
        d["params"][0] = d["calibration"]["fits"]["x"]["params"][0] = value
        d["calibration"]["axes"]["x"]["bias"] = value
    return edit


@pytest.mark.parametrize("kind", ["json", "mat"])
def test_edited_blocks_never_pass_validate(small, tmp_path, capsys, kind):
    """Each readable block of a saved file changed by hand: validate exits 2 with one line
    (never PASS, never FAIL on numbers that are not the calibration's)."""
    truth = small / "set" / "truth.json"
    rc, _, err = _run(capsys, "validate", "--truth", truth, "--calibration", small / f"cal.{kind}")
    assert rc == 0, err  # the file as saved is graded (and passes its own truth)
    edits = dict(JSON_EDITS, consistent=_every_copy_of_bias_x(0.0123))
    for label, edit in edits.items():
        if kind == "json":
            path = _edit_json(small / "cal.json", tmp_path / "e.json", edit)
        else:
            path = _edit_mat(small / "cal.mat", tmp_path / "e.mat", _edit_mat_document(edit))
        msg = _error(capsys, "validate", "--truth", truth, "--calibration", path)
        assert path in msg, label
        assert CONSISTENCY in msg or "not part of format" in msg, (label, msg)
        assert "calibrate" in msg and "--save" in msg, (label, msg)


MAT_EDITS = {
    "params": lambda m: m.update(params=m["params"] + 0.01),
    "std": lambda m: m.update(std=m["std"] * 2),
    "cov": lambda m: m.update(cov=m["cov"] * 2),
    "sigma2": lambda m: m.update(sigma2=m["sigma2"] * 2),
    "chi2_dof": lambda m: m.update(chi2_dof=m["chi2_dof"] * 2),
    "g": lambda m: m.update(g=9.81),
    "n": lambda m: m.update(n=20001.0),
    "method": lambda m: m.update(method="wls"),
    "sigma2_source": lambda m: m.update(sigma2_source="given"),
    "source_sha256": lambda m: m.update(source_sha256="0" * 64),
    "checksum": lambda m: m.update(checksum="f" * 64),
    "units": lambda m: m.update(units="km"),
    "param_names": lambda m: m.update(param_names="a,b,c,d"),
    "added": lambda m: m.update(bias=np.zeros((1, 2))),
    "removed": lambda m: m.pop("cov"),
}


@pytest.mark.parametrize("label", sorted(MAT_EDITS))
def test_edited_mat_variables_are_refused(small, tmp_path, capsys, label):
    path = _edit_mat(small / "cal.mat", tmp_path / "e.mat", MAT_EDITS[label])
    msg = _error(capsys, "validate", "--truth", small / "set" / "truth.json", "--calibration",
                 path)
    key = "cov" if label == "removed" else "bias" if label == "added" else label
    assert path in msg and f"'{key}'" in msg, msg


def test_mat_tool_version_is_cosmetic(small, tmp_path, capsys):
    """``tool_version`` (like ``tool`` in the JSON) is informational: editing it changes no
    number, so the file is read and graded as saved."""
    base = ["validate", "--truth", small / "set" / "truth.json", "--json", "--calibration"]
    path = _edit_mat(small / "cal.mat", tmp_path / "cal.mat",
                     lambda m: m.update(tool_version="9.9.9"))
    a = _run(capsys, *base, small / "cal.mat")
    b = _run(capsys, *base, path)
    assert a[0] == b[0] == 0 and a[1].replace(str(small), str(tmp_path)) == b[1]


def test_seed3_calibration_edited_to_another_truth_is_refused(small, tmp_path, capsys):
    """The fuzzer's case: seed 3's calibration, its readable ``calibration.axes`` block (or
    every copy) set to another set's true values, graded against that set's truth."""
    other = tmp_path / "other"
    assert main(["generate", "calibration", "--count", "300", "--seed", "1", "--bias",
                 "0.5,-0.4", "--scale", "0.05,-0.06", "--out", str(other)]) == 0
    truth = json.loads((other / "truth.json").read_text())
    base = ["validate", "--truth", other / "truth.json", "--calibration"]
    rc, _, _ = _run(capsys, *base, small / "cal.json")
    assert rc == 1  # honest: seed 3's estimates fail seed 1's truth

    def axes_to_truth(d):
        for a in "xy":
            d["calibration"]["axes"][a].update(bias=truth["sensor"][a]["bias"],
                                               scale=truth["sensor"][a]["scale"])

    def everywhere(d):
        axes_to_truth(d)
        for k, a in enumerate("xy"):
            p = [truth["sensor"][a]["bias"], truth["sensor"][a]["scale"]]
            d["calibration"]["fits"][a]["params"] = p
            d["params"][2 * k:2 * k + 2] = p

    for edit in (axes_to_truth, everywhere):
        path = _edit_json(small / "cal.json", tmp_path / "e.json", edit)
        assert CONSISTENCY in _error(capsys, *base, path)


# ------------------------------------------------------------------ impossible numbers
def _fit(d, a="x"):
    return d["calibration"]["fits"][a]


def _rho(d, value, where=("calibration", "fits", "x")):
    node = d
    for k in where:
        node = node[k]
    c = node["cov"]
    c[0][1] = c[1][0] = value * math.sqrt(c[0][0] * c[1][1])


def _not_pd(d):
    """Pairwise |ρ| = 0.9 < 1 among bias_x, scale_x, bias_y, but ρ matrix not PD."""
    c = d["calibration"]["joint"]["cov"]
    sd = [math.sqrt(c[i][i]) for i in range(4)]
    for (i, j), r in {(0, 1): 0.9, (0, 2): 0.9, (1, 2): -0.9}.items():
        c[i][j] = c[j][i] = r * sd[i] * sd[j]


LOADER_CASES = [  # (file, edit, field, words in the message)
    ("cal.json", lambda d: _rho(d, 1.3), "calibration.fits.x.cov", "|ρ| > 1"),
    ("cal.json", lambda d: _rho(d, -1.0000001), "calibration.fits.x.cov", "|ρ| > 1"),
    ("cal.json", lambda d: _rho(d, 1.0), "calibration.fits.x.cov", "positive definite"),
    ("cal.json", lambda d: _fit(d)["cov"][0].__setitem__(1, 0.0), "calibration.fits.x.cov",
     "symmetric"),
    ("cal.json", lambda d: _fit(d)["cov"][0].__setitem__(0, -6.29), "calibration.fits.x.cov",
     "variance"),
    ("wls.json", _not_pd, "calibration.joint.cov", "positive definite"),
    ("wls.json", lambda d: _rho(d, 2.0, ("calibration", "joint")), "calibration.joint.cov",
     "|ρ| > 1"),
    ("cal.json", lambda d: d.update(n=0), "n", "[3,"),
    ("cal.json", lambda d: d.update(n=1), "n", "[3,"),
    ("cal.json", lambda d: d.update(n=2), "n", "[3,"),
    ("cal.json", lambda d: d.update(n=10**12), "n", "[3,"),
    ("cal.json", lambda d: d.update(n=299), "calibration.fits.x.residuals", "rows"),
    ("cal.json", lambda d: d.update(n=300.0), "n", "integer"),
    ("cal.json", lambda d: d.update(n="300"), "n", "integer"),
    ("cal.json", lambda d: d.update(n=True), "n", "integer"),
    ("cal.json", lambda d: _fit(d).update(sigma2=0.0), "calibration.fits.x.sigma2", "(m/s²)²"),
    ("cal.json", lambda d: _fit(d).update(sigma2=-0.25), "calibration.fits.x.sigma2", "(m/s²)²"),
    ("cal.json", lambda d: _fit(d).update(sigma2=1e300), "calibration.fits.x.sigma2", "(m/s²)²"),
    ("cal.json", lambda d: _bump(_fit(d), ["sigma2"], 2.0), "calibration.fits.x.chi2",
     "residuals"),
    ("cal.json", lambda d: _fit(d, "y").update(dof=100), "calibration.fits.y.dof", "n = 300"),
    ("cal.json", lambda d: _fit(d)["residuals"].pop(), "calibration.fits.x.residuals", "rows"),
    ("cal.json", lambda d: _fit(d)["params"].__setitem__(0, float("nan")),
     "calibration.fits.x.params", "NaN"),
    ("cal.json", lambda d: _fit(d)["cov"][1].__setitem__(1, float("inf")),
     "calibration.fits.x.cov", "NaN or Infinity"),
    ("cal.json", lambda d: _fit(d)["params"].__setitem__(1, -1.0), "calibration.fits.x.params",
     "gain"),
    ("cal.json", lambda d: _fit(d)["params"].__setitem__(0, 1e300), "calibration.fits.x.params",
     "bias"),
    ("cal.json", lambda d: d.update(g=0.0), "g", "gravity"),
    ("cal.json", lambda d: d.update(g=-9.8), "g", "gravity"),
    ("cal.json", lambda d: d.update(g=1e6), "g", "gravity"),
    ("cal.json", lambda d: d.update(g="9.8"), "g", "finite number"),
    ("cal.json", lambda d: _fit(d).update(params="abc"), "calibration.fits.x.params", "shape"),
    ("cal.json", lambda d: _fit(d).update(cov=[[1.0, 0.0]]), "calibration.fits.x.cov", "shape"),
    ("cal.json", lambda d: d.pop("checksum"), "checksum", "missing"),
    ("cal.json", lambda d: d["calibration"].pop("fits"), "calibration.fits", "missing"),
    ("cal.json", lambda d: _fit(d, "y").pop("residuals"), "calibration.fits.y.residuals",
     "missing"),
    ("cal.json", lambda d: d.update(format_version=1), "format_version", "re-run"),
    ("cal.json", lambda d: d.update(source={"name": "e.mat"}), "source", "sha256"),
]


@pytest.mark.parametrize("name, edit, field, words", LOADER_CASES,
                         ids=[f"{c[2]}-{i}" for i, c in enumerate(LOADER_CASES)])
def test_loader_refuses_impossible_numbers(small, tmp_path, name, edit, field, words):
    path = _edit_json(small / name, tmp_path / "bad.json", edit)
    with pytest.raises(DataError) as exc:
        load_calibration(path)
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith(path), msg
    assert f"'{field}'" in msg and words in msg, msg


def test_a_negative_variance_never_reaches_a_region(small, tmp_path, capsys):
    """The fuzzer's |ρ| > 1 file (exit 0 with a negative variance inside the arrival region
    before): every command refuses it in one line."""
    path = _edit_json(small / "cal.json", tmp_path / "rho.json", lambda d: _rho(d, 3.0))
    for argv in _consumers(small, path).values():
        assert "|ρ| > 1" in _error(capsys, *argv)


@pytest.mark.parametrize("name, data", [
    ("empty.json", b""), ("blank.json", b"  \n"), ("half.json", b'{"format": "tiltb'),
    ("list.json", b"[1, 2]"), ("latin1.json", b"\xff\xfe{}"), ("empty.mat", b""),
    ("garbage.mat", b"MATLAB 5.0 MAT-file" + bytes(range(256)) * 4),
    ("zeros.mat", bytes(512)), ("text.mat", b"{}"),
])
def test_empty_or_garbage_files_are_one_line(small, tmp_path, capsys, name, data):
    path = tmp_path / name
    path.write_bytes(data)
    for argv in _consumers(small, path).values():
        assert str(path) in _error(capsys, *argv)


def test_truncated_and_empty_mat_exports_are_one_line(small, tmp_path, capsys):
    raw = (small / "cal.mat").read_bytes()
    cases = {"cut.mat": raw[: len(raw) // 2], "head.mat": raw[:128], "tail.mat": raw[:-64]}
    for name, data in cases.items():
        (tmp_path / name).write_bytes(data)
    scipy.io.savemat(str(tmp_path / "novars.mat"), {})
    for name in [*cases, "novars.mat"]:
        msg = _error(capsys, "validate", "--truth", small / "set" / "truth.json",
                     "--calibration", tmp_path / name)
        assert name in msg


def test_version_1_files_are_refused_with_the_way_out(small, tmp_path, capsys):
    path = _edit_json(small / "cal.json", tmp_path / "v1.json",
                      lambda d: (d.update(format_version=1), d.pop("checksum")))
    msg = _error(capsys, *_consumers(small, path)["trajectory"])
    assert "'format_version'" in msg and f"version {FORMAT_VERSION} only" in msg
    assert "re-run `tiltbench calibrate … --save`" in msg


def test_save_refuses_a_calibration_the_loader_would_refuse(tmp_path):
    """A sensor reading 1/10⁴ of the acceleration (gain 10⁻⁴ < 10⁻³): nothing is written."""
    th = np.linspace(0, 2 * np.pi, 200)
    ref = np.column_stack([-9.8 * np.sin(th), -9.8 * np.cos(th)])
    rng = np.random.default_rng(5)
    cal = calibrate(Ensayo(th, 1e-4 * ref + 0.01 * rng.standard_normal(ref.shape)),
                    noise_var=[1e-4, 1e-4])
    with pytest.raises(DataError, match=r"not written.*gain"):
        save_calibration(tmp_path / "c.json", cal, sigma2_source="given")
    assert not (tmp_path / "c.json").exists()


def test_cosmetic_tool_field_changes_nothing(small, tmp_path, capsys):
    base = ["validate", "--truth", small / "set" / "truth.json", "--json", "--calibration"]
    a = _run(capsys, *base, small / "cal.json")
    for edit in (lambda d: d["tool"].update(version="0.0.0-hand"), lambda d: d.pop("tool")):
        path = _edit_json(small / "cal.json", tmp_path / "cal.json", edit)
        b = _run(capsys, *base, path)
        assert a[0] == b[0] == 0 and a[1].replace(str(small), str(tmp_path)) == b[1]
        assert load_calibration(path) == load_calibration(small / "cal.json")


def test_lack_of_fit_tests_are_covered_by_the_checksum(tmp_path):
    """Repeated poses: the lack-of-fit tests (defining: they cannot be re-derived without the
    readings) round-trip, and an edited p-value or an unknown axis is refused."""
    th = np.repeat(np.linspace(0, 2 * np.pi, 12, endpoint=False), 10)
    ref = np.column_stack([-9.8 * np.sin(th), -9.8 * np.cos(th)])
    datos = ref + 0.3 * np.random.default_rng(9).standard_normal(ref.shape)
    cal = calibrate(Ensayo(th, datos), groups=np.repeat(np.arange(12), 10))
    assert cal.lack_of_fit is not None
    path = save_calibration(tmp_path / "lof.json", cal)
    assert load_calibration(path) == cal
    edits = {
        "p": lambda d: d["calibration"]["lack_of_fit"]["x"].update(p_value=0.5),
        "axis": lambda d: d["calibration"]["lack_of_fit"].update(
            z=d["calibration"]["lack_of_fit"]["x"]),
    }
    for label, edit in edits.items():
        bad = _edit_json(path, tmp_path / "bad.json", edit)
        with pytest.raises(DataError, match="lack_of_fit|checksum") as exc:
            load_calibration(bad)
        assert bad in str(exc.value), label
