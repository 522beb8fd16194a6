"""Seeded mutation fuzz of saved calibration files (issue 23 part 1; no Hypothesis).

A ``cal.json`` and its ``cal.mat`` export are mutated many ways with a seeded generator:
signs flipped, covariance entries scaled, |ρ| set above 1, ``n`` ∈ {0, 1, 2, 10¹², …}, NaN and
Infinity, strings and wrong types, keys removed, bytes flipped, the file truncated — and
cosmetic changes (the ``tool`` field, ``tool_version``, indentation, key order). Every mutated
file goes through ``validate``; every accepted one and a seeded sample of the refused ones
also through ``trajectory``, ``nmin`` and ``fuse``. The rule: exit 0 (validate: 0 or 1) with
output identical to the unmutated file's, or exit 2 with exactly one line on stderr and nothing
on stdout — never a traceback, never a different answer. Every cosmetic mutation must be
accepted (the loader is not stricter than the format).
"""

from __future__ import annotations

import copy
import io
import json
import math

import numpy as np
import pytest
import scipy.io

from bench.cli import main
from tests.cli import unwrap

SEED = 23
JSON_KINDS = ("sign", "scale_cov", "rho", "n", "nonfinite", "string", "type", "missing",
              "truncate", "byte", "cosmetic")
MAT_KINDS = ("scale", "string", "remove", "nonfinite", "document", "truncate", "byte", "empty",
             "cosmetic")
N_JSON = 10 * len(JSON_KINDS)
N_MAT = 6 * len(MAT_KINDS)
OTHERS_EVERY = 12  # every k-th refused mutation also goes through trajectory, nmin and fuse


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("calfuzz")
    for argv in (["generate", "calibration", "--count", "200", "--seed", "5", "--out",
                  d / "set"],
                 ["generate", "course", "--seed", "5", "--duration", "6", "--rate", "20",
                  "--count", "200", "--gps", "--out", d / "run"],
                 ["calibrate", d / "set" / "ensayo.mat", "--save", d / "base" / "cal.json"],
                 ["calibrate", d / "set" / "ensayo.mat", "--save", d / "base" / "cal.mat"]):
        assert main([str(a) for a in argv]) == 0
    return d


def _argv(d, cal) -> dict[str, list[str]]:
    veh = ["--acel", d / "run" / "acel.mat", "--puntos", d / "run" / "puntos.mat",
           "--datos", d / "run" / "datos.txt"]
    out = {
        "validate": ["validate", "--truth", d / "set" / "truth.json", "--json",
                     "--calibration", cal],
        "trajectory": ["trajectory", "--calibration", cal, *veh, "--json"],
        "nmin": ["nmin", "--calibration", cal, *veh, "--json", "--workers", "1",
                 "--confirm-runs", "0", "--draws", "0", "--quiet"],
        "fuse": ["fuse", "--calibration", cal, *veh, "--gps", d / "run" / "gps.mat", "--json"],
    }
    return {k: [str(a) for a in v] for k, v in out.items()}


def _outcome(capsys, argv) -> tuple[int | str, str, str]:
    try:
        rc = main(argv)
    except SystemExit as exc:  # argparse
        rc = exc.code
    except Exception as exc:  # noqa: BLE001 - a traceback is what this test looks for
        capsys.readouterr()
        return "traceback", "", f"{type(exc).__name__}: {exc}"
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


