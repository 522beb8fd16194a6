"""The numbers users get from tiltbench, kept by value: generated files and ``--json`` outputs.

The guard of refactors: ``tests/test_snapshot.py`` reruns :func:`collect` in a fresh folder and
compares it with the reference (``tests/reference/snapshot.json`` for structure, words and small
numbers, ``tests/reference/snapshot.npz`` for the large arrays, compressed). When a change is
*meant* to change an output, rerun this script and commit the new reference with the change::

    python tools/snapshot.py            # rewrites tests/reference/snapshot.{json,npz}

What is kept:

* every file that ``generate calibration`` (static, positions and sweep), ``vehicle``,
  ``course`` and ``class`` write for two seeds, and everything ``demo`` writes to its data/ and
  JSON outputs: ``.mat`` variables, ``.json`` trees, ``.txt``/``.csv``/``.md`` text;
* the ``--json`` stdout of every command on the course files (``../shared/course-data``);
* ``.rrd`` recordings by content: per entity path and component column, the values (not the
  random recording id, the row ids or the start time);
* not kept: the demo report's wall-clock step times and file sizes, and the ``versions``
  block of ``truth.json`` / answer keys (CI may install other patch versions of a package).

How it is compared (why by value: the last bits of a float move with the BLAS kernels
OpenBLAS picks for the CPU and with numpy's SIMD dispatch, so a byte hash of full-precision
floats only passes on a CPU like the recording one):

* numbers: ``|got - ref| <= RTOL·|ref| + FLOOR·scale`` elementwise, where ``scale`` is the
  largest finite ``|ref|`` of the array the number belongs to (a JSON list, a ``.mat``
  variable, a recording column; for a lone number in a JSON object, the largest ``|ref|`` of
  the numbers beside it in that object). ``RTOL`` covers kernel rounding through the whole
  computation; the floor covers values that are rounding noise themselves (a covariance
  off-diagonal of −8.85e-19 beside diagonals of 1e-5 has no correct digit to keep). NaN must
  stay NaN, ±Inf the same, integers and booleans equal, shapes and words identical;
* text (``.txt``, ``.csv``, ``.md``): the words exactly; each printed number to the precision
  it was printed at — within one unit of its last printed digit (a value on a rounding
  boundary may print either way) or ``RTOL``; integers exactly.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import math
import os
import re
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
COURSE_DATA = REPO.parent / "shared" / "course-data"
REFERENCE = REPO / "tests" / "reference" / "snapshot.json"
ARRAYS = REFERENCE.with_suffix(".npz")
SEEDS = (0, 7)

RTOL = 1e-8
"""Relative tolerance on every number. Measured on an AMD EPYC (Zen 4) against the reference
recorded there (OpenBLAS picks SkylakeX kernels): under ``OPENBLAS_CORETYPE`` Haswell/Zen the
largest change is 7.4e-10 relative (a gap signature fitted on the lever-arm sweep), i.e. 0.07
of the tolerance; under Sandybridge 0.15 of it (the same fit); with numpy's SIMD dispatch
reduced to its baseline 1.4e-8 of it (``--check`` prints this margin). 1e-8 stays far below
the 4–6 digits any output is read at."""
FLOOR = 1e-12
"""Absolute floor relative to the array's scale: below 1e-12·max|array| a value is rounding
noise (double precision carries ~16 digits; a difference of two equal computations, such as
a covariance off-diagonal of −8.85e-19 beside variances of 1e-5, has none)."""
BIG = 64
"""Arrays with more elements than this go to the compressed .npz; smaller ones stay readable
in the JSON reference (one line each)."""

NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")


# ---- collecting -------------------------------------------------------------------------------

def rrd_content(path: Path) -> dict:
    """A recording's content as a tree: entity ``/a/b/c`` column ``C`` is ``tree[a][b]["c|C"]``
    (so a value logged from a JSON report sits where it sits in the JSON). Each column is the
    concatenation of its chunks in the order of their first row's timeline values (chunk
    order in the file is not content); a one-row column is its row and one-element rows are
    their element. Left out: row ids and the recording's start time. Durations and timestamps
    are int64 nanoseconds."""
    import pyarrow as pa
    from rerun.chunk import RrdReader

    chunks: dict[str, list[tuple[str, dict]]] = {}
    for chunk in RrdReader(str(path)).stream().to_chunks():
        batch = chunk.to_record_batch()
        cols = {}
        for name in sorted(batch.schema.names):
            if name == "rerun.controls.RowId" or name.endswith("start_time"):
                continue
            col = batch.column(name)
            if pa.types.is_duration(col.type) or pa.types.is_timestamp(col.type):
                col = col.cast(pa.int64())  # to_pylist would go through datetime (µs)
            cols[name] = col.to_pylist()
        order = repr(sorted((k, v[:1]) for k, v in cols.items()))
        chunks.setdefault(str(chunk.entity_path), []).append((order, cols))
    tree: dict = {}
    for entity, parts in sorted(chunks.items()):
        merged: dict[str, list] = {}
        for _, cols in sorted(parts, key=lambda p: p[0]):
            for name, values in cols.items():
                merged.setdefault(name, []).extend(values)
        *parents, last = [p for p in entity.split("/") if p] or [""]
        node = tree
        for p in parents:
            node = node.setdefault(p, {})
        for name, values in merged.items():
            if all(isinstance(v, list) and len(v) == 1 for v in values):
                values = [v[0] for v in values]
            node[f"{last}|{name}"] = values[0] if len(values) == 1 else values
    return tree


def mat_content(path: Path) -> dict:
    """A .mat file's variables as numpy arrays / nested dicts (structs)."""
    from scipy.io import loadmat

    return {k: v for k, v in loadmat(path, simplify_cells=True).items()
            if k not in ("__globals__",)}


