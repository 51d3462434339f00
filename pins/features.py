"""Tap features: the pin displacements of one tap as a fixed-size array (paper 002, eq. 1).

A tap z_t = {s_k(j)} has N_samples time samples j of N_dim = 2 P data dimensions k, the x and y
displacements of the P selected pins (paper: 40 samples x 80 dimensions). Layout of a feature
array, shape (n_samples, 2 P):

- columns 0 .. P-1: x displacements (dx, px) of the selected pins, in selection order;
- columns P .. 2P-1: y displacements (dy, px) of the same pins, same order.

`feature_dim_names(P)` names the columns ("pin00_dx" ... "pin39_dx", "pin00_dy" ...).

A tap is recorded at the camera's frame rate for however long it lasts and resampled to
`n_samples` by linear interpolation over its duration (by time stamps when given). Pins lost for
some frames are interpolated over time from the frames where they were seen; a pin never seen
during the tap cannot be: its dx and dy columns are NaN in every sample (a missing dimension, which
the likelihood models marginalise, `perception.likelihood`). `seen_pins` says which pins were seen;
whether a tap with unseen pins is still usable is the caller's rule (`tactip.pipeline`).
"""

from __future__ import annotations

import numpy as np

from .errors import PinsError, ShapeError

__all__ = ["feature_dim_names", "fill_lost", "resample_tap", "seen_pins", "tap_features", "TapRecorder",
           "LostPinError"]


class LostPinError(PinsError):
    """A selected pin was lost during a whole tap (or too many were), so its displacements cannot be filled in."""


def feature_dim_names(n_pins: int) -> list[str]:
    """Names of the 2 P feature columns, in layout order.

    Parameters
    ----------
    n_pins : int
        Number of selected pins P.

    Returns
    -------
    names : list of str
        ``["pin00_dx", ..., f"pin{P-1}_dx", "pin00_dy", ..., f"pin{P-1}_dy"]`` (two digits, more
        when P > 100); the number is the position in the selection order.

    Examples
    --------
    >>> feature_dim_names(2)
    ['pin00_dx', 'pin01_dx', 'pin00_dy', 'pin01_dy']
    """
    if int(n_pins) != n_pins or n_pins < 0:
        raise ValueError(f"n_pins must be a non-negative integer, got {n_pins}")
    width = max(2, len(str(max(int(n_pins) - 1, 0))))
    return [f"pin{k:0{width}d}_{axis}" for axis in ("dx", "dy") for k in range(int(n_pins))]


def fill_lost(series: np.ndarray, *, keep_unseen: bool = False) -> np.ndarray:
    """Fill NaN samples by linear interpolation over time, column by column, all columns at once.

    Samples before the first or after the last valid one take that valid value.

    Parameters
    ----------
    series : (T, ...) ndarray
        Time along axis 0; NaN where unknown.
    keep_unseen : bool
        A column without any valid sample stays NaN (True) or raises (False).

    Returns
    -------
    filled : (T, ...) ndarray of float64

    Raises
    ------
    LostPinError
        A column has no valid sample at all and ``keep_unseen`` is False (the message lists the columns).
    """
    series = np.asarray(series, dtype=np.float64)
    if series.ndim < 1 or series.shape[0] == 0:
        raise ShapeError(f"series must have a time axis with at least one sample, got shape {series.shape}")
    flat = series.reshape(series.shape[0], -1)
    valid = np.isfinite(flat)
    if valid.all():
        return series.copy()
    never = np.flatnonzero(~valid.any(axis=0))
    if never.size and not keep_unseen:
        raise LostPinError(f"{never.size} feature column(s) have no valid sample in the tap "
                           f"(first: {never[:5].tolist()}); the pin was lost for the whole tap")
    steps = flat.shape[0]
    t = np.arange(steps)[:, None]
    # Index of the last valid sample at or before t, and of the first at or after t.
    before = np.maximum.accumulate(np.where(valid, t, -1), axis=0)
    after = np.minimum.accumulate(np.where(valid, t, steps)[::-1], axis=0)[::-1]
    before = np.where(before < 0, after, before)
    after = np.where(after >= steps, before, after)
    if never.size:  # columns without a valid sample point nowhere: any index, they stay NaN
        before, after = np.minimum(before, steps - 1), np.minimum(after, steps - 1)
    columns = np.arange(flat.shape[1])[None, :]
    low, high = flat[before, columns], flat[after, columns]
    span = np.maximum(after - before, 1)
    filled = low + (high - low) * (t - before) / span
    return np.where(valid, flat, filled).reshape(series.shape)


