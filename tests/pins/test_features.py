"""pins.features: feature layout, resampling, NaN filling and the TapRecorder."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pins import (LostPinError, PinsError, PinTracker, ShapeError, TapRecorder, displacement_from_rest,
                  feature_dim_names, fill_lost, resample_tap, seen_pins, select_pins, tap_features)
from tests.pins.conftest import TAP, sensor


def test_dim_names_follow_the_layout():
    names = feature_dim_names(40)
    assert len(names) == 80
    assert names[0] == "pin00_dx" and names[39] == "pin39_dx" and names[40] == "pin00_dy" and names[79] == "pin39_dy"
    assert feature_dim_names(120)[0] == "pin000_dx"
    assert feature_dim_names(0) == []


def test_layout_is_dx_block_then_dy_block():
    steps, pins = 5, 6
    t = np.arange(steps)[:, None]
    displacements = np.stack([np.broadcast_to(np.arange(pins) + 0.01 * t, (steps, pins)),
                              np.broadcast_to(100 + np.arange(pins) + 0.01 * t, (steps, pins))], axis=2)
    selected = np.array([4, 1, 2])
    features = tap_features(displacements, pins=selected, n_samples=steps)
    names = feature_dim_names(3)
    assert features.shape == (steps, 6)
    for column, name in enumerate(names):
        k, axis = int(name[3:5]), name[-2:]
        expected = selected[k] + (100 if axis == "dy" else 0) + 0.01 * np.arange(steps)
        assert np.allclose(features[:, column], expected)


def test_resampling_a_ramp_is_exact():
    series = np.column_stack([np.linspace(0, 7, 23), np.linspace(5, -5, 23)])
    out = resample_tap(series, 40)
    assert out.shape == (40, 2)
    assert np.allclose(out, np.column_stack([np.linspace(0, 7, 40), np.linspace(5, -5, 40)]))


def test_resampling_by_timestamps(rng):
    times = np.sort(rng.uniform(0, 2, 30))
    times[0], times[-1] = 0.0, 2.0
    series = (3.0 * times - 1.0)[:, None]
    # The signal is linear in time, so sampling it evenly in time gives an even ramp.
    out = resample_tap(series, 40, timestamps_s=times)
    assert np.allclose(out[:, 0], 3.0 * np.linspace(0, 2, 40) - 1.0)
    with pytest.raises(ValueError, match="increasing"):
        resample_tap(series, 40, timestamps_s=times[::-1])


def test_fill_lost_interpolates_inside_and_holds_the_edges():
    series = np.array([np.nan, 1.0, np.nan, np.nan, 4.0, np.nan])[:, None]
    assert np.allclose(fill_lost(series)[:, 0], [1.0, 1.0, 2.0, 3.0, 4.0, 4.0])
    with pytest.raises(LostPinError):
        fill_lost(np.full((4, 2), np.nan))


@settings(max_examples=40, deadline=None)
@given(st.integers(2, 30), st.integers(1, 6), st.floats(0.0, 0.8), st.integers(0, 2**32 - 1))
def test_fill_lost_equals_a_plain_loop(steps, columns, lost_fraction, seed):
    generator = np.random.default_rng(seed)
    series = generator.normal(size=(steps, columns))
    series[generator.random(series.shape) < lost_fraction] = np.nan
    series[generator.integers(steps), :] = generator.normal(size=columns)  # at least one valid per column
    expected = series.copy()
    t = np.arange(steps)
    for c in range(columns):
        valid = np.isfinite(series[:, c])
        expected[:, c] = np.interp(t, t[valid], series[valid, c])
    assert np.allclose(fill_lost(series), expected)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_pin_unseen_for_the_whole_tap_gives_nan_columns_and_the_others_are_unchanged(seed):
    rng = np.random.default_rng(seed)
    displacements = rng.normal(size=(17, 30, 2))
    pins = rng.permutation(30)[:12]
    unseen = rng.choice(12, size=3, replace=False)       # positions in the selection
    partly = np.setdiff1d(np.arange(12), unseen)[0]
    lossy = displacements.copy()
    lossy[:, pins[unseen]] = np.nan
    lossy[3:9, pins[partly]] = np.nan                       # lost for some frames: interpolated as before
    features = tap_features(lossy, pins=pins, n_samples=20)
    complete = tap_features(lossy[:, pins[np.setdiff1d(np.arange(12), unseen)]], n_samples=20)
    missing = np.zeros(24, bool)
    missing[np.concatenate([unseen, unseen + 12])] = True
    assert np.isnan(features[:, missing]).all() and np.isfinite(features[:, ~missing]).all()
    assert np.array_equal(features[:, ~missing], complete)
    assert seen_pins(lossy, pins=pins).tolist() == [k not in unseen for k in range(12)]
    with pytest.raises(LostPinError, match=r"no valid sample"):
        fill_lost(np.concatenate([lossy[:, pins, 0], lossy[:, pins, 1]], axis=1))


def test_features_of_a_tracked_tap_match_ground_truth():
    s = sensor(331)
    frames = [s.render()] + list(s.tap(TAP))
    tracker = PinTracker()
    rest = tracker.start(frames[0].image)
    identity = np.argmin(np.linalg.norm(rest[:, None] - s.rest_centres[None], axis=2), axis=1)
    positions = np.stack([rest] + [tracker.update(f.image) for f in frames[1:]])
    truth = np.stack([f.centres[identity] for f in frames])
    selected = select_pins(rest, mm_per_px=s.mm_per_px)
    tracked = tap_features(displacement_from_rest(positions, rest), pins=selected)
    expected = tap_features(displacement_from_rest(truth, truth[0]), pins=selected)
    assert tracked.shape == (40, 80)
    assert np.abs(expected).max() > 5.0
    assert np.abs(tracked - expected).max() < 0.4


def test_recorder_equals_tap_features(rng):
    displacements = rng.normal(size=(25, 12, 2))
    times = np.cumsum(rng.uniform(0.04, 0.06, 25))
    selected = np.array([3, 0, 7, 11])
    recorder = TapRecorder(selected, n_samples=40)
    assert not recorder.add(displacements[0])           # not recording: ignored
    recorder.start()
    for d, t in zip(displacements[5:20], times[5:20]):
        assert recorder.add(d, timestamp_s=t)
    features = recorder.stop()
    assert not recorder.add(displacements[21])
    expected = tap_features(displacements[5:20], pins=selected, timestamps_s=times[5:20])
    assert np.allclose(features, expected)
    assert "idle" in repr(recorder)


def test_recorder_errors():
    recorder = TapRecorder(np.array([0, 1]))
    with pytest.raises(PinsError, match="without start"):
        recorder.stop()
    recorder.start()
    recorder.add(np.zeros((3, 2)))
    with pytest.raises(PinsError, match="at least 2 frames"):
        recorder.stop()
    recorder.start()
    with pytest.raises(ShapeError):
        recorder.add(np.zeros((1, 2)))
    with pytest.raises(ShapeError):
        TapRecorder(np.array([], dtype=int))