def text_content(path: Path) -> str:
    text = path.read_text(encoding="utf-8")
    if path.suffix == ".md":  # the demo report's wall-clock times and file sizes (a
        # recording's size varies by a few bytes) are not content
        text = "\n".join(re.sub(r"\| \d+ (KiB|B) \|", "| size |", ln)
                         for ln in text.splitlines() if not ln.startswith("Step times:"))
    return text


def file_content(path: Path):
    if path.suffix == ".rrd":
        return rrd_content(path)
    if path.suffix == ".mat":
        return mat_content(path)
    if path.suffix == ".json":
        return _json(path.read_text(encoding="utf-8"))
    return text_content(path)


def _run(argv: list[str]) -> str:
    """Run the command line in-process; return its stdout (stderr is not part of the contract
    compared here: progress lines may change)."""
    from bench.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    if code not in (0, 1):
        raise RuntimeError(f"tiltbench {' '.join(argv)} exited {code}: {err.getvalue()}")
    return out.getvalue()


def _json(text: str):
    from bench.dataset import without_versions

    return without_versions(json.loads(text))


def collect(work: Path, course: Path = COURSE_DATA) -> dict:
    """Generate everything into ``work`` (relative paths, so JSON outputs are stable) and
    return ``{output name: content}`` (content: a JSON-like tree, numpy arrays or text)."""
    work.mkdir(parents=True, exist_ok=True)
    old = Path.cwd()
    os.chdir(work)
    try:
        return _collect(course)
    finally:
        os.chdir(old)


