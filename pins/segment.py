"""Tap segmentation of continuous recordings.

A replayed video holds rest periods and taps one after the other. A tap shows as a rise of the
pin displacements: the per-frame *tap signal* is a high percentile (default 90th) of the pins'
displacement magnitudes, so that a contact moving only the pins near the centre still shows.
`segment_taps` finds taps with hysteresis: a tap is a run of frames above `low_px` that reaches
`high_px` somewhere; runs separated by at most `merge_gap_frames` quiet frames are one tap (a
plateau that dips), and runs shorter than `min_frames` are noise. Callers that know when the arm
taps use `pins.features.TapRecorder` instead.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from .displacement import displacement_magnitude
from .errors import ShapeError

__all__ = ["tap_signal", "neighbour_median", "NeighbourMedians", "segment_taps", "converging_frames", "jitter_floor_px"]


def nanmedian_rows(values: np.ndarray) -> np.ndarray:
    """The median of each row's values but NaN over the last axis (NaN where a row has none): `np.nanmedian`'s
    values (the mean of the two middle ones where even), by one sort. `np.nanmedian` on rows shorter than
    600 goes through masked arrays, 3-10x slower on replay's (frames, pins) tables (its tail, issue 20's
    outcome 9)."""
    ordered = np.sort(np.asarray(values, dtype=np.float64), axis=-1)  # NaN last (after +inf, which counts)
    count = np.count_nonzero(~np.isnan(ordered), axis=-1)
    low = np.maximum(count - 1, 0)[..., None] // 2
    high = (count // 2)[..., None]
    if ordered.shape[-1] == 0:
        return np.full(ordered.shape[:-1], np.nan)
    with np.errstate(invalid="ignore"):  # -inf and +inf in the middle: NaN, as np.nanmedian gives
        middle = (np.take_along_axis(ordered, low, -1) + np.take_along_axis(ordered, high, -1))[..., 0] / 2
    return np.where(count > 0, middle, np.nan)


def tap_signal(displacements: np.ndarray, *, percentile: float = 90.0) -> np.ndarray:
    """Per-frame tap signal: a percentile of the pins' displacement magnitudes.

    Parameters
    ----------
    displacements : (T, N, 2) ndarray
        Displacements from rest, px; NaN where lost (ignored).
    percentile : float
        Which percentile over the pins, in [0, 100].

    Returns
    -------
    signal : (T,) ndarray of float64
        px; 0 for frames where every pin is lost.
    """
    displacements = np.asarray(displacements, dtype=np.float64)
    if displacements.ndim != 3 or displacements.shape[2] != 2:
        raise ShapeError(f"displacements must have shape (T, N, 2), got {displacements.shape}")
    if not 0.0 <= percentile <= 100.0:
        raise ValueError(f"percentile must be in [0, 100], got {percentile}")
    # np.nanpercentile's linear rule, vectorised over frames (it loops over rows in Python when
    # some are NaN): sorting puts NaN last, so each row's valid values come first.
    if displacements.shape[1] == 0:
        return np.zeros(len(displacements))
    squared = _squared_lengths(displacements) if displacements[..., 0].size >= _RANKED_FROM else None
    ordered = np.sort(displacement_magnitude(displacements) if squared is None else squared, axis=1)
    count = np.count_nonzero(np.isfinite(ordered), axis=1)
    rank = percentile / 100.0 * np.maximum(count - 1, 0)
    low = np.floor(rank).astype(np.intp)
    high = np.minimum(low + 1, np.maximum(count - 1, 0))
    rows = np.arange(len(ordered))
    if squared is None:
        below, above = ordered[rows, low], ordered[rows, high]
    else:
        below = _ranked_length(displacements, squared, ordered[rows, low], low, count)
        above = below if np.array_equal(high, low) else _ranked_length(displacements, squared, ordered[rows, high],
                                                                       high, count)
    value = below + (above - below) * (rank - low)
    return np.where(count > 0, value, 0.0)


# `tap_signal` ranks the pins by their squared lengths, dx^2 + dy^2 (a third of `np.hypot`'s time), and takes
# `np.hypot` of the one pin at each rank it needs where no other pin's squared length lies within `_TIE` of that pin's
# (relative): each of the square and `np.hypot` is within two units in the last place of the true length, far inside
# `_TIE`, so `np.hypot` ranks that pin there too. A row where another pin does (the rest frame's zeros, a tie; 2 % of
# the rows in replay's tail): every pin's `np.hypot`, sorted. Lengths that cannot be squared in float64 without
# overflow or underflow (components beyond `_SQUARABLE`, or non-zero below its inverse), and infinities: `np.hypot`
# throughout.
_TIE = 1e-9
_SQUARABLE = 1e150
# Below this many pin-frames the few more NumPy calls cost more than np.hypot of every pin saves (795 x 120: 2.6 ->
# 2.0 ms CPU; 128 x 120: 0.20 -> 0.25 ms).
_RANKED_FROM = 32768


def _squared_lengths(displacements: np.ndarray) -> np.ndarray | None:
    """dx^2 + dy^2 of (T, N, 2) `displacements`, (T, N) px^2, NaN where lost; None where a component is infinite,
    beyond `_SQUARABLE` px or non-zero below 1 / `_SQUARABLE` (squares that overflow or underflow)."""
    dx, dy = displacements[..., 0], displacements[..., 1]
    squared = np.multiply(dx, dx)
    squared += np.square(dy)
    largest = np.nanmax(squared, initial=0.0)
    smallest = np.nanmin(squared, initial=np.inf, where=squared > 0.0)
    if not (largest < _SQUARABLE ** 2 and smallest > _SQUARABLE ** -2) or np.isinf(displacements).any():
        return None  # (np.hypot measures an infinite component beside a NaN as infinite, the square as NaN)
    if np.count_nonzero(squared == 0.0) != np.count_nonzero((dx == 0.0) & (dy == 0.0)):
        return None  # a tiny component squared to 0
    return squared


def _ranked_length(displacements: np.ndarray, squared: np.ndarray, at: np.ndarray, rank: np.ndarray,
                   count: np.ndarray) -> np.ndarray:
    """Per row, the `rank`-th smallest `np.hypot` length of its pins (0 where it has none): `squared` (T, N)
    their squared lengths, `at` (T,) the squared length at that rank among them (each row's sorted)."""
    near = (squared >= at[:, None] * (1.0 - _TIE)) & (squared <= at[:, None] * (1.0 + _TIE))  # (False where NaN)
    alone = np.count_nonzero(near, axis=1) == 1
    length = np.zeros(len(squared))
    rows = np.flatnonzero(alone)  # (nearly every row) one pin at that rank: its own length
    pin = np.argmax(near[rows], axis=1)
    length[rows] = np.hypot(displacements[rows, pin, 0], displacements[rows, pin, 1])
    rows = np.flatnonzero(~alone & (count > 0))
    if rows.size:  # ties: every pin's length, sorted (NaN last), as np.hypot ranks them
        part = displacements[rows]
        length[rows] = np.sort(np.hypot(part[..., 0], part[..., 1]), axis=1)[np.arange(rows.size), rank[rows]]
    return length


def neighbour_median(displacements: np.ndarray, rest_positions: np.ndarray, *, neighbours: int = 6,
                     chunk_frames: int = 256) -> np.ndarray:
    """Each pin's displacement replaced by the median (per axis) over it and its nearest neighbours at rest.

    A contact moves a patch of neighbouring pins together (a press spreads them smoothly, a slide drags
    them one way), so a neighbourhood's median keeps its motion; a pin the tracker misplaced alone
    (recovering from a loss after a lift, a jump in noise) is outvoted by its neighbours, which stayed.
    Pins lost (NaN) are left out of the median: it holds while up to half of a neighbourhood is lost or
    misplaced; a pin whose whole neighbourhood is lost stays NaN.

    Parameters
    ----------
    displacements : (T, N, 2) ndarray
        Displacements from rest, px; NaN where lost.
    rest_positions : (N, 2) ndarray
        The pins' rest positions, px (who neighbours whom).
    neighbours : int
        Neighbours per pin (besides itself), >= 0 (6: a hexagonal lattice's ring).
    chunk_frames : int
        Frames per step (memory: ``chunk_frames * N * (neighbours + 1) * 2`` floats).

    Returns
    -------
    smoothed : (T, N, 2) ndarray of float64
        px.

    Examples
    --------
    >>> rest = np.stack(np.meshgrid(np.arange(5), np.arange(5)), -1).reshape(-1, 2) * 10.0
    >>> displacements = np.zeros((1, 25, 2)); displacements[0, 12] = (6.0, 0.0)   # one pin jumps alone
    >>> float(np.abs(neighbour_median(displacements, rest)).max())
    0.0
    """
    data = np.asarray(displacements, dtype=np.float64)
    rest = np.asarray(rest_positions, dtype=np.float64)
    if data.ndim != 3 or data.shape[2] != 2 or rest.shape != data.shape[1:]:
        raise ShapeError(f"displacements must have shape (T, N, 2) and rest_positions (N, 2), got {data.shape} "
                         f"and {rest.shape}")
    index = _neighbourhoods(rest, neighbours)                          # (N, k+1): the pin first
    if index.shape[1] <= 1:
        return data.copy()
    smoothed = np.empty_like(data)
    for first in range(0, len(data), chunk_frames):
        part = data[first:first + chunk_frames][:, index]             # (F, N, k+1, 2)
        smoothed[first:first + chunk_frames] = nanmedian_rows(np.moveaxis(part, 2, -1))
    return smoothed


def _neighbourhoods(rest: np.ndarray, neighbours: int) -> np.ndarray:
    """(N, k+1) indices of each pin and its `neighbours` nearest pins at rest (the pin first; k <= N - 1)."""
    from scipy.spatial import cKDTree

    if int(neighbours) != neighbours or neighbours < 0:
        raise ValueError(f"neighbours must be a non-negative integer, got {neighbours}")
    count = min(int(neighbours) + 1, len(rest))
    if count <= 1:
        return np.arange(len(rest))[:, None]
    return cKDTree(rest).query(rest, k=count)[1]


class NeighbourMedians:
    """`neighbour_median` one frame at a time, as a tracker places the pins: the same numbers, bit for bit.

    Replay computes its contacts' neighbourhood medians while it tracks (`tactip.pipeline.track_pins`'
    ``each_row``) instead of over the whole recording after the last frame, whose work is on its critical path
    whole (issue 20, outcome 9). Each frame's
    medians are computed by one compiled call (`pins._jit_track.displacement_nanmedian`), or by
    `neighbour_median`'s NumPy code on that frame (``TACTIP_KERNELS=numpy``, or Numba missing).

    Parameters
    ----------
    rest_positions : (N, 2) ndarray
        The pins' rest positions, px (who neighbours whom, and where displacements start).
    neighbours : int
        As `neighbour_median`.

    Examples
    --------
    >>> rest = np.stack(np.meshgrid(np.arange(5), np.arange(5)), -1).reshape(-1, 2) * 10.0
    >>> medians = NeighbourMedians(rest)
    >>> moved = rest.copy(); moved[12] += (6.0, 0.0)                           # one pin jumps alone
    >>> medians.add(rest); medians.add(moved)
    >>> table = medians.table()
    >>> table.shape, float(np.abs(table).max())
    ((2, 25, 2), 0.0)
    """

    def __init__(self, rest_positions: np.ndarray, *, neighbours: int = 6):
        self.rest_positions = np.array(rest_positions, dtype=np.float64)
        if self.rest_positions.ndim != 2 or self.rest_positions.shape[1] != 2:
            raise ShapeError(f"rest_positions must have shape (N, 2), got {self.rest_positions.shape}")
        self._index = _neighbourhoods(self.rest_positions, neighbours)
        self._rows: list[np.ndarray] = []

    def __len__(self) -> int:
        return len(self._rows)

    def add(self, positions: np.ndarray) -> None:
        """Append one frame's medians, of the (N, 2) `positions`, px (NaN where lost)."""
        rest = self.rest_positions
        positions = np.asarray(positions, dtype=np.float64)
        if positions.shape != rest.shape:
            raise ShapeError(f"positions must have shape {rest.shape}, got {positions.shape}")
        if self._index.shape[1] <= 1:
            self._rows.append(positions - rest)
            return
        from ._kernels import compiled

        kernels = compiled("_jit_track")
        if kernels is not None:
            self._rows.append(kernels.displacement_nanmedian(positions, rest, self._index))
        else:
            self._rows.append(nanmedian_rows(np.moveaxis((positions - rest)[self._index], 1, -1)))

    def table(self) -> np.ndarray:
        """(F, N, 2) float64 medians of the frames added, px: `neighbour_median` of their displacements."""
        if not self._rows:
            return np.zeros((0, *self.rest_positions.shape))
        return np.stack(self._rows)


def segment_taps(displacements: np.ndarray, *, high_px: float = 1.5, low_px: float = 0.5,
                 min_frames: int = 3, merge_gap_frames: int = 2, pad_frames: int = 1,
                 percentile: float = 90.0) -> list[tuple[int, int]]:
    """Find the taps in a continuous recording.

    Parameters
    ----------
    displacements : (T, N, 2) or (T,) ndarray
        Displacements from rest, px (NaN where lost), or an already computed tap signal.
    high_px : float
        A tap must reach this signal somewhere, px.
    low_px : float
        A tap lasts while the signal stays above this, px (< `high_px`).
    min_frames : int
        Shortest tap, frames (before padding).
    merge_gap_frames : int
        Taps separated by at most this many quiet frames are merged.
    pad_frames : int
        Frames added before and after each tap (clipped to the recording) to keep the onset.
    percentile : float
        Percentile over pins of the tap signal (see `tap_signal`).

    Returns
    -------
    taps : list of (start, stop)
        Frame index ranges, stop exclusive, in order, not overlapping.

    Examples
    --------
    >>> displacements = np.zeros((28, 331, 2))      # (T, N, 2) px
    >>> displacements[10:18] = 3.0                  # one tap, frames 10-17
    >>> segment_taps(displacements)                 # padded by one frame each side
    [(9, 19)]
    """
    data = np.asarray(displacements, dtype=np.float64)
    signal = data if data.ndim == 1 else tap_signal(data, percentile=percentile)
    if not 0.0 <= low_px < high_px:
        raise ValueError(f"need 0 <= low_px < high_px, got low_px={low_px}, high_px={high_px}")
    for name, value in (("min_frames", min_frames), ("merge_gap_frames", merge_gap_frames),
                        ("pad_frames", pad_frames)):
        if int(value) != value or value < 0:
            raise ValueError(f"{name} must be a non-negative integer, got {value}")
    signal = np.nan_to_num(signal, nan=0.0)
    runs, count = ndimage.label(signal > low_px)
    if count == 0:
        return []
    peaks = np.asarray(ndimage.maximum(signal, runs, np.arange(1, count + 1)))
    slices = ndimage.find_objects(runs)
    bounds = np.array([(s[0].start, s[0].stop) for s in slices])[peaks > high_px]
    if len(bounds) == 0:
        return []
    # Merge runs whose quiet gap is short: a new tap starts where the gap is longer.
    gap = bounds[1:, 0] - bounds[:-1, 1]
    first = np.concatenate([[True], gap > merge_gap_frames])
    starts = bounds[first, 0]
    stops = np.maximum.reduceat(bounds[:, 1], np.flatnonzero(first))
    keep = (stops - starts) >= min_frames
    starts = np.maximum(starts[keep] - pad_frames, 0)
    stops = np.minimum(stops[keep] + pad_frames, len(signal))
    # Padding must not make neighbouring taps overlap.
    if len(starts) > 1:
        starts[1:] = np.maximum(starts[1:], stops[:-1])
    return [(int(a), int(b)) for a, b in zip(starts, stops)]


def converging_frames(displacements: np.ndarray, rest_positions: np.ndarray, *, high_px: float = 1.5,
                      cosine: float = -0.5, percentile: float = 90.0, signal: np.ndarray | None = None) -> np.ndarray:
    """Frames whose displaced pins move *towards* the centre of their displacement: a pressed reference.

    A TacTip pressed by an object spreads its pins away from the contact, so displacements
    measured from a true rest frame point outward from the displaced region. When the "rest"
    frame was itself taken during a tap, the frames where the pad is really at rest show the
    opposite: the displaced pins drawn together. This finds those frames.

    For each frame, the pins are weighted by their squared displacement magnitude; the centre is
    the weighted mean of their rest positions; the frame's score is the weighted mean cosine
    between each pin's displacement and its rest position's offset from that centre (+1 all
    outward, -1 all inward). A frame converges when its score is below `cosine` and its tap
    signal (`tap_signal`) exceeds `high_px`.

    Parameters
    ----------
    displacements : (T, N, 2) ndarray
        Displacements from the rest frame, px; NaN where lost (ignored).
    rest_positions : (N, 2) ndarray
        Pin positions in the rest frame, px.
    high_px : float
        Smallest tap signal of a converging frame, px.
    cosine : float
        Largest score of a converging frame, in [-1, 1].
    percentile : float
        Percentile of the tap signal.
    signal : (T,) ndarray, optional
        The tap signal when already computed (`tap_signal` at `percentile`), px.

    Returns
    -------
    frames : (K,) ndarray of int
        Indices of the converging frames, in order.
    """
    data = np.asarray(displacements, dtype=np.float32)
    rest = np.asarray(rest_positions, dtype=np.float32)
    if data.ndim != 3 or data.shape[2] != 2 or rest.shape != data.shape[1:]:
        raise ShapeError(f"displacements must have shape (T, N, 2) and rest_positions (N, 2), got {data.shape} "
                         f"and {rest.shape}")
    if not -1.0 <= cosine <= 1.0:
        raise ValueError(f"cosine must be in [-1, 1], got {cosine}")
    data = np.nan_to_num(data)
    magnitude = np.hypot(data[..., 0], data[..., 1])
    weight = magnitude**2
    total = weight.sum(axis=1) + 1e-12
    centre = (weight @ rest) / total[:, None]
    # Offsets (T, N, 2) of each pin's rest position from its frame's centre.
    offset = rest[None] - centre[:, None]
    along = np.einsum("tnk,tnk->tn", offset, data)
    norms = np.hypot(offset[..., 0], offset[..., 1]) * magnitude
    cosines = np.divide(along, norms, out=np.zeros_like(along), where=norms > 0)
    score = (weight * cosines).sum(axis=1) / total
    if signal is None:
        signal = tap_signal(displacements, percentile=percentile)
    elif np.shape(signal) != (len(data),):
        raise ShapeError(f"signal must have shape ({len(data)},), got {np.shape(signal)}")
    return np.flatnonzero((score < cosine) & (signal > high_px))


def jitter_floor_px(displacements: np.ndarray, *, usable: np.ndarray | None = None) -> float:
    """The tap signal of a still pad, px, estimated from the pins' frame-to-frame jitter.

    Tracking noise of standard deviation sigma per axis, white in time, gives second differences
    ``d[t+1] - 2 d[t] + d[t-1]`` of standard deviation ``sqrt(6) sigma`` per axis, whose magnitude's
    median over the pins is ``1.18 sqrt(6) sigma``; smooth contact motion adds little to them. A
    still pad's tap signal (the 90th percentile over pins of ``|d|``, each pin's rest position
    carrying the same noise) is then ``2.15 sqrt(2) sigma``, about 1.05 times that median. The
    frames' medians are summarised by their 25th percentile, so that fast motion in a few frames
    does not count. Needs no quiet frames, unlike a percentile of the tap signal itself.

    Parameters
    ----------
    displacements : (T, N, 2) ndarray
        Displacements from rest, px; NaN where lost (ignored).
    usable : (T,) ndarray of bool, optional
        Frames to measure on (tracked, not blank); all by default. A second difference needs its
        three frames usable.

    Returns
    -------
    floor : float
        px; infinite when fewer than three consecutive usable frames exist.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> still = rng.normal(0.0, 0.1, (200, 300, 2))          # sigma 0.1 px per axis, no contact
    >>> round(jitter_floor_px(still), 2), round(float(np.median(tap_signal(still - still[0]))), 2)
    (0.29, 0.3)
    """
    data = np.asarray(displacements, dtype=np.float64)
    if data.ndim != 3 or data.shape[2] != 2:
        raise ShapeError(f"displacements must have shape (T, N, 2), got {data.shape}")
    if len(data) < 3:
        return float("inf")
    second = data[2:] - 2.0 * data[1:-1] + data[:-2]
    jitter = np.hypot(second[..., 0], second[..., 1])
    if usable is not None:
        usable = np.asarray(usable, dtype=bool)
        jitter = jitter[usable[2:] & usable[1:-1] & usable[:-2]]
    finite = np.isfinite(jitter)
    rows = finite.any(axis=1)
    if not rows.any():
        return float("inf")
    medians = nanmedian_rows(np.where(finite[rows], jitter[rows], np.nan))
    return 1.05 * float(np.percentile(medians, 25))
