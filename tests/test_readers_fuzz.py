"""Readers under bad and unusual input (issue 11, parts 1 and 4).

Explicit cases for each rule of :mod:`calib.files.course`, :mod:`calib.files.datos_txt` and
:mod:`calib.files.degeneracy`, through the library and the command line, then property-based tests
(hypothesis, ``derandomize=True``) over structurally plausible random ``.mat`` and
``datos.txt`` files. Every outcome is either a correct result or a clean error: a
``ValueError`` naming the file (library), one ``tiltbench …: error:`` line and exit code 2
(command line) — never a traceback, never a non-finite number in ``--json`` output.
Small synthetic files; no MuJoCo runs.
"""

from __future__ import annotations

import json
import math
import os
import warnings

import numpy as np
import pytest
import scipy.io
import scipy.sparse
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from calib.calibration.tilt_plane import calibrate
from calib.files.course import DataError, DataNote, read_acel, read_datos, read_ensayo, read_puntos
from tests.checks import result_only
from tests.cli import one_line_error, unwrap
from tests.cli import run as _run

G = 9.8
NV = "0.25,0.64"
FUZZ_EXAMPLES = int(os.environ.get("TILTBENCH_FUZZ_EXAMPLES", "50"))
"""Cases per property test (50: the file runs in ≈ 10 s; raise it for a longer hunt)."""
FUZZ = settings(derandomize=True, max_examples=FUZZ_EXAMPLES, deadline=None, database=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow])


# ------------------------------------------------------------------ helpers
def _readings(theta, rng=None, gain=(0.97, 1.01), bias=(0.07, -0.02), sd=(0.5, 0.8)):
    theta = np.asarray(theta, dtype=float)
    ref = np.column_stack([-G * np.sin(theta), -G * np.cos(theta)])
    out = ref * np.asarray(gain) + np.asarray(bias)
    if rng is not None:
        out = out + rng.normal(0.0, sd, ref.shape)
    return out


def _theta(n=200):
    return np.linspace(0.0, 2 * np.pi, n)


def _save(path, **variables):
    scipy.io.savemat(path, variables)
    return path


