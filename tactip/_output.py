"""Output files written under a temporary name and renamed at the end (nothing half-written is left)."""

from __future__ import annotations

import os
import pathlib

__all__ = ["claim_output"]


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
    if path.is_dir():
        raise IsADirectoryError(21, "output path is a directory", str(path))
    part = path.with_name(f".{path.stem}.{os.getpid()}.part{suffix if suffix is not None else path.suffix}")
    try:
        with open(part, "wb"):
            pass
    except OSError as exc:
        raise OSError(exc.errno, f"cannot write {str(path)!r} ({exc.strerror})") from None
    return part
