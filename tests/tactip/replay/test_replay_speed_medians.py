"""Replay's contacts' neighbourhood medians computed frame by frame while it tracks (issue 20, outcome 9: off the
tail that follows the last decoded frame) are `pins.neighbour_median`'s numbers over the whole track, bit for bit."""

import cv2
import numpy as np
import pytest

import tactip.replay.contacts as contacts
from pins import PinsError, PinTracker, neighbour_median
from pins._kernels import choose
from pins.segment import NeighbourMedians
from tactip.replay.video import track_video
from tactip.sim import SyntheticTacTip


@pytest.mark.parametrize("kernels", ["compiled", "numpy"])
@pytest.mark.parametrize("seed, pins", [(0, 120), (1, 331), (2, 7), (3, 2), (4, 1)])
def test_frame_by_frame_medians_are_the_whole_tracks(kernels, seed, pins):
    rng = np.random.default_rng(seed)
    rest = rng.uniform(0.0, 400.0, (pins, 2))
    positions = rest + rng.normal(0.0, 2.0, (60, pins, 2))
    positions[rng.random((60, pins)) < 0.3] = np.nan                        # lost pins
    positions[rng.random((60, pins)) < 0.02, 1] = np.nan                    # an axis alone
    positions[5] = np.nan                                                   # a frame the tracker failed on
    positions[7, : max(1, pins // 3)] = rest[: max(1, pins // 3)]           # still pins: displacement 0
    positions[9, 0] = (np.inf, -np.inf)                                     # infinities count, as there
    before = choose(kernels)
    try:
        medians = NeighbourMedians(rest)
        for frame in positions:
            medians.add(frame)
        table = medians.table()
    finally:
        choose(before)
    reference = neighbour_median(positions - rest, rest)
    assert table.shape == reference.shape == (60, pins, 2)
    assert np.array_equal(table, reference, equal_nan=True)
    assert np.isnan(table[5]).all() and np.isfinite(table[7]).any()


def _slides(tmp_path, seed):
    """Two slides of radial-led-120 (120 frames/s, 3-frame rests) as a folder of PNG frames."""
    sensor = SyntheticTacTip.from_preset("radial-led-120", seed=seed)
    angles = np.random.default_rng(seed).choice(range(0, 360, 45), 2, replace=False)
    run = sensor.slides(angles.astype(float), distance_mm=3.0 * sensor.pin_spacing_mm, rest_s=3.0 / 120.0)
    folder = tmp_path / "frames"
    folder.mkdir()
    for k, frame in enumerate(run):
        cv2.imwrite(str(folder / f"frame{k:05d}.png"), frame.image)
    return folder


@pytest.mark.parametrize("seed, rest_frame, fail_at", [(0, 0, None), (1, 4, 30)])
def test_replay_finds_contacts_on_the_medians_it_computed_while_tracking(tmp_path, monkeypatch, seed, rest_frame,
                                                                         fail_at):
    folder = _slides(tmp_path, seed)
    given = []
    find = contacts.find_contacts

    def spy(displacements, **options):
        given.append((displacements, options["rest_positions"], options["medians"]))
        return find(displacements, **options)

    monkeypatch.setattr(contacts, "find_contacts", spy)
    if fail_at is not None:  # the tracker raises on one frame: every pin lost there, as track_pins records it
        update, calls = PinTracker.update, [0]

        def failing(self, image):
            calls[0] += 1
            if calls[0] == fail_at:
                raise PinsError("a frame the tracker failed on")
            return update(self, image)

        monkeypatch.setattr(PinTracker, "update", failing)
    track, analysis, _, _ = track_video(folder, rest_frame=rest_frame)
    (displacements, rest, medians), = given
    assert medians is not None                                              # computed while tracking
    reference = neighbour_median(displacements, rest)
    assert np.array_equal(medians, reference, equal_nan=True)
    assert np.isnan(medians[:rest_frame]).all() and np.isfinite(medians[rest_frame:]).any()
    if fail_at is not None:
        assert np.isnan(medians[rest_frame + fail_at]).all() and track.lost[rest_frame + fail_at].all()
    assert "update" not in vars(track.tracker)                              # the tracker as it was
    assert len(analysis["bounds"]) >= 2                                      # (3 where a failed frame splits one)
    # The same contacts and kinds as from the medians of the whole track.
    signal = contacts.tap_signal(displacements)
    again = find(displacements, signal=signal, blank=track.blank, thresholds_px=analysis["tap_thresholds_px"],
                 rest_positions=rest)
    assert repr(again) == repr((analysis["bounds"], analysis["kinds"]))       # (repr: a press's direction is NaN)


def test_medians_that_do_not_cover_the_track_are_computed_again():
    rest = np.random.default_rng(5).uniform(0.0, 100.0, (20, 2))
    medians = NeighbourMedians(rest)
    medians.add(rest)

    class Track:
        rest_frame, rest_positions, timestamps_s = 0, rest, np.zeros(3)

    assert contacts.neighbour_medians_of(Track(), medians) is None          # 1 frame of 3
    assert contacts.neighbour_medians_of(Track(), None) is None
    medians.add(rest)
    medians.add(rest)
    assert contacts.neighbour_medians_of(Track(), medians).shape == (3, 20, 2)
    Track.rest_positions = rest + 1.0                                       # other rest positions
    assert contacts.neighbour_medians_of(Track(), medians) is None
