"""From raw 8-bit taxel readings to taps: high-pass filter, normalise, segment and resample.

Paper 000 (Sec. III-A): "Data were collected at 8 bit resolution and then highpass filtered and
normalized". A capacitive taxel reads about 235 counts at rest and *lower* under pressure (the iCub skin
convention), and its rest reading drifts slowly with temperature. So:

1. ``highpass``: a Butterworth high-pass (default 2nd order, 0.02 Hz, i.e. a ~8 s time constant) over
   the continuous stream removes the rest level and its drift but keeps the ~0.3 s taps. It starts in
   steady state on the first reading, so a stream does not begin with a filter transient.
2. ``taxel_pressure``: flips the sign so that pressure is positive, and normalises by the 8-bit full
   scale (255 counts): values are fractions of the sensor's range, the same for every taxel and every
   session (no statistics of the data are used, so training, test and live data are scaled alike).
3. ``segment_taps``: cuts one window per tap, either at explicit start (and optional stop) times, e.g.
   the arm's tap commands, or where the pressure on any taxel first exceeds a threshold (with a
   pre-trigger), then resamples each window linearly onto ``samples`` evenly spaced instants, giving
   ``(samples, taxels)`` float arrays like the optical front end's taps.
4. ``remove_tap_baseline``: subtracts from each tap the mean of its first ``baseline_samples`` samples
   (before contact). A high-pass filter over a train of taps also removes their average, which leaves
   each tap on a small negative offset that depends on the taps before it; a live sequence of taps at
   changing locations would then not look like the training sweep. The per-tap baseline removes it.

`TapSegmenter` does the same on a live stream, reading by reading or in blocks.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "FULL_SCALE_COUNTS", "BASELINE_SAMPLES", "HighPassFilter", "highpass", "taxel_pressure", "resample_taps",
    "remove_tap_baseline", "detect_taps", "segment_taps", "TapSegments", "TapSegmenter",
]

#: Samples at the start of each tap window taken as its rest level (before contact).
BASELINE_SAMPLES = 8

FULL_SCALE_COUNTS = 255.0


class HighPassFilter:
    """A Butterworth high-pass filter that keeps its state between blocks of readings.

    Parameters
    ----------
    taxels : int
        Number of taxels ``K``.
    sample_rate_hz : float
        Readings per second.
    cutoff_hz : float
        -3 dB frequency, Hz.
    order : int
        Filter order.

    Examples
    --------
    >>> hp = HighPassFilter(2, sample_rate_hz=50.0)
    >>> out = hp(np.full((100, 2), 235.0))     # a constant rest level is removed
    >>> bool(np.abs(out).max() < 1e-6)
    True
    """

    def __init__(self, taxels: int, *, sample_rate_hz: float = 50.0, cutoff_hz: float = 0.02, order: int = 2):
        if not 0 < cutoff_hz < sample_rate_hz / 2:
            raise ValueError(f"cutoff_hz must be in (0, {sample_rate_hz / 2}), got {cutoff_hz}")
        self.taxels = int(taxels)
        self.sample_rate_hz = float(sample_rate_hz)
        self.cutoff_hz = float(cutoff_hz)
        self.order = int(order)
        from scipy import signal   # deferred: scipy.signal takes ~0.5 s to import, and the CLI imports tactip

        self._sos = signal.butter(self.order, self.cutoff_hz, btype="highpass", fs=self.sample_rate_hz, output="sos")
        self._zi = None

    def __repr__(self) -> str:
        return (f"HighPassFilter(taxels={self.taxels}, sample_rate_hz={self.sample_rate_hz}, "
                f"cutoff_hz={self.cutoff_hz}, order={self.order})")

    def reset(self) -> None:
        """Forget the state: the next block starts in steady state on its first reading."""
        self._zi = None

    def __call__(self, readings) -> np.ndarray:
        """Filter the next block of readings.

        Parameters
        ----------
        readings : (T, K) array_like
            Consecutive readings, counts.

        Returns
        -------
        (T, K) ndarray of float64
        """
        x = np.asarray(readings, dtype=np.float64)
        if x.ndim != 2 or x.shape[1] != self.taxels:
            raise ValueError(f"readings must have shape (T, {self.taxels}), got {x.shape}")
        if len(x) == 0:
            return x.copy()
        from scipy import signal

        if self._zi is None:
            # steady state for a constant input equal to the first reading: no start-up transient
            self._zi = signal.sosfilt_zi(self._sos)[:, :, None] * x[0][None, None, :]
        y, self._zi = signal.sosfilt(self._sos, x, axis=0, zi=self._zi)
        return y


def highpass(readings, *, sample_rate_hz: float = 50.0, cutoff_hz: float = 0.02, order: int = 2) -> np.ndarray:
    """High-pass filter a whole stream of readings, starting in steady state.

    Parameters
    ----------
    readings : (T, K) array_like
        Readings in time order, counts.
    sample_rate_hz, cutoff_hz, order
        As `HighPassFilter`.

    Returns
    -------
    (T, K) ndarray of float64
        The readings without their slow rest level, counts.
    """
    x = np.asarray(readings, dtype=np.float64)
    if x.ndim != 2:
        raise ValueError(f"readings must have shape (T, K), got {x.shape}")
    return HighPassFilter(x.shape[1], sample_rate_hz=sample_rate_hz, cutoff_hz=cutoff_hz, order=order)(x)


def taxel_pressure(readings, *, sample_rate_hz: float = 50.0, cutoff_hz: float = 0.02,
                   contact_lowers_reading: bool = True, full_scale_counts: float = FULL_SCALE_COUNTS) -> np.ndarray:
    """Pressure signal of a stream: high-pass filtered, positive under contact, normalised.

    Parameters
    ----------
    readings : (T, K) array_like
        Raw readings, 8-bit counts, in time order.
    sample_rate_hz, cutoff_hz
        Of the high-pass filter (`highpass`).
    contact_lowers_reading : bool
        True for iCub taxels (rest ~235, lower under pressure); False if pressure raises the reading.
    full_scale_counts : float
        Divisor of the normalisation (255 for 8 bits).

    Returns
    -------
    (T, K) ndarray of float64
        Pressure as a fraction of full scale (0 at rest).
    """
    sign = -1.0 if contact_lowers_reading else 1.0
    return highpass(readings, sample_rate_hz=sample_rate_hz, cutoff_hz=cutoff_hz) * (sign / full_scale_counts)


def resample_taps(timestamps_s, values, starts_s, *, stops_s=None, duration_s: float = 1.0,
                  samples: int = 50) -> np.ndarray:
    """Linearly resample the stream in each tap window onto ``samples`` evenly spaced instants.

    Sample ``j`` of a tap starting at ``s`` and lasting ``D`` seconds is at ``s + j * D / samples``, so
    a 1 s window of a 50 Hz stream gives its 50 readings back unchanged.

    Parameters
    ----------
    timestamps_s : (T,) array_like
        Strictly increasing reading times, s.
    values : (T, K) array_like
        The stream (e.g. `taxel_pressure`).
    starts_s : (N,) array_like
        Window start times, s.
    stops_s : (N,) array_like, optional
        Window end times, s; default ``starts_s + duration_s``.
    duration_s : float
        Window length when ``stops_s`` is not given, s.
    samples : int
        Samples per tap.

    Returns
    -------
    (N, samples, K) ndarray of float64

    Raises
    ------
    ValueError
        If a window reaches outside the stream or the timestamps are not increasing.
    """
    t = np.asarray(timestamps_s, dtype=np.float64)
    v = np.asarray(values, dtype=np.float64)
    starts = np.atleast_1d(np.asarray(starts_s, dtype=np.float64))
    if v.ndim != 2 or t.shape != (len(v),):
        raise ValueError(f"timestamps_s (T,) and values (T, K) do not match: {t.shape} and {v.shape}")
    if samples < 1:
        raise ValueError(f"samples must be >= 1, got {samples}")
    if len(t) > 1 and not np.all(np.diff(t) > 0):
        raise ValueError("timestamps_s must be strictly increasing")
    stops = starts + duration_s if stops_s is None else np.atleast_1d(np.asarray(stops_s, dtype=np.float64))
    if stops.shape != starts.shape or np.any(stops <= starts):
        raise ValueError("stops_s must match starts_s and come after each start")
    if len(starts) == 0:
        return np.zeros((0, samples, v.shape[1]))
    grid = starts[:, None] + (stops - starts)[:, None] * (np.arange(samples) / samples)[None, :]   # (N, S)
    last = grid[:, -1]
    tol = 1e-9
    if len(t) == 0 or grid.min() < t[0] - tol or last.max() > t[-1] + tol:
        span = f"[{t[0]:.3f}, {t[-1]:.3f}] s" if len(t) else "empty"
        raise ValueError(f"a tap window [{grid.min():.3f}, {last.max():.3f}] s reaches outside the stream {span}")
    right = np.clip(np.searchsorted(t, grid, side="right"), 1, max(len(t) - 1, 1))
    left = right - 1
    if len(t) == 1:
        return np.broadcast_to(v[0], (len(starts), samples, v.shape[1])).copy()
    # linear interpolation: v(g) = v[l] + (g - t[l]) / (t[r] - t[l]) * (v[r] - v[l])
    w = np.clip((grid - t[left]) / (t[right] - t[left]), 0.0, 1.0)[..., None]
    return v[left] + w * (v[right] - v[left])


def remove_tap_baseline(taps, *, baseline_samples: int = BASELINE_SAMPLES) -> np.ndarray:
    """Subtract from each tap the mean of its first ``baseline_samples`` samples, per taxel.

    Parameters
    ----------
    taps : (N, samples, K) or (samples, K) array_like
    baseline_samples : int
        Samples before contact; 0 leaves the taps unchanged.

    Returns
    -------
    ndarray of float64, the shape of ``taps``
    """
    x = np.asarray(taps, dtype=np.float64)
    if baseline_samples < 0 or baseline_samples > x.shape[-2]:
        raise ValueError(f"baseline_samples must be in [0, {x.shape[-2]}], got {baseline_samples}")
    if baseline_samples == 0:
        return x.copy()
    return x - x[..., :baseline_samples, :].mean(axis=-2, keepdims=True)


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
