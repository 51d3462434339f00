"""Noise of the camera and of each window's centroid, for `pins._refine.Refiner` (paper 002, III-A.3).

`noise_sigma` measures a grey image's pixel noise (the rest frame's, whose level then draws the noise
that bounds each rest window's scatter before any is learnt, `pins._rest`); `temporal_noise_sigma`
measures it from two frames of a still pad instead, as a video codec leaves it (a codec smooths the
noise within a frame, which `noise_sigma` reads, but not the noise that moves a window's centroid:
`bench/bench_noise_codecs.py`); `_learn_mean_square` is
the running mean square by which each window learns its scatter frame by frame while its pin is still.
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["noise_sigma", "binned_noise_sigma", "temporal_noise_sigma"]

# Weight of each still step in a window's learnt scatter (`Refiner.observe_still`), and how many
# times that scatter a still pin's window may lie from where its still neighbours place it.
_JITTER_RATE = 0.2
_JITTER_FIRST = 3
_JITTER_BOUND = 3.0


def noise_sigma(image: np.ndarray) -> float:
    """Standard deviation of a grey image's pixel noise, grey levels (Immerkaer's Laplacian-difference
    estimator made robust: the median absolute response over 6 sigma, so that edges and tips, a
    minority of pixels, do not count; saturated or flat regions, which show none, are left out)."""
    # A saturated surround (and its clipped fringe) or a black margin shows no noise, or less.
    clipped = cv2.dilate(((image <= 2) | (image >= 253)).astype(np.uint8), np.ones((5, 5), np.uint8))[1:-1, 1:-1]
    if image.dtype == np.uint8 and image.ndim == 2:
        return float(_median_response_uint8(image, clipped) / (0.6745 * 6.0))
    response = np.abs(cv2.filter2D(image.astype(np.float32), -1, _LAPLACE_DIFFERENCE))[1:-1, 1:-1]
    response = response[clipped == 0]
    return float(np.median(response) / (0.6745 * 6.0)) if response.size else 0.0


def binned_noise_sigma(image: np.ndarray, factor: int = 2) -> float:
    """Standard deviation of a grey image's pixel noise as it reads at a coarser scale, grey levels: `noise_sigma`'s
    estimator on the image averaged over `factor` x `factor` px blocks, times `factor` (white noise reads the same
    as at full scale).

    A video codec or JPEG (a webcam's MJPG) smooths the noise within a frame: the finest scale, which
    `noise_sigma` reads, loses most of it (2-10 x less), but the noise at the scale of a pin tip, which a
    blurred threshold meets, survives. Binned 2 x 2 (radial-led-120 filmed through MJPG at quality 75, noise
    5.0-7.6): 4.5-6.4 against `noise_sigma`'s 2.0-5.2. Structure (tips, shading) reads as noise too, more on
    a dense pad (tactip-331 with noise 4: 5.9), so this is a bound for thresholds, not the tracker's noise.
    """
    image = np.asarray(image)
    if image.ndim != 2:
        raise ValueError(f"image must be 2-D, got shape {image.shape}")
    height, width = (image.shape[0] // factor) * factor, (image.shape[1] // factor) * factor
    if height < 3 * factor or width < 3 * factor:
        return noise_sigma(image)
    crop = image[:height, :width].astype(np.float32)
    # A block's mean and whether any of its pixels is saturated or black, from its `factor` x `factor` strided views
    # (NumPy's reduction over two axes of the blocks costs ten times as much: ~2.3 ms each at 640 x 480). A sum of
    # integer grey levels is exact in any order, so the means are `mean(axis=(1, 3))`'s bit for bit.
    views = [(row, column) for row in range(factor) for column in range(factor)]
    if np.issubdtype(image.dtype, np.integer) and image.dtype.itemsize <= 2:
        binned = crop[::factor, ::factor].copy()
        for row, column in views[1:]:
            binned += crop[row::factor, column::factor]
        binned /= np.float32(factor * factor)
    else:  # (non-integer levels: NumPy's order of summation)
        binned = crop.reshape(height // factor, factor, width // factor, factor).mean(axis=(1, 3))
    # A block with any saturated or black pixel shows less noise: left out (with its fringe, as `noise_sigma`).
    clipped_pixels = (crop <= 2) | (crop >= 253)
    dead = clipped_pixels[::factor, ::factor].copy()
    for row, column in views[1:]:
        dead |= clipped_pixels[row::factor, column::factor]
    clipped = cv2.dilate(dead.astype(np.uint8), np.ones((3, 3), np.uint8))[1:-1, 1:-1]
    response = np.abs(cv2.filter2D(binned, -1, _LAPLACE_DIFFERENCE))[1:-1, 1:-1][clipped == 0]
    return float(factor * np.median(response) / (0.6745 * 6.0)) if response.size else 0.0


def temporal_noise_sigma(first: np.ndarray, second: np.ndarray) -> float:
    """Standard deviation of the pixel noise, grey levels, from two uint8 frames of a still scene of the
    same shape: the rms difference of their pixels over sqrt 2, clipped at `_CLIP_SIGMAS` times itself
    (three rounds: pixels that changed, a minority such as tips that moved, do not count); saturated
    or black pixels in either frame, which show no noise, are left out; 0 when none is left.

    Through a video codec it reads the noise that survives the codec, which moves the windows'
    centroids; `noise_sigma` of one such frame reads 2-10 x less (a codec smooths the noise within a
    frame), and a median of the differences reads 1.7-6 x less (an mp4v P-frame copies most blocks of
    a still scene, their differences 0): `bench/bench_noise_codecs.py`.

    >>> rng = np.random.default_rng(0)
    >>> scene = np.full((200, 200), 120.0)
    >>> a, b = (np.clip(np.rint(scene + rng.normal(0, 4.0, scene.shape)), 0, 255).astype(np.uint8) for _ in range(2))
    >>> round(temporal_noise_sigma(a, b), 1)
    4.0
    """
    if first.shape != second.shape:
        raise ValueError(f"the frames differ in shape: {first.shape} and {second.shape}")
    first, second = np.asarray(first, np.uint8), np.asarray(second, np.uint8)
    usable = ~((first <= 2) | (first >= 253) | (second <= 2) | (second >= 253))
    difference = cv2.absdiff(first, second)[usable]
    counts = np.bincount(difference.ravel(), minlength=256).astype(np.float64)   # of |d| = 0 ... 255
    levels = np.arange(256.0)
    bound = 255.0
    for _ in range(3):
        kept = counts * (levels <= bound)
        n = kept.sum()
        if n == 0:
            return 0.0
        rms = float(np.sqrt((kept * levels ** 2).sum() / n))
        bound = max(_CLIP_SIGMAS * rms, 1.0)
    return rms / float(np.sqrt(2.0))


#: Differences of two frames beyond this many times their rms are change, not noise (`temporal_noise_sigma`).
_CLIP_SIGMAS = 3.5

#: Immerkaer's 3 x 3 kernel: the difference of two Laplacians, blind to a linear ramp.
_LAPLACE_DIFFERENCE = np.array([[1, -2, 1], [-2, 4, -2], [1, -2, 1]], np.float32)
_MAX_RESPONSE = 16 * 255  # the largest |response| of a uint8 image


def _median_response_uint8(image: np.ndarray, clipped: np.ndarray) -> np.float32:
    """`noise_sigma`'s median absolute response of a 2-D uint8 image over the interior pixels not
    ``clipped``, as float32 (np.median of the float32 responses, bit for bit; 0 when none), from a
    histogram of the integer responses (4 x cheaper on a 640 x 480 px frame than sorting them)."""
    response = np.abs(cv2.filter2D(image, cv2.CV_16S, _LAPLACE_DIFFERENCE)[1:-1, 1:-1])   # exact integers
    response[clipped != 0] = _MAX_RESPONSE + 1   # counted in a bin past the largest, then dropped
    n, lower, upper = _middle_values(np.bincount(response.ravel(), minlength=_MAX_RESPONSE + 2)[:_MAX_RESPONSE + 1])
    return (np.float32(lower) + np.float32(upper)) / np.float32(2.0) if n else np.float32(0.0)


def median_uint8(values: np.ndarray) -> float:
    """``np.median`` of uint8 `values` (any shape), bit for bit, from their histogram (no sort); NaN when empty.

    >>> median_uint8(np.array([3, 1, 200, 4], np.uint8)), median_uint8(np.array([7], np.uint8))
    (3.5, 7.0)
    """
    n, lower, upper = _middle_values(np.bincount(values.ravel(), minlength=256))
    return 0.5 * (lower + upper) if n else float("nan")


def _middle_values(histogram: np.ndarray) -> tuple[int, int, int]:
    """(n, the values at sorted indices (n - 1) // 2 and n // 2) of n >= 0 integers given by their
    `histogram` (counts of 0, 1, 2, ...): a median is their mean (equal when n is odd; zeros when n = 0)."""
    counts = np.cumsum(histogram)
    n = int(counts[-1])
    if n == 0:
        return 0, 0, 0
    return n, int(np.searchsorted(counts, (n - 1) // 2 + 1)), int(np.searchsorted(counts, n // 2 + 1))


def _learn_mean_square(mean_sq: np.ndarray, seen: np.ndarray, index, value: np.ndarray, candidate: np.ndarray) -> None:
    """Update running mean squares in place: ``mean_sq[index]`` (px^2) with ``value`` where ``candidate``.

    The first `_JITTER_FIRST` values of each entry are averaged; later ones count, with weight
    `_JITTER_RATE`, only within `_JITTER_BOUND` times the mean so far (a pin that begins to move with a
    contact is no noise). ``seen[index]`` counts the values learnt; NaN values learn nothing.
    """
    so_far, count = mean_sq[index], seen[index]
    first = count < _JITTER_FIRST
    learn = candidate & (first | (value <= _JITTER_BOUND ** 2 * so_far))
    rate = np.where(first, 1.0 / (count + 1.0), _JITTER_RATE)
    mean_sq[index] = so_far + np.where(learn, rate * (value - so_far), 0.0)
    seen[index] = count + learn

