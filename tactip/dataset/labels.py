"""The labels CSV of ``tactip dataset build``: its rows, and the label turned into a dataset identity.

A labels file is a CSV with a header. Its ``path`` column names a recording (a video, a folder of
frames, or an image) relative to the CSV's folder; other columns hold labels, and optionally ``rest``
(an image's rest image, relative to the CSV) and ``split`` (``train`` or ``test``, for
``--split column``). Every row keeps its line number in the file, so a bad one can be named.

A label is one of three kinds (`LabelScheme`):

- **numbers** (``depth_mm``: 0.5, 1.0, ...): each distinct value a class, or ``classes`` equal-width
  bins over the labels' range, the identity then the bin's centre;
- **names** (``shape``: cube, sphere, ...): each distinct name a class, the identity its index in the
  sorted names (stored as the dataset's ``identity_names``);
- **angles** (numbers with a ``period``, e.g. 360 deg): the identity wraps into [0, period), and errors
  between identities wrap (315 and 0 deg are 45 deg apart); ``classes`` bins wrap too, centred on
  0, period / classes, ... (8 classes of 360 deg: 0, 45, ..., 315; 350 deg falls in the class of 0).

>>> scheme = LabelScheme.from_values(["350", "10", "100"], period=360.0, classes=4)
>>> scheme.kind, [scheme.identity("350"), scheme.identity("100")], scheme.class_name(90.0)
('angle', [0.0, 90.0], '90')
"""

from __future__ import annotations

import csv
import math
import pathlib
from dataclasses import dataclass, field

import numpy as np

from tactip.errors import TactipError

__all__ = ["LabelsError", "LabelRow", "LabelScheme", "read_labels", "RESERVED_COLUMNS", "UNIT_SUFFIXES"]

#: Columns that are not labels: the recording, an image's rest image and the split of ``--split column``.
RESERVED_COLUMNS = ("path", "rest", "split")
#: A label column named ``NAME_UNIT`` with one of these units gives the identity's unit (``depth_mm`` -> mm).
UNIT_SUFFIXES = ("mm", "um", "cm", "m", "deg", "rad", "px", "s", "ms", "n", "g", "kg")
#: Distinct number labels above which a warning suggests binning them (``--classes``).
MANY_CLASSES = 50


class LabelsError(TactipError, ValueError):
    """The labels CSV (or the recordings it names) cannot make a dataset; the message names the line."""


@dataclass(frozen=True)
class LabelRow:
    """One row of the labels CSV.

    Attributes
    ----------
    line : int
        Line number in the CSV file (the header is line 1).
    path : pathlib.Path
        The recording, resolved against the CSV's folder.
    label : str
        The label's text, stripped ("" when empty).
    rest : pathlib.Path or None
        The rest image of an image row (the ``rest`` column), resolved against the CSV's folder.
    split : str
        The ``split`` column's text, lower case ("" when absent).
    """

    line: int
    path: pathlib.Path
    label: str
    rest: pathlib.Path | None = None
    split: str = ""


