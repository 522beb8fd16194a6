"""Faults while writing (issue 11, parts 5 and 7): kills, concurrent runs, read-only and full
disks. Each case asserts a clean one-line error with exit code 2 (or a correct result), the
target exactly the old set or exactly the new one, and no temporary file left behind.

Kills and concurrent runs use real ``tiltbench`` processes (SIGKILL at several points: as
soon as the temporary set appears, and after fixed delays). Full and read-only disks use a
small tmpfs where the machine allows mounting one (root), and an injected ``ENOSPC`` in
process everywhere.
"""

from __future__ import annotations

import contextlib
import errno
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from bench.cli import main
from calib.files import atomic
from tests.cli import unwrap

# small sets: the faults, not the physics, are under test
COURSE = ["generate", "course", "--count", "201", "--duration", "5"]


def _tree(root: Path) -> dict[str, bytes]:
    """Every file under ``root`` (hidden ones too) → its bytes."""
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*"))
            if p.is_file()}


def _leftovers(parent: Path) -> list[str]:
    """Our temporary and lock names in ``parent`` (and one level down)."""
    names = [p for p in parent.rglob(".*") if p.name.endswith((".tmp", ".lock"))]
    return sorted(str(p.relative_to(parent)) for p in names)


def _run(capsys, *argv) -> tuple[int, str]:
    capsys.readouterr()
    rc = main([str(a) for a in argv])
    return rc, capsys.readouterr().err


def _spawn(*argv) -> subprocess.Popen:
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1]),
               OPENBLAS_NUM_THREADS="1")
    return subprocess.Popen([sys.executable, "-m", "bench.cli", *map(str, argv)], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)


def _wait_for_tmp(parent: Path, name: str, proc: subprocess.Popen, timeout: float = 30.0
                  ) -> bool:
    """Poll (1 ms) until a temporary set ``.name.*.tmp`` appears; False if the run ended."""
    end = time.monotonic() + timeout
    while time.monotonic() < end and proc.poll() is None:
        if any(n.startswith(f".{name}.") and n.endswith(".tmp") for n in os.listdir(parent)):
            return True
        time.sleep(0.001)
    return False


def _kill(proc: subprocess.Popen) -> None:
    with contextlib.suppress(ProcessLookupError):
        proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    proc.stderr.close()


# ---------------------------------------------------------------- kill during write
def test_killed_course_rewrite_leaves_the_old_set_or_the_new_one(capsys, tmp_path):
    ref_new = tmp_path / "ref"
    assert _run(capsys, *COURSE, "--seed", "2", "--out", ref_new)[0] == 0
    new = _tree(ref_new)
    work = tmp_path / "w"
    work.mkdir()
    target = work / "set"
    assert _run(capsys, *COURSE, "--seed", "1", "--out", target)[0] == 0
    old = _tree(target)
    assert old != new
    seen = set()
    for delay in ("tmp", "tmp", 0.05, 0.2):  # at the temporary set's appearance, then later
        proc = _spawn(*COURSE, "--seed", "2", "--out", target, "--force")
        if delay == "tmp":
            _wait_for_tmp(work, "set", proc)
        else:
            time.sleep(delay)
        _kill(proc)
        got = _tree(target)
        assert got in (old, new), "a mixed set"
        seen.add("old" if got == old else "new")
        if got == new:  # next attempt rewrites the old set again
            assert _run(capsys, *COURSE, "--seed", "1", "--out", target, "--force")[0] == 0
    # the next run cleans what the killed ones left and writes the whole set
    assert _run(capsys, *COURSE, "--seed", "2", "--out", target, "--force")[0] == 0
    assert _tree(target) == new
    assert _leftovers(work) == []