# ------------------------------------------------------------------ mutations
def _leaves(node, path=()):
    """(path, value) of the scalar leaves; long lists (residuals) give 3 entries only."""
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _leaves(v, (*path, k))
    elif isinstance(node, list):
        idx = range(len(node)) if len(node) <= 8 else (0, len(node) // 2, len(node) - 1)
        for i in idx:
            yield from _leaves(node[i], (*path, i))
    else:
        yield path, node


def _dicts(node, path=()):
    if isinstance(node, dict):
        if node:
            yield path
        for k, v in node.items():
            yield from _dicts(v, (*path, k))
    elif isinstance(node, list) and len(node) <= 8:
        for i, v in enumerate(node):
            yield from _dicts(v, (*path, i))


def _set(doc, path, value):
    node = doc
    for k in path[:-1]:
        node = node[k]
    node[path[-1]] = value


def _covs(doc):
    out = [("cov",)]
    for a in "xy":
        out += [("calibration", "axes", a, "cov"), ("calibration", "fits", a, "cov")]
    return out


def _pick(rng, items):
    return items[int(rng.integers(len(items)))]


COSMETIC = "cosmetic"


def _json_mutation(rng, doc, kind: str) -> tuple[str, object]:
    """(kind, new document or raw bytes): a random mutation of ``doc`` of this kind."""
    doc = copy.deepcopy(doc)
    numbers = [(p, v) for p, v in _leaves(doc) if isinstance(v, (int, float))
               and not isinstance(v, bool)]
    if kind == "sign":
        p, v = _pick(rng, numbers)
        _set(doc, p, -v if v != 0 else -1e-3)
    elif kind == "scale_cov":
        c = _pick(rng, _covs(doc))
        i, j = (int(k) for k in rng.integers(2, size=2))
        f = _pick(rng, [-1.0, 0.0, 1e-6, 1.001, 10.0, 1e6, 1e300])
        node = doc
        for k in c:
            node = node[k]
        node[i][j] *= f
        if rng.random() < 0.5:
            node[j][i] = node[i][j]
    elif kind == "rho":
        node = doc
        for k in _pick(rng, _covs(doc)):
            node = node[k]
        r = _pick(rng, [1.0, 1.0001, 1.5, -2.0, 1e3])
        node[0][1] = node[1][0] = r * math.sqrt(abs(node[0][0] * node[1][1]))
    elif kind == "n":
        p = _pick(rng, [("n",), ("calibration", "axes", "x", "n"),
                        ("calibration", "axes", "y", "n")])
        _set(doc, p, _pick(rng, [0, 1, 2, 10**12, -5, 199, 201, 200.5]))
    elif kind == "nonfinite":
        p, _ = _pick(rng, numbers)
        _set(doc, p, _pick(rng, [float("nan"), float("inf"), -float("inf")]))
    elif kind == "string":
        p, _ = _pick(rng, list(_leaves(doc)))
        _set(doc, p, _pick(rng, ["abc", "", "1.0", "NaN"]))
    elif kind == "type":
        p, _ = _pick(rng, list(_leaves(doc)))
        _set(doc, p, _pick(rng, [None, True, [], {}, [1, 2]]))
    elif kind == "missing":
        p = _pick(rng, list(_dicts(doc)))
        node = doc
        for k in p:
            node = node[k]
        del node[_pick(rng, list(node))]
    elif kind in ("truncate", "byte"):
        raw = bytearray((json.dumps(doc, indent=2) + "\n").encode())
        at = int(rng.integers(len(raw)))
        if kind == "truncate":
            return kind, bytes(raw[:at])
        raw[at] = int(rng.integers(256))
        return kind, bytes(raw)
    else:
        how = int(rng.integers(4))
        if how == 0:
            doc["tool"]["version"] = f"{rng.integers(100)}.{rng.integers(100)}-hand"
        elif how == 1:
            del doc["tool"]
        elif how == 2:
            return kind, json.dumps(doc, sort_keys=True).encode()
        else:
            return kind, json.dumps(dict(reversed(list(doc.items()))), indent=4).encode()
    return kind, doc


def _mat_bytes(variables: dict) -> bytes:
    buf = io.BytesIO()
    scipy.io.savemat(buf, variables, format="5", oned_as="row")
    return buf.getvalue()


def _mat_mutation(rng, mat: dict, doc: dict, raw: bytes, kind: str) -> tuple[str, bytes]:
    m = dict(mat)
    numeric = [k for k, v in m.items() if np.asarray(v).dtype.kind == "f"]
    if kind == "scale":
        k = _pick(rng, numeric)
        m[k] = m[k] * _pick(rng, [-1.0, 0.0, 2.0, 1e300, 1.0 + 1e-12])
    elif kind == "string":
        m[_pick(rng, sorted(m))] = _pick(rng, ["abc", "", "tiltbench-calibration"])
    elif kind == "remove":
        del m[_pick(rng, sorted(m))]
    elif kind == "nonfinite":
        k = _pick(rng, numeric)
        m[k] = np.full_like(m[k], _pick(rng, [np.nan, np.inf]))
    elif kind == "document":
        sub, new = _json_mutation(rng, doc, _pick(rng, JSON_KINDS))
        text = new.decode("latin-1") if isinstance(new, bytes) else json.dumps(new)
        m["document"] = text
        kind = f"document/{sub}" if sub != COSMETIC else COSMETIC
    elif kind == "truncate":
        return kind, raw[: int(rng.integers(len(raw)))]
    elif kind == "byte":
        b = bytearray(raw)
        b[int(rng.integers(len(b)))] = int(rng.integers(256))
        return kind, bytes(b)
    elif kind == "empty":
        return kind, b""
    else:
        m["tool_version"] = f"{rng.integers(100)}.0-hand"
    return kind, _mat_bytes(m)


# ------------------------------------------------------------------ the test
def _check(capsys, files, path, kind, label, base, others, problems, accepted):
    """Run validate (and maybe the other commands) on ``path``; record what breaks the rule."""
    commands = ["validate"]
    runs = {}
    for name in ("validate", "trajectory", "nmin", "fuse"):
        if name not in commands:
            continue
        rc, out, err = _outcome(capsys, _argv(files, path)[name])
        runs[name] = (rc, out, err)
        want_rc, want_out = base[name]
        if rc == 2:
            lines = unwrap(err).splitlines()
            if out or len(lines) != 1 or "error:" not in lines[0] or "Traceback" in err:
                problems.append(f"{label} {kind} {name}: not one line: {err[:300]!r}")
        elif rc == want_rc and out.replace(str(path), "<cal>") == want_out:
            if name == "validate":
                accepted.append(label)
                commands += ["trajectory", "nmin", "fuse"]  # accepted: every command
        else:
            problems.append(f"{label} {kind} {name}: rc {rc}, a different answer or a "
                            f"traceback: {err[:300]!r}")
        if name == "validate" and rc == 2 and others:
            commands += ["trajectory", "nmin", "fuse"]
    msgs = {n: unwrap(r[2]).split("error:", 1)[-1].strip() for n, r in runs.items() if r[0] == 2}
    if len(set(msgs.values())) > 1 or (msgs and len(msgs) != len(runs)):
        problems.append(f"{label} {kind}: the commands disagree: {runs}")
    if kind == COSMETIC and label not in accepted:
        problems.append(f"{label}: a cosmetic change was refused: {runs['validate'][2]!r}")


@pytest.mark.slow
def test_mutated_calibration_files_exit_0_identical_or_2_one_line(files, capsys, tmp_path):
    """N_JSON mutations of cal.json and N_MAT of cal.mat (seed SEED): the kinds in turn (10
    of each JSON kind, 6 of each mat kind), what they touch drawn at random."""
    base = {}
    for ext in ("json", "mat"):
        cal = files / "base" / f"cal.{ext}"
        for name, argv in _argv(files, cal).items():
            rc, out, err = _outcome(capsys, argv)
            assert rc in ((0, 1) if name == "validate" else (0,)), (name, err)
            base[ext, name] = (rc, out.replace(str(cal), "<cal>"))
    rng = np.random.default_rng(SEED)
    problems: list[str] = []
    accepted: list[str] = []
    kinds: dict[str, int] = {}
    doc = json.loads((files / "base" / "cal.json").read_text())
    raw_mat = (files / "base" / "cal.mat").read_bytes()
    mat = {k: v for k, v in scipy.io.loadmat(str(files / "base" / "cal.mat")).items()
           if not k.startswith("__")}
    refused = 0
    for i in range(N_JSON + N_MAT):
        ext = "json" if i < N_JSON else "mat"
        if ext == "json":
            kind, new = _json_mutation(rng, doc, JSON_KINDS[i % len(JSON_KINDS)])
            data = new if isinstance(new, bytes) else json.dumps(new, indent=2).encode()
        else:
            kind, data = _mat_mutation(rng, mat, doc, raw_mat, MAT_KINDS[(i - N_JSON)
                                                                          % len(MAT_KINDS)])
        kinds[f"{ext}:{kind.split('/')[0]}"] = kinds.get(f"{ext}:{kind.split('/')[0]}", 0) + 1
        path = tmp_path / f"m{i:03d}" / f"cal.{ext}"
        path.parent.mkdir()
        path.write_bytes(data)
        before = len(accepted)
        _check(capsys, files, path, kind, f"#{i}", {n: base[ext, n] for n in
               ("validate", "trajectory", "nmin", "fuse")}, refused % OTHERS_EVERY == 0,
               problems, accepted)
        refused += len(accepted) == before
    assert not problems, "\n".join(problems[:20])
    assert refused >= (N_JSON + N_MAT) * 0.7, (refused, kinds)  # most mutations are real edits
