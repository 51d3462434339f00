"""Which taps go to training and which to test: ``--split alternate|group|column``.

- ``alternate``: the taps of each class alternate, in recording order, train, test, train, ...: the
  taps of a recording alternate, and so do single-image taps of one class across their rows.
- ``group``: whole recordings on one side (taps of one recording are alike: keeping them together
  measures how a model does on a recording it has not seen). Per class, the recordings are shuffled
  (seeded) and each goes to the side further below its share of the class's taps (``test_fraction``).
- ``column``: the ``split`` column of each row (``train`` or ``test``).

>>> import numpy as np
>>> alternate_split(np.array([0.0, 0.0, 0.0, 1.0, 1.0])).tolist()
[False, True, False, False, True]
"""

from __future__ import annotations

import numpy as np

__all__ = ["SPLITS", "alternate_split", "group_split", "column_split"]

#: The split methods of ``tactip dataset build --split``.
SPLITS = ("alternate", "group", "column")


def alternate_split(identity: np.ndarray) -> np.ndarray:
    """Test mask alternating within each class: the k-th tap of a class is a test tap when k is odd.

    Parameters
    ----------
    identity : (N,) ndarray
        The class of each tap, in recording order.

    Returns
    -------
    test : (N,) ndarray of bool
    """
    identity = np.asarray(identity)
    _, inverse = np.unique(identity, return_inverse=True)
    order = np.argsort(inverse, kind="stable")  # taps grouped by class, in their order
    first = np.searchsorted(inverse[order], inverse[order])  # where each tap's class starts in that order
    rank = np.empty(len(identity), dtype=np.int64)
    rank[order] = np.arange(len(identity)) - first
    return rank % 2 == 1


def group_split(identity: np.ndarray, recording: np.ndarray, *, test_fraction: float = 0.5,
                seed: int = 0) -> np.ndarray:
    """Test mask keeping every recording whole, balanced per class as far as whole recordings allow.

    Parameters
    ----------
    identity : (N,) ndarray
        The class of each tap (one class per recording).
    recording : (N,) ndarray of int
        The recording of each tap.
    test_fraction : float in (0, 1)
        Share of each class's taps wanted in the test set.
    seed : int
        Seed of the shuffle of each class's recordings.

    Returns
    -------
    test : (N,) ndarray of bool
    """
    if not 0.0 < test_fraction < 1.0:
        raise ValueError(f"test_fraction must be in (0, 1), got {test_fraction}")
    identity, recording = np.asarray(identity), np.asarray(recording)
    rng = np.random.default_rng(seed)
    test = np.zeros(len(identity), dtype=bool)
    for value in np.unique(identity):
        ours = identity == value
        names, sizes = np.unique(recording[ours], return_counts=True)
        total, in_test, in_train = sizes.sum(), 0, 0
        for k in rng.permutation(len(names)):
            # the side further below its share of this class's taps; ties to training
            if test_fraction * total - in_test > (1.0 - test_fraction) * total - in_train:
                test |= recording == names[k]
                in_test += sizes[k]
            else:
                in_train += sizes[k]
    return test


def column_split(values) -> np.ndarray:
    """Test mask from a ``split`` column's values (``train`` or ``test``, any case).

    Raises
    ------
    ValueError
        A value other than train or test (naming it).
    """
    values = [str(v).strip().lower() for v in values]
    bad = sorted({v for v in values if v not in ("train", "test")})
    if bad:
        raise ValueError(f"split values must be 'train' or 'test', got {bad[:5]}")
    return np.array([v == "test" for v in values], dtype=bool)
