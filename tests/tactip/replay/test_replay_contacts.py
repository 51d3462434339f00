"""Replay finds every contact rendered, with short rests between them, and says press or slide (issue 20)."""

import cv2
import h5py
import numpy as np
import pytest

from tactip.replay.video import replay_video
from tactip.sim import SyntheticTacTip
from tactip.sim.sequence import Stroke


def _write(run, folder):
    folder.mkdir()
    frames = list(run)
    for k, frame in enumerate(frames):
        cv2.imwrite(str(folder / f"frame{k:05d}.png"), frame.image)
    return frames


def _angle_error(a, b):
    return abs((a - b + 180.0) % 360.0 - 180.0)


# Seed 1 once lost a faint outer-ring pin in the bright veil on the pad back at rest: placed where its
# still neighbours put it, its window's own scatter in noise (up to 0.9 px) was bounded by theirs.
@pytest.mark.parametrize("preset, seed", [("radial-led-120", 0), ("radial-led-120", 1), ("radial-led-120", 3),
                                          ("tactip-331", 2)])
def test_slides_and_presses_with_short_rests_are_each_found(tmp_path, preset, seed):
    sensor = SyntheticTacTip.from_preset(preset, seed=seed)
    rng = np.random.default_rng(seed)
    pitch = sensor.pin_spacing_mm
    strokes = [Stroke(2.0, float(a), 3.0 * pitch) for a in rng.permutation(range(0, 360, 45))[:4]]
    strokes.insert(2, Stroke(3.0, gap_width_mm=2.0))
    # rests of 3 frames; each stroke about a third of a second
    run = sensor.sequence(strokes, rest_s=3 / 120.0, press_s=0.1, hold_s=0.1, slide_s=0.15,
                          lift_s=0.1, frame_rate=120.0)
    frames = _write(run, tmp_path / "frames")
    result = replay_video(tmp_path / "frames", tmp_path / "r.h5")
    assert len(result.tap_bounds) == len(run.events), (result.tap_bounds, run.events)
    for (start, stop), kind, event in zip(result.tap_bounds, result.contact_kinds, run.events):
        assert event.start_frame - 1 <= start and stop <= event.stop_frame + 1  # inside the contact, padded
        assert stop - start >= 0.5 * (event.stop_frame - event.start_frame)
        assert kind.kind == event.kind
        if event.kind == "slide":
            assert _angle_error(kind.direction_deg, event.direction_deg) <= 10.0
    with h5py.File(tmp_path / "r.h5") as h5:
        assert [k.decode() for k in h5["tap_kinds"][:]] == [e.kind for e in run.events]
        directions = h5["tap_directions_deg"][:]
        assert np.isnan(directions[2]) and np.isfinite(np.delete(directions, 2)).all()
    summary = result.summary()
    assert summary.count(" slide ") == 4 and summary.count(" press") == 1
    # Back at rest after the last contact: every visible pin within 1 px of its rest position (issue 20's
    # bar: identities held, nothing left behind), and of its true place wherever detection put it right.
    from scipy.spatial import cKDTree
    positions = h5py.File(tmp_path / "r.h5")["positions"][:]
    placed, identity = cKDTree(frames[0].centres).query(positions[0])
    last = frames[-1]
    visible = last.visible[identity]
    returned = np.linalg.norm(positions[-1] - positions[0], axis=1)
    assert np.all(returned[visible] <= 1.0), np.sort(returned[visible])[-5:]
    error = np.linalg.norm(positions[-1] - last.centres[identity], axis=1)
    right = visible & (placed <= 1.0)
    assert np.all(error[right] <= 1.0), np.sort(error[right])[-5:]
    # Detection's own error at rest is the pin field's bar (tests/pins): a faint outer-ring tip in the veil,
    # found by the lattice probe at evidence near its bar, may sit 1-2 px off (radial seed 1: one, 1.70 px).
    assert np.count_nonzero(visible & (placed > 1.0)) <= 1, np.sort(placed[visible])[-3:]
