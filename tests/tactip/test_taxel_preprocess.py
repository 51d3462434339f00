"""Taxel pre-processing: high-pass filter, normalisation, resampling, tap detection and segmentation."""

import numpy as np
import pytest

from tactip.taxel import (FULL_SCALE_COUNTS, HighPassFilter, TapSegmenter, TaxelSimulator, detect_taps, highpass,
                          remove_tap_baseline, resample_taps, segment_taps, taxel_pressure)

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


def _tap_train(starts_s, length_s=40.0, taxels=3):
    """Pressure stream with 0.2 s bumps starting at the given times."""
    t = np.arange(0, length_s, 1 / FS)
    p = np.zeros((len(t), taxels))
    for s in starts_s:
        bump = np.clip(1 - np.abs(t - s - 0.1) / 0.1, 0, None) * 0.2
        p[:, 1] += bump
        p[:, 2] += 0.5 * bump
    return t, p


def test_detect_taps_by_magnitude_finds_each_onset_once():
    onsets = np.array([3.0, 7.5, 12.26, 30.0])
    t, p = _tap_train(onsets)
    p[int(7.8 * FS), 0] = 0.05                                   # a second crossing within the same tap
    starts = detect_taps(t, p, threshold=0.03, pre_trigger_s=0.3)
    # trigger on the first sample above threshold: 0.015 s after onset, at most one sample later
    assert len(starts) == 4
    assert np.all((starts - (onsets - 0.3) >= 0) & (starts - (onsets - 0.3) < 0.015 + 0.02 + 1e-9))
    # a window that would run past the end of the stream is dropped
    assert len(detect_taps(t[: int(30.5 * FS)], p[: int(30.5 * FS)])) == 3


def test_segment_taps_explicit_and_by_magnitude_agree():
    sim = TaxelSimulator("fingertip", seed=1)
    # first a tap that misses (2 mm): magnitude finds only the 12 contacts
    stream = sim.stream(np.r_[2.0, np.linspace(8, 20, 12)], seed=2)
    pressure = taxel_pressure(stream.readings)
    explicit = segment_taps(stream.timestamps_s, pressure, starts_s=stream.tap_starts_s[1:])
    found = segment_taps(stream.timestamps_s, pressure)
    assert found.taps.shape == explicit.taps.shape == (12, 50, 12)
    # the contact starts 0.25 s after the tap command; the trigger comes on the rise
    np.testing.assert_allclose(found.starts_s - stream.tap_starts_s[1:], 0.0, atol=0.08)
    np.testing.assert_allclose(found.taps.max(axis=1), explicit.taps.max(axis=1), atol=3 / FULL_SCALE_COUNTS)
    with pytest.raises(ValueError, match="stops_s needs starts_s"):
        segment_taps(stream.timestamps_s, pressure, stops_s=[1.0])


@pytest.mark.parametrize("block", [1, 7, 100])
def test_streaming_segmenter_matches_batch_segmentation(block):
    sim = TaxelSimulator("fingertip", seed=3)
    stream = sim.stream(np.r_[2.0, np.linspace(8, 20, 6)], seed=4)   # starts with a miss, as above
    t, raw = stream.timestamps_s, stream.readings
    batch = segment_taps(t, taxel_pressure(raw))
    segmenter = TapSegmenter(12)
    taps = [tap for i in range(0, len(t), block) for tap in segmenter.feed(t[i:i + block], raw[i:i + block])]
    assert len(taps) == len(batch.taps) == 6
    np.testing.assert_allclose(np.stack(taps), batch.taps, atol=1e-6)


def test_streaming_segmenter_with_explicit_marks():
    sim = TaxelSimulator("fingertip", seed=3)
    stream = sim.stream([10.0, 2.0, 14.0], seed=5)              # the middle tap has no contact
    segmenter = TapSegmenter(12, mode="explicit")
    for start in stream.tap_starts_s:
        segmenter.mark(start)
    segmenter.mark(4.0, 4.5)                                     # explicit stop: a 0.5 s window
    taps = segmenter.feed(stream.timestamps_s, stream.readings)
    batch = segment_taps(stream.timestamps_s, taxel_pressure(stream.readings), starts_s=stream.tap_starts_s).taps
    assert len(taps) == 4
    np.testing.assert_allclose(np.stack(taps[:3]), batch, atol=1e-6)
    assert np.abs(taps[1]).max() < 0.02                          # no contact: only noise
    with pytest.raises(ValueError, match="mode"):
        TapSegmenter(12, mode="sometimes")
    with pytest.raises(ValueError, match="must come after"):
        segmenter.mark(3.0, 2.0)
    with pytest.raises(ValueError, match="before the oldest buffered reading"):
        segmenter.mark(0.5)                                      # 5.5 s ago: no longer buffered
