"""Taxel pre-processing: high-pass filter, normalisation, resampling, per-tap baseline."""

import numpy as np
import pytest

from tactip.taxel import FULL_SCALE_COUNTS, HighPassFilter, highpass, remove_tap_baseline, resample_taps, taxel_pressure

FS = 50.0


def test_highpass_removes_rest_level_and_slow_drift_but_keeps_taps():
    t = np.arange(0, 600, 1 / FS)
    drift = 235.0 + 5.0 * np.sin(2 * np.pi * t / 600.0)          # 0.0017 Hz thermal drift
    tap = 60.0 * np.exp(-0.5 * ((t - 300.0) / 0.08) ** 2)         # ~0.2 s contact
    out = highpass(np.column_stack([drift, drift + tap]))
    assert np.abs(out[len(t) // 10:, 0]).max() < 0.6                # drift: 5 counts -> < 0.6
    assert out[:, 1].max() - out[:, 0].max() > 0.95 * 60.0         # tap kept


def test_highpass_class_in_blocks_equals_the_function():
    rng = np.random.default_rng(0)
    x = 235 + rng.normal(0, 3, (1000, 4)).cumsum(axis=0) * 0.1
    hp = HighPassFilter(4)
    blocks = [hp(x[i:j]) for i, j in ((0, 1), (1, 333), (333, 334), (334, 1000))]
    np.testing.assert_allclose(np.concatenate(blocks), highpass(x), atol=1e-9)
    hp.reset()
    np.testing.assert_allclose(hp(x), highpass(x), atol=1e-12)
    assert "cutoff_hz=0.02" in repr(hp)
    with pytest.raises(ValueError, match="readings must have shape"):
        hp(np.zeros((3, 5)))
    with pytest.raises(ValueError, match="cutoff_hz"):
        HighPassFilter(4, cutoff_hz=30.0)


def test_pressure_is_positive_under_contact_and_normalised():
    readings = np.full((500, 2), 235.0)
    readings[250:260, 1] -= 51.0                                  # contact lowers the reading by 51 counts
    p = taxel_pressure(readings)
    assert p[250:260, 1].mean() == pytest.approx(51.0 / FULL_SCALE_COUNTS, rel=0.02)
    assert np.abs(p[:, 0]).max() < 1e-6
    raised = taxel_pressure(470.0 - readings, contact_lowers_reading=False)
    np.testing.assert_allclose(raised, p, atol=1e-9)


def test_resample_on_the_reading_grid_returns_the_readings():
    t = np.arange(200) / FS
    v = np.random.default_rng(1).normal(size=(200, 3))
    taps = resample_taps(t, v, [0.0, 1.0, 2.0])
    np.testing.assert_allclose(taps, v[:150].reshape(3, 50, 3), atol=1e-12)


def test_resample_interpolates_jittered_timestamps_like_np_interp():
    rng = np.random.default_rng(2)
    t = np.cumsum(rng.uniform(0.015, 0.025, 300))
    v = rng.normal(size=(300, 2))
    starts, stops = np.array([0.5, 1.7]), np.array([1.4, 3.3])
    taps = resample_taps(t, v, starts, stops_s=stops, samples=40)
    for n in range(2):                                           # plain loop kept as the reference
        grid = starts[n] + (stops[n] - starts[n]) * np.arange(40) / 40
        for k in range(2):
            np.testing.assert_allclose(taps[n, :, k], np.interp(grid, t, v[:, k]), atol=1e-12)


def test_resample_refuses_windows_outside_the_stream():
    t = np.arange(100) / FS
    with pytest.raises(ValueError, match="outside the stream"):
        resample_taps(t, np.zeros((100, 2)), [1.5])
    with pytest.raises(ValueError, match="strictly increasing"):
        resample_taps(t[::-1], np.zeros((100, 2)), [0.0])
    assert resample_taps(t, np.zeros((100, 2)), []).shape == (0, 50, 2)


def test_remove_tap_baseline():
    taps = np.zeros((2, 50, 3)) + np.array([1.0, -2.0, 0.5])
    taps[:, 20:25] += 7.0
    out = remove_tap_baseline(taps, baseline_samples=8)
    np.testing.assert_allclose(out[:, :20], 0.0)
    np.testing.assert_allclose(out[:, 20:25], 7.0)
    np.testing.assert_allclose(remove_tap_baseline(taps, baseline_samples=0), taps)
