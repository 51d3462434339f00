"""Simulated capacitive taxel sensors (iCub fingertip and skin) tapping along a location range.

This reproduces the data collection of paper 000 (Sec. III-A): a Cartesian robot taps the sensor
vertically onto an object (fingertip: 8 mm rod; skin: 8 mm sphere), then moves it by a small step
along the location range before the next tap. Each tap is a 1 s window of 50 readings per taxel
(50 Hz, 8 bit), followed by a 1 s pause so that transients decay. The simulator produces the raw
8-bit stream; `TaxelSimulator.taps` passes it through the same pre-processing as recorded and live
data (`tactip.taxel.preprocess`).

Model of one reading of taxel ``k`` at time ``t`` (counts)::

    reading = rest_k + drift_k(t) + common(t) - response_k(t) + white,   rounded, clipped to 0..255
    response_k(t) = peak_counts * gain_k * a * profile(t - onset) * field_k(x + position error)

- ``field_k(x)``: the taxel's Gaussian receptive field at contact location ``x`` times how much the
  object presses there (`tactip.taxel.sensors.receptive_field_response`, geometry documented there).
- ``profile``: the contact pressure over a tap, a smooth (raised-cosine) rise of ``rise_s`` (0.1 s,
  "~0.1 sec to reach peak amplitude"), a short hold, a release of ``release_s``, passed through a
  first-order lag of ``relax_s`` for the visco-elastic recovery of the foam (the decay tail in
  Figs 9 and 12). Contact starts ``contact_delay_s`` after the tap command (the downward travel), with
  a few ms of jitter.
- ``a``: tap-to-tap force variation (log-normal, 3 %); ``position error``: robot repeatability
  (paper: ~20 um, so 0.02 mm standard deviation).
- ``gain_k``: per-taxel gain variation (10 % standard deviation, fixed for a sensor); ``rest_k``: rest
  reading per taxel (235 counts +- 8, the iCub convention: contact *lowers* the reading).
- Noise: white read noise (0.5 counts before rounding to integer counts, so about 0.65 counts in
  all with the common mode: the capacitance-to-digital converter resolves 16 bits and the iCub keeps
  8 of them), a common-mode noise shared by all taxels of the sensor (0.3 counts, AR(1) with a 0.2 s
  correlation time: supply and interference on the shared converter), and a slow per-taxel thermal
  drift of the rest level (Ornstein-Uhlenbeck, 3 counts, 120 s), which the high-pass filter removes.

Calibration: with these values and the paper's protocol (3000 training and 3000 test taps, 100 bins,
Monte Carlo over the test set, fixation at the centre of the range) the fingertip reproduces Table II
of paper 000: passive perception ~4 mm mean error at every class count (contacts at the two ends of
the range give no response and are confused with each other), active perception 0.02-0.1 mm at
about 2 taps (see ``bench/bench_taxel_table2.py`` and ``tests/perception/test_table2.py``). The
geometry and the tap profile follow the paper; the read noise is what was calibrated: with 0.6 counts
white and 0.5 counts common-mode noise one simulated sensor in six (seed 4) missed 0.2 mm at 300
classes; with the values above all ten sensors of seeds 0-9 stay below 0.18 mm.

Everything is drawn from ``numpy.random.default_rng``: a simulator built with the same seed gives the
same sensor (gains, rest levels) and, for the same collection seed, the same readings. Two collections
with different seeds are independent noise realisations on the same physical sensor, as the training
and test sets of the paper ("All data were collected twice").
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Iterator

import numpy as np

from tactip.taxel.preprocess import BASELINE_SAMPLES, FULL_SCALE_COUNTS, HighPassFilter, remove_tap_baseline, resample_taps
from tactip.taxel.sensors import TaxelSensor, receptive_field_response, taxel_sensor

__all__ = ["TaxelStream", "TaxelSimulator", "contact_profile", "sweep_locations"]


def contact_profile(t_s, *, rise_s: float = 0.1, hold_s: float = 0.05, release_s: float = 0.1) -> np.ndarray:
    """Contact pressure over a tap as a fraction of its peak: raised-cosine rise, hold, release.

    Parameters
    ----------
    t_s : array_like
        Time since contact onset, s.
    rise_s, hold_s, release_s : float
        Durations of the three phases, s.

    Returns
    -------
    ndarray of float64 in [0, 1], the shape of ``t_s``

    Examples
    --------
    >>> contact_profile([-0.1, 0.05, 0.12, 0.3]).round(2).tolist()
    [0.0, 0.5, 1.0, 0.0]
    """
    t = np.asarray(t_s, dtype=np.float64)
    rising = 0.5 * (1.0 - np.cos(np.pi * np.clip(t / rise_s, 0.0, 1.0)))
    falling = 0.5 * (1.0 + np.cos(np.pi * np.clip((t - rise_s - hold_s) / release_s, 0.0, 1.0)))
    return np.where(t < rise_s + hold_s, rising, falling) * (t >= 0)


def sweep_locations(sensor: TaxelSensor, taps: int, *, taps_per_location: int = 1) -> np.ndarray:
    """Locations of a sweep over the sensor's range: ``taps`` evenly spaced steps, centred in each step.

    Paper 000 steps 0.01 mm: 3000 taps over the fingertip's 30 mm, 5000 over the skin's 50 mm.

    Returns
    -------
    (taps * taps_per_location,) ndarray of float64, mm, in collection order
    """
    if taps < 1 or taps_per_location < 1:
        raise ValueError(f"taps and taps_per_location must be >= 1, got {taps} and {taps_per_location}")
    lo, hi = sensor.location_range_mm
    step = (hi - lo) / taps
    return np.repeat(lo + step * (np.arange(taps) + 0.5), taps_per_location)


@dataclass(frozen=True)
class TaxelStream:
    """A continuous recording of raw taxel readings with the taps it contains.

    Attributes
    ----------
    timestamps_s : (T,) ndarray of float64
        Reading times, s.
    readings : (T, K) ndarray of uint8
        Raw 8-bit readings.
    tap_starts_s : (N,) ndarray of float64
        Time of each tap command (start of its 1 s window), s.
    locations_mm : (N,) ndarray of float64
        Commanded location of each tap, mm.
    """

    timestamps_s: np.ndarray
    readings: np.ndarray
    tap_starts_s: np.ndarray
    locations_mm: np.ndarray


class TaxelSimulator:
    """A simulated taxel sensor on a Cartesian robot tapping an object (model in the module docstring).

    Parameters
    ----------
    sensor : str or TaxelSensor
        ``"fingertip"``, ``"skin"`` or a custom `TaxelSensor`.
    seed : int
        Seed of the sensor's constants (gains, rest levels) and of the default collection noise.
    white_noise_counts, common_noise_counts, drift_counts : float
        Noise standard deviations, counts.
    common_noise_tau_s, drift_tau_s : float
        Correlation times of the common-mode noise and of the drift, s.
    gain_spread : float
        Standard deviation of the per-taxel gain (fraction).
    rest_spread_counts : float
        Standard deviation of the per-taxel rest reading, counts.
    amplitude_jitter : float
        Standard deviation of the log of the tap force from tap to tap.
    position_noise_mm : float
        Standard deviation of the robot's placement, mm.
    contact_delay_s, onset_jitter_s : float
        Time from tap command to contact and its standard deviation, s.
    rise_s, hold_s, release_s, relax_s : float
        Contact profile (`contact_profile`) and the foam's recovery time constant, s.
    samples, tap_duration_s, tap_period_s : int, float, float
        Samples per tap window, its length and the time from one tap command to the next, s.

    Examples
    --------
    >>> sim = TaxelSimulator("fingertip", seed=0)
    >>> sim.taps([15.0, 15.0], seed=1).shape
    (2, 50, 12)
    """

    def __init__(self, sensor: str | TaxelSensor = "fingertip", *, seed: int = 0,
                 white_noise_counts: float = 0.5, common_noise_counts: float = 0.3, common_noise_tau_s: float = 0.2,
                 drift_counts: float = 3.0, drift_tau_s: float = 120.0, gain_spread: float = 0.10,
                 rest_spread_counts: float = 8.0, amplitude_jitter: float = 0.03, position_noise_mm: float = 0.02,
                 contact_delay_s: float = 0.25, onset_jitter_s: float = 0.005, rise_s: float = 0.1,
                 hold_s: float = 0.05, release_s: float = 0.1, relax_s: float = 0.04,
                 samples: int = 50, tap_duration_s: float = 1.0, tap_period_s: float = 2.0):
        self.sensor = taxel_sensor(sensor) if isinstance(sensor, str) else sensor
        for name, value in (("white_noise_counts", white_noise_counts), ("common_noise_counts", common_noise_counts),
                            ("drift_counts", drift_counts), ("gain_spread", gain_spread),
                            ("position_noise_mm", position_noise_mm), ("amplitude_jitter", amplitude_jitter)):
            if not value >= 0:
                raise ValueError(f"{name} must be >= 0, got {value}")
        if not tap_period_s >= tap_duration_s > 0:
            raise ValueError(f"need tap_period_s >= tap_duration_s > 0, got {tap_period_s} and {tap_duration_s}")
        self.seed = seed
        self.white_noise_counts = white_noise_counts
        self.common_noise_counts = common_noise_counts
        self.common_noise_tau_s = common_noise_tau_s
        self.drift_counts = drift_counts
        self.drift_tau_s = drift_tau_s
        self.amplitude_jitter = amplitude_jitter
        self.position_noise_mm = position_noise_mm
        self.contact_delay_s = contact_delay_s
        self.onset_jitter_s = onset_jitter_s
        self.profile = dict(rise_s=rise_s, hold_s=hold_s, release_s=release_s)
        self.relax_s = relax_s
        self.samples = int(samples)
        self.tap_duration_s = float(tap_duration_s)
        self.tap_period_s = float(tap_period_s)
        sensor_rng = np.random.default_rng([seed, 0])
        k = self.sensor.n_taxels
        self.gains = np.clip(1.0 + gain_spread * sensor_rng.standard_normal(k), 0.5, 1.5)
        self.rest_counts = self.sensor.rest_counts + rest_spread_counts * sensor_rng.standard_normal(k)
        self._noise_rng = np.random.default_rng([seed, 1])

    def __repr__(self) -> str:
        return f"TaxelSimulator({self.sensor.name!r}, seed={self.seed})"

    @property
    def sample_rate_hz(self) -> float:
        """Readings per second."""
        return self.sensor.sample_rate_hz

    def stream(self, locations_mm, *, seed=None, progress: Callable[[int], None] | None = None) -> TaxelStream:
        """Record one collection: a tap at each location, in order, as one continuous raw stream.

        Parameters
        ----------
        locations_mm : (N,) array_like
            Commanded location of each tap, mm.
        seed : int or sequence of int, optional
            Seed of this collection's noise; default: continue the simulator's own noise generator.
        progress : callable, optional
            Called with the number of taps done after each block.

        Returns
        -------
        TaxelStream
        """
        blocks = list(self._blocks(locations_mm, seed, progress))
        return TaxelStream(
            timestamps_s=np.concatenate([b[0] for b in blocks]),
            readings=np.concatenate([b[1] for b in blocks]),
            tap_starts_s=np.concatenate([b[2] for b in blocks]),
            locations_mm=np.asarray(locations_mm, dtype=np.float64).reshape(-1),
        )

    def taps(self, locations_mm, *, seed=None, cutoff_hz: float = 0.02, baseline_samples: int = BASELINE_SAMPLES,
             progress: Callable[[int], None] | None = None, field=None) -> np.ndarray:
        """Record one collection and cut it into pre-processed taps.

        The raw stream goes through `tactip.taxel.preprocess` (high-pass, sign, normalisation, cut at
        the tap commands, per-tap baseline), exactly as a recorded or live stream would.

        Parameters
        ----------
        locations_mm : (N,) array_like
            Commanded location of each tap, mm.
        seed, progress
            As `stream`.
        field : callable, optional
            ``field(location_mm (n,), taps slice) -> ((n, K), delay_s)``: the fraction of its peak
            each taxel reads for the taps of a block (e.g. `tactip.reproduce.stimuli.Stimulus.field` of
            each tap's identity) and the contact's delay past ``contact_delay_s`` (s, scalar or
            (n,)); default the sensor's own object (`receptive_field_response`), no delay.
        cutoff_hz : float
            High-pass cut-off, Hz.
        baseline_samples : int
            Rest samples at the start of each tap (`remove_tap_baseline`).

        Returns
        -------
        (N, samples, K) ndarray of float32
            Pressure, fraction of full scale.
        """
        hp = HighPassFilter(self.sensor.n_taxels, sample_rate_hz=self.sample_rate_hz, cutoff_hz=cutoff_hz)
        out = []
        for t, raw, starts in self._blocks(locations_mm, seed, progress, field=field):
            pressure = hp(raw) * (-1.0 / FULL_SCALE_COUNTS)
            taps = resample_taps(t, pressure, starts, duration_s=self.tap_duration_s, samples=self.samples)
            out.append(remove_tap_baseline(taps, baseline_samples=baseline_samples).astype(np.float32))
        return np.concatenate(out) if out else np.zeros((0, self.samples, self.sensor.n_taxels), np.float32)

    def _blocks(self, locations_mm, seed, progress, block_taps: int = 250, field=None) -> Iterator[tuple]:
        """Yield ``(timestamps (T,), readings (T, K) uint8, tap_starts (n,))`` for consecutive blocks of taps."""
        locations = np.asarray(locations_mm, dtype=np.float64).reshape(-1)
        if not np.all(np.isfinite(locations)):
            raise ValueError("locations_mm must be finite")
        from scipy import signal   # deferred: slow to import, and the CLI imports tactip

        rng = self._noise_rng if seed is None else np.random.default_rng(seed)
        fs = self.sample_rate_hz
        period = int(round(self.tap_period_s * fs))
        k = self.sensor.n_taxels
        common = _ArNoise(1, self.common_noise_counts, self.common_noise_tau_s, fs, rng)
        drift = _ArNoise(k, self.drift_counts, self.drift_tau_s, fs, rng)
        relax = np.exp(-1.0 / (fs * self.relax_s)) if self.relax_s > 0 else 0.0
        t_in_period = np.arange(period) / fs
        for first in range(0, len(locations), block_taps):
            x = locations[first:first + block_taps]
            n = len(x)
            placed = x + self.position_noise_mm * rng.standard_normal(n)
            field_, delay = ((receptive_field_response(self.sensor, placed), 0.0) if field is None
                             else field(placed, slice(first, first + n)))
            amplitude = np.exp(self.amplitude_jitter * rng.standard_normal(n))
            onset = self.contact_delay_s + delay + self.onset_jitter_s * rng.standard_normal(n)
            profile = contact_profile(t_in_period[None, :] - onset[:, None], **self.profile)       # (n, period)
            # visco-elastic recovery of the foam: first-order lag y[i] = relax * y[i-1] + (1 - relax) * p[i]
            profile = signal.lfilter([1.0 - relax], [1.0, -relax], profile, axis=1)
            response = (self.sensor.peak_counts * amplitude[:, None, None] * profile[:, :, None]
                        * (field_ * self.gains)[:, None, :]).reshape(n * period, k)
            noise = common(n * period) + drift(n * period) + self.white_noise_counts * rng.standard_normal((n * period, k))
            raw = np.clip(np.rint(self.rest_counts + noise - response), 0, 255).astype(np.uint8)
            sample0 = first * period
            t = (sample0 + np.arange(n * period)) / fs
            starts = (sample0 + period * np.arange(n)) / fs
            if progress is not None:
                progress(first + n)
            yield t, raw, starts


class _ArNoise:
    """Stationary AR(1) noise (a sampled Ornstein-Uhlenbeck process) that continues across blocks."""

    def __init__(self, channels: int, sigma: float, tau_s: float, fs: float, rng: np.random.Generator):
        self.a = float(np.exp(-1.0 / (fs * tau_s)))
        self.sigma = sigma
        self.rng = rng
        self.channels = channels
        # start in the stationary distribution: zi = a * y[-1], y[-1] ~ N(0, sigma)
        self.zi = (self.a * sigma * rng.standard_normal(channels))[None, :]

    def __call__(self, n: int) -> np.ndarray:
        from scipy import signal

        e = self.sigma * np.sqrt(1.0 - self.a**2) * self.rng.standard_normal((n, self.channels))
        # y[i] = a * y[i-1] + sqrt(1 - a^2) * sigma * e[i]
        y, self.zi = signal.lfilter([1.0], [1.0, -self.a], e, axis=0, zi=self.zi)
        return y
