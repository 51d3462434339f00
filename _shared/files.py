"""Atomic file writing and honest write errors, shared by every package that writes files.

- `atomic_path`: a context manager giving a temporary name beside the output (``.NAME.PID.part``
  plus the output's suffix); on success the file is fsynced and renamed over the output (and the
  folder fsynced), on any error it is removed, so the output is either the old file or the new one.
- `refuse_overwriting_inputs`: raises before any work when an output is one of the command's inputs.
- `write_error`: an `OSError` raised while writing, re-raised as what it is ("disk full while
  writing X", "permission denied writing X").
- `remove_stale_temporaries`: the temporaries of an output left by killed writers (SIGKILL, power
  cut) are removed when the output is next written.
- `hdf5_in_memory`: an HDF5 file built in memory and written by Python, so a full disk is an
  `OSError` rather than a crash inside HDF5.
- `cut_short`: whether an HDF5 file failed to open because it is shorter than its header says (an
  interrupted copy or write), so readers say that rather than "not an HDF5 file".
- `stream_target`, `publish`: an output that is not a regular file (``-`` for stdout, ``/dev/null``,
  a terminal, a FIFO with a reader, ``/dev/stdout`` and other links to them) is written in place by
  streaming the finished temporary file into it, never renamed over; a block device, a socket or a
  FIFO nobody reads is refused at once (it would be destroyed, or the write would hang). A symlink
  to a regular file is followed: the file it points to is replaced and the link kept.
"""

from __future__ import annotations

import contextlib
import errno
import glob
import os
import pathlib
import re
import shutil
import stat
import sys
import tempfile
from typing import Iterable, Iterator

__all__ = ["atomic_path", "refuse_overwriting_inputs", "write_error", "fsync_path", "temporary_name", "cut_short",
           "remove_stale_temporaries", "hdf5_in_memory", "stream_target", "output_temporary", "publish", "discard_temporary"]

_WHAT = {
    errno.ENOSPC: "disk full while writing",
    errno.EDQUOT: "disk quota exceeded while writing",
    errno.EFBIG: "file size limit reached while writing",
    errno.EACCES: "permission denied writing",
    errno.EPERM: "permission denied writing",
    errno.EROFS: "read-only file system: cannot write",
    errno.EIO: "input/output error while writing",
}


def write_error(exc: BaseException, path) -> OSError:
    """The `OSError` to raise for ``exc``, an error met while writing ``path``, named for what it is.

    Parameters
    ----------
    exc : BaseException
        The error met (an `OSError`, or an h5py/SQLite error carrying ``errno`` or a message).
    path : str or os.PathLike
        The output being written (the final name, not its temporary one).

    Returns
    -------
    OSError
        With the errno of ``exc`` (``ENOSPC`` recognised from an HDF5 or SQLite message too) and a
        message such as ``"disk full while writing 'out/model.h5'"``.
    """
    code = getattr(exc, "errno", None)
    text = str(exc)
    if code not in _WHAT:
        lowered = text.lower()
        if "no space left" in lowered or "disk is full" in lowered or "errno = 28" in lowered:
            code = errno.ENOSPC
        elif "permission denied" in lowered or "errno = 13" in lowered or "readonly" in lowered:
            code = errno.EACCES
        elif "errno = 27" in lowered or "file too large" in lowered:
            code = errno.EFBIG
    what = _WHAT.get(code)
    if what is None:
        strerror = getattr(exc, "strerror", None) or " ".join(text.split()) or type(exc).__name__
        return OSError(code or errno.EIO, f"cannot write {str(path)!r}: {strerror}")
    return OSError(code, f"{what} {str(path)!r}")


def cut_short(exc: BaseException) -> tuple[int, int] | None:
    """``(size, expected)`` in bytes when ``exc``, raised opening an HDF5 file, says the file is truncated.

    Parameters
    ----------
    exc : BaseException
        The error of ``h5py.File(...)``.

    Returns
    -------
    tuple of int or None
        The file's size and the size its header records, or None for any other error.
    """
    found = re.search(r"truncated file: eof = (\d+).*stored_eof = (\d+)", str(exc).lower())
    if found and int(found.group(2)) > int(found.group(1)):
        return int(found.group(1)), int(found.group(2))
    return None


def stream_target(path) -> bool:
    """Whether ``path`` is an output to stream into rather than replace: not a regular file (or none).

    ``-`` (standard output), a character device (``/dev/null``, a terminal), a FIFO with a reader, and
    links to them (``/dev/stdout``) are streamed into. A missing path, a regular file or a link to one
    is replaced atomically.

    Raises
    ------
    OSError
        A block device or a socket (``"... is a block device: refusing to write a file onto it"``).
        (A FIFO is not probed for a reader here: opening and closing its write end would end the
        reader's stream; `publish` finds out.)
    """
    if str(path) == "-":
        return True
    try:
        mode = os.stat(path).st_mode                                   # follows links, as opening does
    except FileNotFoundError:
        return False
    except OSError as exc:
        raise OSError(exc.errno, f"cannot write {str(path)!r} ({exc.strerror})") from None
    if stat.S_ISREG(mode) or stat.S_ISDIR(mode):
        return False
    if stat.S_ISBLK(mode) or stat.S_ISSOCK(mode):
        kind = "a block device" if stat.S_ISBLK(mode) else "a socket"
        raise OSError(errno.EINVAL, f"output {str(path)!r} is {kind}: refusing to write a file onto it; "
                                    f"choose a file name")
    return True


