"""Class sets: one unique course set per student plus a private answer key.

``tiltbench generate class --students K --seed S --out DIR`` writes::

    DIR/student_001/ ensayo.mat acel.mat puntos.mat datos.txt      (what student 1 gets)
    ...
    DIR/student_K/   ...
    DIR/answer_key.csv    one row per student: seed, answer letter, true parameters
    DIR/answer_key.json   the same plus every student's full truth.json object

Nothing inside a student folder reveals the truth (no ``truth.json``, no seed; the .mat
headers are a fixed text). Keep ``answer_key.*`` private: hand out the ``student_*`` folders
only. The key files are written mode 0600 (owner only), and while the class is being written
it lives in a temporary folder beside DIR that only its owner can open (0700), never inside a
student folder: a run killed before the end leaves no key that others can read, and the next
run removes that folder at start-up.

Seeds: ``SeedSequence(S).spawn(K)``; student i gets the 63-bit integer
``child_i.generate_state(1, uint64)[0] >> 1`` as the seed of its course set
(:func:`bench.course.make_course_set`), so ``tiltbench generate course --seed <that seed>``
reproduces the folder byte for byte. The sets are checked to be pairwise different (seeds and
file contents).

Validate a student's estimates with ``tiltbench validate --truth DIR/answer_key.json
--student student_007 --estimates est.json``.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from calib.files.atomic import atomic_dir, write_text
from calib.files.course import DataError, dumps
from calib.stats.runs import Mapper, serial_map
from calib.units import nest, with_units

STUDENT_FILES = ("ensayo.mat", "acel.mat", "puntos.mat", "datos.txt")
KEY_CSV = "answer_key.csv"
KEY_JSON = "answer_key.json"
KEY_MODE = 0o600
"""Mode of the answer-key files: readable and writable by their owner only."""
CSV_COLUMNS = ("student", "seed", "answer", "raw_end_decoy", "bias_x", "scale_x", "bias_y",
               "scale_y", "noise_var_x", "noise_var_y", "true_final_x", "true_final_y",
               "candidates")


def student_seeds(seed: int, count: int) -> list[int]:
    """Seeds of the ``count`` course sets derived from ``seed`` (module docstring)."""
    if count < 1:
        raise ValueError(f"the number of students must be >= 1, got {count}")
    if seed < 0:
        raise ValueError(f"the class seed must be >= 0, got {seed}")
    out = [int(c.generate_state(1, np.uint64)[0] >> np.uint64(1))
           for c in np.random.SeedSequence(int(seed)).spawn(int(count))]
    if len(set(out)) != len(out):  # 2^-63 per pair: would be a bug, not chance
        raise RuntimeError("derived seeds collide")
    return out


def student_name(i: int, count: int, prefix: str = "student") -> str:
    """``student_001`` … (zero padded to at least 3 digits)."""
    return f"{prefix}_{i + 1:0{max(3, len(str(count)))}d}"


@dataclass(frozen=True)
class ClassSet:
    """What :func:`generate_class` wrote: folders, answer-key paths and the key rows."""

    out: Path
    folders: dict[str, Path]
    key_csv: Path
    key_json: Path
    rows: list[dict]


def _row(name: str, seed: int, truth: dict) -> dict:
    s = truth["sensor"]
    return {"student": name, "seed": seed, "answer": truth["answer"],
            "raw_end_decoy": truth.get("raw_end_decoy"),
            "bias_x": s["x"]["bias"], "scale_x": s["x"]["scale"],
            "bias_y": s["y"]["bias"], "scale_y": s["y"]["scale"],
            "noise_var_x": s["x"]["noise_var"], "noise_var_y": s["y"]["noise_var"],
            "true_final_x": truth["true_final_position"][0],
            "true_final_y": truth["true_final_position"][1],
            "candidates": json.dumps(truth["candidates"], sort_keys=True)}


def key_csv_text(rows: list[dict]) -> str:
    """The CSV answer key (floats written with ``repr``: exact)."""
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=CSV_COLUMNS, lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: repr(v) if isinstance(v, float) else v for k, v in r.items()})
    return buf.getvalue()


def _student_set(task: tuple) -> tuple[dict[str, bytes], dict]:
    """One student's course set, made in memory: ``({file name: bytes}, truth)``.

    A sweep task (module level, picklable in and out): the files are written to a private
    temporary folder of the worker and read back, so the task runs the same in this
    process, a local pool or on a Dask worker of another machine; the caller writes them.
    """
    import tempfile

    from bench.course import make_course_set, write_course_files

    config, seed = task
    course = make_course_set(config, seed)
    with tempfile.TemporaryDirectory(prefix="tiltbench-student-") as tmp:
        write_course_files(course, tmp, truth=False)
        files = {f: (Path(tmp) / f).read_bytes() for f in STUDENT_FILES}
    return files, course.truth()


CLASS_BLOCK = 64
"""Students generated per mapper call: bounds the files held in memory (≈ 0.7 MB each, so
≈ 45 MB) while the pool stays busy (one pool start per block)."""


def generate_class(out: str | Path, count: int, seed: int = 0, force: bool = False,
                   config=None, prefix: str = "student",
                   progress: Callable[[int, int], None] | None = None,
                   mapper: Mapper = serial_map) -> ClassSet:
    """Write ``count`` unique course sets and the private answer key into ``out``.

    Parameters
    ----------
    out : class directory.  count : number of students K.  seed : class seed S.
    force : replace existing files (checked for every target before anything is written).
        The class directory is written as one set: see the comment in the body.
    config : :class:`bench.course.CourseConfig` shared by all sets (default: the course's).
    prefix : folder prefix.  progress : called as ``progress(done, count)`` (students).
    mapper : where the students' sets are made (:mod:`calib.stats.runs`; a local process pool or a
        Dask cluster from :mod:`bench.sweep`); the files do not depend on it.
    """
    from bench.dataset import truth_units, versions

    out = Path(out)
    seeds = student_seeds(seed, count)
    names = [student_name(i, count, prefix) for i in range(count)]
    owned = [KEY_CSV, KEY_JSON] + [f"{n}/{f}" for n in names
                                   for f in (*STUDENT_FILES, "truth.json")]
    clash = [str(out / p) for p in owned if (out / p).exists()]
    if clash and not force:
        raise FileExistsError(f"{out}: {clash[0]}{' and others' if len(clash) > 1 else ''} "
                              "already exist(s)")
    folders, rows, truths, digests = {}, [], {}, {}
    # The class is one set (calib.files.atomic.atomic_dir): written beside OUT and swapped in
    # whole. The truth of a student is kept in memory and goes to the answer key only; it
    # is never written inside a student folder, not even for a moment. Student folders are
    # replaced whole (nothing of an old folder is carried into the new one).
    with atomic_dir(out, force, owned=owned, exclusive=names) as tmp:
        for start in range(0, count, CLASS_BLOCK):
            block = list(range(start, min(start + CLASS_BLOCK, count)))
            report = None if progress is None else (
                lambda done, _total, s=start: progress(s + done, count))
            made = mapper(_student_set, [(config, seeds[i]) for i in block], report)
            for i, (files, course_truth) in zip(block, made, strict=True):
                name, s = names[i], seeds[i]
                folder = tmp / name
                folder.mkdir()
                h = hashlib.sha256()
                for f in STUDENT_FILES:
                    (folder / f).write_bytes(files[f])
                    h.update(files[f])
                # exactly what truth.json of `generate course --seed s` holds, read back
                truth = json.loads(dumps({**course_truth, "seed": int(s),
                                          "versions": versions()}))
                digest = h.hexdigest()
                if digest in digests:
                    raise RuntimeError(f"{name} and {digests[digest]} got identical files")
                digests[digest] = name
                folders[name] = out / name
                truths[name] = truth
                rows.append(_row(name, s, truth))
        # The key is private (0600) from its first byte: its temporary name, the set's
        # temporary folder (0700 until it is renamed into place, beside OUT and never inside a
        # student folder) and the published file. A run killed before the final rename leaves
        # nothing another user can read; the next run removes it at start-up.
        write_text(tmp / KEY_CSV, key_csv_text(rows), force=True, mode=KEY_MODE)
        key = {"kind": "class", "class_seed": int(seed), "count": int(count),
               "seed_derivation": "SeedSequence(class_seed).spawn(count)[i]"
                                  ".generate_state(1, uint64)[0] >> 1",
               "versions": versions(), "columns": list(CSV_COLUMNS),
               "students": [{"student": r["student"], "folder": r["student"],
                             "seed": r["seed"], "answer": r["answer"],
                             "truth": truths[r["student"]]} for r in rows]}
        units = {"class_seed": "—", "count": "count", "students.seed": "—",
                 **nest("students.truth", truth_units())}  # docs/units.md
        write_text(tmp / KEY_JSON, dumps(with_units(key, units)), force=True, mode=KEY_MODE)
    return ClassSet(out, folders, out / KEY_CSV, out / KEY_JSON, rows)


def student_truth(key: dict, student: str) -> dict:
    """One student's ``truth.json`` object from an ``answer_key.json`` object."""
    for s in key.get("students", []):
        if s.get("student") == student:
            return s["truth"]
    names = [s.get("student") for s in key.get("students", [])]
    raise DataError(f"answer key: no student '{student}' (have {', '.join(names[:5])}"
                    f"{' …' if len(names) > 5 else ''})")


__all__ = ["ClassSet", "generate_class", "student_seeds", "student_truth"]