def resample_tap(series: np.ndarray, n_samples: int, *, timestamps_s: np.ndarray | None = None) -> np.ndarray:
    """Resample a tap to `n_samples` evenly spaced samples over its duration (linear interpolation).

    Parameters
    ----------
    series : (T, C) ndarray
        T >= 2 samples of C columns, no NaN (a column NaN throughout stays NaN).
    n_samples : int
        Number of output samples (paper: 40).
    timestamps_s : (T,) ndarray, optional
        Strictly increasing sample times, s; evenly spaced frames when not given.

    Returns
    -------
    resampled : (n_samples, C) ndarray of float64
        First and last samples equal the first and last input samples.
    """
    series = np.asarray(series, dtype=np.float64)
    if series.ndim != 2:
        raise ShapeError(f"series must have shape (T, C), got {series.shape}")
    steps = series.shape[0]
    if steps < 2:
        raise PinsError(f"a tap needs at least 2 frames to resample, got {steps}")
    if int(n_samples) != n_samples or n_samples < 2:
        raise ValueError(f"n_samples must be an integer >= 2, got {n_samples}")
    if timestamps_s is None:
        position = np.linspace(0.0, steps - 1.0, int(n_samples))
    else:
        times = np.asarray(timestamps_s, dtype=np.float64)
        if times.shape != (steps,):
            raise ShapeError(f"timestamps_s must have shape ({steps},), got {times.shape}")
        if not np.all(np.diff(times) > 0):
            raise ValueError("timestamps_s must be strictly increasing")
        targets = np.linspace(times[0], times[-1], int(n_samples))
        # Fractional frame index of each target time.
        position = np.interp(targets, times, np.arange(steps, dtype=np.float64))
    low = np.minimum(np.floor(position).astype(np.intp), steps - 2)
    fraction = (position - low)[:, None]
    return series[low] * (1.0 - fraction) + series[low + 1] * fraction


def tap_features(displacements: np.ndarray, *, pins: np.ndarray | None = None, n_samples: int = 40,
                 timestamps_s: np.ndarray | None = None) -> np.ndarray:
    """The feature array of one tap.

    Parameters
    ----------
    displacements : (T, N, 2) ndarray
        Displacements from rest of all N tracked pins over the T frames of the tap, px; NaN where lost.
    pins : (P,) ndarray of int, optional
        Selected pin indices (`pins.select.select_pins`), in selection order; all pins when omitted.
    n_samples : int
        Samples per tap after resampling (paper: 40).
    timestamps_s : (T,) ndarray, optional
        Frame times, s (for uneven frame intervals).

    Returns
    -------
    features : (n_samples, 2 P) ndarray of float64
        Columns 0..P-1 = dx, P..2P-1 = dy of the selected pins (see `feature_dim_names`); both columns
        of a pin lost in every frame of the tap are NaN in every sample (`seen_pins`).

    Examples
    --------
    >>> displacements = np.random.default_rng(0).normal(size=(25, 331, 2))   # (T, N, 2) px, one tap
    >>> tap_features(displacements, pins=np.arange(40)).shape
    (40, 80)
    """
    displacements = np.asarray(displacements, dtype=np.float64)
    if displacements.ndim != 3 or displacements.shape[2] != 2:
        raise ShapeError(f"displacements must have shape (T, N, 2), got {displacements.shape}")
    if pins is not None:
        pins = np.asarray(pins, dtype=np.intp)
        if pins.ndim != 1 or (pins.size and (pins.min() < 0 or pins.max() >= displacements.shape[1])):
            raise ShapeError(f"pins must be a 1-D array of indices below {displacements.shape[1]}")
        displacements = displacements[:, pins]
    # (T, P, 2) -> (T, 2P) with all dx first, then all dy.
    series = np.concatenate([displacements[:, :, 0], displacements[:, :, 1]], axis=1)
    # A pin seen in some frames is interpolated over time; one never seen keeps NaN columns.
    return resample_tap(fill_lost(series, keep_unseen=True), n_samples, timestamps_s=timestamps_s)