def test_killed_class_rewrite_never_mixes_and_never_exposes_the_key(capsys, tmp_path):
    work = tmp_path / "w"
    work.mkdir()
    target = work / "class"
    assert _run(capsys, "generate", "class", "--students", "2", "--seed", "1", "--out",
                target)[0] == 0
    old = _tree(target)
    for delay in ("tmp", 0.6):
        proc = _spawn("generate", "class", "--students", "8", "--seed", "2", "--out", target,
                      "--force")
        if delay == "tmp":
            assert _wait_for_tmp(work, "class", proc)
        else:
            time.sleep(delay)
        # while it runs: nothing of the truth inside any student folder, temporary or not
        for folder in work.glob("*/student_*"):
            assert not {"truth.json", "answer_key.json", "answer_key.csv"} & {
                p.name for p in folder.iterdir()}
        _kill(proc)
        assert _tree(target) == old
    assert _run(capsys, "generate", "class", "--students", "3", "--seed", "2", "--out",
                target, "--force")[0] == 0
    assert _leftovers(work) == []
    names = {p.name for p in target.iterdir()}
    # old student folders not in the new class are kept (as before), each still whole
    assert names == {"answer_key.csv", "answer_key.json", "student_001", "student_002",
                     "student_003"}
    for folder in target.glob("student_*"):
        assert sorted(p.name for p in folder.iterdir()) == ["acel.mat", "datos.txt",
                                                            "ensayo.mat", "puntos.mat"]


def test_interrupted_swap_is_undone_by_the_next_run(tmp_path):
    """The two-rename swap (filesystems without RENAME_EXCHANGE) killed between its renames
    leaves the old set under a backup name; the next run puts it back."""
    dead = subprocess.Popen(["true"])
    dead.wait()
    target = tmp_path / "set"
    backup = tmp_path / f".set.{dead.pid}-0a1b2c3d.bak.tmp"
    backup.mkdir()
    (backup / "a.txt").write_text("old")
    stray = tmp_path / f".set.{dead.pid}-deadbeef.tmp"
    stray.mkdir()
    (stray / "a.txt").write_text("half")
    legacy = tmp_path / ".set.ab12_xyz.tmp"  # older versions' mkstemp name
    legacy.write_text("x")
    with atomic.output_lock(target):
        atomic.clean_stale(target, locked=True)
    assert _tree(target) == {"a.txt": b"old"}
    assert sorted(os.listdir(tmp_path)) == ["set"]


def test_two_rename_swap_replaces_the_set(tmp_path, monkeypatch):
    monkeypatch.setattr(atomic, "_exchange", lambda a, b: False)
    target = tmp_path / "set"
    target.mkdir()
    (target / "a.txt").write_text("old")
    (target / "mine.txt").write_text("kept")
    with atomic.atomic_dir(target, force=True, owned=["a.txt"]) as tmp:
        (tmp / "a.txt").write_text("new")
    assert _tree(target) == {"a.txt": b"new", "mine.txt": b"kept"}
    assert sorted(os.listdir(tmp_path)) == ["set"]


# ---------------------------------------------------------------- concurrent writes
def test_second_run_on_the_same_out_is_refused_and_the_first_completes(capsys, tmp_path):
    target = tmp_path / "class"
    first = _spawn("generate", "class", "--students", "12", "--seed", "3", "--out", target)
    assert _wait_for_tmp(tmp_path, "class", first), "the first run ended before writing"
    rc, err = _run(capsys, *COURSE, "--out", target)
    assert rc == 2
    line, = unwrap(err).splitlines()
    assert f"another tiltbench run is writing {target} (pid {first.pid})" in line
    assert first.wait(timeout=60) == 0, first.stderr.read().decode()
    first.stderr.close()
    assert len(list(target.glob("student_*"))) == 12
    assert not (target / "ensayo.mat").exists()  # nothing of the refused run
    assert _leftovers(tmp_path) == []


def test_lock_is_per_target_and_released(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    with atomic.output_lock(a):
        with pytest.raises(atomic.OutputBusyError, match=f"writing {a} \\(pid {os.getpid()}"):
            with atomic.output_lock(a):
                pass
        with atomic.output_lock(b):
            pass
    with atomic.output_lock(a):
        pass
    assert os.listdir(tmp_path) == []


# ---------------------------------------------------------------- read-only and full disks
@contextlib.contextmanager
def _tmpfs(path: Path, size: str):
    """A tmpfs of ``size`` at ``path`` (root only); skip the test where it cannot be made."""
    path.mkdir()
    if os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root")
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(path)],
                       capture_output=True)
    if r.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {r.stderr.decode().strip()}")
    try:
        yield path
    finally:
        subprocess.run(["umount", "-l", str(path)], check=False)


def _fill(fs: Path, leave: int) -> None:
    """Fill ``fs`` up to ``leave`` free bytes."""
    st = os.statvfs(fs)
    free = st.f_bavail * st.f_frsize
    with open(fs / "filler", "wb") as fh:
        fh.write(b"\0" * max(free - leave, 0))