def _read_fuzzed(read, path):
    """``read(path)`` with every warning recorded (none shown): ``(result, warnings)``, or
    ``(the ValueError, warnings)`` when the file is refused — a refusal names the file."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            return read(path), caught
        except ValueError as exc:
            assert str(path) in str(exc), str(exc)
            return exc, caught


def _error(capsys, *argv) -> str:
    """A command that must fail cleanly (warnings aside): :func:`tests.cli.one_line_error`."""
    return one_line_error(capsys, *argv, ignore=("warning:",))


def _no_constant(name):
    raise AssertionError(f"non-finite number {name} in the JSON output")


def _finite_json(text: str):
    """Parse one JSON object; NaN/Infinity anywhere fail the test."""
    return json.loads(text, parse_constant=_no_constant)


@pytest.fixture
def ensayo(tmp_path):
    rng = np.random.default_rng(11)
    th = _theta()
    return _save(tmp_path / "ensayo.mat", tita=th[:, None], datos=_readings(th, rng))


@pytest.fixture
def vehicle(tmp_path):
    t = np.arange(300) * 0.01
    acel = _save(tmp_path / "acel.mat", t=t[:, None], Aerr=np.tile([0.07, -0.02], (t.size, 1)))
    puntos = _save(tmp_path / "puntos.mat", A=np.array([[3.0, 9.0]]),
                   B=np.array([[50.0, 50.0]]), C=np.array([[-50.0, 50.0]]),
                   D=np.array([[3.0, -60.0]]))
    return acel, puntos


COURSE_DATOS = ("Posición inicial = [0 0]\nVelocidad inicial = [1 3]\n"
                "varianza del ruido de los acelerómetros = [0.25 0.64]")


# ------------------------------------------------------------------ .mat: types
NOT_NUMBERS = {
    "logical": (lambda a: a > 0, "logical"),
    "char": (lambda a: "abc", "text"),
    "cell": (lambda a: np.array([[1.0, "a"]], dtype=object), "cell"),
    "struct": (lambda a: {"f": a}, "struct"),
    "complex": (lambda a: a + 1j, "complex"),
}


@pytest.mark.parametrize("kind", NOT_NUMBERS)
@pytest.mark.parametrize("variable", ["tita", "datos"])
def test_ensayo_variable_that_is_not_numbers(kind, variable, tmp_path, capsys):
    th = _theta()
    variables = {"tita": th[:, None], "datos": _readings(th)}
    make, word = NOT_NUMBERS[kind]
    variables[variable] = make(variables[variable])
    path = _save(tmp_path / "e.mat", **variables)
    with pytest.raises(DataError) as info:
        read_ensayo(path)
    msg = str(info.value)
    assert str(path) in msg and f"'{variable}'" in msg and word in msg
    cli = _error(capsys, "calibrate", path, "--noise-var", NV)
    assert str(path) in cli and f"'{variable}'" in cli and word in cli


@pytest.mark.parametrize("kind", NOT_NUMBERS)
def test_acel_and_puntos_variables_that_are_not_numbers(kind, tmp_path):
    make, word = NOT_NUMBERS[kind]
    t = np.arange(10) * 0.1
    acel = _save(tmp_path / "a.mat", t=t[:, None], Aerr=make(np.ones((10, 2))))
    with pytest.raises(DataError, match=word) as info:
        read_acel(acel)
    assert str(acel) in str(info.value) and "'Aerr'" in str(info.value)
    pts = {k: np.array([[i, 2.0 * i]]) for i, k in enumerate("ABCD")}
    pts["C"] = make(pts["C"])
    puntos = _save(tmp_path / "p.mat", **pts)
    with pytest.raises(DataError, match=word) as info:
        read_puntos(puntos)
    assert str(puntos) in str(info.value) and "'C'" in str(info.value)


def test_logical_tita_is_refused_before_any_fit(tmp_path, capsys):
    """A logical θ used to reach the bench as 0/1 rad ("scale must be > -1 … got -16605")."""
    th = _theta()
    path = _save(tmp_path / "e.mat", tita=(th > 3.0)[:, None], datos=_readings(th))
    for cmd in (["calibrate", path, "--noise-var", NV], ["gap", path, "--noise-var", NV]):
        msg = _error(capsys, *cmd)
        assert "logical" in msg and "'tita'" in msg and "scale must be" not in msg


def test_single_precision_is_accepted(tmp_path, capsys):
    """float32 θ over 0 … 2π (its 2π is above float64's) and float32 readings load and give
    the fit of the same numbers in float64."""
    rng = np.random.default_rng(5)
    th32 = np.linspace(0.0, 2 * np.pi, 400, dtype=np.float32)
    assert float(th32[-1]) > 2 * np.pi
    datos32 = _readings(th32.astype(float), rng).astype(np.float32)
    p32 = _save(tmp_path / "single.mat", tita=th32[:, None], datos=datos32)
    p64 = _save(tmp_path / "double.mat", tita=th32.astype(float)[:, None],
                datos=datos32.astype(float))
    e32, e64 = read_ensayo(p32), read_ensayo(p64)
    np.testing.assert_array_equal(e32.tita, th32.astype(float))  # exact conversion
    np.testing.assert_array_equal(e32.datos, e64.datos)
    rc32, out32, _ = _run(capsys, "calibrate", p32, "--noise-var", NV, "--json")
    rc64, out64, _ = _run(capsys, "calibrate", p64, "--noise-var", NV, "--json")
    assert rc32 == rc64 == 0
    assert result_only(_finite_json(out32)) == result_only(_finite_json(out64))


def test_integer_and_sparse_numbers_are_numbers(tmp_path):
    rng = np.random.default_rng(6)
    th = _theta()
    datos = np.round(_readings(th, rng) * 100).astype(np.int16)  # counts of 0.01 m/s²
    path = _save(tmp_path / "e.mat", tita=th[:, None], datos=datos)
    np.testing.assert_array_equal(read_ensayo(path).datos, datos.astype(float))
    pts = {k: scipy.sparse.csc_matrix(np.array([[i + 1.0, 2.0]])) for i, k in enumerate("ABCD")}
    out = read_puntos(_save(tmp_path / "p.mat", **pts))
    assert out["C"].tolist() == [3.0, 2.0]


# ------------------------------------------------------------------ .mat: variables
def test_puntos_truncated_after_a_and_b_is_refused(tmp_path, capsys, ensayo, vehicle):
    acel, _ = vehicle
    path = _save(tmp_path / "cut.mat", A=np.array([[1.0, 2.0]]), B=np.array([[3.0, 4.0]]))
    with pytest.raises(DataError) as info:
        read_puntos(path)
    msg = str(info.value)
    assert str(path) in msg and "C, D missing" in msg
    cli = _error(capsys, "trajectory", "--ensayo", ensayo, "--acel", acel, "--puntos", path,
                 "--datos", _datos(tmp_path, COURSE_DATOS))
    assert str(path) in cli and "C, D" in cli


def test_leftover_ans_is_ignored_and_named(tmp_path, capsys, ensayo, vehicle):
    acel, puntos = vehicle
    pts = scipy.io.loadmat(puntos)
    extra = _save(tmp_path / "puntos_ans.mat", ans=np.array([[1.0, 1.0]]),
                  **{k: pts[k] for k in "ABCD"})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        got = read_puntos(extra)
    assert list(got) == ["A", "B", "C", "D"]
    notes = [str(w.message) for w in caught if issubclass(w.category, DataNote)]
    assert len(notes) == 1 and "'ans'" in notes[0] and str(extra) in notes[0]
    datos = _datos(tmp_path, COURSE_DATOS)
    base = ["trajectory", "--ensayo", ensayo, "--acel", acel, "--datos", datos, "--json"]
    rc0, out0, _ = _run(capsys, *base, "--puntos", puntos)
    rc1, out1, err1 = _run(capsys, *base, "--puntos", extra)
    assert rc0 == rc1 == 0
    assert "'ans'" in err1 and "warning:" in err1
    tree = _finite_json(out1)
    assert sorted(tree["candidates"]) == ["A", "B", "C", "D"]
    assert tree == _finite_json(out0)


def test_extra_variables_in_ensayo_and_acel_are_noted(tmp_path, capsys):
    th = _theta()
    path = _save(tmp_path / "e.mat", tita=th[:, None], datos=_readings(th), ans=7.0)
    with pytest.warns(DataNote, match="'ans'"):
        e = read_ensayo(path)
    assert e.t is None  # t is the one optional variable; ans is not used
    t = np.arange(10) * 0.1
    acel = _save(tmp_path / "a.mat", t=t[:, None], Aerr=np.ones((10, 2)), x=1.0)
    with pytest.warns(DataNote, match="'x'"):
        read_acel(acel)
    rc, out, err = _run(capsys, "calibrate", path, "--noise-var", NV, "--json")
    assert rc == 0 and "'ans'" in err
    _finite_json(out)


@pytest.mark.parametrize("reader, variables, missing", [
    (read_ensayo, {"tita": np.zeros((5, 1))}, "'datos'"),
    (read_ensayo, {"datos": np.zeros((5, 2))}, "'tita'"),
    (read_acel, {"t": np.zeros((5, 1))}, "'Aerr'"),
    (read_puntos, {"A": np.ones((1, 2)), "C": np.ones((1, 2)), "ans": np.ones((1, 2))}, "B, D"),
])
def test_missing_variables_are_named(reader, variables, missing, tmp_path):
    path = _save(tmp_path / "f.mat", **variables)
    with pytest.raises(DataError, match=missing) as info:
        reader(path)
    assert str(path) in str(info.value)


def test_empty_vehicle_run_names_the_file(tmp_path):
    acel = _save(tmp_path / "a.mat", t=np.zeros((0, 1)), Aerr=np.zeros((0, 2)))
    with pytest.raises(DataError, match="at least 3") as info:
        read_acel(acel)
    assert str(acel) in str(info.value)


@pytest.mark.parametrize("where", ["tita", "datos", "puntos", "t"])
def test_absurd_magnitudes_are_refused(where, tmp_path):
    th = _theta()
    variables = {"tita": th[:, None], "datos": _readings(th)}
    if where == "tita":
        variables["tita"] = th[:, None] + 1e200
    elif where == "datos":
        variables["datos"] = variables["datos"] * 1e200
    elif where == "t":
        variables["t"] = (np.arange(th.size) * 1e200)[:, None]
    if where == "puntos":
        path = _save(tmp_path / "p.mat", A=np.array([[1e200, 0.0]]), B=np.ones((1, 2)),
                     C=np.ones((1, 2)), D=np.ones((1, 2)))
        reader = read_puntos
    else:
        path = _save(tmp_path / "e.mat", **variables)
        reader = read_ensayo
    with pytest.raises(DataError) as info:
        reader(path)
    assert str(path) in str(info.value)


# ------------------------------------------------------------------ degenerate data
def _degenerate(kind: str) -> dict:
    rng = np.random.default_rng(21)
    th = _theta()
    good = _readings(th, rng)
    if kind == "pure noise":
        return {"tita": th[:, None], "datos": rng.normal(0.0, 1.0, good.shape)}
    if kind == "dead y":
        good[:, 1] = 0.0
        return {"tita": th[:, None], "datos": good}
    if kind == "one theta":
        return {"tita": np.full((200, 1), 0.3), "datos": good}
    if kind == "swapped":
        return {"tita": th[:, None], "datos": good[:, ::-1]}
    if kind == "sign flipped x":
        good[:, 0] *= -1.0
        return {"tita": th[:, None], "datos": good}
    raise KeyError(kind)


DEGENERATE = {
    "pure noise": ["do not follow −g sin θ at all", "R² =", "right column/file"],
    "dead y": ["y sensor reads a constant 0 m/s²", "dead sensor?"],
    "one theta": ["only 1 distinct θ", "at least 2"],
    "swapped": ["do not follow", "swapped"],
    "sign flipped x": ["do not follow −g sin θ", "sign flipped"],
}


@pytest.mark.parametrize("kind", DEGENERATE)
def test_degenerate_data_are_told_in_the_users_terms(kind, tmp_path, capsys):
    path = _save(tmp_path / "e.mat", **_degenerate(kind))
    with pytest.raises(DataError) as info:
        read_ensayo(path)
    for words in DEGENERATE[kind]:
        assert words in str(info.value), str(info.value)
    for cmd in ("calibrate", "gap"):
        msg = _error(capsys, cmd, path, "--noise-var", NV)
        assert str(path) in msg and ("'datos'" in msg or "'tita'" in msg)
        for bad in ("scale must be", "SVD", "different signs", "converge"):
            assert bad not in msg


def test_mirror_poses_name_the_unidentifiable_scale(tmp_path, capsys):
    """θ and π - θ: two distinct θ, but the same A_rx — the fit says which scale."""
    th = np.repeat([0.5, np.pi - 0.5], 3)
    datos = _readings(th) + np.arange(6)[:, None] * 1e-3
    path = _save(tmp_path / "mirror.mat", tita=th[:, None], datos=datos)
    msg = _error(capsys, "calibrate", path, "--noise-var", NV)
    assert str(path) in msg and "scale_x" in msg


def test_weak_but_real_signals_are_accepted(tmp_path, capsys):
    """Not refused: a tiny θ range (the gain is undetermined, not contradicted), a local g of
    1.62 m/s² (gain 0.17 at g = 9.8), a sensor 40 % off, noiseless data, two poses."""
    rng = np.random.default_rng(8)
    tiny = np.linspace(0.3, 0.31, 400)
    moon = _theta()
    cases = {
        "tiny": (tiny, _readings(tiny, rng)),
        "moon": (moon, _readings(moon, rng, gain=(1.62 / G, 1.62 / G), sd=(0.05, 0.05))),
        "off40": (moon, _readings(moon, rng, gain=(0.6, 1.4))),
        "noiseless": (moon, _readings(moon)),
        "two poses": (np.repeat([0.0, 2.0], 30), _readings(np.repeat([0.0, 2.0], 30), rng)),
    }
    for label, (th, datos) in cases.items():
        path = _save(tmp_path / f"{label.replace(' ', '_')}.mat", tita=th[:, None], datos=datos)
        assert read_ensayo(path).n == th.size, label
    rc, out, err = _run(capsys, "calibrate", tmp_path / "moon.mat", "--noise-var", "0.0025,0.0025",
                        "--g", "1.62", "--json")
    assert rc == 0, err
    assert abs(_finite_json(out)["axes"]["x"]["scale"]) < 0.05


# ------------------------------------------------------------------ datos.txt
def _datos(tmp_path, text: str | bytes, name="datos.txt"):
    path = tmp_path / name
    path.write_bytes(text if isinstance(text, bytes) else text.encode("utf-8"))
    return path


MINUS = {"hyphen-minus": "-", "minus U+2212": "\u2212", "en dash": "\u2013",
         "em dash": "\u2014", "figure dash": "\u2012"}


@pytest.mark.parametrize("minus", MINUS)
def test_datos_unicode_minus_and_dashes(minus, tmp_path, capsys, ensayo, vehicle):
    m = MINUS[minus]
    text = COURSE_DATOS.replace("[1 3]", f"[{m}1 3]").replace("[0 0]", f"[{m}2.5 {m}0.5e{m}1]")
    d = read_datos(_datos(tmp_path, text))
    assert d.v0.tolist() == [-1.0, 3.0] and d.p0.tolist() == [-2.5, -0.05]
    acel, puntos = vehicle
    base = ["trajectory", "--ensayo", ensayo, "--acel", acel, "--puntos", puntos, "--json"]
    rc, out, err = _run(capsys, *base, "--datos", _datos(tmp_path, text, "d.txt"))
    assert rc == 0, err
    tree = _finite_json(out)
    assert tree["v0"] == [-1.0, 3.0]


ENCODINGS = ["utf-8", "utf-8-sig", "latin-1", "cp1252", "utf-16"]
NEWLINES = {"LF": "\n", "CRLF": "\r\n", "CR": "\r"}


@pytest.mark.parametrize("encoding", ENCODINGS)
@pytest.mark.parametrize("newline", NEWLINES)
def test_datos_encodings_and_line_ends(encoding, newline, tmp_path):
    text = COURSE_DATOS.replace("[1 3]", "[\u20131 3]").replace("\n", NEWLINES[newline])
    if encoding == "latin-1":  # no dash in Latin-1: a plain minus
        text = text.replace("\u2013", "-")
    d = read_datos(_datos(tmp_path, text.encode(encoding)))
    assert d.p0.tolist() == [0.0, 0.0] and d.v0.tolist() == [-1.0, 3.0]
    assert d.noise_var.tolist() == [0.25, 0.64]


@pytest.mark.parametrize("pair, expected", [
    ("[0.25 0.64]", [0.25, 0.64]), ("[0,25 0,64]", [0.25, 0.64]),
    ("[0.25, 0.64]", [0.25, 0.64]), ("[0.25,0.64]", [0.25, 0.64]),
    ("[0,25; 0,64]", [0.25, 0.64]), ("[0,25, 0,64]", [0.25, 0.64]),
    ("[0.25; 0.64]", [0.25, 0.64]), ("[ 2.5e-1\t6.4E-1 ]", [0.25, 0.64]),
    ("[0,25\u00a00,64]", [0.25, 0.64]), ("[1,3]", [1.0, 3.0]), ("[1 , 3]", [1.0, 3.0]),
    ("[+.25 .64]", [0.25, 0.64]),
])
def test_datos_decimal_styles(pair, expected, tmp_path):
    text = COURSE_DATOS.replace("[0.25 0.64]", pair)
    assert read_datos(_datos(tmp_path, text)).noise_var.tolist() == expected


@pytest.mark.parametrize("text, line, words", [
    (COURSE_DATOS.replace("[1 3]", "[1 abc]"), 2, "'abc' is not a number"),
    (COURSE_DATOS + "\nPosición inicial = [5 5]", 4, "given twice (first on line 1)"),
    (COURSE_DATOS.replace("[1 3]", "[1 3 4]"), 2, "two numbers"),
    (COURSE_DATOS.replace("[1 3]", "[1]"), 2, "two numbers"),
    (COURSE_DATOS.replace("[1 3]", "1 3"), 2, "[ ]"),
    (COURSE_DATOS.replace("[0.25 0.64]", "[1,5,2,5]"), 3, "ambiguous"),
    (COURSE_DATOS.replace("[0.25 0.64]", "[0,25 0.64]"), 3, "mixes"),
    (COURSE_DATOS.replace("[0.25 0.64]", "[NaN 0.64]"), 3, "not a number"),
    (COURSE_DATOS.replace("[0.25 0.64]", "[1e999 0.64]"), 3, "finite"),
    (COURSE_DATOS.replace("[0.25 0.64]", "[0 0.64]"), 3, "positive"),
    (COURSE_DATOS.replace("[0.25 0.64]", "[\u22120.25 0.64]"), 3, "positive"),
    (COURSE_DATOS.replace("[0.25 0.64]", "[1e-320 0.64]"), 3, "positive"),
    (COURSE_DATOS.replace("[0 0]", "[1e200 0]"), 1, "check the units"),
])
def test_datos_bad_lines_name_file_line_and_field(text, line, words, tmp_path, capsys,
                                                  ensayo):
    path = _datos(tmp_path, text)
    with pytest.raises(DataError) as info:
        read_datos(path)
    msg = str(info.value)
    assert str(path) in msg and f"line {line} " in msg and words in msg, msg
    cli = _error(capsys, "calibrate", ensayo, "--datos", path)
    assert str(path) in cli and f"line {line} " in cli


def test_datos_missing_field_and_binary_file(tmp_path):
    path = _datos(tmp_path, COURSE_DATOS.replace("Velocidad inicial = [1 3]\n", ""))
    with pytest.raises(DataError, match="Velocidad inicial") as info:
        read_datos(path)
    assert str(path) in str(info.value)
    binary = _datos(tmp_path, b"MATLAB 5.0 MAT-file\x00\x00\x01", "bin.txt")
    with pytest.raises(DataError, match="binary"):
        read_datos(binary)


def test_datos_unknown_bracketed_line_is_noted(tmp_path):
    path = _datos(tmp_path, "% course data\n" + COURSE_DATOS + "\nans = [1 2]\n")
    with pytest.warns(DataNote, match="line 5"):
        d = read_datos(path)
    assert d.v0.tolist() == [1.0, 3.0]


def test_course_datos_reads_as_before():
    d = read_datos("/work/shared/course-data/datos.txt") if _course() else None
    if d is not None:
        assert (d.p0.tolist(), d.v0.tolist(), d.noise_var.tolist()) == (
            [0.0, 0.0], [1.0, 3.0], [0.25, 0.64])


def _course() -> bool:
    from pathlib import Path

    return Path("/work/shared/course-data/datos.txt").exists()


# ------------------------------------------------------------------ property: datos.txt
LABELS = {"p0": ["Posición inicial", "posicion inicial", "POSICIÓN INICIAL", "Initial position"],
          "v0": ["Velocidad inicial", "velocidad  inicial", "Initial velocity"],
          "noise_var": ["varianza del ruido de los acelerómetros", "Varianza", "noise variance"]}


@st.composite
def _number(draw, positive=False):
    """(value, text as a person might write it, uses a decimal comma)."""
    mantissa = draw(st.integers(0 if not positive else 1, 99999))
    decimals = draw(st.integers(0, 4))
    value = mantissa / 10**decimals
    text = f"{value:.{decimals}f}"
    exponent = draw(st.sampled_from([None, -3, 2]))
    if exponent is not None:
        text += f"e{exponent}"
        value = float(text)
    negative = not positive and draw(st.booleans()) and value != 0.0
    if negative:
        text = draw(st.sampled_from(["-", *MINUS.values()])) + text
        value = -value
    return value, text


@st.composite
def _datos_file(draw):
    """A datos.txt in a random style; returns (bytes, expected values or None if broken)."""
    comma = draw(st.booleans())
    lines, expected = [], {}
    for key in draw(st.permutations(list(LABELS))):
        a = draw(_number(positive=key == "noise_var"))
        b = draw(_number(positive=key == "noise_var"))
        ta, tb = a[1], b[1]
        if comma:
            ta, tb = ta.replace(".", ","), tb.replace(".", ",")
        sep = draw(st.sampled_from([" ", "  ", "\t", "; "] + ([] if comma else [", ", ","])))
        if comma and "," not in ta + tb:
            sep = draw(st.sampled_from([" ", "; "]))
        label = draw(st.sampled_from(LABELS[key]))
        lines.append(f"{label} = [{ta}{sep}{tb}]")
        expected[key] = [a[0], b[0]]
    if draw(st.booleans()):
        lines.insert(draw(st.integers(0, len(lines))), "% comentario")
    broken = draw(st.sampled_from([None, None, "drop", "duplicate", "garbage", "count"]))
    i = draw(st.sampled_from([j for j, line in enumerate(lines) if "[" in line]))
    if broken == "drop":
        lines.pop(i)
    elif broken == "duplicate":
        lines.append(lines[i])
    elif broken == "garbage":
        lines[i] = lines[i].replace("[", "[x", 1)
    elif broken == "count":
        lines[i] = lines[i].replace("]", " 7]", 1)
    newline = draw(st.sampled_from(list(NEWLINES.values())))
    text = newline.join(lines) + draw(st.sampled_from(["", newline]))
    encoding = draw(st.sampled_from(ENCODINGS))
    try:
        data = text.encode(encoding)
    except UnicodeEncodeError:
        data = text.encode("utf-8")
    return data, (None if broken else expected)


@FUZZ
@given(case=_datos_file())
def test_property_datos_txt(case, tmp_path_factory):
    data, expected = case
    path = tmp_path_factory.mktemp("datos") / "datos.txt"
    path.write_bytes(data)
    d, _ = _read_fuzzed(read_datos, path)
    if isinstance(d, ValueError):  # a clean error naming the file
        event("datos.txt refused")
        assert expected is None or not all(v > 0 for v in expected["noise_var"]), str(d)
        return
    event("datos.txt read")
    assert expected is not None, data
    for key, values in expected.items():
        np.testing.assert_allclose(getattr(d, key), values, rtol=1e-15, atol=0)


# ------------------------------------------------------------------ property: .mat files
@st.composite
def _mat_ensayo(draw):
    """Structurally plausible ensayo.mat variables, good or bad in one random way each."""
    rng = np.random.default_rng(draw(st.integers(0, 2**31 - 1)))
    n = draw(st.sampled_from([0, 1, 2, 3, 5, 40, 300]))
    style = draw(st.sampled_from(["sweep", "held", "random", "turns", "negative"]))
    lo, span = draw(st.floats(-20, 20)), draw(st.sampled_from([1e-3, 0.5, 3.0, 6.3, 30.0]))
    th = {"sweep": np.linspace(lo, lo + span, n),
          "held": np.repeat(lo + span * np.arange(4) / 4, -(-n // 4))[:n],
          "random": lo + span * rng.uniform(size=n),
          "turns": np.linspace(0, 4 * np.pi, n), "negative": -np.linspace(0, span, n)}[style]
    sd = draw(st.sampled_from([0.0, 0.01, 0.5, 3.0]))
    datos = _readings(th, rng, sd=(sd, sd)) if n else np.zeros((0, 2))
    fault = draw(st.sampled_from([None, None, "nan", "inf", "huge", "noise", "dead", "swap",
                                  "bool", "text", "complex", "cell", "float32", "int",
                                  "transposed", "short", "degrees", "ans", "t", "t_bad"]))
    variables = {"tita": th[:, None], "datos": datos}
    if fault == "nan" and n:
        datos[rng.integers(n), rng.integers(2)] = np.nan
    elif fault == "inf" and n:
        th[rng.integers(n)] = np.inf
    elif fault == "huge":
        variables["datos"] = datos * 1e200
    elif fault == "noise":
        variables["datos"] = rng.normal(0, 1, datos.shape)
    elif fault == "dead":
        datos[:, rng.integers(2)] = 1.5
    elif fault == "swap":
        variables["datos"] = datos[:, ::-1]
    elif fault == "bool":
        variables["tita"] = (th > lo)[:, None]
    elif fault == "text":
        variables["datos"] = "datos"
    elif fault == "complex":
        variables["tita"] = th[:, None] * (1 + 1j)
    elif fault == "cell":
        variables["datos"] = np.array([[datos, "x"]], dtype=object)
    elif fault == "float32":
        variables = {"tita": th.astype(np.float32)[:, None], "datos": datos.astype(np.float32)}
    elif fault == "int":
        variables["datos"] = np.round(datos).astype(np.int32)
    elif fault == "transposed":
        variables = {"tita": th[None, :], "datos": datos.T}
    elif fault == "short":
        variables["datos"] = datos[: max(n - 1, 0)]
    elif fault == "degrees":
        variables["tita"] = np.rad2deg(th)[:, None]
    elif fault == "ans":
        variables["ans"] = np.float64(3.0)
    elif fault == "t":
        variables["t"] = (np.arange(n) * 0.01)[:, None]
    elif fault == "t_bad":
        variables["t"] = rng.permutation(np.arange(n) * 0.01)[:, None]
    return variables


@FUZZ
@given(variables=_mat_ensayo())
def test_property_ensayo_library(variables, tmp_path_factory):
    def read_and_calibrate(path):
        e = read_ensayo(path)
        return e, calibrate(e, [0.25, 0.64])

    path = _save(tmp_path_factory.mktemp("mat") / "ensayo.mat", **variables)
    got, _ = _read_fuzzed(read_and_calibrate, path)
    if isinstance(got, ValueError):
        event(f"refused: {type(got).__name__}")
        assert "\n" not in str(got)
        return
    e, cal = got
    event("calibrated")
    assert e.n >= 3 and np.isfinite(e.tita).all() and np.isfinite(e.datos).all()
    assert np.isfinite(cal.params).all() and np.isfinite(cal.cov).all()


@FUZZ
@given(variables=_mat_ensayo(), command=st.sampled_from(["calibrate", "calibrate-estimated",
                                                         "calibrate-wls"]))
def test_property_ensayo_cli(variables, command, tmp_path_factory, capsys):
    path = _save(tmp_path_factory.mktemp("cli") / "ensayo.mat", **variables)
    argv = ["calibrate", path, "--json"]
    if command != "calibrate-estimated":
        argv += ["--noise-var", NV]
    if command == "calibrate-wls":
        argv += ["--method", "wls"]
    rc, out, err = _run(capsys, *argv)
    assert "Traceback" not in err
    event(f"exit code {rc}")
    if rc == 2:
        # warnings aside (each wrapped at 100 columns like the error: unwrapped first)
        lines = [ln for ln in unwrap(err).splitlines() if not ln.startswith("warning:")]
        assert len(lines) == 1 and str(path) in lines[0] and out == "", err
        return
    assert rc == 0, err
    tree = _finite_json(out)
    assert all(math.isfinite(tree["axes"][a][k]) for a in "xy" for k in ("bias", "scale"))


@st.composite
def _mat_puntos(draw):
    names = [k for k in "ABCD" if draw(st.integers(0, 9)) > 0]  # each kept 9 times in 10
    names += draw(st.lists(st.sampled_from(["E", "ans", "x"]), unique=True, max_size=3))
    variables = {}
    for name in names:
        kind = draw(st.sampled_from(["ok"] * 30 + ["col", "three", "nan", "bool", "text",
                                                    "huge"]))
        p = np.array([[draw(st.floats(-1e3, 1e3)), draw(st.floats(-1e3, 1e3))]])
        variables[name] = {"ok": p, "col": p.T, "three": np.ones((1, 3)),
                           "nan": p * np.nan, "bool": p > 0, "text": "p",
                           "huge": p + 1e300}[kind]
    return variables


@FUZZ
@given(variables=_mat_puntos())
def test_property_puntos(variables, tmp_path_factory):
    path = _save(tmp_path_factory.mktemp("puntos") / "puntos.mat", **variables)
    got, caught = _read_fuzzed(read_puntos, path)
    if isinstance(got, ValueError):
        event("puntos.mat refused")
        missing = [k for k in "ABCD" if k not in variables]
        if missing:
            assert ", ".join(missing) in str(got)
        return
    event("puntos.mat read")
    assert list(got) == ["A", "B", "C", "D"]  # never a fifth candidate
    for k in "ABCD":
        np.testing.assert_array_equal(got[k], np.ravel(variables[k]))
    extra = sorted(set(variables) - set("ABCD"))
    notes = " ".join(str(w.message) for w in caught if issubclass(w.category, DataNote))
    assert all(f"'{k}'" in notes for k in extra)
