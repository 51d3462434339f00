"""Output files: written under a temporary name, fsynced and renamed at the end, never over an input.

Every command that writes a file goes through these helpers (the logic lives in `_shared`, the
shared leaf every package may import, so that calibration and perception use it too):

- `claim_output`: create the temporary file early, so an unwritable output fails before the work;
- `atomic_output`: a context manager yielding the temporary name, renamed over the output on success;
- `write_text_atomic`: a whole text file at once;
- `publish`, `discard_temporary`: put a finished temporary in place (renamed over a file, streamed into
  ``-``, ``/dev/null``, a terminal or a FIFO: never renamed over a device), or remove an unfinished one;
- `refuse_overwriting_inputs`: no output may be one of the command's inputs (resolved paths, samefile);
- `write_error`: a write error named for what it is ("disk full while writing X");
- `write_json`: a command's JSON report, to standard output (``-``) or a file, the same in every command;
- `project_file`, `refuse_replacing_project_files`: a file the project wrote (a model, a calibration,
  collected taps, a replay, a results database, a station TOML), recognised by its content, is replaced
  only with ``--overwrite``, whatever the command; a new path or a foreign file is written as before;
- `check_video_written`, `out_of_space`: OpenCV's video writer ignores write errors, so a video is
  watched while written (free space, size limit) and read back, its frames counted, before it is
  renamed into place.
"""

from __future__ import annotations

import errno
import os
import pathlib

from _shared import atomic_path as atomic_output
from _shared import (discard_temporary, output_temporary, publish, refuse_overwriting_inputs, remove_stale_temporaries,
                     stream_target, write_error)

__all__ = ["write_json", "project_file", "refuse_replacing_project_files", "claim_output", "atomic_output", "write_text_atomic", "refuse_overwriting_inputs", "write_error",
           "check_video_written", "out_of_space", "publish", "discard_temporary"]


def claim_output(path: pathlib.Path, suffix: str | None = None) -> pathlib.Path:
    """Create the temporary file ``path`` will be renamed from; fails early if ``path`` is not writable.

    Parameters
    ----------
    path : pathlib.Path
        The final output file.
    suffix : str, optional
        Suffix of the temporary file (default ``path``'s), so writers that pick a format by suffix work.

    Returns
    -------
    pathlib.Path
        ``.STEM.PID.partSUFFIX`` beside ``path`` (in a private temporary folder when ``path`` is a
        stream such as ``/dev/null`` or ``-``); the caller puts it in place with `publish` or
        removes it with `discard_temporary`.
    """
    path = pathlib.Path(path)
    if path.is_dir():
        raise IsADirectoryError(21, "output path is a directory", str(path))
    part = output_temporary(path, suffix)
    if not stream_target(path):
        remove_stale_temporaries(path)  # left by a writer that was killed
    try:
        with open(part, "wb"):
            pass
    except OSError as exc:
        raise OSError(exc.errno, f"cannot write {str(path)!r} ({exc.strerror})") from None
    return part


def write_text_atomic(path, text: str, *, inputs=()) -> pathlib.Path:
    """Write ``text`` (UTF-8) to ``path`` atomically, refusing to overwrite one of ``inputs``; returns ``path``.

    On a write error (disk full, permissions) ``path`` keeps its old content and the error names it.
    """
    path = pathlib.Path(path)
    with atomic_output(path, inputs=inputs) as tmp:
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
    return path


def check_video_written(part: pathlib.Path, final: pathlib.Path, frames: int) -> None:
    """Raise a write error unless the video ``part`` (closed) holds its ``frames`` frames.

    ``cv2.VideoWriter.write`` reports nothing when the disk fills or the file size limit is reached:
    it prints a warning and goes on, and the file is cut short. The file is read back instead (its
    frame count, from the container) and a short one is named for the likely cause.

    Parameters
    ----------
    part : pathlib.Path
        The temporary video just written and released.
    final : pathlib.Path
        Its final name (named in the error).
    frames : int
        The number of frames written to it.

    Raises
    ------
    OSError
        ``"disk full while writing 'out.mp4'"``, ``"file size limit reached while writing ..."``, or
        ``"cannot write 'out.mp4': the video encoder stored N of M frames"``.
    """
    import cv2

    capture = cv2.VideoCapture(str(part))
    try:
        stored = int(capture.get(cv2.CAP_PROP_FRAME_COUNT)) if capture.isOpened() else 0
    finally:
        capture.release()
    if stored == frames:
        return
    raise write_error(OSError(out_of_space(part), f"the video encoder stored {stored} of {frames} frames"), final)


def out_of_space(path: pathlib.Path) -> int | None:
    """Whether the file ``path`` being written has run out of room: ENOSPC (under 1 MiB free on its file
    system), EFBIG (within 64 kB of the process's file size limit), or None."""
    import resource

    try:
        stat = os.statvfs(path.parent if str(path.parent) else ".")
        if stat.f_bavail * stat.f_frsize < 1024 * 1024:
            return errno.ENOSPC
        limit = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
        if limit != resource.RLIM_INFINITY and path.stat().st_size >= limit - 64 * 1024:
            return errno.EFBIG
    except OSError:
        pass
    return None