def seen_pins(displacements: np.ndarray, *, pins: np.ndarray | None = None) -> np.ndarray:
    """Which pins were seen (had a displacement) in at least one frame of a tap.

    Parameters
    ----------
    displacements : (T, N, 2) ndarray
        Displacements from rest of all N tracked pins over the T frames of the tap, px; NaN where lost.
    pins : (P,) ndarray of int, optional
        Selected pin indices, in selection order; all pins when omitted.

    Returns
    -------
    seen : (P,) ndarray of bool
        In selection order; False for a pin whose feature columns `tap_features` leaves NaN.

    Examples
    --------
    >>> displacements = np.zeros((5, 3, 2))
    >>> displacements[:, 1] = np.nan                    # pin 1 lost in every frame
    >>> seen_pins(displacements).tolist()
    [True, False, True]
    """
    displacements = np.asarray(displacements, dtype=np.float64)
    if displacements.ndim != 3 or displacements.shape[2] != 2:
        raise ShapeError(f"displacements must have shape (T, N, 2), got {displacements.shape}")
    if pins is not None:
        displacements = displacements[:, np.asarray(pins, dtype=np.intp)]
    return np.isfinite(displacements).all(axis=2).any(axis=0)


class TapRecorder:
    """Accumulate the displacements of frames between `start` and `stop` into one tap's features.

    For callers that know when the arm taps (the station): ``start()`` when the tap begins,
    ``add(displacements)`` every frame, ``stop()`` when it ends to get the feature array.
    Frames added while not recording are ignored.

    Parameters
    ----------
    pins : (P,) ndarray of int
        Selected pin indices, in selection order.
    n_samples : int
        Samples per tap (paper: 40).

    Examples
    --------
    >>> recorder = TapRecorder(np.arange(40), n_samples=40)
    >>> recorder.start()
    >>> for k in range(25):                  # each frame: tracker.update(frame) - rest, (N, 2) px
    ...     _ = recorder.add(np.full((331, 2), 0.1 * k), timestamp_s=k / 50)
    >>> recorder.stop().shape
    (40, 80)
    """

    def __init__(self, pins: np.ndarray, *, n_samples: int = 40) -> None:
        pins = np.asarray(pins, dtype=np.intp)
        if pins.ndim != 1 or pins.size == 0:
            raise ShapeError(f"pins must be a non-empty 1-D array of indices, got shape {pins.shape}")
        if int(n_samples) != n_samples or n_samples < 2:
            raise ValueError(f"n_samples must be an integer >= 2, got {n_samples}")
        self.pins = pins
        self.n_samples = int(n_samples)
        self.recording = False
        self._frames: list[np.ndarray] = []
        self._times: list[float | None] = []

    def __repr__(self) -> str:
        return (f"TapRecorder(pins={len(self.pins)}, n_samples={self.n_samples}) "
                f"[{'recording' if self.recording else 'idle'}, {len(self._frames)} frames]")

    def start(self) -> None:
        """Begin a tap (forgets any frames of an unfinished one)."""
        self.recording = True
        self._frames.clear()
        self._times.clear()

    def add(self, displacements: np.ndarray, *, timestamp_s: float | None = None) -> bool:
        """Record one frame's displacements if a tap is being recorded.

        Parameters
        ----------
        displacements : (N, 2) ndarray
            Displacements of all tracked pins from rest, px; NaN where lost.
        timestamp_s : float, optional
            Frame time, s (give it for every frame of a tap or for none).

        Returns
        -------
        recorded : bool
            False when not recording (the frame is ignored).
        """
        if not self.recording:
            return False
        displacements = np.asarray(displacements, dtype=np.float64)
        if displacements.ndim != 2 or displacements.shape[1] != 2 or displacements.shape[0] <= self.pins.max():
            raise ShapeError(f"displacements must have shape (N, 2) with N > {self.pins.max()}, "
                             f"got {displacements.shape}")
        self._frames.append(displacements[self.pins].copy())
        self._times.append(None if timestamp_s is None else float(timestamp_s))
        return True

    def stop(self) -> np.ndarray:
        """End the tap and return its features.

        Returns
        -------
        features : (n_samples, 2 P) ndarray of float64
            Layout as in `tap_features`; NaN columns for a pin lost throughout.

        Raises
        ------
        PinsError
            Not recording, or fewer than 2 frames recorded.

        Notes
        -----
        A selected pin lost for the whole tap has NaN columns (`tap_features`).
        """
        if not self.recording:
            raise PinsError("TapRecorder.stop called without start()")
        self.recording = False
        if len(self._frames) < 2:
            raise PinsError(f"a tap needs at least 2 frames, recorded {len(self._frames)}")
        times = None if any(t is None for t in self._times) else np.array(self._times)
        return tap_features(np.stack(self._frames), n_samples=self.n_samples, timestamps_s=times)