def _collect(course: Path) -> dict:
    out: dict = {}
    e, a, p, d = (str(course / f) for f in ("ensayo.mat", "acel.mat", "puntos.mat",
                                            "datos.txt"))
    for s in SEEDS:
        gens = {
            f"static-{s}": ["generate", "calibration", "--count", "2001", "--rrd",
                            f"static-{s}.rrd"],
            f"positions-{s}": ["generate", "calibration", "--positions", "12",
                               "--per-position", "20", "--effect", "misalignment:x:delta=0.02"],
            f"sweep-{s}": ["generate", "calibration", "--mode", "sweep", "--sweep-profile",
                           "updown", "--duration", "8", "--effect", "lever_arm:x:pos_x=0.2"],
            f"vehicle-{s}": ["generate", "vehicle", "--rrd", f"vehicle-{s}.rrd"],
            f"course-{s}": ["generate", "course", "--rrd", f"course-{s}.rrd"],
            f"class-{s}": ["generate", "class", "--students", "2"],
        }
        for name, argv in gens.items():
            out[f"stdout {name}"] = _json(_run(argv + ["--seed", str(s), "--out", name,
                                                       "--json"]))
    out["stdout calibrate"] = _json(_run(["calibrate", e, "--datos", d, "--json",
                                          "--rrd", "calibrate.rrd"]))
    out["stdout calibrate wls"] = _json(_run(["calibrate", e, "--datos", d, "--method",
                                              "wls", "--json"]))
    out["stdout calibrate estimated"] = _json(_run(["calibrate", e, "--json"]))
    traj = ["--ensayo", e, "--acel", a, "--puntos", p, "--datos", d, "--json"]
    out["stdout trajectory"] = _json(_run(["trajectory", *traj, "--rrd", "trajectory.rrd"]))
    out["stdout nmin"] = _json(_run(["nmin", *traj, "--runs", "20", "--mc-n", "2001"]))
    out["stdout gap"] = _json(_run(["gap", e, "--datos", d, "--json", "--rrd", "gap.rrd",
                                    "--report", "gap-report"]))
    out["stdout gap data/sweep-lever-arm"] = _json(_run(
        ["gap", str(REPO / "data" / "sweep-lever-arm" / "ensayo.mat"), "--noise-var",
         "0.25,0.64", "--json"]))
    Path("est.json").write_text(_run(["calibrate", "course-0/ensayo.mat", "--datos",
                                      "course-0/datos.txt", "--json"]))
    out["stdout validate"] = _json(_run(["validate", "--truth", "course-0/truth.json",
                                         "--estimates", "est.json", "--json"]))
    for rrd in ("calibrate.rrd", "trajectory.rrd", "gap.rrd", "course-0.rrd"):
        out[f"stdout record read {rrd}"] = _json(_run(["record", "read", rrd, "--json"]))
    _run(["demo", "--out", "demo", "--quiet", "--coverage-runs", "20", "--figures", "png"])
    for f in sorted(Path(".").rglob("*")):
        if f.is_file() and f.suffix in (".mat", ".txt", ".json", ".csv", ".rrd", ".md") \
                and f.name != "est.json":
            out[f"file {f.as_posix()}"] = file_content(f)
    return out


# ---- flattening into leaves -------------------------------------------------------------------

@dataclass(frozen=True)
class Leaf:
    """One compared value: a numeric array with the scale its floor is relative to, a text,
    a list of texts, or a JSON scalar that is not a number (None)."""

    value: object
    scale: float = 0.0


def _is_number(v) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)


def _float_max(obj) -> float:
    """Largest finite |x| over the floats in ``obj`` (any nesting); integers and booleans are
    counts, flags and timeline indices, not magnitudes, and do not count."""
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind != "f" or not obj.size:
            return 0.0 if obj.dtype.kind != "O" else _float_max(obj.tolist())
        a = np.abs(obj[np.isfinite(obj)])
        return float(a.max()) if a.size else 0.0
    if isinstance(obj, (float, np.floating)):
        return abs(float(obj)) if math.isfinite(obj) else 0.0
    if isinstance(obj, dict):
        return max((_float_max(v) for v in obj.values()), default=0.0)
    if isinstance(obj, (list, tuple)):
        return max((_float_max(v) for v in obj), default=0.0)
    return 0.0


def _nested_numbers(obj, values: list, lengths: list) -> bool:
    """Append the numbers of a (possibly ragged) nest of lists to ``values`` and each list's
    length to ``lengths`` (depth first); False when anything else is inside."""
    if isinstance(obj, list):
        lengths.append(len(obj))
        return all(_nested_numbers(v, values, lengths) for v in obj)
    if _is_number(obj):
        values.append(obj)
        return True
    return False


def _numeric(obj) -> tuple[np.ndarray, np.ndarray | None] | None:
    """``obj`` as one numeric array (rectangular) or as values + nesting lengths (ragged);
    None when it holds anything but numbers."""
    if isinstance(obj, np.ndarray) and obj.dtype.kind in "biuf":
        return obj, None
    if not isinstance(obj, list) or not obj:
        return None
    values: list = []
    lengths: list = []
    if not _nested_numbers(obj, values, lengths):
        if all(isinstance(v, bool) for v in obj):
            return np.asarray(obj), None
        return None
    try:
        arr = np.asarray(obj)
        if arr.dtype.kind in "iuf":
            return arr, None
    except ValueError:  # ragged
        pass
    return np.asarray(values), np.asarray(lengths)


