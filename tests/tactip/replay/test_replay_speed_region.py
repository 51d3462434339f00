"""Replay maps luma to grey only where the tracker reads (`tactip.replay.luma.mapped`'s ``region``, the tracker's
`pins.PinTracker.frame_region`; issue 20, outcome 9): inside it the table's pixels, outside it the luma as decoded,
each frame's part asked for just before that frame; replay's file as with every pixel mapped."""

import cv2
import h5py
import numpy as np

import tactip.replay.luma as luma_module
from tactip.replay.luma import mapped
from tactip.replay.video import replay_video
from tactip.sources import Frame
from tests.tactip.replay.test_replay_luma import _write


def test_only_the_region_asked_for_each_frame_is_looked_up():
    rng = np.random.default_rng(4)
    table = rng.integers(0, 256, 256, dtype=np.uint8)
    frames = [Frame(k, k / 120.0, rng.integers(0, 256, (48, 64), dtype=np.uint8)) for k in range(4)]
    raw = [frame.image.copy() for frame in frames]
    parts = [None, (slice(5, 30), slice(7, 50)), (slice(0, 48), slice(60, 64)), (slice(47, 48), slice(0, 1))]
    asked = []

    def region():
        asked.append(len(asked))
        return parts[len(asked) - 1]

    for k, frame in enumerate(mapped(iter(frames), table, region=region)):
        assert asked == list(range(k + 1))  # asked for just before its frame
        part = parts[k] or (slice(None), slice(None))
        expected = raw[k].copy()
        expected[part] = cv2.LUT(raw[k][part], table)
        assert np.array_equal(frame.image, expected)
    assert not np.array_equal(frames[1].image[:5], cv2.LUT(raw[1][:5], table))  # outside: left as decoded


def test_replay_maps_only_the_trackers_region_and_writes_the_same_file(tmp_path, monkeypatch):
    video = tmp_path / "tap.mp4"
    _write(video, "mp4v", frames=16)
    regions = []
    plain = luma_module.mapped

    def spied(frames, table, region=None):
        for frame in plain(frames, table, region):
            regions.append(region())
            yield frame

    monkeypatch.setattr(luma_module, "mapped", spied)
    replay_video(video, tmp_path / "region.h5", decode_threads=1)
    assert regions[0] is None and all(r is not None for r in regions[1:])  # the rest frame whole, then the region
    monkeypatch.setattr(luma_module, "mapped", lambda frames, table, region=None: plain(frames, table))
    replay_video(video, tmp_path / "whole.h5", decode_threads=1)
    with h5py.File(tmp_path / "region.h5") as a, h5py.File(tmp_path / "whole.h5") as b:
        for name in ("positions", "lost", "retired", "blank", "displacements", "taps", "tap_bounds"):
            assert np.array_equal(a[name][:], b[name][:], equal_nan=a[name].dtype.kind == "f")
