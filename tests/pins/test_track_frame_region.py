"""`pins.PinTracker.frame_region`: the part of a frame that `update` reads (replay maps luma to grey there alone,
`tactip.replay.luma.mapped`). Noise everywhere else in the frames changes no position, lost or retired pin."""

import numpy as np
import pytest

from pins import DetectionParams, PinTracker, SensorDisc
from tests.pins.conftest import slide_run


@pytest.mark.parametrize("name, seed", [("radial-led-120", 5), ("small-pad-100", 3), ("tactip-331", 4)])
def test_pixels_beyond_the_frame_region_are_never_read(name, seed):
    s, run, drawn = slide_run(name, seed, [30, 210], distance_mm=6.0, rest_s=3 / 120,
                              press_s=0.08, slide_s=0.2, lift_s=0.05)
    rng = np.random.default_rng(seed)
    tracks, regions, detections = [], [], []
    for scrambled in (False, True):
        # (detect_every=1: blob detection, which reads the disc beyond the crop, on every frame a pin is missing)
        tracker = PinTracker(detection=DetectionParams(dark_pins=s.dark_pins), disc=SensorDisc(*s.disc),
                             detect_every=1)
        assert tracker.frame_region is None
        tracker.start(run[0].image, pins=run[0].centres[drawn])
        region = tracker.frame_region
        track = []
        for frame in run[1:]:
            image = frame.image
            if scrambled:
                image = rng.integers(0, 256, image.shape, dtype=np.uint8)
                image[region] = frame.image[region]
            track.append((tracker.update(image), tracker.lost.copy(), tracker.retired.copy()))
        tracks.append(track)
        regions.append(region)
        detections.append(tracker.detection_frames)
    assert regions[0] == regions[1]
    for got, want in zip(*tracks):
        for a, b in zip(got, want):
            np.testing.assert_array_equal(a, b)
    rows, columns = regions[0]
    height, width = run[0].image.shape[:2]
    # The region holds the disc; on these presets it leaves some of the frame out (the noise was read nowhere).
    cx, cy, radius = s.disc
    assert rows.start <= cy - radius and rows.stop >= cy + radius and columns.start <= cx - radius
    assert (rows.stop - rows.start) * (columns.stop - columns.start) < height * width
    assert detections[0] == detections[1] > 0  # (blob detection, reading the disc beyond the crop, ran)
