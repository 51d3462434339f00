"""A noisy webcam's frames through JPEG (issue 20, outcomes 5 and 7): noise blobs are not taken for pins.

JPEG (an MJPG webcam) smooths the noise within each 8 x 8 block, so Immerkaer's estimate (`noise_sigma`) of a
decoded frame reads 2-10 x low, and the candidate offsets of `find_pin_field` were floored at a fraction of
the noise their blur leaves: at offset 5 a lattice of noise blobs between the radial spokes won the vote, and
their short spacing made the pitch short and the scale up to 67 % large (bench_user_chain radial-led-120
seed 50: 136 pins, 18 of them noise, +41 %). The floor now reads the noise binned 2 x 2
(`pins._noise.binned_noise_sigma`), which JPEG leaves. Frames: the noiseless render, Gaussian camera noise,
JPEG at quality 75 (`bench/bench_conditions.py`'s camera).
"""

import cv2
import numpy as np
import pytest

from pins import find_pin_field, sensor_scale
from pins._noise import binned_noise_sigma, noise_sigma
from tactip.sim import SyntheticTacTip
from tests.pins.conftest import match


def _webcam(seed: int, sigma: float, quality: int = 75, preset: str = "radial-led-120", **options):
    """(frame, visible true centres px) of a preset at rest with camera noise `sigma` and JPEG `quality`."""
    frame = SyntheticTacTip.from_preset(preset, seed=seed, noise_sigma=0.0, **options).render()
    rng = np.random.default_rng(seed + 1000)
    image = np.clip(np.rint(frame.image + rng.normal(0.0, sigma, frame.image.shape)), 0, 255).astype(np.uint8)
    image = cv2.imdecode(cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, quality])[1], cv2.IMREAD_UNCHANGED)
    return image, frame.centres[frame.visible]


@pytest.mark.parametrize("sigma", [6.0, 8.0, 10.0])
@pytest.mark.parametrize("quality", [60, 75, 90])
def test_binned_noise_reads_the_noise_jpeg_leaves(sigma, quality):
    """White noise on a flat grey through JPEG: the binned estimate reads 0.65-1.1 of the noise (0.66-1.04 when
    written), where at quality 60-75 Immerkaer's reads less than 0.7 of it (0.08-0.4: the reason for the binned
    one); on the raw noise both agree within 5 %."""
    rng = np.random.default_rng(int(sigma) * 100 + quality)
    raw = np.clip(np.rint(120.0 + rng.normal(0.0, sigma, (240, 320))), 0, 255).astype(np.uint8)
    assert binned_noise_sigma(raw) == pytest.approx(noise_sigma(raw), rel=0.05)
    coded = cv2.imdecode(cv2.imencode(".jpg", raw, [cv2.IMWRITE_JPEG_QUALITY, quality])[1], cv2.IMREAD_UNCHANGED)
    if quality <= 75:
        assert noise_sigma(coded) < 0.7 * sigma
    assert 0.65 * sigma <= binned_noise_sigma(coded) <= 1.1 * sigma


@pytest.mark.parametrize("seed, sigma, options", [(5, 8.0, {"glare_gradient": 50.0}),
                                                  (10, 8.0, {"glare_gradient": 50.0}),
                                                  (47, 9.0, {})])
def test_noise_blobs_through_jpeg_are_not_pins_and_do_not_move_the_scale(seed, sigma, options):
    """Before: 136-149 pins of 120, precision 0.66-0.84, scale +5 % to +36 % (these frames); seeds 0-11 with the
    glare (noise 8, 9) and 40-47 without (noise 9): 12 of 32 frames with precision below 0.9, scale up to +67 %.
    After: precision 1.00 and the scale within 1 % here; over those 32 frames precision >= 0.9 and the scale
    within 2.3 % but one (noise 9, seed 1: 127 pins, +6.8 %)."""
    image, truth = _webcam(seed, sigma, **options)
    field = find_pin_field(image)
    recall, precision, _ = match(field.centres, truth)
    assert recall >= 0.97 and precision >= 0.98, (recall, precision, field.summary())
    found = sensor_scale(field.centres, sensor="radial-led-120").mm_per_px
    true = sensor_scale(truth, sensor="radial-led-120").mm_per_px
    assert found == pytest.approx(true, rel=0.02)


@pytest.mark.parametrize("seed", [1, 2, 11])
def test_noise_blobs_the_lowest_offset_alone_keeps_are_not_pins(seed):
    """The lowest candidate offset keeps the pins and a few noise blobs (between the spokes, on the LED
    reflections): more than 97 % of any other set's pins, it voted alone and won. Before: 122-127 pins of 120,
    precision 0.92-0.98 (these frames: noise 8, glare 50, JPEG 75); after: the sets keeping the next most pins
    vote too, and the noise blobs one set alone keeps lose (119-120 pins, precision 1.00). Seeds 0-23: 5 of 24
    frames with noise blobs -> 2 (seeds 3 and 13: blobs other sets keep as well); 4 pins fewer missed in all
    (3 frames miss one more, seeds 1 and 23 find 6 and 2 more)."""
    image, truth = _webcam(seed, 8.0, glare_gradient=50.0)
    field = find_pin_field(image)
    recall, precision, _ = match(field.centres, truth)
    assert precision >= 0.99 and recall >= 0.98, (recall, precision, field.summary())


@pytest.mark.parametrize("seed", [8, 12, 13])
def test_the_surround_is_no_membrane_round_a_small_pads_rim_pins(seed):
    """small-pad-100 (1 px tips on a pad 60 px across, a bright surround) under noise 8, glare 50 and JPEG 75:
    the flat-top test (`pins._tipprobe.flat_pins`) fitted the membrane round the outermost pins through the
    surround's bright pixels, a slope that rose over their cores: one true rim pin per frame was taken for a
    reflection's flat top (1.6 standard errors and 0.18 of its neighbours' contrast above the fit). Before:
    99 of 100 (these frames; seeds 0-15: 8 of 16 frames lost one); after: every pin (seeds 0-15: 2 of 16 lose
    one, a rim tip merged with the surround's blurred edge, rejected for its size)."""
    image, truth = _webcam(seed, 8.0, preset="small-pad-100", glare_gradient=50.0)
    field = find_pin_field(image)
    recall, precision, _ = match(field.centres, truth)
    assert recall == 1.0 and precision == 1.0, (recall, precision, field.summary())
