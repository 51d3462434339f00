"""Checks of the tap dataset (`perception.dataset`): its labels, its taps and its file's schema.

The constants of the schema (``tactip-dataset/1``: front ends, required arrays, the complete-tap
count attribute), the identity-label check that datasets and models share, and the checks a
dataset file must pass when it is read or resumed (schema, arrays of numbers of the right rank,
the count of complete taps).
"""

from __future__ import annotations

import numpy as np

from .errors import DatasetError

__all__ = ["SCHEMA", "FRONT_ENDS", "COUNT_ATTRIBUTE", "check_identity_labels"]

SCHEMA = "tactip-dataset/1"
FRONT_ENDS = ("tactip", "taxel")
_ARRAYS = ("taps", "location", "identity")
#: Attribute holding how many taps are complete: written (and flushed) after each tap's data, so a
#: tap whose data never reached the disk (full disk, crash) is not counted, and never read back.
COUNT_ATTRIBUTE = "complete_taps"


def check_identity_labels(period, names, identity=None) -> tuple[float | None, tuple[str, ...]]:
    """The checked ``(identity_period, identity_names)`` of a dataset or model.

    Parameters
    ----------
    period : float or None
        Finite and > 0, or None.
    names : sequence of str
        Distinct non-empty names; with names, every identity must be an index 0..len(names)-1.
    identity : array, optional
        The identities to check against the names.

    Raises
    ------
    DatasetError
        Naming what is wrong.
    """
    if period is not None:
        try:
            period = float(period)
        except (TypeError, ValueError):
            raise DatasetError(f"identity_period must be a number > 0 or None, got {period!r}") from None
        if not (np.isfinite(period) and period > 0):
            raise DatasetError(f"identity_period must be a finite number > 0 or None, got {period!r}")
    names = tuple(str(n) for n in (names or ()))
    if names:
        if period is not None:
            raise DatasetError("a named identity has no period: give identity_names or identity_period, not both")
        if len(set(names)) != len(names) or not all(names):
            raise DatasetError(f"identity_names must be distinct and non-empty, got {list(names)[:10]}")
        if identity is not None and len(identity):
            bad = (identity != np.round(identity)) | (identity < 0) | (identity >= len(names))
            if bad.any():
                raise DatasetError(f"a named identity holds class indices 0..{len(names) - 1}, got "
                                   f"{identity[bad][0]:g} (tap {int(np.argmax(bad))})")
    return period, names


def _check_observed(taps: np.ndarray) -> None:
    """Raise DatasetError for a tap without a single observed value (nothing to classify it by)."""
    if taps.size == 0:
        return
    empty = np.isnan(taps).all(axis=(1, 2))
    if empty.any():
        raise DatasetError(f"taps holds {int(empty.sum())} tap(s) with no observed value (all NaN; first: tap "
                           f"{int(np.argmax(empty))}); leave such taps out")


def _check_schema(f, path) -> None:
    schema = f.attrs.get("schema")
    if isinstance(schema, bytes):
        schema = schema.decode()
    if schema != SCHEMA:
        raise DatasetError(f"{path} is not a {SCHEMA} file (schema {schema!r})")


def _check_arrays(f, path) -> None:
    """Each array of the schema holds numbers (not bytes, strings or records) and has the right rank."""
    for name, rank in (("taps", 3), ("location", 1), ("identity", 1), ("lateral", 1)):
        if name not in f:
            continue
        node = f[name]
        if not hasattr(node, "dtype"):
            raise DatasetError(f"{path}: {name!r} is a group, not a dataset of numbers")
        if node.dtype.kind not in "fiu":
            raise DatasetError(f"{path}: dataset {name!r} holds {node.dtype} values, not numbers "
                               f"(required by {SCHEMA})")
        if node.ndim != rank:
            raise DatasetError(f"{path}: dataset {name!r} has {node.ndim} dimensions, not {rank}")


def _complete_count(f) -> int | None:
    """The complete-tap count attribute, or None for files written before it existed."""
    if COUNT_ATTRIBUTE not in f.attrs:
        return None
    value = f.attrs[COUNT_ATTRIBUTE]
    try:
        count = int(value)
    except (TypeError, ValueError):
        raise DatasetError(f"{f.filename}: attribute {COUNT_ATTRIBUTE} is {value!r}, not a count") from None
    if count < 0:
        raise DatasetError(f"{f.filename}: attribute {COUNT_ATTRIBUTE} is negative ({count})")
    return count
