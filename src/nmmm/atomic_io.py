"""Outputs that are either complete or absent: atomic files, atomic output folders, folder locks.

- :func:`atomic_path` — a context manager yielding a temporary path beside a target file; the
  temporary file replaces the target (``os.replace``, atomic on one file system) only when the
  block ends without an exception, and is removed otherwise.
- :func:`atomic_write_text`, :func:`atomic_write_bytes` — a whole file at once through
  :func:`atomic_path`.
- :func:`folder_lock` — an exclusive, non-blocking lock on an output folder (``fcntl.flock`` on
  a hidden lock file beside it, released by the kernel if the process dies): a second run into a
  folder in use is refused with :class:`~nmmm.errors.InvalidInputError` naming the folder.
- :func:`atomic_output_dir` — a context manager for a run's output folder: the run writes into
  a temporary folder beside the target under the folder's lock; on success the temporary folder
  becomes the target (renamed when the target does not exist; otherwise its files are moved in
  one by one and the files a previous nmmm run left there but this one did not write are
  removed, as listed by the ``.nmmm-outputs.json`` manifest written last); on failure the
  temporary folder is removed, so nothing that looks complete is left behind.
- :func:`sha256_file` — the SHA-256 hex digest of a file (sweep manifests).

A disk that fills up mid-write raises :class:`~nmmm.errors.DataFileError` naming the file and
the cause (``No space left on device``) instead of leaving a truncated file in place.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import shutil
import socket
import tempfile
from pathlib import Path

from nmmm.errors import DataFileError, InvalidInputError

__all__ = ["atomic_path", "atomic_write_text", "atomic_write_bytes", "folder_lock", "atomic_output_dir",
           "sha256_file", "MANIFEST_NAME"]

#: the file, written last into an output folder, that lists what a run wrote
MANIFEST_NAME = ".nmmm-outputs.json"


def _write_error(path, exc: OSError) -> DataFileError:
    return DataFileError(f"cannot write {str(path)!r}: {exc.strerror or exc} (free space or choose another "
                         "output folder; nothing incomplete was left under that name)")


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _plain_mode(path: Path, default: int) -> int:
    """The mode a file or folder written at ``path`` gets: that of the one it replaces, else
    ``default & ~umask`` (as ``open``/``mkdir`` would give; mkstemp/mkdtemp give 0600/0700)."""
    try:
        return path.stat().st_mode & 0o7777
    except OSError:
        return default & ~_umask()


@contextlib.contextmanager
def atomic_path(path):
    """Yield a temporary path beside ``path``; it replaces ``path`` when the block succeeds."""
    p = Path(path)
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".part" + p.suffix, dir=p.parent)
        os.close(fd)
    except OSError as exc:
        raise _write_error(p, exc) from None
    tmp = Path(tmp)
    try:
        yield tmp
        if tmp.exists():
            os.chmod(tmp, _plain_mode(p, 0o666))
        os.replace(tmp, p)
    except OSError as exc:
        raise _write_error(p, exc) from None
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink()


def atomic_write_bytes(path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically (complete, or the old file untouched)."""
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
    return Path(path)


def atomic_write_text(path, text: str, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` atomically."""
    return atomic_write_bytes(path, text.encode(encoding))


def sha256_file(path, chunk: int = 1 << 20) -> str:
    """SHA-256 hex digest of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(chunk), b""):
            h.update(block)
    return h.hexdigest()


def _lock_file(folder: Path) -> Path:
    folder = Path(os.path.abspath(folder))
    return folder.parent / f".{folder.name}.nmmm-lock"


@contextlib.contextmanager
def folder_lock(folder):
    """Hold an exclusive lock on ``folder`` (which need not exist yet) for the block.

    Raises :class:`InvalidInputError` at once when another process holds it.
    """
    folder = Path(folder)
    lock = _lock_file(folder)
    try:
        lock.parent.mkdir(parents=True, exist_ok=True)
        fh = open(lock, "a+")
    except OSError as exc:
        raise DataFileError(f"cannot create the output folder {str(folder)!r}: {exc.strerror or exc}") from None
    try:
        try:
            import fcntl
        except ImportError:  # pragma: no cover - not POSIX: no locking
            fcntl = None
        if fcntl is not None:
            try:
                fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                fh.seek(0)
                who = fh.read().strip() or "another process"
                raise InvalidInputError(
                    f"output folder {str(folder)!r} is in use by another nmmm run ({who}); wait until it "
                    "finishes or give another output folder (-o)") from None
        fh.seek(0)
        fh.truncate()
        fh.write(f"pid {os.getpid()} on {socket.gethostname()}")
        fh.flush()
        yield
    finally:
        fh.close()


def _previous_outputs(target: Path) -> list[str]:
    try:
        return list(json.loads((target / MANIFEST_NAME).read_text(encoding="utf-8")).get("files", []))
    except (OSError, ValueError, AttributeError):
        return []


@contextlib.contextmanager
def atomic_output_dir(target, lock: bool = True):
    """Yield a temporary folder beside ``target``; it becomes ``target`` when the block succeeds.

    See the module docstring for what happens to an existing ``target``.
    """
    target = Path(target)
    ctx = folder_lock(target) if lock else contextlib.nullcontext()
    with ctx:
        if target.exists() and not target.is_dir():
            raise InvalidInputError(f"output {str(target)!r} exists and is a file; give a folder (-o)")
        try:
            target.parent.mkdir(parents=True, exist_ok=True)
            tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.incomplete-", dir=target.parent))
        except OSError as exc:
            raise DataFileError(f"cannot create the output folder {str(target)!r}: {exc.strerror or exc}") from None
        try:
            yield tmp
            files = sorted(str(p.relative_to(tmp)) for p in tmp.rglob("*") if p.is_file())
            (tmp / MANIFEST_NAME).write_text(json.dumps({"files": files}, indent=1), encoding="utf-8")
            if not target.exists():
                os.chmod(tmp, _plain_mode(target, 0o777))
                os.replace(tmp, target)
            else:
                old = _previous_outputs(target)
                for rel in files + [MANIFEST_NAME]:
                    dst = target / rel
                    dst.parent.mkdir(parents=True, exist_ok=True)
                    if dst.is_dir():
                        shutil.rmtree(dst)
                    os.replace(tmp / rel, dst)
                for rel in set(old) - set(files):
                    with contextlib.suppress(OSError):
                        (target / rel).unlink()
        except OSError as exc:
            raise _write_error(target, exc) from None
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
