"""Checksums of everything users get from tiltbench: generated files and ``--json`` outputs.

The byte-identity guard of refactors: ``tests/test_snapshot.py`` reruns :func:`snapshot` in a
fresh folder and compares it with ``tests/reference/snapshot.json``. When a change is *meant*
to change an output, rerun this script and commit the new file together with the change::

    python tools/snapshot.py            # rewrites tests/reference/snapshot.json

What is compared:

* every file that ``generate calibration`` (static and sweep), ``vehicle``, ``course`` and
  ``class`` write for two seeds, and everything ``demo`` writes to its data/ and JSON outputs;
* the ``--json`` stdout of every command on the course files (``../shared/course-data``);
* ``.rrd`` recordings by content (entity paths and column values, not the random recording
  id or the start time), as the recording tests do;
* the demo report without its wall-clock step times and file sizes;
* ``truth.json`` / answer keys without their ``versions`` block (CI may install other patch
  versions of matplotlib or Python; the numbers must not move).
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import re
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
COURSE_DATA = REPO.parent / "shared" / "course-data"
SNAPSHOT = REPO / "tests" / "reference" / "snapshot.json"
SEEDS = (0, 7)


def _strip_versions(obj):
    if isinstance(obj, dict):
        return {k: _strip_versions(v) for k, v in obj.items() if k != "versions"}
    if isinstance(obj, list):
        return [_strip_versions(v) for v in obj]
    return obj


def rrd_digest(path: Path) -> str:
    """sha256 of a recording's content: per chunk, the entity path and every column but the
    row ids and the recording's start time, chunks sorted (their order is not content)."""
    import pyarrow as pa
    from rerun.chunk import RrdReader

    parts = []
    for chunk in RrdReader(str(path)).stream().to_chunks():
        batch = chunk.to_record_batch()
        h = hashlib.sha256(str(chunk.entity_path).encode())
        for name in sorted(batch.schema.names):
            if name == "rerun.controls.RowId" or name.endswith("start_time"):
                continue
            col = batch.column(name)
            if pa.types.is_duration(col.type) or pa.types.is_timestamp(col.type):
                col = col.cast(pa.int64())  # to_pylist would go through datetime (µs)
            h.update(name.encode())
            h.update(repr(col.to_pylist()).encode())
        parts.append(h.hexdigest())
    return hashlib.sha256("".join(sorted(parts)).encode()).hexdigest()


def file_digest(path: Path) -> str:
    if path.suffix == ".rrd":
        return rrd_digest(path)
    data = path.read_bytes()
    if path.suffix == ".md":  # the demo report's wall-clock times and file sizes (a recording's
        # size varies by a few bytes) are not content
        data = b"\n".join(re.sub(rb"\| \d+ (KiB|B) \|", b"| size |", ln)
                          for ln in data.splitlines() if not ln.startswith(b"Step times:"))
    if path.suffix == ".json":
        obj = _strip_versions(json.loads(data))
        data = json.dumps(obj, sort_keys=True).encode()
    return hashlib.sha256(data).hexdigest()


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


def _json_digest(text: str) -> str:
    return hashlib.sha256(json.dumps(_strip_versions(json.loads(text)),
                                     sort_keys=True).encode()).hexdigest()


def snapshot(work: Path, course: Path = COURSE_DATA) -> dict[str, str]:
    """Generate everything into ``work`` (relative paths, so JSON outputs are stable) and
    return ``{name: sha256}``."""
    work.mkdir(parents=True, exist_ok=True)
    old = Path.cwd()
    os.chdir(work)
    try:
        return _snapshot(course)
    finally:
        os.chdir(old)


def _snapshot(course: Path) -> dict[str, str]:
    out: dict[str, str] = {}
    e, a, p, d = (str(course / f) for f in ("ensayo.mat", "acel.mat", "puntos.mat",
                                            "datos.txt"))
    for s in SEEDS:
        gens = {
            f"static-{s}": ["generate", "calibration", "--count", "2001", "--rrd",
                            f"static-{s}.rrd"],
            f"positions-{s}": ["generate", "calibration", "--positions", "12",
                               "--per-position", "20", "--effect", "misalignment:x:delta=0.02"],
            f"sweep-{s}": ["generate", "calibration", "--mode", "sweep", "--profile", "updown",
                           "--duration", "8", "--effect", "lever_arm:x:pos_x=0.2"],
            f"vehicle-{s}": ["generate", "vehicle", "--rrd", f"vehicle-{s}.rrd"],
            f"course-{s}": ["generate", "course", "--rrd", f"course-{s}.rrd"],
            f"class-{s}": ["generate", "class", "--students", "2"],
        }
        for name, argv in gens.items():
            out[f"stdout {name}"] = _json_digest(
                _run(argv + ["--seed", str(s), "--out", name, "--json"]))
    out["stdout calibrate"] = _json_digest(_run(["calibrate", e, "--datos", d, "--json",
                                                 "--rrd", "calibrate.rrd"]))
    out["stdout calibrate wls"] = _json_digest(_run(["calibrate", e, "--datos", d, "--method",
                                                     "wls", "--json"]))
    out["stdout calibrate estimated"] = _json_digest(_run(["calibrate", e, "--json"]))
    traj = ["--ensayo", e, "--acel", a, "--puntos", p, "--datos", d, "--json"]
    out["stdout trajectory"] = _json_digest(_run(["trajectory", *traj, "--rrd",
                                                  "trajectory.rrd"]))
    out["stdout nmin"] = _json_digest(_run(["nmin", *traj, "--runs", "20", "--mc-n", "2001"]))
    out["stdout gap"] = _json_digest(_run(["gap", e, "--datos", d, "--json", "--rrd",
                                           "gap.rrd", "--report", "gap-report"]))
    out["stdout gap data/sweep-lever-arm"] = _json_digest(_run(
        ["gap", str(REPO / "data" / "sweep-lever-arm" / "ensayo.mat"), "--noise-var",
         "0.25,0.64", "--json"]))
    Path("est.json").write_text(_run(["calibrate", "course-0/ensayo.mat", "--datos",
                                      "course-0/datos.txt", "--json"]))
    out["stdout validate"] = _json_digest(_run(["validate", "--truth", "course-0/truth.json",
                                                "--estimates", "est.json", "--json"]))
    for rrd in ("calibrate.rrd", "trajectory.rrd", "gap.rrd", "course-0.rrd"):
        out[f"stdout record read {rrd}"] = _json_digest(_run(["record", "read", rrd,
                                                              "--json"]))
    _run(["demo", "--out", "demo", "--quiet", "--coverage-runs", "20", "--figures", "png"])
    for f in sorted(Path(".").rglob("*")):
        if f.is_file() and f.suffix in (".mat", ".txt", ".json", ".csv", ".rrd", ".md") \
                and f.name != "est.json":
            out[f"file {f.as_posix()}"] = file_digest(f)
    return out


def main() -> int:
    import tempfile

    sys.path.insert(0, str(REPO))
    with tempfile.TemporaryDirectory() as tmp:
        snap = snapshot(Path(tmp))
    SNAPSHOT.write_text(json.dumps(snap, indent=1, sort_keys=True) + "\n")
    print(f"{SNAPSHOT}: {len(snap)} checksums")
    return 0


if __name__ == "__main__":
    sys.exit(main())
