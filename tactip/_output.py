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

__all__ = ["claim_output", "atomic_output", "write_text_atomic", "refuse_overwriting_inputs", "write_error",
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
