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
3. ``segment_taps`` (in `tactip.taxel.segment`): cuts one window per tap, either at explicit start (and optional stop) times, e.g.
   the arm's tap commands, or where the pressure on any taxel first exceeds a threshold (with a
   pre-trigger), then resamples each window linearly onto ``samples`` evenly spaced instants, giving
   ``(samples, taxels)`` float arrays like the optical front end's taps.
4. ``remove_tap_baseline``: subtracts from each tap the mean of its first ``baseline_samples`` samples
   (before contact). A high-pass filter over a train of taps also removes their average, which leaves
   each tap on a small negative offset that depends on the taps before it; a live sequence of taps at
   changing locations would then not look like the training sweep. The per-tap baseline removes it.

`tactip.taxel.segment.TapSegmenter` does the same on a live stream, reading by reading or in blocks.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "FULL_SCALE_COUNTS", "BASELINE_SAMPLES", "HighPassFilter", "highpass", "taxel_pressure", "resample_taps",
    "remove_tap_baseline",
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
