"""Zip exports: phyphox's "CSV (zip)" export, read directly.

phyphox (https://phyphox.org, RWTH Aachen) exports an experiment as a zip holding one CSV per
sensor view (``Accelerometer.csv`` for "Acceleration with g", ``Raw Data.csv`` for the raw
sensor experiments, ``Gyroscope.csv`` …) and a ``meta/`` folder (``device.csv``, ``time.csv``)
describing the phone and the clock. The reader picks the member with the readings and hands it
to the CSV reader (:mod:`calib.logs.csvlog`) unchanged: the same header recognition, units and
checks as for the CSV alone.

Which member (never a guess between two candidates):

the members that are CSV files outside ``meta/``: exactly one → that one; several → the one
among :data:`PREFERRED` (in that order) that exists; else refused in one line listing the
members (unzip the export and give the member's CSV).

The member is extracted to a private temporary file for the CSV reader (it reads a path; zip
members are deflated streams, not seekable files) and removed afterwards. Messages name the
member as ``export.zip:Accelerometer.csv`` with the member's own line numbers; the provenance
records the zip's sha256 and the member (``reader.zip_member``).
"""

from __future__ import annotations

import contextlib
import shutil
import tempfile
import zipfile
from collections.abc import Iterator
from pathlib import Path

from calib.input_rules import DataError, file_head

ZIP_MAGIC = b"PK\x03\x04"
PREFERRED = ("Accelerometer.csv", "Raw Data.csv", "Acceleration.csv")
"""phyphox member names with acceleration including gravity, in order of preference."""


def is_zip(path: Path) -> bool:
    """A zip archive, recognized from its magic bytes (not its name)."""
    return path.is_file() and file_head(path, 4) == ZIP_MAGIC


def csv_members(path: Path) -> list[str]:
    """The CSV members of the zip outside ``meta/`` (phyphox's metadata), in archive order."""
    try:
        with zipfile.ZipFile(path) as z:
            names = [i.filename for i in z.infolist() if not i.is_dir()]
    except (zipfile.BadZipFile, OSError) as exc:
        raise DataError(f"{path}: not a readable zip archive ({exc}); export it again") from None
    return [n for n in names if n.lower().endswith((".csv", ".tsv"))
            and not n.lower().startswith("meta/")]


def choose_member(path: Path) -> str:
    """The member to read (module docstring); DataError naming the members otherwise."""
    members = csv_members(path)
    if len(members) == 1:
        return members[0]
    by_name = {Path(m).name: m for m in members}
    for name in PREFERRED:
        if name in by_name:
            return by_name[name]
    if not members:
        raise DataError(f"{path}: a zip with no CSV member outside meta/; not a phyphox "
                        "export of readings")
    raise DataError(f"{path}: a zip with {len(members)} CSV members ({', '.join(members)}); "
                    "unzip the export and give the member's CSV")


@contextlib.contextmanager
def extracted(path: Path, member: str) -> Iterator[Path]:
    """The member as a temporary file (removed on exit); DataError messages raised inside
    name ``path:member`` instead of the temporary file."""
    tmp = Path(tempfile.mkdtemp(prefix="tiltbench-zip-"))
    target = tmp / Path(member).name
    try:
        with zipfile.ZipFile(path) as z, z.open(member) as src, open(target, "wb") as dst:
            shutil.copyfileobj(src, dst, 1 << 20)
    except (zipfile.BadZipFile, OSError, RuntimeError) as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        raise DataError(f"{path}: member {member!r} cannot be read ({exc}); export it "
                        "again") from None
    try:
        yield target
    except DataError as exc:
        raise DataError(str(exc).replace(str(target), f"{path}:{member}")) from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


__all__ = ["PREFERRED", "ZIP_MAGIC", "choose_member", "csv_members", "extracted", "is_zip"]