#: HDF5 ``schema`` / ``format`` attribute prefix -> what a file of that kind holds.
_HDF5_KINDS = {"tactip-model/": "a trained model", "tactip-dataset/": "collected taps",
               "tactip-calibration/": "a sensor calibration", "tactip-replay/": "a replay (pins, displacement)"}

#: Tables that make a TOML file a station's configuration.
_STATION_TABLES = ("station", "sensor", "arm")

#: Largest text file read to see whether it is a station TOML, bytes (station files are a few kB).
_TOML_LIMIT_BYTES = 1 << 20


def project_file(path) -> str | None:
    """What ``path`` holds when the project wrote it, recognised by its content; None otherwise.

    Recognised: HDF5 files whose ``schema`` or ``format`` attribute names a tactip format (models,
    calibrations, collected taps, replays), SQLite databases (results databases, and any other, which
    a text export would destroy), and TOML files with a ``[station]``, ``[sensor]`` or ``[arm]`` table.
    A missing path, a stream (``-``, a device, a FIFO: never read, a read could wait for ever) or any
    other file gives None.

    Parameters
    ----------
    path : str or os.PathLike
        A file about to be written.

    Returns
    -------
    str or None
        E.g. ``"a trained model (tactip-model/1)"``.
    """
    path = pathlib.Path(path)
    try:
        if not path.is_file():
            return None
        with open(path, "rb") as f:
            head = f.read(16)
        size = path.stat().st_size
    except OSError:
        return None                                     # unreadable: the writer reports what it meets
    if head.startswith(b"SQLite format 3\0"):
        return _sqlite_kind(path)
    if head.startswith(b"\x89HDF\r\n\x1a\n"):
        return _hdf5_kind(path)
    if size <= _TOML_LIMIT_BYTES:
        return _toml_kind(path)
    return None


def _hdf5_kind(path: pathlib.Path) -> str | None:
    import h5py

    try:
        with h5py.File(path, "r") as f:
            marks = [f.attrs.get(key) for key in ("schema", "format")]
    except (OSError, ValueError):
        return None
    for mark in marks:
        mark = mark.decode(errors="replace") if isinstance(mark, bytes) else mark
        for prefix, what in _HDF5_KINDS.items():
            if isinstance(mark, str) and mark.startswith(prefix):
                return f"{what} ({mark})"
    return None


def _sqlite_kind(path: pathlib.Path) -> str:
    import contextlib
    import sqlite3

    try:
        with contextlib.closing(sqlite3.connect(f"{path.resolve().as_uri()}?mode=ro&immutable=1", uri=True)) as con:
            tables = {row[0] for row in con.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
    except sqlite3.Error:
        tables = set()
    return "inspection results (a results database)" if "inspections" in tables else "an SQLite database"


def _toml_kind(path: pathlib.Path) -> str | None:
    import tomllib

    try:
        table = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError, ValueError):
        return None
    found = [name for name in _STATION_TABLES if isinstance(table.get(name), dict)]
    return f"a station configuration (TOML with [{found[0]}])" if found else None


def refuse_replacing_project_files(paths, *, overwrite: bool, flag: str = "--overwrite") -> None:
    """Refuse, before any work, to replace a file the project wrote unless ``overwrite`` was asked.

    Parameters
    ----------
    paths : iterable of path or None
        The files a command is about to write (None entries skipped).
    overwrite : bool
        The user asked for it (``--overwrite``): nothing is refused.
    flag : str
        The flag named in the message.

    Raises
    ------
    TactipError
        ``"'model.h5' holds a trained model (tactip-model/1): replacing it would destroy it; add
        --overwrite to replace it, or choose another name"``.
    """
    if overwrite:
        return
    from tactip.errors import TactipError

    for path in paths:
        if path is None or str(path) == "-":
            continue
        what = project_file(path)
        if what:
            raise TactipError(f"{str(path)!r} holds {what}: replacing it would destroy {_them(what)}; add {flag} "
                              f"to replace it, or choose another name")


def _them(what: str) -> str:
    return "them" if what.startswith(("collected", "inspection")) else "it"


#: The real standard output while a command's other lines are sent to standard error (``--json -``).
JSON_STDOUT = None


def write_json(target, data, *, inputs=(), indent: int | None = 1) -> None:
    """Write a command's JSON report: ``-`` to standard output, else the file ``target`` (atomically; a
    FIFO or a device is streamed into), refusing to write over one of ``inputs``.

    Parameters
    ----------
    target : str or os.PathLike
        ``-`` or a file.
    data : object
        JSON-serialisable (lists, dicts, numbers, strings, None).
    inputs : iterable of path
        Files the command read.
    indent : int or None
        JSON indentation (None: one line).
    """
    import json
    import sys

    text = json.dumps(data, indent=indent) + "\n"
    if str(target) == "-":
        out = JSON_STDOUT if JSON_STDOUT is not None else sys.stdout
        out.write(text)
        out.flush()
        return
    write_text_atomic(target, text, inputs=inputs)