def _texts(obj) -> list[str] | None:
    """A list of strings (or of one-string lists, as a recording's text columns come)."""
    if not isinstance(obj, list) or not obj:
        return None
    flat = [v[0] if isinstance(v, list) and len(v) == 1 else v for v in obj]
    return flat if all(isinstance(v, str) for v in flat) else None


def leaves(obj, path: str = "", context: float | None = None) -> dict[str, Leaf]:
    """Flatten an output into ``{path: Leaf}``.

    A rectangular numeric list is one array leaf with its own scale; a ragged one is
    ``path#values`` and ``path#lengths`` (the nesting); a list of strings is one leaf. A lone
    number (or a one-element array) takes as scale the largest float of its *section*: the
    object two levels up (its container and that container's siblings), or the whole output
    near the top. ``context`` is that section's scale, handed down.
    """
    here = _float_max(obj) if context is None else None
    out: dict[str, Leaf] = {}
    if isinstance(obj, (dict, list)) and not isinstance(obj, np.ndarray):
        num = _numeric(obj) if isinstance(obj, list) else None
        if num is not None:
            arr, lengths = num
            scale = _float_max(arr) if arr.size > 1 else max(_float_max(arr), context or 0.0)
            if lengths is None:
                return {path: Leaf(arr, scale)}
            return {f"{path}#values": Leaf(arr, scale), f"{path}#lengths": Leaf(lengths)}
        texts = _texts(obj) if isinstance(obj, list) else None
        if texts is not None:
            return {path: Leaf(texts)}
        if not obj:
            return {path: Leaf("{}" if isinstance(obj, dict) else "[]")}
        items = obj.items() if isinstance(obj, dict) else enumerate(obj)
        mine = _float_max(obj)
        for k, v in items:
            # a child container's lone numbers take this object's scale (two levels up
            # from them); this object's own lone numbers take the one handed down
            child_context = mine if isinstance(v, (dict, list)) else (
                context if context is not None else here)
            out.update(leaves(v, f"{path}/{k}", child_context))
        return out
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind in "US":
            return {path: Leaf(str(obj.tolist()) if obj.ndim == 0 else list(obj.ravel()))}
        if obj.dtype.kind in "biuf":
            scale = _float_max(obj) if obj.size > 1 else max(_float_max(obj), context or 0.0)
            return {path: Leaf(obj, scale)}
        return leaves(obj.tolist(), path, context)
    if isinstance(obj, (bool, np.bool_)):
        return {path: Leaf(np.asarray(bool(obj)))}
    if _is_number(obj):
        return {path: Leaf(np.asarray(obj), max(_float_max(obj), context or here or 0.0))}
    if isinstance(obj, bytes):  # a .mat header
        obj = obj.decode("latin-1")
    if obj is None or isinstance(obj, str):
        return {path: Leaf(obj)}
    raise TypeError(f"{path}: cannot compare a {type(obj).__name__}")


def flatten(outputs: dict) -> dict[str, Leaf]:
    return {f"{name}::{p}": leaf for name, content in outputs.items()
            for p, leaf in leaves(content).items()}


# ---- comparing --------------------------------------------------------------------------------

def _last_digit(token: str) -> float:
    """One unit in the last printed digit of a number token; 0 for an integer."""
    mant, _, exp = token.lower().partition("e")
    if "." not in mant and not exp:
        return 0.0
    decimals = len(mant.split(".", 1)[1]) if "." in mant else 0
    return 10.0 ** (int(exp or 0) - decimals) * (1 + 1e-9)  # 0.0035 - 0.0034 > 1e-4 in floats


def compare_text(ref: str, got: str) -> list[str]:
    """Words exactly, numbers to their printed precision: within one unit of the last printed
    digit, ``RTOL``, or ``FLOOR`` times the largest number on the same line (a line is the
    array a printed number belongs to). Returns the differences found."""
    rl, gl = ref.split("\n"), got.split("\n")
    if len(rl) != len(gl):
        return [f"{len(rl)} -> {len(gl)} lines"]
    out = []
    for i, (a, b) in enumerate(zip(rl, gl, strict=True)):
        if NUMBER.split(a) != NUMBER.split(b):
            out.append(f"line {i + 1}: {_short(a)} -> {_short(b)}")
            continue
        rn, gn = NUMBER.findall(a), NUMBER.findall(b)
        scale = max((abs(float(x)) for x in rn if math.isfinite(float(x))), default=0.0)
        for x, y in zip(rn, gn, strict=True):
            tol = max(_last_digit(x), _last_digit(y), RTOL * abs(float(x)), FLOOR * scale)
            if abs(float(y) - float(x)) > tol:
                out.append(f"line {i + 1}: {x} -> {y} (printed to ±{tol:.3g})")
    return out


