"""`pins._noise.temporal_noise_sigma` against renders of known noise, raw and through video codecs (issue 20).

A codec (MJPG from a webcam, mp4v as `tactip record` writes) smooths the noise within a frame, so
Immerkaer's spatial estimate (`noise_sigma`) of a decoded frame reads a fraction of it; the
difference of two frames of a still pad reads the noise that survives, which is what moves the
windows' centroids (`bench/bench_noise_codecs.py`).
"""

import pathlib

import cv2
import numpy as np
import pytest

from pins._noise import noise_sigma, temporal_noise_sigma
from tactip.sim import SyntheticTacTip


def _still(preset, seed, frames=2):
    sensor = SyntheticTacTip.from_preset(preset, seed=seed)
    images = [sensor.render().image for _ in range(frames)]
    return sensor, [im if im.ndim == 2 else cv2.cvtColor(im, cv2.COLOR_BGR2GRAY) for im in images]


def _through(images, codec, folder: pathlib.Path):
    """`images` through `codec` and back, at 30 frames/s (`tests.pins.test_track_codec_still._through`)."""
    from tests.pins.test_track_codec_still import _through as through

    return through(images, codec, folder, frame_rate=30.0)


@pytest.mark.parametrize("preset", ["radial-led-120", "tactip-331", "white-dark-331", "small-pad-100"])
@pytest.mark.parametrize("seed", [0, 2])
def test_raw_renders_read_their_noise(preset, seed):
    sensor, (first, second) = _still(preset, seed)
    # (small-pad-100's fine tips fool the spatial estimate upwards: 8.9 for 4 grey levels.)
    assert temporal_noise_sigma(first, second) == pytest.approx(sensor.noise_sigma, rel=0.15)


@pytest.mark.parametrize("codec", ["MJPG", "mp4v"])
@pytest.mark.parametrize("preset", ["tactip-331", "white-dark-331"])
def test_through_a_codec_the_pair_reads_the_noise_one_frame_hides(codec, preset, tmp_path):
    sensor, images = _still(preset, seed=0)
    first, second = _through(images, codec, tmp_path)[:2]
    sigma = sensor.noise_sigma
    assert noise_sigma(first) < 0.5 * sigma          # the spatial estimate, fooled by the codec
    # (mp4v removes some of the noise itself: the std of two still frames' difference over sqrt 2
    # reads 0.65-0.7 of it, and the windows' scatter shrinks little.)
    assert 0.6 * sigma <= temporal_noise_sigma(first, second) <= 1.15 * sigma


def test_changed_pixels_and_saturation_do_not_count():
    rng = np.random.default_rng(3)
    scene = np.full((240, 320), 110.0)
    scene[:, :80] = 255.0                                     # a saturated surround
    noisy = [np.clip(np.rint(scene + rng.normal(0.0, 3.0, scene.shape)), 0, 255).astype(np.uint8) for _ in range(2)]
    noisy[1][100:130, 100:200] = 200                          # a tenth of the membrane changed (a tip moved)
    assert temporal_noise_sigma(*noisy) == pytest.approx(3.0, rel=0.05)
    assert temporal_noise_sigma(noisy[0], noisy[0]) == 0.0
    with pytest.raises(ValueError):
        temporal_noise_sigma(noisy[0], noisy[1][:, 1:])