def test_read_only_target_directory_is_a_clean_error(capsys, tmp_path):
    if os.geteuid() == 0:
        ctx = _tmpfs(tmp_path / "ro", "4m")
    else:
        ctx = contextlib.nullcontext(tmp_path / "ro")
        (tmp_path / "ro").mkdir()
    with ctx as ro:
        target = ro / "set"
        assert _run(capsys, *COURSE, "--seed", "1", "--out", target)[0] == 0
        old = _tree(ro)
        if os.geteuid() == 0:
            subprocess.run(["mount", "-o", "remount,ro", str(ro)], check=True)
        else:
            ro.chmod(0o555)
            target.chmod(0o555)
        try:
            rc, err = _run(capsys, *COURSE, "--seed", "2", "--out", target, "--force")
        finally:
            if os.geteuid() != 0:
                ro.chmod(0o755)
                target.chmod(0o755)
        assert rc == 2
        line, = unwrap(err).splitlines()
        assert str(target) in line and ("Read-only" in line or "Permission denied" in line)
        assert "Traceback" not in err and ".tmp" not in line
        assert _tree(ro) == old
        assert _leftovers(ro) == []


def test_full_disk_set_is_a_clean_error_and_leaves_nothing(capsys, tmp_path):
    with _tmpfs(tmp_path / "fs", "2m") as fs:
        target = fs / "set"
        assert _run(capsys, *COURSE, "--seed", "1", "--out", target)[0] == 0
        _fill(fs, 64 * 1024)  # the default set needs ~630 kB
        old = _tree(fs)
        t0 = time.monotonic()
        rc, err = _run(capsys, "generate", "course", "--seed", "2", "--out", target, "--force")
        assert time.monotonic() - t0 < 30
        assert rc == 2
        line, = unwrap(err).splitlines()
        assert "No space left on device" in line and str(target) in line and ".tmp" not in line
        assert _tree(fs) == old
        assert _leftovers(fs) == []


def test_full_disk_recording_ends_within_seconds(tmp_path):
    with _tmpfs(tmp_path / "fs", "1m") as fs:
        (fs / "old.rrd").write_bytes(b"previous recording")
        _fill(fs, 32 * 1024)
        old = _tree(fs)
        proc = _spawn("generate", "calibration", "--count", "20001", "--out",
                      tmp_path / "cal", "--rrd", fs / "cal.rrd")
        try:
            _, err = proc.communicate(timeout=60)  # a hang is a failure, not a stuck suite
        except subprocess.TimeoutExpired:
            _kill(proc)
            pytest.fail("--rrd onto a full disk hangs")
        err = err.decode()
        assert proc.returncode == 2, err
        line, = unwrap(err).splitlines()
        assert f"{fs / 'cal.rrd'}: No space left on device" in line
        assert _tree(fs) == old
        assert _leftovers(fs) == []


def test_read_only_filesystem_single_file_is_one_line_and_loses_nothing(capsys, tmp_path,
                                                                        course_dir):
    """A single-file output (issue 23) on a read-only filesystem: refused at start-up (its
    lock cannot be made), before any work; the old file stays."""
    with _tmpfs(tmp_path / "ro", "4m") as ro:
        out = ro / "cal.json"
        out.write_bytes(b"the previous result")
        subprocess.run(["mount", "-o", "remount,ro", str(ro)], check=True)
        rc, err = _run(capsys, "calibrate", course_dir / "ensayo.mat", "--noise-var",
                       "0.25,0.64", "--save", out, "--force")
        assert rc == 2
        line, = unwrap(err).splitlines()
        assert line.endswith(f"{out}: Read-only file system") and ".lock" not in line
        assert _tree(ro) == {"cal.json": b"the previous result"}


def test_full_disk_single_file_is_one_line_and_loses_nothing(capsys, tmp_path, course_dir):
    with _tmpfs(tmp_path / "fs", "1m") as fs:
        out = fs / "cal.json"
        out.write_bytes(b"the previous result")
        _fill(fs, 64 * 1024)  # cal.json of the course run is ~1.2 MB
        old = _tree(fs)
        rc, err = _run(capsys, "calibrate", course_dir / "ensayo.mat", "--noise-var",
                       "0.25,0.64", "--save", out, "--force")
        assert rc == 2
        line, = unwrap(err).splitlines()
        assert line.endswith(f"{out}: No space left on device") and ".tmp" not in line
        assert _tree(fs) == old
        assert _leftovers(fs) == []


