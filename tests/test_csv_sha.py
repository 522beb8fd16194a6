"""The CSV reader hashes the file as it reads it (no second read for the provenance): the
digest equals :func:`calib.logs.reader.file_sha256` for plain, gzip, BOM and Latin-1 files,
and a phyphox zip's provenance hashes the zip, not its member."""

from __future__ import annotations

import gzip
import zipfile

import numpy as np
import pytest

from calib.logs.csvlog import read_csv
from calib.logs.reader import file_sha256, read_log


def _text(n=2000, seed=0) -> str:
    rng = np.random.default_rng(seed)
    rows = [f"{k / 100:.2f},{x:.6f},{y:.6f},{z:.6f}" for k, (x, y, z) in
            enumerate(rng.normal([0.0, 0.0, 9.8], 0.01, (n, 3)))]
    return "t (s),ax (m/s^2),ay (m/s^2),az (m/s^2)\n" + "\n".join(rows) + "\n"


@pytest.mark.parametrize("kind", ["plain", "gzip", "bom", "latin1", "big"])
def test_the_readers_hash_is_the_files(tmp_path, kind, monkeypatch):
    import calib.logs.csvlog as csvlog

    text = _text()
    path = tmp_path / ("log.csv.gz" if kind == "gzip" else "log.csv")
    if kind == "gzip":
        path.write_bytes(gzip.compress(text.encode()))
    elif kind == "bom":
        path.write_bytes(b"\xef\xbb\xbf" + text.encode())
    elif kind == "latin1":  # a non-UTF-8 byte late in the file: the reader starts again
        path.write_bytes(text.replace("t (s)", "t (s) \xb0", 1).encode("latin-1"))
    else:
        path.write_text(text)
    if kind == "big":  # the streaming (pandas) path in small blocks
        monkeypatch.setattr(csvlog, "SMALL_BYTES", 0)
        monkeypatch.setattr(csvlog, "CHUNK_BYTES", 4096)
    raw = read_csv(path)
    assert raw.sha256 == file_sha256(path)
    assert read_log(path).provenance["source"]["sha256"] == file_sha256(path)


def test_a_zips_provenance_hashes_the_zip(tmp_path):
    path = tmp_path / "export.zip"
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("Accelerometer.csv", _text())
    prov = read_log(path).provenance
    assert prov["source"]["sha256"] == file_sha256(path)