def read_labels(csv_path, *, label: str | None = None) -> tuple[list[LabelRow], str, list[tuple[int, str]]]:
    """Read a labels CSV.

    Parameters
    ----------
    csv_path : str or path
        The CSV file, with a header holding ``path`` and at least one label column.
    label : str, optional
        The label column; default the only column that is not ``path``, ``rest`` or ``split``.

    Returns
    -------
    rows : list of LabelRow
        Every data row, in file order (blank lines skipped); rows with an empty ``path`` included
        (their ``path`` is the CSV's folder, to be reported as bad rows).
    column : str
        The label column used.
    problems : list of (int, str)
        Rows that cannot be read at all: (line number, reason), left out of ``rows``.

    Raises
    ------
    LabelsError
        The file is missing or not a CSV with a header, has no ``path`` column, or the label column
        is missing or ambiguous (the message lists the candidates).
    """
    csv_path = pathlib.Path(csv_path)
    try:
        text = csv_path.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise LabelsError(f"no labels file at {csv_path}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise LabelsError(f"cannot read the labels file {csv_path} ({exc})") from None
    reader = csv.reader(text.splitlines())
    header = next(reader, None)
    if not header or not any(h.strip() for h in header):
        raise LabelsError(f"{csv_path} is empty: give a header line, e.g. 'path,depth_mm'")
    header = [h.strip() for h in header]
    if "path" not in header:
        raise LabelsError(f"{csv_path} has no 'path' column (its columns: {', '.join(header)}); the path column names "
                          f"each recording, relative to the CSV")
    candidates = [h for h in header if h and h not in RESERVED_COLUMNS]
    if label is None:
        if len(candidates) != 1:
            raise LabelsError(f"{csv_path}: choose the label column with --label ({', '.join(candidates) or 'none'} "
                              f"found besides {', '.join(c for c in RESERVED_COLUMNS if c in header)})")
        label = candidates[0]
    elif label not in header or label in RESERVED_COLUMNS:
        raise LabelsError(f"{csv_path} has no label column {label!r}; its label columns: "
                          f"{', '.join(candidates) or 'none'}")
    where = {name: header.index(name) for name in (*RESERVED_COLUMNS, label) if name in header}
    folder = csv_path.parent
    rows, problems = [], []
    for number, cells in enumerate(reader, start=2):
        if not any(c.strip() for c in cells):
            continue
        if len(cells) != len(header):
            problems.append((number, f"{len(cells)} fields, the header has {len(header)}"))
            continue

        def cell(name: str) -> str:
            return cells[where[name]].strip() if name in where else ""

        rest = cell("rest")
        rows.append(LabelRow(number, folder / cell("path"), cell(label), folder / rest if rest else None,
                             cell("split").lower()))
    return rows, label, problems


@dataclass(frozen=True)
class LabelScheme:
    """How label texts become identities: numbers, names or angles, optionally binned into classes.

    Build it with `from_values`. Attributes: ``kind`` ("number", "name" or "angle"), ``unit``,
    ``period`` (angles), ``names`` (names, sorted), ``classes`` (bins, 0 for none) and ``low``,
    ``high`` (the numbers' range, for the bins).
    """

    kind: str
    unit: str = "none"
    period: float | None = None
    names: tuple[str, ...] = ()
    classes: int = 0
    low: float = 0.0
    high: float = 0.0
    warnings: tuple[str, ...] = field(default=(), compare=False)

    @classmethod
    def from_values(cls, values, *, period: float | None = None, classes: int | None = None,
                    unit: str | None = None, column: str = "") -> LabelScheme:
        """The scheme of a label column from its (non-empty) values.

        Parameters
        ----------
        values : iterable of str
            The label texts of the usable rows.
        period : float, optional
            The period of an angle (e.g. 360 for deg): the labels are then angles.
        classes : int, optional
            Bin numbers (or angles) into this many equal-width classes.
        unit : str, optional
            The identity's unit; default the column name's suffix (``depth_mm``: mm), "deg" for a
            period of 360, else "none".
        column : str
            The column's name (for the unit and messages).

        Raises
        ------
        LabelsError
            Names with ``period`` or ``classes``, no values, or a bad ``period`` / ``classes``.
        """
        values = [v for v in values if v != ""]
        if not values:
            raise LabelsError(f"no label values in column {column!r}")
        if period is not None and not (math.isfinite(period) and period > 0):
            raise LabelsError(f"--period must be a finite number > 0, got {period}")
        if classes is not None and classes < 1:
            raise LabelsError(f"--classes must be at least 1, got {classes}")
        numbers = [_number(v) for v in values]
        guess = unit or _unit_of(column) or ("deg" if period == 360 else None)
        if period is None and classes is None and any(_text_is_name(v) for v in values):
            return cls("name", unit or "none", names=tuple(sorted(set(values))))
        # Numbers (--period and --classes ask for them): a text that is not one is a bad row, said there.
        numbers = np.array([n for n in numbers if n is not None], dtype=float)
        if not numbers.size:
            flag = "--period" if period is not None else "--classes"
            raise LabelsError(f"{flag} needs number labels; column {column!r} holds names (e.g. {values[0]!r})")
        warnings = [] if guess else [f"the unit of label {column!r} is unknown (give --unit, or name the column "
                                     f"e.g. {column or 'label'}_mm)"]
        if period is not None:
            return cls("angle", guess or "none", period=float(period), classes=int(classes or 0),
                       warnings=tuple(warnings))
        low, high = float(numbers.min()), float(numbers.max())
        distinct = len(np.unique(numbers))
        if not classes and distinct > MANY_CLASSES:
            warnings.append(f"{distinct} distinct values of {column!r}, each a class: bin them with --classes N")
        if classes and high == low:
            warnings.append(f"every label of {column!r} is {low:g}: one class")
        return cls("number", guess or "none", classes=int(classes or 0), low=low, high=high, warnings=tuple(warnings))

    def identity(self, text: str) -> float:
        """The identity of a label text: the number, its bin's centre, the wrapped angle or the name's index.

        Raises
        ------
        LabelsError
            An empty label, a name not in the scheme, or a text that is not a number where numbers are.
        """
        if text == "":
            raise LabelsError("empty label")
        if self.kind == "name":
            try:
                return float(self.names.index(text))
            except ValueError:
                raise LabelsError(f"label {text!r} is not one of the names {list(self.names)[:10]}") from None
        value = _number(text)
        if value is None:
            raise LabelsError(f"label {text!r} is not a finite number")
        if self.kind == "angle":
            if self.classes:
                width = self.period / self.classes
                # bins centred on 0, width, 2 width, ...: the one nearest the angle, wrapping
                return float((round(value / width) % self.classes) * width)
            return float(value % self.period)
        if self.classes:
            if self.high == self.low:
                return self.low
            width = (self.high - self.low) / self.classes
            index = min(max(int(math.floor((value - self.low) / width)), 0), self.classes - 1)
            return float(f"{self.low + (index + 0.5) * width:.12g}")  # 2.898, not 2.8979999999999997
        return float(value)

    def class_name(self, identity: float) -> str:
        """A class's name for people: the name, or the identity's number (``0.75``, ``45``)."""
        if self.kind == "name":
            return self.names[int(identity)]
        return f"{identity:.6g}"

    def describe(self) -> str:
        """One line: the kind, the unit and the classes."""
        if self.kind == "name":
            return f"names ({len(self.names)} classes)"
        bins = f", {self.classes} equal-width classes" if self.classes else ", each value a class"
        if self.kind == "angle":
            return f"angles in {self.unit}, period {self.period:g}{bins}"
        return f"numbers in {self.unit}{bins}"

    def to_dict(self) -> dict:
        """The scheme as JSON-ready values (for ``summary.json``)."""
        return {"kind": self.kind, "unit": self.unit, "period": self.period, "names": list(self.names),
                "classes": self.classes, "range": [self.low, self.high] if self.kind == "number" else None}


def _number(text: str) -> float | None:
    """The finite float of a text, else None."""
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def _text_is_name(text: str) -> bool:
    """Whether a label text is a name: not even a float (``nan`` and ``inf`` are bad numbers, not names)."""
    try:
        float(text)
    except ValueError:
        return True
    return False


def _unit_of(column: str) -> str | None:
    """The unit a column's name ends with (``depth_mm`` -> mm), else None."""
    head, _, suffix = column.rpartition("_")
    return suffix.lower() if head and suffix.lower() in UNIT_SUFFIXES else None
