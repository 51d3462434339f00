"""Argument types shared by the subcommands: each names the bad value and the accepted range.

Every number is finite (``nan`` and ``inf`` are refused: they say nothing and poison what follows),
whole numbers have an upper bound where a huge value would exhaust memory or time, and output files
are checked before any work starts (an existing folder, a missing parent folder, a folder on a
read-only file system or without write permission, an image format the plotting library cannot write;
missing folders are created by the writer). A file the project wrote is replaced only with ``--overwrite``
(`OutputPath`). `check_memory` refuses a job whose arrays cannot fit in memory.
"""

from __future__ import annotations

import argparse
import errno
import math
import os
from pathlib import Path

from _shared import outside_range
from _shared.ranges import MAX_SEED
from tactip.errors import TactipError

__all__ = ["int_at_least", "int_in_range", "positive_int", "non_negative_int", "seed", "finite_float",
           "float_in_range", "positive_float", "non_negative_float", "fraction", "fractions", "output_file", "creatable_file",
           "OutputPath", "json_target", "add_json_argument", "output_folder",
           "image_file", "worker_count", "check_memory", "available_memory_bytes", "format_bytes"]


def int_at_least(low: int, high: int | None = None):
    """An argparse type: a whole number >= ``low`` (and <= ``high`` when given)."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be a whole number, got {text!r}") from None
        accepted = outside_range(value, low, high)
        if accepted:
            raise argparse.ArgumentTypeError(f"{accepted}, got {text}")
        return value
    return parse


def int_in_range(low: int, high: int):
    """An argparse type: a whole number in ``low..high`` (both included)."""
    return int_at_least(low, high)


positive_int = int_at_least(1)
non_negative_int = int_at_least(0)
#: A random seed: a whole number in 0..MAX_SEED.
seed = int_at_least(0, MAX_SEED)


def finite_float(text: str) -> float:
    """An argparse type: any finite number."""
    return _float(text)


def float_in_range(low: float, high: float, *, low_open: bool = False, unit: str = ""):
    """An argparse type: a finite number in ``[low, high]`` (``(low, high]`` with ``low_open``)."""
    def parse(text: str) -> float:
        value = _float(text)
        accepted = outside_range(value, float(low), float(high), low_open=low_open, unit=unit)
        if accepted:
            raise argparse.ArgumentTypeError(f"{accepted}, got {text}")
        return value
    return parse


def positive_float(text: str) -> float:
    """An argparse type: a finite number > 0."""
    value = _float(text)
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be a finite number > 0, got {text}")
    return value


def non_negative_float(text: str) -> float:
    """An argparse type: a finite number >= 0."""
    value = _float(text)
    if not value >= 0:
        raise argparse.ArgumentTypeError(f"must be a finite number >= 0, got {text}")
    return value


def fraction(text: str) -> float:
    """An argparse type: a number in [0, 1]."""
    value = _float(text)
    if not 0.0 <= value <= 1.0:
        raise argparse.ArgumentTypeError(f"must be in [0, 1], got {text}")
    return value


def fractions(text: str) -> list[float]:
    """An argparse type: comma-separated numbers in [0, 1] (e.g. thresholds)."""
    try:
        values = [_float(v) for v in text.split(",") if v.strip()]
    except argparse.ArgumentTypeError:
        values = []
    if not values or any(not 0.0 <= v <= 1.0 for v in values):
        raise argparse.ArgumentTypeError(f"thresholds must be in [0, 1], got {text!r}")
    return values


def output_file(text: str) -> Path:
    """An argparse type: a file to write (its missing folders are created, so ``--out out/model.h5`` works
    in a fresh folder); refused when it names a folder. ``-`` (standard output), ``/dev/null``, a terminal
    or a FIFO are written into as streams."""
    return creatable_file(text)


def json_target(text: str) -> "OutputPath":
    """An argparse type for ``--json [FILE|-]``: ``-`` (standard output) or a file to write, whose missing
    folders are created (as `creatable_file`). An existing file that is not ``.json`` is refused: ``--json``
    takes an optional value, so ``detect --json FRAME.png OTHER.png`` would otherwise write over the frame."""
    if text == "-":
        return OutputPath("-")
    path = creatable_file(text)
    from tactip._output import project_file

    # (A file the project wrote is left to `refuse_replacing_project_files`, which names what it holds.)
    if path.suffix.lower() != ".json" and path.is_file() and not path.is_symlink() and not project_file(path):
        raise argparse.ArgumentTypeError(f"{text!r} exists and is not a .json file: --json would destroy it (put the "
                                         f"command's inputs before --json, or name a .json file)")
    return path


def add_json_argument(parser: argparse.ArgumentParser, what: str) -> None:
    """Add ``--json [FILE|-]``, the same in every command that reports: with no value or ``-`` the JSON goes
    to standard output (and every other line to standard error), with FILE to that file (written atomically;
    a FIFO or a device is streamed into)."""
    parser.add_argument("--json", type=json_target, nargs="?", const=OutputPath("-"), default=None,
                        metavar="FILE|-", help=f"{what} as JSON: to standard output (no value or -; other lines "
                                               f"go to standard error) or to FILE")


class OutputPath(type(Path())):
    """A path parsed as a file the command writes: `tactip.cli.main` refuses, before the command runs, to
    replace a file the project wrote there (a model, collected taps ...) unless ``--overwrite`` is given
    (`tactip._output.refuse_replacing_project_files`)."""

    __slots__ = ()


def creatable_file(text: str) -> Path:
    """An argparse type: a file to write whose missing folders the writer creates; refused when it names a
    folder, or when one of its folders is a file or cannot be written. (A file the project wrote there is
    replaced only with ``--overwrite``: `OutputPath`.)"""
    if not text.strip():
        raise argparse.ArgumentTypeError("must name a file, got ''")
    path = Path(text)
    _name_fits(path, text)
    if path.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is a folder; give a file name")
    if _stream(path, text):      # streamed into, never replaced: nothing to check in its folder, nothing to read
        return OutputPath(path)
    _writable(_folders_or_missing(path.parent, text), text)
    return OutputPath(path)


def _stream(path: Path, text: str) -> bool:
    """Whether ``path`` is an output streamed into (``-``, a device such as /dev/null, a FIFO, /dev/stdout);
    a block device or a socket is refused (`_shared.stream_target`)."""
    from _shared import stream_target

    try:
        return stream_target(path)
    except OSError as exc:
        raise argparse.ArgumentTypeError(exc.strerror or str(exc)) from None


def output_folder(text: str) -> Path:
    """An argparse type: a folder to write into (created if missing); refused when it is a file."""
    if not text.strip():
        raise argparse.ArgumentTypeError("must name a folder, got ''")
    path = Path(text)
    _name_fits(path, text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is a file, not a folder")
    _folders_or_missing(path.parent, text)
    return path


def _name_fits(path: Path, text: str) -> None:
    """Refuse a path whose file name or whole length the system cannot take (ENAMETOOLONG)."""
    try:
        os.stat(path)
    except OSError as exc:
        if exc.errno == errno.ENAMETOOLONG:
            raise argparse.ArgumentTypeError(f"the name {text[:40]!r}... is too long for the file system "
                                             f"({len(path.name.encode())} bytes; at most 255 per name)") from None


def _folders_or_missing(folder: Path, text: str) -> Path:
    """The nearest existing folder of ``folder`` (itself or a parent); refused when that is a file."""
    for parent in (folder, *folder.parents):
        if parent.exists():
            if not parent.is_dir():
                raise argparse.ArgumentTypeError(f"{str(parent)!r} (in {text!r}) is a file, not a folder")
            return parent
    return Path(".")


def _writable(folder: Path, text: str) -> None:
    """Refuse ``text`` when its existing ``folder`` cannot be written (read-only file system, no permission)."""
    try:
        read_only = bool(os.statvfs(folder).f_flag & os.ST_RDONLY)
    except (OSError, AttributeError):
        read_only = False
    if read_only:
        raise argparse.ArgumentTypeError(f"cannot write {text!r}: the folder {str(folder)!r} is on a read-only "
                                         f"file system")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise argparse.ArgumentTypeError(f"cannot write {text!r}: permission denied in the folder {str(folder)!r}")


def image_file(text: str) -> Path:
    """An argparse type: an image file to plot into, in a format the plotting library writes (png, pdf, svg ...)."""
    path = output_file(text)
    formats = _image_formats()
    suffix = path.suffix.lower().lstrip(".")
    if suffix not in formats:
        got = f"'.{suffix}'" if suffix else "no extension"
        raise argparse.ArgumentTypeError(f"cannot plot to {text!r} ({got}); use one of the image formats "
                                         f"{', '.join(sorted(formats))}")
    return path


def worker_count(text: str) -> int:
    """An argparse type: a number of worker processes in ``1..4 x CPU count``."""
    cpus = os.cpu_count() or 1
    high = 4 * cpus
    try:
        return int_at_least(1, high)(text)
    except argparse.ArgumentTypeError as exc:
        raise argparse.ArgumentTypeError(f"{exc} (at most 4 x the {cpus} CPUs)") from None


def available_memory_bytes() -> int | None:
    """Memory the system can give a new allocation without swapping, bytes (None when unknown)."""
    try:
        with open("/proc/meminfo") as handle:
            for line in handle:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def format_bytes(nbytes: float) -> str:
    """``nbytes`` for a person: ``'1.5 GiB'``."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if abs(nbytes) < 1024 or unit == "PiB":
            return f"{nbytes:.0f} {unit}" if unit == "B" else f"{nbytes:.1f} {unit}"
        nbytes /= 1024
    return f"{nbytes:.1f} PiB"  # pragma: no cover


def check_memory(nbytes: float, *, what: str, hint: str) -> None:
    """Refuse a job whose arrays need more memory than is available.

    Parameters
    ----------
    nbytes : float
        Estimated peak memory of the job's arrays, bytes.
    what : str
        The job, for the message (``"5000000 Monte Carlo runs of 44 classes"``).
    hint : str
        What to change (``"use fewer --runs"``).

    Raises
    ------
    TactipError
        Naming the estimate, the memory available and the hint.
    """
    available = available_memory_bytes()
    if available is None:
        return
    usable = 0.8 * available
    if nbytes > usable:
        raise TactipError(f"{what} need about {format_bytes(nbytes)} of memory, more than the {format_bytes(usable)} "
                          f"usable (80% of the {format_bytes(available)} available): {hint}")


def _image_formats() -> set[str]:
    from matplotlib.backend_bases import FigureCanvasBase

    return set(FigureCanvasBase.get_supported_filetypes())


def _float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text}")
    return value