def output_temporary(path, suffix: str | None = None) -> pathlib.Path:
    """Where an output is built before `publish`: ``.STEM.PID.partSUFFIX`` beside a file (same file
    system, so the rename is atomic; missing folders are created), or in a private temporary folder for a
    stream (nothing is ever created beside ``/dev/null`` or a FIFO). A symlink to a file is followed."""
    path = pathlib.Path(path)
    if stream_target(path):
        name = pathlib.Path("stdout" if str(path) == "-" else path.name)
        return pathlib.Path(tempfile.mkdtemp(prefix=_STREAM_FOLDER)) / temporary_name(name, suffix).name
    target = _followed(path)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)   # `--out out/model.h5` in a fresh folder
    except FileExistsError:
        raise NotADirectoryError(errno.ENOTDIR, f"cannot write {str(path)!r}: {str(target.parent)!r} is a file, "
                                                f"not a folder") from None
    except OSError as exc:
        raise OSError(exc.errno, f"cannot write {str(path)!r} ({exc.strerror})") from None
    return temporary_name(target, suffix)


def discard_temporary(tmp: pathlib.Path) -> None:
    """Remove an unfinished temporary output (and the private folder of a stream's); never raises."""
    tmp = pathlib.Path(tmp)
    with contextlib.suppress(OSError):
        tmp.unlink(missing_ok=True)
    if tmp.parent.name.startswith(_STREAM_FOLDER):
        with contextlib.suppress(OSError):
            tmp.parent.rmdir()


_STREAM_FOLDER = "tactip-out-"


def _followed(path: pathlib.Path) -> pathlib.Path:
    """A symlink's final target (so it is replaced, not the link); other paths as they are."""
    return path.resolve() if path.is_symlink() else path


def publish(tmp: pathlib.Path, path) -> None:
    """Put the finished temporary ``tmp`` in place of ``path``: fsync and rename for a file, copy its
    bytes into a stream (`stream_target`) and remove it and its private folder.

    Raises
    ------
    OSError
        Named by `write_error` ("disk full while writing X", ...); a FIFO that no process reads (the
        write would wait for ever) is refused at once, and the finished output is kept where the
        message says.
    """
    path = pathlib.Path(path)
    try:
        if stream_target(path):
            out = _open_stream(path, tmp)
            try:
                with open(tmp, "rb") as source, out:
                    shutil.copyfileobj(source, out)
                    out.flush()
            except BrokenPipeError:  # the reader went away (| head): what it wanted it has
                pass
            tmp.unlink(missing_ok=True)
            with contextlib.suppress(OSError):
                tmp.parent.rmdir()
            return
        target = _followed(path)
        fsync_path(tmp)
        os.replace(tmp, target)
        fsync_path(target.parent if str(target.parent) else pathlib.Path("."), folder=True)
    except OSError as exc:
        raise write_error(exc, path) from None


def _open_stream(path: pathlib.Path, tmp: pathlib.Path):
    """A binary file object writing into a stream output (stdout for ``-``); a FIFO without a reader is an error."""
    if str(path) == "-":
        sys.stdout.flush()
        return os.fdopen(os.dup(sys.stdout.fileno()), "wb")
    if stat.S_ISFIFO(os.stat(path).st_mode):
        try:
            fd = os.open(path, os.O_WRONLY | os.O_NONBLOCK)
        except OSError as exc:
            if exc.errno != errno.ENXIO:
                raise
            raise OSError(errno.ENXIO, f"output {str(path)!r} is a FIFO that no process is reading (the write "
                                       f"would wait for ever); the result is kept in {str(tmp)!r}") from None
        os.set_blocking(fd, True)
        return os.fdopen(fd, "wb")
    return open(path, "wb")


def temporary_name(path: pathlib.Path, suffix: str | None = None) -> pathlib.Path:
    """``.STEM.PID.partSUFFIX`` beside ``path`` (hidden, per process, keeping a suffix writers need)."""
    path = pathlib.Path(path)
    tail = f".{os.getpid()}.part{path.suffix if suffix is None else suffix}"
    stem = path.stem
    # A name near the file system's 255-byte limit leaves no room for the temporary's: shorten its stem.
    while len(f".{stem}{tail}".encode()) > 255 and stem:
        stem = stem[:-1]
    return path.with_name(f".{stem}{tail}")