def compare_leaf(ref: Leaf, got: Leaf) -> str | None:
    """None when ``got`` matches ``ref``; otherwise what changed and by how much."""
    r, g = ref.value, got.value
    if isinstance(r, Fingerprint) and isinstance(g, np.ndarray):
        return compare_fingerprint(r, g, ref.scale)
    if isinstance(r, np.ndarray) != isinstance(g, np.ndarray):
        return f"{_short(r)} -> {_short(g)}"
    if not isinstance(r, np.ndarray):
        if isinstance(r, str) and isinstance(g, str):
            diffs = compare_text(r, g)
        elif isinstance(r, list) and isinstance(g, list) and len(r) == len(g):
            diffs = [f"[{i}] {d}" for i, (x, y) in enumerate(zip(r, g, strict=True))
                     for d in compare_text(x, y)]
        else:
            diffs = [] if r == g else [f"{_short(r)} -> {_short(g)}"]
        if not diffs:
            return None
        return "; ".join(diffs[:3]) + (f" (+{len(diffs) - 3} more)" if len(diffs) > 3 else "")
    if r.shape != g.shape:
        return f"shape {r.shape} -> {g.shape}"
    if r.dtype.kind in "biu" and g.dtype.kind in "biu":
        bad = np.flatnonzero(r.ravel() != g.ravel())
        if bad.size:
            return (f"{bad.size} of {r.size} integers differ, first at {bad[0]}: "
                    f"{r.ravel()[bad[0]]} -> {g.ravel()[bad[0]]}")
        return None
    rf, gf = r.astype(float).ravel(), g.astype(float).ravel()
    same_special = (np.isnan(rf) & np.isnan(gf)) | (np.isinf(rf) & (rf == gf))
    finite = np.isfinite(rf) & np.isfinite(gf)
    tol = RTOL * np.abs(np.where(finite, rf, 0.0)) + FLOOR * ref.scale
    err = np.where(finite, np.abs(gf - rf), np.inf)
    bad = np.flatnonzero(~same_special & (err > tol))
    if not bad.size:
        return None
    worst = bad[np.argmax(np.where(finite[bad], err[bad] / np.maximum(tol[bad], 1e-300),
                                   np.inf))]
    rel = err[worst] / abs(rf[worst]) if rf[worst] else math.inf
    return (f"{bad.size} of {rf.size} values differ; worst at {worst}: {rf[worst]!r} -> "
            f"{gf[worst]!r} (|Δ| {err[worst]:.3g}, relative {rel:.3g}; tolerance "
            f"{tol[worst]:.3g} = {RTOL:g}·|ref| + {FLOOR:g}·{ref.scale:.3g})")


def _short(v) -> str:
    s = repr(v.tolist() if isinstance(v, np.ndarray) else v)
    return s if len(s) < 80 else s[:77] + "..."


def compare(ref: dict[str, Leaf], got: dict[str, Leaf]) -> list[str]:
    """Every difference between two flattened snapshots, one line each."""
    out = [f"missing: {k}" for k in sorted(set(ref) - set(got))]
    out += [f"new: {k}" for k in sorted(set(got) - set(ref))]
    for k in sorted(set(ref) & set(got)):
        diff = compare_leaf(ref[k], got[k])
        if diff:
            out.append(f"{k}: {diff}")
    return out


