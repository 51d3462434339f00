"""pins.track on a still pad through a video codec (issue 20, outcome 1): no faint pin is lost.

A codec (MJPG from a webcam, mp4v as `tactip record` writes) smooths the noise within a frame, so the
rest frame's own noise (Immerkaer's estimate) predicted a scatter of the windows' contrast 0.25-0.6 of the
one they show from frame to frame, and the faint tips on radial-led-120's LED reflections, whose contrast
may fall by a few times that scatter (`pins._like`), were lost on a still pad. The first still frame
after the rest frame shows the real scatter (`pins._rest._AtRest.heed_camera_noise`).
"""

import pathlib

import cv2
import numpy as np
import pytest

import pins._kernels
from pins import DetectionParams, PinTracker, SensorDisc, find_pin_field
from tactip.sim import SyntheticTacTip


def _grey(image):
    return image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)


def _through(images, codec, folder: pathlib.Path, frame_rate=120.0):
    """`images` (grey) written through ``cv2.VideoWriter`` with `codec` and read back, grey; as given for raw."""
    if codec == "raw":
        return images
    height, width = images[0].shape
    path = str(folder / ("still.avi" if codec == "MJPG" else "still.mp4"))
    writer = cv2.VideoWriter(path, cv2.VideoWriter_fourcc(*codec), frame_rate, (width, height), True)
    if not writer.isOpened():
        pytest.skip(f"no {codec} encoder in this OpenCV build")
    for image in images:
        writer.write(cv2.cvtColor(image, cv2.COLOR_GRAY2BGR))
    writer.release()
    capture, out = cv2.VideoCapture(path), []
    ok, frame = capture.read()
    while ok:
        out.append(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY))
        ok, frame = capture.read()
    capture.release()
    assert len(out) == len(images)
    return out


def _still_pad(preset, seed, frames, codec, folder):
    """The rest frame and `frames` - 1 more of the still pad (fresh noise), through `codec`; and its sensor."""
    sensor = SyntheticTacTip.from_preset(preset, seed=seed, frame_rate=120.0)
    return sensor, _through([_grey(sensor.render().image) for _ in range(frames)], codec, folder)


def _started(sensor, image):
    """A tracker started on `image` from the still pad's true centres (its visible pins), as from a calibration."""
    rest = sensor.render()  # (its truth: the same pins as every still frame's)
    tracker = PinTracker(detection=DetectionParams(dark_pins=sensor.dark_pins), disc=SensorDisc(*sensor.disc))
    tracker.start(image, pins=rest.centres[np.flatnonzero(rest.visible)])
    return tracker


def _contrast_scatter(tracker, images):
    """The median over the rest windows of their contrast's std over `images` (the truth the bounds need)."""
    refiner = tracker._refiner
    points = refiner.rest_positions - refiner.origin
    contrast = np.stack([refiner.windows.contrast(tracker._bright(tracker._cropped(image)), points)
                         for image in images])
    return float(np.nanmedian(np.std(contrast, axis=0, ddof=1)))


@pytest.mark.parametrize("codec", ["MJPG", "mp4v"])
@pytest.mark.parametrize("preset", ["radial-led-120", "tactip-331"])
def test_through_a_codec_the_first_still_frame_shows_the_contrast_scatter(preset, codec, tmp_path):
    sensor, images = _still_pad(preset, 0, 8, codec, tmp_path)
    tracker = _started(sensor, images[0])
    truth = _contrast_scatter(tracker, images)
    before = tracker._refiner.contrast_noise
    assert before < 0.6 * truth  # the rest frame alone: the codec hid most of the noise
    tracker.update(images[0])    # the rest frame again is no still pair: nothing learnt
    assert tracker._refiner.contrast_noise == before
    tracker.update(images[1])
    assert 0.8 * truth <= tracker._refiner.contrast_noise <= 1.6 * truth


@pytest.mark.parametrize("preset", ["radial-led-120", "tactip-331", "small-pad-100", "white-dark-331"])
def test_raw_renders_keep_the_bounds_their_rest_frame_draws(preset, tmp_path):
    # Without a codec the rest frame's own noise predicts the contrast's scatter (0.9-1.3 x over seeds 0-11):
    # the still frame changes no bound.
    sensor, images = _still_pad(preset, 1, 2, "raw", tmp_path)
    tracker = _started(sensor, images[0])
    refiner = tracker._refiner
    before, at_least = refiner.contrast_noise, refiner._at_least.copy()
    tracker.update(images[1])
    assert refiner._rest_for_noise is None  # the pair was seen ...
    assert refiner.contrast_noise == before  # ... and changed nothing
    np.testing.assert_array_equal(refiner._rest_least, at_least)
    # (Faint tips, still, have the bounds of their level, `pins._rest._AtRest._learn_levels`; the others' stand.)
    others = np.setdiff1d(np.arange(at_least.shape[1]), refiner._faint)
    np.testing.assert_array_equal(refiner._at_least[:, others], at_least[:, others])


