"""Cutting taxel streams into taps: at explicit start (and stop) times or by signal magnitude.

`segment_taps` works on a whole recorded stream of pressure (`tactip.taxel.preprocess.taxel_pressure`);
`TapSegmenter` does the same on a live stream of raw readings, block by block, and returns each tap
as soon as the stream has passed the end of its window. Both resample each window onto ``samples``
evenly spaced instants and subtract the tap's rest level (`remove_tap_baseline`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tactip.taxel.preprocess import BASELINE_SAMPLES, FULL_SCALE_COUNTS, HighPassFilter, remove_tap_baseline, resample_taps

__all__ = ["detect_taps", "segment_taps", "TapSegments", "TapSegmenter"]


def detect_taps(timestamps_s, pressure, *, threshold: float = 0.03, pre_trigger_s: float = 0.3,
                duration_s: float = 1.0, min_interval_s: float | None = None) -> np.ndarray:
    """Start times of the taps in a pressure stream, found by signal magnitude.

    A tap is triggered where the largest pressure over the taxels rises above ``threshold``; its window
    starts ``pre_trigger_s`` earlier. Triggers closer than ``min_interval_s`` (default ``duration_s``)
    after the previous one are part of the same tap. Windows that would leave the stream are dropped.

    Parameters
    ----------
    timestamps_s : (T,) array_like
        Reading times, s.
    pressure : (T, K) array_like
        Output of `taxel_pressure` (fraction of full scale, positive under contact).
    threshold : float
        Trigger level, fraction of full scale (0.03 is ~8 counts).
    pre_trigger_s, duration_s, min_interval_s : float
        Window placement, s.

    Returns
    -------
    (N,) ndarray of float64
        Window start times, s.
    """
    t = np.asarray(timestamps_s, dtype=np.float64)
    p = np.asarray(pressure, dtype=np.float64)
    if p.ndim != 2 or t.shape != (len(p),):
        raise ValueError(f"timestamps_s (T,) and pressure (T, K) do not match: {t.shape} and {p.shape}")
    if len(t) < 2:
        return np.zeros(0)
    above = p.max(axis=1) > threshold
    onsets = np.flatnonzero(above[1:] & ~above[:-1]) + 1
    starts = _debounce(t[onsets], min_interval_s if min_interval_s is not None else duration_s) - pre_trigger_s
    keep = (starts >= t[0]) & (starts + duration_s <= t[-1] + 1e-9)
    return starts[keep]


def _debounce(times: np.ndarray, min_interval_s: float) -> np.ndarray:
    """Keep each trigger time that comes at least ``min_interval_s`` after the last kept one."""
    kept: list[float] = []
    for time in times:            # one iteration per tap, not per reading
        if not kept or time - kept[-1] >= min_interval_s:
            kept.append(float(time))
    return np.array(kept, dtype=np.float64)


@dataclass(frozen=True)
class TapSegments:
    """Taps cut from a stream.

    Attributes
    ----------
    taps : (N, samples, K) ndarray of float32
        Resampled pressure of each tap (fraction of full scale).
    starts_s : (N,) ndarray of float64
        Window start of each tap, s.
    """

    taps: np.ndarray
    starts_s: np.ndarray


def segment_taps(timestamps_s, pressure, *, starts_s=None, stops_s=None, samples: int = 50,
                 duration_s: float = 1.0, threshold: float = 0.03, pre_trigger_s: float = 0.3,
                 baseline_samples: int = BASELINE_SAMPLES) -> TapSegments:
    """Cut a pressure stream into taps: at explicit start (and stop) times, or by signal magnitude.

    Parameters
    ----------
    timestamps_s : (T,) array_like
        Reading times, s.
    pressure : (T, K) array_like
        Output of `taxel_pressure`.
    starts_s, stops_s : (N,) array_like, optional
        Explicit windows, s (e.g. the arm's tap commands). Without ``starts_s`` taps are found by
        `detect_taps` with ``threshold`` and ``pre_trigger_s``.
    samples : int
        Samples per tap (paper 000: 50 per 1 s tap).
    duration_s : float
        Window length when ``stops_s`` is not given, s.
    baseline_samples : int
        Rest samples at the start of each window (`remove_tap_baseline`); 0 keeps the filtered level.

    Returns
    -------
    TapSegments
    """
    if starts_s is None:
        if stops_s is not None:
            raise ValueError("stops_s needs starts_s")
        starts = detect_taps(timestamps_s, pressure, threshold=threshold, pre_trigger_s=pre_trigger_s,
                             duration_s=duration_s)
    else:
        starts = np.atleast_1d(np.asarray(starts_s, dtype=np.float64))
    taps = resample_taps(timestamps_s, pressure, starts, stops_s=stops_s, duration_s=duration_s, samples=samples)
    taps = remove_tap_baseline(taps, baseline_samples=baseline_samples)
    return TapSegments(taps=taps.astype(np.float32), starts_s=starts)


@dataclass
class TapSegmenter:
    """Cut taps out of a live stream of raw readings, block by block.

    Readings go through the same `HighPassFilter` and normalisation as `taxel_pressure`. In
    ``"magnitude"`` mode taps are triggered as in `detect_taps`; in ``"explicit"`` mode the caller marks
    each tap with `mark` (start, and optionally stop, in the stream's clock). A tap is returned by
    `feed` as soon as the stream has passed the end of its window.

    Parameters
    ----------
    taxels : int
        Number of taxels ``K``.
    mode : str
        ``"magnitude"`` or ``"explicit"``.
    samples, duration_s, threshold, pre_trigger_s, baseline_samples
        As `segment_taps`.
    sample_rate_hz, cutoff_hz, contact_lowers_reading
        As `taxel_pressure`.

    Examples
    --------
    >>> seg = TapSegmenter(12)
    >>> taps = seg.feed(timestamps, readings)       # doctest: +SKIP
    >>> [tap.shape for tap in taps]                 # doctest: +SKIP
    [(50, 12)]
    """

    taxels: int
    mode: str = "magnitude"
    samples: int = 50
    duration_s: float = 1.0
    threshold: float = 0.03
    pre_trigger_s: float = 0.3
    baseline_samples: int = BASELINE_SAMPLES
    sample_rate_hz: float = 50.0
    cutoff_hz: float = 0.02
    contact_lowers_reading: bool = True
    _filter: HighPassFilter = field(init=False, repr=False)
    _t: np.ndarray = field(init=False, repr=False)
    _p: np.ndarray = field(init=False, repr=False)
    _windows: list = field(init=False, repr=False)
    _above: bool = field(init=False, repr=False, default=False)
    _last_trigger: float = field(init=False, repr=False, default=-np.inf)

    def __post_init__(self):
        if self.mode not in ("magnitude", "explicit"):
            raise ValueError(f"mode must be 'magnitude' or 'explicit', got {self.mode!r}")
        self._filter = HighPassFilter(self.taxels, sample_rate_hz=self.sample_rate_hz, cutoff_hz=self.cutoff_hz)
        self._t = np.zeros(0)
        self._p = np.zeros((0, self.taxels))
        self._windows = []

    def mark(self, start_s: float, stop_s: float | None = None) -> None:
        """Mark a tap window (explicit mode), in the stream's clock, s.

        Raises
        ------
        ValueError
            If the window ends before it starts, or starts before the oldest reading still buffered
            (about ``pre_trigger_s + 2 * duration_s`` back): mark each tap as it is commanded.
        """
        stop = start_s + self.duration_s if stop_s is None else stop_s
        if stop <= start_s:
            raise ValueError(f"stop_s ({stop_s}) must come after start_s ({start_s})")
        if len(self._t) and start_s < self._t[0]:
            raise ValueError(f"tap window starts at {start_s:.3f} s, before the oldest buffered reading "
                             f"({self._t[0]:.3f} s); mark each tap when it is commanded")
        self._windows.append((float(start_s), float(stop)))

    def feed(self, timestamps_s, readings) -> list[np.ndarray]:
        """Add readings; return the taps completed by them.

        Parameters
        ----------
        timestamps_s : (T,) array_like or float
            Reading times, s, increasing across calls.
        readings : (T, K) or (K,) array_like
            Raw readings, counts.

        Returns
        -------
        list of (samples, K) ndarray of float32
        """
        t = np.atleast_1d(np.asarray(timestamps_s, dtype=np.float64))
        x = np.asarray(readings, dtype=np.float64).reshape(len(t), -1)
        if x.shape[1] != self.taxels:
            raise ValueError(f"readings must have {self.taxels} taxels, got {x.shape[1]}")
        sign = -1.0 if self.contact_lowers_reading else 1.0
        p = self._filter(x) * (sign / FULL_SCALE_COUNTS)
        if self.mode == "magnitude":
            self._trigger(t, p)
        self._t = np.concatenate([self._t, t])
        self._p = np.concatenate([self._p, p])
        done = [w for w in self._windows if w[1] <= self._t[-1]] if len(self._t) else []
        taps = []
        for start, stop in done:
            self._windows.remove((start, stop))
            if start >= self._t[0]:
                tap = resample_taps(self._t, self._p, [start], stops_s=[stop], samples=self.samples)[0]
                taps.append(remove_tap_baseline(tap, baseline_samples=self.baseline_samples).astype(np.float32))
        self._trim()
        return taps

    def _trigger(self, t: np.ndarray, p: np.ndarray) -> None:
        above = p.max(axis=1) > self.threshold
        previous = np.concatenate([[self._above], above[:-1]])
        for onset in t[above & ~previous]:
            if onset - self._last_trigger >= self.duration_s:
                self._last_trigger = float(onset)
                start = onset - self.pre_trigger_s
                self._windows.append((start, start + self.duration_s))
        if len(above):
            self._above = bool(above[-1])

    def _trim(self) -> None:
        keep_from = (self._t[-1] if len(self._t) else 0.0) - (self.pre_trigger_s + 2.0 * self.duration_s)
        if self._windows:
            keep_from = min(keep_from, min(w[0] for w in self._windows))
        first = max(int(np.searchsorted(self._t, keep_from)) - 1, 0)
        self._t, self._p = self._t[first:], self._p[first:]