def worst_margin(ref: dict[str, Leaf], got: dict[str, Leaf]) -> tuple[float, str]:
    """The largest ``|got − ref| / tolerance`` over the numbers compared (above 1 is a
    difference) and where: how close a run came to the tolerance."""
    worst, where = 0.0, ""
    for k in sorted(set(ref) & set(got)):
        r, g, scale = ref[k].value, got[k].value, ref[k].scale
        if isinstance(r, Fingerprint):
            if not isinstance(g, np.ndarray) or tuple(g.shape) != r.shape:
                continue
            r, g = r.sample, g.ravel()[r.index]
        if not (isinstance(r, np.ndarray) and isinstance(g, np.ndarray)) or r.shape != g.shape \
                or r.dtype.kind != "f":
            continue
        rf, gf = r.ravel(), g.astype(float).ravel()
        ok = np.isfinite(rf) & np.isfinite(gf)
        tol = RTOL * np.abs(rf[ok]) + FLOOR * scale
        err = np.abs(gf[ok] - rf[ok])
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(err > 0, err / tol, 0.0)
        if ratio.size and ratio.max() > worst:
            worst, where = float(ratio.max()), k
    return worst, where


# ---- storing ----------------------------------------------------------------------------------

@dataclass(frozen=True)
class Fingerprint:
    """What the reference keeps of an array longer than ``FULL`` (a recording's 40,002-sample
    column, a .mat variable of 20,001 rows): its shape, ``FULL`` elements at an even stride
    (first and last included) compared one by one, the number of non-finite values, and
    ``PROJECTIONS`` weighted sums ``Σ w_i x_i`` over the finite values with fixed weights
    ``w_i = frac((i + 1)·√p) − ½`` (p = 2, 3, 5, 7: no random generator whose stream could
    change). A sum is compared within ``RTOL·Σ|w_i x_i| + FLOOR·scale·Σ|w_i|``, the
    propagated element tolerance, so a change of the whole array, of its order, or of many
    elements is caught between the kept ones; a change of one unkept element alone is seen
    only through the outputs computed from it."""

    shape: tuple[int, ...]
    index: np.ndarray
    sample: np.ndarray
    nonfinite: int
    sums: np.ndarray
    abs_sums: np.ndarray

    @classmethod
    def of(cls, arr: np.ndarray) -> Fingerprint:
        flat = arr.ravel().astype(float)
        index = np.unique(np.linspace(0, flat.size - 1, FULL).round().astype(np.int64))
        finite = np.isfinite(flat)
        x = np.where(finite, flat, 0.0)
        w = _weights(flat.size)
        return cls(tuple(arr.shape), index, arr.ravel()[index], int((~finite).sum()), w @ x,
                   np.abs(w) @ np.abs(x))


FULL = 1024
"""Arrays longer than this are kept as a :class:`Fingerprint` (the reference stays ≈ 2 MB;
all of it would be ≈ 16 MB of random digits that do not compress)."""
PROJECTIONS = 4


def _weights(n: int) -> np.ndarray:
    i = np.arange(1, n + 1, dtype=float)
    return np.stack([np.modf(i * math.sqrt(p))[0] - 0.5 for p in (2, 3, 5, 7)[:PROJECTIONS]])


def compare_fingerprint(ref: Fingerprint, got: np.ndarray, scale: float) -> str | None:
    if tuple(got.shape) != ref.shape:
        return f"shape {ref.shape} -> {tuple(got.shape)}"
    fp = Fingerprint.of(got)
    diff = compare_leaf(Leaf(ref.sample, scale), Leaf(fp.sample, scale))
    if diff:
        return f"at the kept elements (every {ref.index[1] - ref.index[0]}th): {diff}"
    if fp.nonfinite != ref.nonfinite:
        return f"{ref.nonfinite} -> {fp.nonfinite} non-finite values"
    tol = RTOL * ref.abs_sums + FLOOR * scale * np.abs(_weights(got.size)).sum(axis=1)
    err = np.abs(fp.sums - ref.sums)
    if (err > tol).any():
        j = int(np.argmax(err / tol))
        return (f"values between the kept elements changed: weighted sum {j} "
                f"{ref.sums[j]!r} -> {fp.sums[j]!r} (|Δ| {err[j]:.3g}, tolerance {tol[j]:.3g})")
    return None


