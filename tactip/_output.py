"""Output files: written under a temporary name, fsynced and renamed at the end, never over an input.

Every command that writes a file goes through these helpers (the logic lives in `perception._files`,
the lowest package that writes files, so that calibration and perception share it):

- `claim_output`: create the temporary file early, so an unwritable output fails before the work;
- `atomic_output`: a context manager yielding the temporary name, renamed over the output on success;
- `write_text_atomic`: a whole text file at once;
- `refuse_overwriting_inputs`: no output may be one of the command's inputs (resolved paths, samefile);
- `write_error`: a write error named for what it is ("disk full while writing X").
"""

from __future__ import annotations

import os
import pathlib

from perception._files import atomic_path as atomic_output
from perception._files import refuse_overwriting_inputs, temporary_name, write_error

__all__ = ["claim_output", "atomic_output", "write_text_atomic", "refuse_overwriting_inputs", "write_error"]


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
        ``.STEM.PID.partSUFFIX`` beside ``path``; the caller renames it with `os.replace` or unlinks it.
    """
    path = pathlib.Path(path)
    if path.is_dir():
        raise IsADirectoryError(21, "output path is a directory", str(path))
    part = temporary_name(path, suffix)
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
