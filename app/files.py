"""Files theoria writes (a recording, an HTML export): whole or absent.

`check_out` validates the target before any simulation runs (its directory exists and takes a
new file, it is not a directory, it has the suffix `theoria replay` reads, and an existing file
is replaced only when asked). `write_whole` writes the bytes to a temporary file beside the
target (`.NAME.XXXX.part`: same directory, so the rename cannot cross file systems), flushes it
to disk, checks its size and renames it over the target. Until that rename the target is
untouched: an older file stays as it was. On a full disk, any other write error, Ctrl-C or
SIGTERM the temporary file is removed and the error raised (`WriteError`: one line). A stop that
comes during the rename waits for it; one that comes after it finds the file in place and whole,
and the command line reports it written (`written_whole`), not as a stop that changed nothing.
The bytes are produced in memory before the write, so no library's own file sink is involved
(rerun's blocks forever in its flush on a full disk).
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

from ..physics.errors import ParameterError
from .interrupt import signals_held, sigterm_raises

CHUNK = 1 << 20  # bytes per write call
# the targets this process has put in place whole: a command stopped after the rename reports the
# file as written (it is, and whole), not as an interruption that changed nothing
_WRITTEN: set[str] = set()
# the targets `check_out` found absent without being told to replace them: put in place only while
# still absent (a file made there during a run of hours is not replaced without --force either)
_NEW_ONLY: dict[str, str] = {}  # key → how to ask for the replacement


class WriteError(OSError):
    """The file could not be written; the target is as it was. Message: one line; `errno` the
    system's reason when there was one (ENOSPC for a full disk), as an OSError carries it."""

    def __init__(self, message: str, errno: int | None = None):
        super().__init__(message)
        self.errno = errno


def check_out(path: str | os.PathLike, suffixes: tuple[str, ...], force: bool = False, what: str = "--out",
              reader: str = "theoria replay") -> Path:
    """The target path, validated before a run: ParameterError naming `what` when its directory
    is missing or does not take a new file, when it is a directory, has another suffix than
    `suffixes`, or exists and `force` is not given."""
    try:
        raw = os.fspath(path)
    except TypeError:
        raw = None
    if not isinstance(raw, str):
        raise ParameterError(what, repr(path), "a file name: text or a pathlib.Path")
    if not raw or raw.endswith(os.sep) or (os.altsep and raw.endswith(os.altsep)):
        raise ParameterError(what, str(path), "a file name, not a directory")
    if "\0" in raw:  # no system takes it (the file calls raised ValueError)
        raise ParameterError(what, repr(raw), "a file name without a NUL character")
    p = Path(raw).expanduser()
    try:
        p.lstat()
    except FileNotFoundError:
        pass
    except OSError as e:  # a name too long for the file system, a loop of links
        raise ParameterError(what, str(path), f"a path this system takes ({e.strerror or type(e).__name__})") from None
    if p.is_dir():
        raise ParameterError(what, str(path), "a file, not a directory")
    if p.suffix.lower() not in suffixes:
        raise ParameterError(what, str(path), "a file name ending in " + " or ".join(suffixes) +
                             (f" (what {reader} reads)" if reader else ""))
    parent = p.resolve().parent
    if not parent.is_dir():
        raise ParameterError(what, str(path), f"a file in an existing directory ({parent} does not exist)")
    if p.exists() and not p.is_file():
        raise ParameterError(what, str(path), "a regular file (this is a device, a pipe or a socket)")
    if p.exists() and not force:
        raise ParameterError(what, str(path), "a new file: it exists; " +
                             ("add --force to replace it" if what.startswith("--") else "force=True replaces it"))
    if force:
        _NEW_ONLY.pop(_written_key(p), None)
    else:
        _NEW_ONLY[_written_key(p)] = "add --force to replace it" if what.startswith("--") else "force=True replaces it"
    try:  # the only sure test that the directory takes a new file (read-only mounts, permissions, ACLs)
        with tempfile.NamedTemporaryFile(dir=parent, prefix=f".{p.name}.", suffix=".probe"):
            pass
    except OSError as e:
        raise ParameterError(what, str(path), f"a file in a writable directory ({parent}: "
                             f"{e.strerror or type(e).__name__})") from None
    return p


def _mode_for(target: Path) -> int:
    try:
        return target.stat().st_mode & 0o7777  # a replaced file keeps its permissions
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        n = os.write(fd, view[:CHUNK])
        view = view[n:]


def _written_key(path: str | os.PathLike) -> str:
    target = Path(os.fspath(path).rstrip("/" + os.sep) or os.sep).expanduser()
    return str((target.resolve() if target.is_symlink() else target).absolute())


def mark_written(path: str | os.PathLike) -> None:
    """Note that this process has put a whole result in place at `path` (a file by `write_whole`,
    a sweep's store or table by its writer)."""
    _WRITTEN.add(_written_key(path))


def written_whole(path: str | os.PathLike) -> bool:
    """Whether this process has put a whole result in place at `path` (`mark_written`)."""
    return _written_key(path) in _WRITTEN


class AppearedMeanwhile(FileExistsError):
    pass


def _put(tmp: str, target: Path, new_only: str | None) -> None:
    """The temporary file becomes `target`. With `new_only` (how to ask for a replacement), only
    while no file is there: a hard link makes the name or fails if it exists, in one step (where
    the file system has no hard links, the name is looked at just before the rename)."""
    if new_only is None:
        os.replace(tmp, target)
        return
    appeared = AppearedMeanwhile(0, f"a file appeared there during the run; it was left as it is ({new_only})")
    try:
        os.link(tmp, target)
    except FileExistsError:
        raise appeared from None
    except OSError:
        if os.path.lexists(target):
            raise appeared from None
        os.replace(tmp, target)
        return
    os.unlink(tmp)


def write_whole(path: str | os.PathLike, data: bytes) -> int:
    """Write `data` to `path` whole or not at all (see the module). Returns the bytes written."""
    target = Path(os.fspath(path)).expanduser()
    if target.is_symlink():  # replace the file the link points to; the link stays
        target = target.resolve()
    mode = _mode_for(target)
    fd, tmp = -1, None
    with sigterm_raises():
        try:
            fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".part", dir=target.parent)
            _write_all(fd, data)
            os.fsync(fd)
            size = os.fstat(fd).st_size
            if size != len(data):
                raise OSError(0, f"short write ({size} of {len(data)} bytes)")
            os.fchmod(fd, mode)
            os.close(fd)
            fd = -1
            with signals_held():  # the rename and the note that it happened are not cut apart
                _put(tmp, target, _NEW_ONLY.get(_written_key(path)))
                tmp = None
                mark_written(target)
                _NEW_ONLY.pop(_written_key(path), None)
        except BaseException as e:
            if fd >= 0:
                os.close(fd)
            if tmp is not None:
                try:
                    os.unlink(tmp)
                except OSError:
                    pass
            if isinstance(e, AppearedMeanwhile):
                raise WriteError(f"{path}: {e.strerror}; the new result was not written", e.errno) from None
            if isinstance(e, OSError):
                reason = e.strerror or str(e) or type(e).__name__
                raise WriteError(f"{path}: cannot write ({reason}); nothing was changed", e.errno) from None
            raise
    try:  # the rename itself is durable once the directory is
        dfd = os.open(target.parent, os.O_RDONLY)
        try:
            os.fsync(dfd)
        finally:
            os.close(dfd)
    except OSError:
        pass
    return len(data)
