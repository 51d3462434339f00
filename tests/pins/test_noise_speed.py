"""`pins._noise.binned_noise_sigma` bins by strided views (the field search's noise floor, on the start of every
replay): the same bits as NumPy's mean and any over the blocks' two axes, as it did before."""

import cv2
import numpy as np
import pytest

from pins._noise import _LAPLACE_DIFFERENCE, binned_noise_sigma, noise_sigma


def _by_block_axes(image, factor=2):
    """The estimate as `binned_noise_sigma` computed it until session 22: blocks reduced over their two axes."""
    image = np.asarray(image)
    height, width = (image.shape[0] // factor) * factor, (image.shape[1] // factor) * factor
    if height < 3 * factor or width < 3 * factor:
        return noise_sigma(image)
    crop = image[:height, :width].astype(np.float32)
    binned = crop.reshape(height // factor, factor, width // factor, factor).mean(axis=(1, 3))
    dead = ((crop <= 2) | (crop >= 253)).reshape(height // factor, factor, width // factor, factor).any(axis=(1, 3))
    clipped = cv2.dilate(dead.astype(np.uint8), np.ones((3, 3), np.uint8))[1:-1, 1:-1]
    response = np.abs(cv2.filter2D(binned, -1, _LAPLACE_DIFFERENCE))[1:-1, 1:-1][clipped == 0]
    return float(factor * np.median(response) / (0.6745 * 6.0)) if response.size else 0.0


def _images(seed: int, count: int):
    """Grey images of odd and even sizes: noise of several levels, a saturated or black part or specks, uint16,
    float levels."""
    rng = np.random.default_rng(seed)
    for k in range(count):
        height, width = (int(v) for v in rng.integers(5, 90, 2))
        image = np.clip(rng.normal(128.0, 3.0 * (k % 6 + 1), (height, width)), 0, 255).astype(np.uint8)
        if k % 3 == 0:
            image[: height // 2] = 255 if k % 2 else 0
        if k % 4 == 1:
            image[rng.random((height, width)) < 0.03] = 255 if k % 8 == 1 else 0        # specks of glare or black
        if k % 5 == 0:
            image = image.astype(np.uint16) * 3
        if k % 7 == 0:
            image = image.astype(np.float64) + rng.random((height, width))
        yield image


@pytest.mark.parametrize("factor", [2, 3, 4])
def test_the_binned_noise_is_the_block_axes_mean_bit_for_bit(factor):
    for image in _images(factor, 40):
        assert binned_noise_sigma(image, factor) == _by_block_axes(image, factor)


def test_a_rendered_pad_gives_the_same_noise():
    from tactip.sim import SyntheticTacTip

    for preset in ("radial-led-120", "tactip-331"):
        image = SyntheticTacTip.from_preset(preset, seed=2).render().image
        assert binned_noise_sigma(image) == _by_block_axes(image) > 0.0