def save(flat: dict[str, Leaf], json_path: Path = REFERENCE, npz_path: Path = ARRAYS) -> None:
    """Write the reference: one line per leaf in JSON — ``[values, scale]`` for numbers (full
    repr precision, which round-trips exactly; ints stay ints), the text itself (a string,
    null or a list of strings) otherwise; arrays of more than ``BIG`` elements go to a
    compressed npz (``{"npz": key, "scale": s}``, identical arrays stored once), those over
    ``FULL`` as a :class:`Fingerprint`."""
    from calib.files.atomic import write_bytes, write_text

    lines, arrays, seen = [], {}, {}
    for k, leaf in sorted(flat.items()):
        v = leaf.value
        if isinstance(v, np.ndarray) and v.size > BIG:
            digest = hashlib.sha256(v.dtype.str.encode() + str(v.shape).encode()
                                    + v.tobytes()).hexdigest()
            if digest not in seen:
                key = seen[digest] = f"a{len(seen)}"
                if v.size > FULL:
                    fp = Fingerprint.of(v)
                    arrays.update({f"{key}.shape": np.asarray(fp.shape),
                                   f"{key}.index": fp.index, f"{key}.sample": fp.sample,
                                   f"{key}.nonfinite": np.asarray(fp.nonfinite),
                                   f"{key}.sums": fp.sums, f"{key}.abs_sums": fp.abs_sums})
                else:
                    arrays[key] = v
            entry = {"npz": seen[digest], "scale": leaf.scale}
        elif isinstance(v, np.ndarray):
            if v.dtype.kind not in "biuf":
                raise TypeError(f"{k}: {v.dtype} array")
            entry = [v.tolist(), leaf.scale]
        elif isinstance(v, list):
            entry = {"texts": v}
        else:
            entry = v
        lines.append(f"{json.dumps(k)}: {json.dumps(entry)}")
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    write_bytes(npz_path, buf.getvalue(), force=True)  # the update script: rewriting is its job
    write_text(json_path, "{\n" + ",\n".join(lines) + "\n}\n", force=True)


def load(json_path: Path = REFERENCE, npz_path: Path = ARRAYS) -> dict[str, Leaf]:
    doc = json.loads(json_path.read_text(encoding="utf-8"))
    with np.load(npz_path) as npz:
        arrays = {k: npz[k] for k in npz.files}
    out = {}
    for k, e in doc.items():
        if isinstance(e, dict) and "npz" in e:
            key = e["npz"]
            if key in arrays:
                v = arrays[key]
            else:
                v = Fingerprint(tuple(int(n) for n in arrays[f"{key}.shape"]),
                                arrays[f"{key}.index"], arrays[f"{key}.sample"],
                                int(arrays[f"{key}.nonfinite"]), arrays[f"{key}.sums"],
                                arrays[f"{key}.abs_sums"])
            out[k] = Leaf(v, e["scale"])
        elif isinstance(e, dict):
            out[k] = Leaf(e["texts"])
        elif isinstance(e, list):
            out[k] = Leaf(np.asarray(e[0]), e[1])
        else:
            out[k] = Leaf(e)
    return out


def check(work: Path, course: Path = COURSE_DATA) -> list[str]:
    """Regenerate everything into ``work`` and return its differences from the reference."""
    return compare(load(), flatten(collect(work, course)))


def check_with_margin(work: Path, course: Path = COURSE_DATA) -> tuple[list[str], float, str]:
    """:func:`check` and :func:`worst_margin` of the same run."""
    ref, got = load(), flatten(collect(work, course))
    return (compare(ref, got), *worst_margin(ref, got))


def main(argv: list[str] | None = None) -> int:
    """``python tools/snapshot.py`` rewrites the reference; ``--check`` compares a fresh run
    with it instead (exit 1 and one line per difference when something changed). CI runs the
    check under other BLAS kernels and SIMD levels (see .ci/run)."""
    import tempfile

    argv = sys.argv[1:] if argv is None else argv
    if argv not in ([], ["--check"]):
        print("usage: python tools/snapshot.py [--check]", file=sys.stderr)
        return 2
    sys.path.insert(0, str(REPO))
    with tempfile.TemporaryDirectory() as tmp:
        if argv:
            diffs, margin, where = check_with_margin(Path(tmp))
            for d in diffs:
                print(d)
            print(f"snapshot: {len(diffs)} differences from {REFERENCE.name}; closest to its "
                  f"tolerance: {margin:.3g} of it at {where}", file=sys.stderr)
            return 1 if diffs else 0
        flat = flatten(collect(Path(tmp)))
    save(flat)
    print(f"{REFERENCE}: {len(flat)} values ({REFERENCE.stat().st_size // 1024} KiB + "
          f"{ARRAYS.name} {ARRAYS.stat().st_size // 1024} KiB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
