"""Atomic outputs: one file, one directory (a *set* of files) and the lock between runs.

Guarantees (each writer here):

* **never half written** — everything goes to a hidden temporary name beside the target
  (``.NAME.PID-XXXXXXXX.tmp``, file or directory) and is renamed into place at the end, after
  the data and the directory entries are flushed to disk (``fsync`` of every file, then of
  the directories);
* **a set is replaced as a whole** — :func:`atomic_dir` swaps the old directory for the new
  one with one ``renameat2(RENAME_EXCHANGE)`` where the filesystem has it (at every instant
  the target is the old set or the new one); elsewhere with two renames (old → backup name,
  new → target; a run killed between them leaves the old set under the backup name and the
  next run puts it back);
* **one writer per target** — :func:`output_lock` takes a non-blocking ``flock`` on
  ``.NAME.lock`` beside the target; a second run fails at once with :class:`OutputBusyError`
  ("another tiltbench run is writing OUT (pid N)");
* **no leftovers** — every error path removes its temporary files; temporary names left by
  a killed run (its pid is gone, or we hold the target's lock) are removed by the next run;
* **errors name the target**, never a temporary name (a full disk reads
  ``OUT: No space left on device``).

Exception: a target that is a mount point or holds the working directory is not swapped;
its new files are renamed into it one by one (each file atomic, the set not).

Files that are not ours are kept: entries of an existing target directory that the new set
does not write are carried into it (hard links), except inside the ``exclusive`` folders,
which the new set replaces whole.
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import fcntl
import os
import re
import secrets
import shutil
import stat
import tempfile
import time
from collections.abc import Iterable, Iterator
from pathlib import Path

TMP_SUFFIX = ".tmp"
BACKUP_SUFFIX = ".bak.tmp"

_RENAME_EXCHANGE = 2
_AT_FDCWD = -100


class OutputBusyError(OSError):
    """Another process holds the lock of this output (message names it and the pid)."""


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _tmp_prefix(name: str) -> str:
    return f".{name}.{os.getpid()}-"


def _stale_pattern(name: str) -> re.Pattern:
    # ours: .NAME.PID-XXXXXXXX.tmp (and .bak.tmp); older versions: .NAME.XXXXXXXX.tmp
    return re.compile(rf"^\.{re.escape(name)}\.(?:(\d+)-[A-Za-z0-9_]+|[A-Za-z0-9_]{{8}})"
                      rf"(\.bak)?\.tmp$")


_ANY_TMP = re.compile(r"^\..+\.(?:\d+-[A-Za-z0-9_]+|[A-Za-z0-9_]{8})(?:\.bak)?\.tmp$")
"""Any of our temporary names (not carried into a new set)."""
LEGACY_AGE = 3600.0
"""Seconds after which a temporary name without a pid (older versions) counts as stale."""


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        with contextlib.suppress(FileNotFoundError):
            path.unlink()


def clean_stale(target: str | os.PathLike, locked: bool = False) -> list[Path]:
    """Remove temporary names of ``target`` left by killed runs; return what was removed.

    A temporary name is stale when the process named in it is gone (a name without a pid,
    from older versions: when untouched for :data:`LEGACY_AGE`), or when ``locked``
    (the caller holds :func:`output_lock` of ``target``, so no live run can own one). A
    backup of an interrupted swap is renamed back to ``target`` if ``target`` is missing.
    Best effort: what cannot be removed (a read-only directory) is left.
    """
    target = Path(target)
    parent = target.parent if str(target.parent) else Path(".")
    pattern = _stale_pattern(target.name)
    removed = []
    try:
        entries = sorted(os.listdir(parent))
    except OSError:
        return removed
    for entry in entries:
        m = pattern.match(entry)
        if not m:
            continue
        pid = m.group(1)
        path = parent / entry
        if not locked and pid is not None and _alive(int(pid)):
            continue
        if not locked and pid is None:
            with contextlib.suppress(OSError):
                if time.time() - os.lstat(path).st_mtime < LEGACY_AGE:
                    continue
        if m.group(2) and not os.path.lexists(target):
            with contextlib.suppress(OSError):
                os.rename(path, target)  # the old set of an interrupted swap
                _fsync_dir(parent)
                continue
        _remove(path)
        removed.append(path)
    return removed


def _named(exc: OSError, shown: str | os.PathLike, tmp: str | os.PathLike | None = None):
    """``exc`` naming ``shown`` (or the file under it) instead of a temporary name."""
    filename = exc.filename
    if tmp is not None and filename is not None and str(filename).startswith(str(tmp)):
        rel = os.path.relpath(filename, tmp)
        filename = str(shown) if rel == "." else os.path.join(str(shown), rel)
    elif tmp is None or filename is None:
        filename = str(shown)
    if isinstance(exc, OutputBusyError) or exc.errno is None or filename == exc.filename:
        return exc
    return type(exc)(exc.errno, exc.strerror or os.strerror(exc.errno), filename)


def _reraise(exc: OSError, shown, tmp=None):
    new = _named(exc, shown, tmp)
    if new is exc:
        raise exc
    raise new from exc


def _fsync_dir(path: str | os.PathLike) -> None:
    try:
        fd = os.open(path, os.O_RDONLY | os.O_DIRECTORY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError as exc:  # some filesystems cannot sync a directory: not an error
        if exc.errno not in (errno.EINVAL, errno.EBADF, errno.ENOTSUP):
            raise
    finally:
        os.close(fd)


def _fsync_tree(root: Path) -> None:
    """fsync every regular file under ``root``, then every directory (deepest first)."""
    dirs = []
    for here, _, files in os.walk(root):
        dirs.append(here)
        for f in files:
            p = os.path.join(here, f)
            if os.path.islink(p):
                continue
            fd = os.open(p, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
    for d in reversed(dirs):
        _fsync_dir(d)


def write_bytes(path: str | os.PathLike, data: bytes, force: bool = False) -> Path:
    """Write ``data`` to ``path`` atomically and durably (temporary file, fsync, rename).

    Refuses a directory (:class:`ValueError`) and an existing file unless ``force``
    (:class:`FileExistsError`). Stale temporary files of ``path`` left by killed runs are
    removed first. The file gets the mode a plain ``open()`` would give it.
    """
    path = Path(path)
    if path.is_dir():  # a ValueError, as calib.io.DataError: one line at the command line
        raise ValueError(f"{path}: is a directory; expected an output file name")
    if path.exists() and not force:
        raise FileExistsError(f"{path}: exists")
    parent = path.parent
    tmp = None
    try:
        parent.mkdir(parents=True, exist_ok=True)
        clean_stale(path)
        fd, tmp = tempfile.mkstemp(dir=parent, prefix=_tmp_prefix(path.name), suffix=TMP_SUFFIX)
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
            os.fchmod(fh.fileno(), 0o666 & ~_umask())  # mkstemp creates 0600
        os.replace(tmp, path)
        tmp = None
        _fsync_dir(parent)
    except OSError as exc:
        _reraise(exc, path)
    finally:
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
    return path


def write_text(path: str | os.PathLike, text: str, force: bool = False) -> Path:
    """:func:`write_bytes` of ``text`` in UTF-8."""
    return write_bytes(path, text.encode("utf-8"), force=force)


@contextlib.contextmanager
def output_lock(target: str | os.PathLike) -> Iterator[Path]:
    """Hold the exclusive lock of ``target`` (``.NAME.lock`` beside it; removed on release).

    Non-blocking: if another process holds it, raise :class:`OutputBusyError` at once. The lock
    is the kernel's ``flock``: a killed run releases it with its last file descriptor.
    """
    target = Path(target)
    real = Path(os.path.realpath(target))
    lock_path = real.parent / f".{real.name}.lock"
    while True:
        try:
            fd = os.open(lock_path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o666)
        except OSError as exc:
            _reraise(exc, target)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            try:
                pid = os.pread(fd, 32, 0).decode("ascii", "replace").strip() or "unknown"
            finally:
                os.close(fd)
            raise OutputBusyError(f"another tiltbench run is writing {target} (pid {pid}); "
                             "wait for it to end or choose another output") from None
        try:  # the holder before us may have removed the file: lock the one on disk
            same = os.path.samestat(os.fstat(fd), os.stat(lock_path))
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    try:
        with contextlib.suppress(OSError):  # the pid is for the message only (full disk)
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        yield lock_path
    finally:
        with contextlib.suppress(OSError):
            os.unlink(lock_path)
        os.close(fd)


def _exchange(a: Path, b: Path) -> bool:
    """Swap ``a`` and ``b`` atomically; False where the system or filesystem cannot."""
    try:
        fn = ctypes.CDLL(None, use_errno=True).renameat2
    except (AttributeError, OSError):
        return False
    fn.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    fn.restype = ctypes.c_int
    if fn(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP, errno.EOPNOTSUPP):
        return False
    raise OSError(err, os.strerror(err), str(b))


def _carry_over(old: Path, new: Path, exclusive: set[str], rel: str = "") -> None:
    """Hard-link (else copy) into ``new`` every entry of ``old`` that ``new`` does not have."""
    for entry in os.scandir(old):
        if _ANY_TMP.match(entry.name):  # a killed writer's leftover: dropped with the old set
            continue
        r = f"{rel}{entry.name}"
        dst = new / entry.name
        if entry.is_dir(follow_symlinks=False):
            if r in exclusive and dst.exists():
                continue
            if not dst.exists():
                dst.mkdir()
                shutil.copymode(entry.path, dst)
            elif not dst.is_dir() or dst.is_symlink():
                continue
            _carry_over(Path(entry.path), dst, exclusive, r + "/")
        elif not os.path.lexists(dst):
            if entry.is_symlink():
                os.symlink(os.readlink(entry.path), dst)
                continue
            try:
                os.link(entry.path, dst, follow_symlinks=False)
            except OSError:
                shutil.copy2(entry.path, dst, follow_symlinks=False)


def _commit(tmp: Path, real: Path) -> None:
    """Put the finished ``tmp`` at ``real`` (replacing an old directory as a whole)."""
    parent = real.parent
    if not real.exists():
        os.chmod(tmp, 0o777 & ~_umask())
        os.rename(tmp, real)
        _fsync_dir(parent)
        return
    os.chmod(tmp, stat.S_IMODE(os.stat(real).st_mode))
    if _exchange(tmp, real):  # tmp now holds the old set
        _fsync_dir(parent)
        shutil.rmtree(tmp, ignore_errors=True)
        return
    backup = parent / f"{_tmp_prefix(real.name)}{secrets.token_hex(4)}{BACKUP_SUFFIX}"
    os.rename(real, backup)
    try:
        os.rename(tmp, real)
    except BaseException:
        os.rename(backup, real)  # restore the old set
        raise
    _fsync_dir(parent)
    shutil.rmtree(backup, ignore_errors=True)


def _holds_cwd(path: Path) -> bool:
    try:
        cwd = Path(os.getcwd())
    except OSError:
        return False
    return cwd == path or path in cwd.parents


def _commit_in_place(tmp: Path, real: Path, exclusive: set[str]) -> None:
    """Move the new entries into ``real`` one file at a time (each rename atomic, the set
    not): for a target that cannot be swapped (a mount point, the working directory)."""
    for rel in sorted(exclusive):
        old, new = real / rel, tmp / rel
        if new.is_dir() and old.is_dir() and not old.is_symlink():
            for entry in os.listdir(old):
                if not os.path.lexists(new / entry):
                    _remove(old / entry)
    for here, _dirs, files in os.walk(tmp):
        rel = Path(here).relative_to(tmp)
        (real / rel).mkdir(exist_ok=True)
        for f in files:
            os.replace(Path(here) / f, real / rel / f)
        _fsync_dir(real / rel)
    shutil.rmtree(tmp, ignore_errors=True)


@contextlib.contextmanager
def atomic_dir(target: str | os.PathLike, force: bool = False, owned: Iterable[str] = (),
               exclusive: Iterable[str] = ()) -> Iterator[Path]:
    """Write a set of files as a whole: yields an empty temporary directory beside ``target``.

    Write everything into the yielded directory; on normal exit it is flushed and replaces
    ``target`` in one step (see the module docstring); on any error (or interrupt) it is
    removed and ``target`` is untouched. The target's lock is held throughout
    (:class:`OutputBusyError` if another run writes it).

    Parameters
    ----------
    target : the output directory (created if missing; its parents too).
    force : replace the ``owned`` entries if they exist; else :class:`FileExistsError`
        (checked under the lock, before anything is written).
    owned : relative paths the set writes (the overwrite check).
    exclusive : relative folders replaced whole: nothing of the old one is carried over.
    """
    shown = Path(target)
    real = Path(os.path.realpath(shown))
    if real.exists() and not real.is_dir():
        raise NotADirectoryError(errno.ENOTDIR, "exists and is not a directory", str(shown))
    try:
        real.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        _reraise(exc, shown)
    # A target that cannot be renamed (a mount point) or that holds the working directory
    # (the shell would be left in the removed old one) gets its new files one by one, from a
    # temporary directory inside it: each file atomic, the set not.
    in_place = real.is_dir() and (os.path.ismount(real) or _holds_cwd(real))
    tmp_parent = real if in_place else real.parent
    with output_lock(shown):
        clean_stale(real, locked=True)
        if in_place:
            clean_stale(real / real.name, locked=True)
        if not force and real.is_dir():
            clash = [n for n in owned if os.path.lexists(real / n)]
            if clash:
                raise FileExistsError(f"{shown}: {', '.join(clash[:4])}"
                                      f"{' …' if len(clash) > 4 else ''} already exist(s)")
        try:
            tmp = Path(tempfile.mkdtemp(dir=tmp_parent, prefix=_tmp_prefix(real.name),
                                        suffix=TMP_SUFFIX))
        except OSError as exc:
            _reraise(exc, shown)
        try:
            yield tmp
            if in_place:
                _fsync_tree(tmp)
                _commit_in_place(tmp, real, set(exclusive))
            else:
                if real.is_dir():
                    _carry_over(real, tmp, set(exclusive))
                _fsync_tree(tmp)
                _commit(tmp, real)
        except OSError as exc:
            shutil.rmtree(tmp, ignore_errors=True)
            _reraise(exc, shown, tmp)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise


__all__ = ["OutputBusyError", "atomic_dir", "clean_stale", "output_lock", "write_bytes",
           "write_text"]