@pytest.mark.parametrize("kernels", ["compiled", "numpy"])
@pytest.mark.parametrize("codec", ["MJPG", "mp4v"])
def test_a_still_pad_through_a_codec_loses_no_pin(codec, kernels, tmp_path, monkeypatch):
    # Replay's start (the pin field, then the tracker) on radial-led-120 through each codec. Seeds 9 and 10
    # lost faint tips on reflections within these frames before (MJPG: frames 7 and 3; mp4v: 1-8 and 1, 3);
    # over 40 still frames and seeds 0-11, lost pin-frames were MJPG 8, mp4v 32 (raw 0).
    if kernels == "numpy":
        monkeypatch.setattr(pins._kernels, "_NUMPY", True)
    for seed in (9, 10):
        sensor, images = _still_pad("radial-led-120", seed, 9, codec, tmp_path)
        field = find_pin_field(images[0])
        tracker = PinTracker(detection=field.params, disc=field.disc)
        tracker.start(images[0], field.centres)
        for k, image in enumerate(images[1:], start=1):
            tracker.update(image)
            assert not tracker.lost.any(), f"seed {seed}, frame {k}: pins {np.flatnonzero(tracker.lost)} lost"


def _still_through_mp4v(seed, tmp_path):
    """Replay's start on 41 still frames of radial-led-120 through mp4v, no pin lost in any (asserted): the
    tracker and each pin's distance to the nearest true tip at the end, px."""
    sensor, images = _still_pad("radial-led-120", seed, 41, "mp4v", tmp_path)
    field = find_pin_field(images[0])
    tracker = PinTracker(detection=field.params, disc=field.disc)
    tracker.start(images[0], field.centres)
    truth = sensor.render().centres
    for k, image in enumerate(images):
        positions = tracker.update(image)
        assert not tracker.lost.any(), f"frame {k}: pins {np.flatnonzero(tracker.lost)} lost"
    return tracker, np.linalg.norm(positions[:, None] - truth[None], axis=2).min(axis=1)


@pytest.mark.parametrize("seed", [15, 22])
def test_faint_tips_whose_area_the_codec_inflated_at_rest_are_kept(seed, tmp_path):
    # codec10's leftovers through mp4v (replay's start, 40 still frames): seed 15's tip of contrast 12, just
    # above the reach, showed half its rest frame's area and compactness in every P-frame (10 pin-frames
    # lost), seed 22's pin 0 failed its own rest frame and was never found again (33). Both still fail on
    # b4070ad (follow10's overlaps merged) and pass since a91b0e4 capped the overlap radius (a faint tip's
    # area at rest, inflated by the codec, no longer pairs it with neighbours).
    _, error = _still_through_mp4v(seed, tmp_path)
    assert np.all(error < 1.0)  # each on a true tip at the end


@pytest.mark.parametrize("seed", [7, 24])
def test_a_still_faint_tip_may_read_fainter_than_in_the_rest_frame(seed, tmp_path):
    # Through mp4v the rest frame (an I-frame) is less like the still frames after it than they are like each
    # other: radial-led-120's faint tip beside a reflection (pin 98 on these seeds) read 18.7 / 23.2 grey levels
    # at rest and 15.3 on average over 40 still frames, and was lost in 1 / 2 of them below its bound of its
    # contrast less 5 scatters. A still judged tip may now fall by sqrt 2 times that (`pins._rest._PAIR_REACH`).
    tracker, error = _still_through_mp4v(seed, tmp_path)
    assert np.all(error < 1.0)
    # A pin that moves keeps the bound of one reach: identities through slides hold as before.
    refiner = tracker._refiner
    moving = np.zeros(len(error), dtype=bool)
    moving[::2] = True
    refiner.still = ~moving
    np.testing.assert_array_equal(refiner._at_least[1, moving], refiner._contrast_moving[moving])
    assert np.all(refiner._contrast_still <= refiner._contrast_moving)


@pytest.mark.parametrize("codec", ["mp4v"])
def test_the_first_still_frame_through_a_codec_loses_no_pin(codec, tmp_path):
    # The rest frame is the video's first frame, decoded like every other; through mp4v it is an I-frame and the
    # first still frame a P-frame. radial-led-120 seed 3's pin 119 (contrast 28, judged by all three measures)
    # read an area of 66 at rest and 240 in the first still frame (98, 78 later): beyond twice its rest area, and
    # not yet calm there (no window's scatter learnt, the rest frame's noise 3.5 x too low). Lost in that frame
    # before; the still pair now grows the calm test's scatter by its ratio of noises, in that frame only.
    sensor, images = _still_pad("radial-led-120", 3, 3, codec, tmp_path)
    field = find_pin_field(images[0])
    tracker = PinTracker(detection=field.params, disc=field.disc)
    tracker.start(images[0], field.centres)
    refiner = tracker._refiner
    before = refiner._noise_scatter_sq.copy()
    truth = sensor.render().centres
    for k, image in enumerate(images[1:], start=1):
        positions = tracker.update(image)
        assert not tracker.lost.any(), f"frame {k}: pins {np.flatnonzero(tracker.lost)} lost"
        assert np.linalg.norm(positions[:, None] - truth[None], axis=2).min(axis=1).max() < 1.0
    assert refiner._contrast_still is not None  # (the still pair widened the bounds)
    np.testing.assert_array_equal(refiner._noise_scatter_sq, before)  # (grown in that frame only)
