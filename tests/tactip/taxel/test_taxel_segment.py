"""Cutting taxel streams into taps: detection by magnitude, explicit windows, batch against streaming."""

import numpy as np
import pytest

from tactip.taxel import (FULL_SCALE_COUNTS, TapSegmenter, TaxelSimulator, detect_taps, segment_taps,
                          taxel_pressure)

FS = 50.0


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
