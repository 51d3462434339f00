"""The one path from frames to features: the live station and replay run the same pipeline.

The frames of one simulated tap go through the station's front end and, written losslessly as an
image folder, through `replay_video` with the station's calibration: the pins tracked are the same,
and the features replay writes for each contact it finds are the station's own tracking resampled
over that contact.
"""

import dataclasses

import cv2
import h5py
import numpy as np
import pytest

from tactip.pipeline import contact_features, frames_to_features, track_pins
from tactip.replay.video import replay_video
from tactip.sim import Contact
from tactip.sources import Frame
from tactip.station.station import OpticalFrontEnd, Station


@pytest.fixture(scope="module")
def tap(sim_station, tmp_path_factory):
    """(frames, folder) of one tap of the simulated station's camera, off contact before and after."""
    with Station(sim_station.config, calibration=sim_station.calibration) as station:
        camera = station.camera
        camera.sensor.reseed_noise(11)
        frames = [f.image for f in camera.sensor.tap(Contact(indentation_mm=3.0, gap_width_mm=2.0),
                                                      frame_rate=camera.frame_rate, rest_before_s=0.3,
                                                      rest_after_s=0.4)]
    folder = tmp_path_factory.mktemp("tap")
    for k, image in enumerate(frames):
        assert cv2.imwrite(str(folder / f"{k:04d}.png"), image)
    return frames, folder


def test_station_and_replay_track_the_same_pins_and_give_the_same_features(sim_station, tap, tmp_path):
    frames, folder = tap
    out = tmp_path / "replay.h5"
    result = replay_video(folder, out, calibration=sim_station.calibration)
    with h5py.File(out) as h5:
        positions, taps, times = h5["positions"][:], h5["taps"][:], h5["timestamps"][:]
    front_end = OpticalFrontEnd(sim_station.calibration, samples=40)
    station = front_end.track(frames, times)
    assert len(result.tap_bounds) == 1 and positions.shape == station.positions.shape
    np.testing.assert_array_equal(positions, station.positions.astype(np.float32))
    # Replay's features of its contact are the station's tracking resampled over the same frames.
    over_contact = contact_features(station, result.tap_bounds, sim_station.calibration.selected_pins)
    np.testing.assert_array_equal(taps, over_contact.features.astype(np.float32))
    # And the station's own tap, the whole capture as one contact, is what `features` returns.
    whole = front_end.features(frames, times)
    np.testing.assert_array_equal(whole, contact_features(station, [(0, len(frames))],
                                                          sim_station.calibration.selected_pins).features[0]
                                  .astype(np.float32))
    assert not np.array_equal(whole, taps[0])  # the two windows differ: the comparison is not vacuous


def test_a_blank_first_frame_is_skipped_and_counted_lost(sim_station, tap):
    frames, _ = tap
    front_end = OpticalFrontEnd(sim_station.calibration, samples=40)
    black = np.zeros_like(frames[0])
    track = front_end.track([black, *frames], None)
    assert track.rest_frame == 1 and track.lost[0].all() and np.isnan(track.positions[0]).all()
    again = front_end.track(frames, None)
    np.testing.assert_array_equal(track.positions[1:], again.positions)


def test_tracking_is_the_same_whatever_feeds_the_frames(sim_station, tap):
    frames, _ = tap
    stream = [Frame(k, k / 20.0, image) for k, image in enumerate(frames)]
    start = OpticalFrontEnd(sim_station.calibration)._start
    one = track_pins(stream, start=start)
    two = frames_to_features(iter(stream), start=start, selected=sim_station.calibration.selected_pins,
                             contacts=[(2, 9)], n_samples=10)
    np.testing.assert_array_equal(one.positions, two.positions)
    assert two.contacts == [(2, 9)] and two.features.shape == (1, 10, 2 * len(sim_station.calibration.selected_pins))
    assert one.features is None and two.valid.all()
    # A callable progress hears of every frame read, ten at a time and the rest at the end; the same track.
    counts = []
    three = track_pins(stream, start=start, progress=counts.append)
    np.testing.assert_array_equal(three.positions, one.positions)
    assert sum(counts) == len(stream) and counts[:-1] == [10] * (len(counts) - 1) and 0 < counts[-1] <= 10


@pytest.mark.parametrize("seed", [0, 1])
def test_a_contact_with_unseen_feature_pins_keeps_the_seen_ones_and_needs_half_of_them(sim_station, tap, seed):
    frames, _ = tap
    selected = np.asarray(sim_station.calibration.selected_pins)
    pins = len(selected)
    track = OpticalFrontEnd(sim_station.calibration).track(frames, None)
    complete = contact_features(track, [(0, len(frames))], selected).features[0]
    rng = np.random.default_rng(seed)
    order = rng.permutation(pins)
    for seen in (pins // 2 - 1, pins // 2, pins - 5, pins):
        hidden = order[:pins - seen]
        positions = track.positions.copy()
        positions[:, selected[hidden]] = np.nan          # feature pins lost in every frame of the contact
        positions[2:5, selected[order[-1]]] = np.nan     # and one lost for a few frames only: interpolated
        lossy = contact_features(dataclasses.replace(track, positions=positions), [(0, len(frames))], selected)
        assert lossy.pins_seen.tolist() == [seen]
        assert lossy.valid[0] == (2 * seen >= pins)
        if not lossy.valid[0]:
            assert np.isnan(lossy.features).all() and f"only {seen} of {pins}" in str(lossy.errors[0])
            continue
        missing = np.zeros(2 * pins, bool)
        missing[np.concatenate([hidden, hidden + pins])] = True
        features = lossy.features[0]
        assert np.isnan(features[:, missing]).all() and np.isfinite(features[:, ~missing]).all()
        kept = np.setdiff1d(np.arange(pins), np.append(hidden, order[-1]))
        columns = np.concatenate([kept, kept + pins])
        np.testing.assert_array_equal(features[:, columns], complete[:, columns])


def test_the_station_keeps_a_tap_whose_feature_pins_are_partly_unseen(sim_station, tap, monkeypatch):
    # Three feature pins unseen after the rest frame (the tracker reports them lost in every later
    # frame): the tap is no longer discarded, their columns are missing, the other pins' are unchanged.
    import pins

    frames, _ = tap
    front_end = OpticalFrontEnd(sim_station.calibration, samples=40)
    selected = np.asarray(sim_station.calibration.selected_pins)
    clean = front_end.features(frames, None)
    hidden = np.array([0, len(selected) // 2, len(selected) - 1])
    update = pins.PinTracker.update

    def losing(self, image):
        moved = np.array(update(self, image), dtype=np.float64)
        moved[selected[hidden]] = np.nan
        return moved

    monkeypatch.setattr(pins.PinTracker, "update", losing)
    features = front_end.features(frames, None)
    count = len(selected)
    missing = np.zeros(2 * count, bool)
    missing[np.concatenate([hidden, hidden + count])] = True
    assert np.isnan(features[:, missing]).all() and np.isfinite(features[:, ~missing]).all()
    np.testing.assert_array_equal(features[:, ~missing], clean[:, ~missing])
