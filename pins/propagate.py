"""Pins matched across one large deformation (a rest image and a pressed one, nothing in between).

Frame-to-frame tracking assumes small steps; between a rest image and an image of a deep press the
rim pins move by most of a pin pitch, so a pin's nearest blob is often its neighbour's. The
deformation of the skin is smooth, though: `match_by_propagation` first matches the pins whose
nearest blob is unambiguous (close, and the second nearest far: near the contact's still parts), then
grows the match outwards, predicting each unmatched pin's displacement as the median of its matched
neighbours' and taking the blob nearest that prediction when it is unambiguous; a match that moved
unlike its neighbours is dropped at the end. Pins whose blob is not found (merged, hidden, outside the
frame) stay unmatched (NaN). A drag of the whole skin by more than about half a pitch (a slide) has
no unambiguous seeds: a lattice shifted by a pitch looks the same, so record slides as videos.

>>> import numpy as np
>>> rest = np.array([[x, y] for x in range(0, 100, 20) for y in range(0, 100, 20)], float)
>>> moved = rest + 0.13 * (rest - 40.0)                  # up to 5.2 px of outward stretch
>>> found = match_by_propagation(rest, moved[::-1], spacing_px=20.0)
>>> bool(np.allclose(found, moved))
True
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["match_by_propagation"]


def match_by_propagation(rest_positions: np.ndarray, blobs: np.ndarray, *, spacing_px: float, neighbours: int = 6,
                         seed_fraction: float = 0.25, gate_fraction: float = 0.35) -> np.ndarray:
    """Each pin's blob after a smooth deformation of any size, grown outwards from unambiguous matches.

    Parameters
    ----------
    rest_positions : (N, 2) ndarray
        Pins (x, y) at rest, px.
    blobs : (M, 2) ndarray
        Blob centres (x, y) in the deformed image, px (`detect_pins`).
    spacing_px : float
        Pin spacing at rest, px (`median_spacing_px`).
    neighbours : int
        Neighbours at rest whose displacements predict a pin's.
    seed_fraction : float
        A seed's nearest blob is within ``seed_fraction * spacing_px`` of its rest position and its
        second nearest beyond ``(1 - seed_fraction) * spacing_px``.
    gate_fraction : float
        A grown match lies within ``gate_fraction * spacing_px`` of the prediction, and its blob
        is less than half as far as the second nearest.

    Returns
    -------
    positions : (N, 2) ndarray of float64
        Each pin's blob (x, y), px; NaN where none was matched. A blob is matched to one pin at most.
    """
    rest = np.asarray(rest_positions, dtype=np.float64).reshape(-1, 2)
    blobs = np.asarray(blobs, dtype=np.float64).reshape(-1, 2)
    positions = np.full_like(rest, np.nan)
    if len(rest) == 0 or len(blobs) < 2 or not spacing_px > 0:
        return positions
    tree = cKDTree(blobs)
    near = cKDTree(rest).query(rest, k=min(neighbours + 1, len(rest)))[1][:, 1:]
    taken = np.zeros(len(blobs), dtype=bool)
    matched = np.zeros(len(rest), dtype=bool)

    def accept(pins: np.ndarray, distance: np.ndarray, blob: np.ndarray) -> int:
        """Match pins to blobs, one pin per blob (the nearest), skipping blobs already taken."""
        order = np.argsort(distance, kind="stable")
        pins, blob = pins[order], blob[order]
        first = np.unique(blob, return_index=True)[1]
        pins, blob = pins[first], blob[first]
        free = ~taken[blob]
        pins, blob = pins[free], blob[free]
        positions[pins], matched[pins], taken[blob] = blobs[blob], True, True
        return len(pins)

    distance, index = tree.query(rest, k=2)
    seeds = (distance[:, 0] < seed_fraction * spacing_px) & (distance[:, 1] > (1 - seed_fraction) * spacing_px)
    accept(np.flatnonzero(seeds), distance[seeds, 0], index[seeds, 0])
    while True:
        shift = positions - rest  # NaN where unmatched
        candidates = np.flatnonzero(~matched & matched[near].any(axis=1))
        if not candidates.size:
            break
        predicted = rest[candidates] + np.nanmedian(shift[near[candidates]], axis=1)
        distance, index = tree.query(predicted, k=2)
        good = (distance[:, 0] < gate_fraction * spacing_px) & (distance[:, 0] < 0.5 * distance[:, 1])
        good &= ~taken[index[:, 0]]
        if not good.any() or accept(candidates[good], distance[good, 0], index[good, 0]) == 0:
            break
    # A match its neighbours disagree with (moved unlike the skin around it) is dropped: a wrong blob.
    shift = positions - rest
    around = np.nanmedian(shift[near], axis=1)  # nan (all-NaN neighbours) compares False below
    with np.errstate(invalid="ignore"):
        odd = matched & (np.linalg.norm(shift - around, axis=1) > gate_fraction * spacing_px)
    positions[odd] = np.nan
    return positions