def remove_stale_temporaries(path) -> list[pathlib.Path]:
    """Remove the temporaries of ``path`` left by writers that were killed (SIGKILL, a power cut).

    A temporary ``.STEM.PID.part*`` whose process no longer runs on this machine can never be renamed
    into place; the next write of ``path`` removes it. Temporaries of live processes are kept.

    Parameters
    ----------
    path : str or os.PathLike
        The output about to be written.

    Returns
    -------
    list of pathlib.Path
        The temporaries removed.
    """
    path = pathlib.Path(path)
    prefix = temporary_name(path, "").name.rsplit(".", 2)[0] + "."      # ".STEM."
    removed = []
    try:
        candidates = list(path.parent.glob(f"{glob.escape(prefix)}*.part*"))
    except OSError:
        return removed
    for candidate in candidates:
        pid = candidate.name[len(prefix):].split(".", 1)[0]
        if not pid.isdigit() or int(pid) == os.getpid() or _process_alive(int(pid)):
            continue
        with contextlib.suppress(OSError):
            candidate.unlink()
            removed.append(candidate)
    return removed


def _process_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True
    return True


@contextlib.contextmanager
def hdf5_in_memory(path) -> Iterator:
    """An HDF5 file built in memory and written to ``path`` by Python when the block ends.

    HDF5 that meets a full disk while flushing at close can crash the process (a segfault in
    h5py's cleanup): building the file in memory and writing its bytes with Python makes a full
    disk an ordinary `OSError` (ENOSPC) that `atomic_path` names. For files written whole
    (models, calibrations, datasets, replays), which are in memory anyway.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write (usually `atomic_path`'s temporary name).

    Yields
    ------
    h5py.File
        Open for writing.
    """
    import io

    import h5py

    buffer = io.BytesIO()
    with h5py.File(buffer, "w") as f:
        yield f
    with open(path, "wb") as out:
        out.write(buffer.getbuffer())


def fsync_path(path: pathlib.Path, *, folder: bool = False) -> None:
    """Flush a file (or, with ``folder``, a folder's entries) to the disk."""
    fd = os.open(path, os.O_RDONLY | (getattr(os, "O_DIRECTORY", 0) if folder else 0))
    try:
        os.fsync(fd)
    except OSError:
        if not folder:  # some file systems cannot fsync a folder; a file must be flushed
            raise
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_path(path, *, suffix: str | None = None, inputs: Iterable = ()) -> Iterator[pathlib.Path]:
    """Write ``path`` atomically: yield a temporary name, then fsync and rename it over ``path``.

    Parameters
    ----------
    path : str or os.PathLike
        The final output file; replaced only when the body finishes without error.
    suffix : str, optional
        Suffix of the temporary file (default ``path``'s), for writers that pick a format by suffix.
    inputs : iterable of path
        Files the command reads: ``path`` must not be one of them (`refuse_overwriting_inputs`).

    Yields
    ------
    pathlib.Path
        The temporary file to write (it does not exist yet).

    Raises
    ------
    OSError
        A write error, named for what it is (`write_error`); the temporary file is removed and
        ``path`` keeps its old content.
    """
    path = pathlib.Path(path)
    refuse_overwriting_inputs([path], inputs)
    if path.is_dir():
        raise IsADirectoryError(errno.EISDIR, f"output path {str(path)!r} is a directory")
    streamed = stream_target(path)
    tmp = output_temporary(path, suffix)
    if not streamed:
        remove_stale_temporaries(_followed(path))
    kept = False
    try:
        try:
            yield tmp
        except OSError as exc:
            if _is_write_error(exc):
                raise write_error(exc, path) from None
            raise
        try:
            publish(tmp, path)
        except OSError as exc:
            kept = exc.errno == errno.ENXIO and streamed        # a FIFO without a reader: the result is kept
            raise
    finally:
        if not kept:
            with contextlib.suppress(OSError):
                tmp.unlink()
        if streamed and not kept:
            with contextlib.suppress(OSError):
                tmp.parent.rmdir()


def _is_write_error(exc: OSError) -> bool:
    text = str(exc).lower()
    return exc.errno in _WHAT or "write failed" in text or "no space" in text or "errno = 28" in text


def _same_file(a: pathlib.Path, b: pathlib.Path) -> bool:
    try:
        if a.resolve() == b.resolve():
            return True
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def refuse_overwriting_inputs(outputs: Iterable, inputs: Iterable) -> None:
    """Raise `FileExistsError` when an output is one of the inputs, or two outputs are one file.

    Compares resolved paths and, for existing files, `os.path.samefile` (hard links, symlinks).

    Parameters
    ----------
    outputs : iterable of path or None
        Files the command writes (None entries are skipped).
    inputs : iterable of path or None
        Files the command reads (None entries, and non-path inputs such as a camera index, are skipped).

    Raises
    ------
    FileExistsError
        ``"output 'X' is the input 'Y': writing it would destroy the input; choose another output"``.
    """
    outs = [pathlib.Path(p) for p in outputs if isinstance(p, (str, os.PathLike))]
    ins = [pathlib.Path(p) for p in inputs if isinstance(p, (str, os.PathLike))]
    for k, out in enumerate(outs):
        for other in ins:
            if _same_file(out, other):
                raise FileExistsError(errno.EEXIST, f"output {str(out)!r} is the input {str(other)!r}: writing it "
                                                    f"would destroy the input; choose another output")
        for other in outs[k + 1:]:
            if _same_file(out, other):
                raise FileExistsError(errno.EEXIST, f"outputs {str(out)!r} and {str(other)!r} are the same file; "
                                                    f"choose two different outputs")