def _no_space_under(root: Path):
    """An ``os.fsync`` that fails with ENOSPC for files and directories under ``root``."""
    real_fsync = os.fsync

    def fsync(fd):
        if os.readlink(f"/proc/self/fd/{fd}").startswith(str(root)):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real_fsync(fd)

    return fsync


def test_injected_enospc_on_a_set(capsys, tmp_path, monkeypatch):
    """Where no small filesystem can be mounted: the disk fills at flush time (fsync)."""
    target = tmp_path / "set"
    assert _run(capsys, *COURSE, "--seed", "1", "--out", target)[0] == 0
    old = _tree(tmp_path)
    monkeypatch.setattr(atomic.os, "fsync", _no_space_under(tmp_path))
    rc, err = _run(capsys, *COURSE, "--seed", "2", "--out", target, "--force")
    assert rc == 2
    line, = unwrap(err).splitlines()
    assert "No space left on device" in line and str(target) in line and ".tmp" not in line
    assert _tree(tmp_path) == old
    assert _leftovers(tmp_path) == []


def test_injected_enospc_on_a_recording(capsys, tmp_path, monkeypatch):
    rrd = tmp_path / "r" / "cal.rrd"
    rrd.parent.mkdir()
    rrd.write_bytes(b"previous recording")
    monkeypatch.setattr(atomic.os, "fsync", _no_space_under(rrd.parent))
    t0 = time.monotonic()
    rc, err = _run(capsys, "generate", "calibration", "--count", "2001", "--out",
                   tmp_path / "cal", "--rrd", rrd, "--force")
    assert time.monotonic() - t0 < 30
    assert rc == 2
    line, = unwrap(err).splitlines()
    assert f"{rrd}: No space left on device" in line
    assert _tree(rrd.parent) == {"cal.rrd": b"previous recording"}
    assert _leftovers(tmp_path) == []


def test_working_directory_as_out_is_filled_in_place(tmp_path, monkeypatch):
    """``--out .``: the directory is not swapped (the shell would stay in the old one)."""
    target = tmp_path / "here"
    target.mkdir()
    (target / "a.txt").write_text("old")
    (target / "mine.txt").write_text("kept")
    inode = target.stat().st_ino
    monkeypatch.chdir(target)
    with atomic.atomic_dir(".", force=True, owned=["a.txt"]) as tmp:
        (tmp / "a.txt").write_text("new")
        (tmp / "sub").mkdir()
        (tmp / "sub" / "b.txt").write_text("b")
    assert target.stat().st_ino == inode
    assert _tree(target) == {"a.txt": b"new", "mine.txt": b"kept", "sub/b.txt": b"b"}
    assert sorted(os.listdir(tmp_path)) == ["here"]


def test_leftover_temporary_files_are_not_carried_into_the_new_set(tmp_path):
    target = tmp_path / "demo"
    target.mkdir()
    (target / ".demo.rrd.k2j4_x9q.tmp").write_bytes(b"7 MB of a killed recording")
    (target / ".report.md.123-abcdefgh.tmp").write_text("half")
    (target / "notes.txt").write_text("mine")
    with atomic.atomic_dir(target, force=True) as tmp:
        (tmp / "report.md").write_text("new")
    assert _tree(target) == {"notes.txt": b"mine", "report.md": b"new"}


def test_stale_file_of_a_dead_writer_is_removed_by_the_next_write(tmp_path):
    """A single file is written under its lock, so every temporary of that name is stale
    (no live run can own one); temporaries of other names are not touched."""
    dead = subprocess.Popen(["true"])
    dead.wait()
    stale = tmp_path / f".x.rrd.{dead.pid}-abcdefgh.tmp"
    stale.write_bytes(b"left by a kill")
    other = tmp_path / f".y.rrd.{os.getpid()}-abcdefgh.tmp"  # another target's: kept
    other.write_bytes(b"being written")
    atomic.write_bytes(tmp_path / "x.rrd", b"data")
    assert sorted(os.listdir(tmp_path)) == [other.name, "x.rrd"]
