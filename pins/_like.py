"""A tip like the pin's own at rest, for `pins._refine.Refiner` (paper 002, III-A.3): the bounds on a windowed
tip's area, contrast and compactness (`pins._window`) from the pin's tip in the rest frame.

A hidden pin has no contrast; a neighbour, glare or a speck in the window pulls the centroid, adds area and
spreads the mass: a tip is like at rest when its contrast and compactness are at least a share of its own at
rest, and its area within a factor of it. On renders and the sample video (5-6 mm taps) centroids stay
within 0.01 spacings of LK, area within 0.9-1.3 and compactness within 0.92-1.09 of rest.

The rest frame is one noisy frame: a faint tip's measures there are partly noise (issue 20: a pin beside an
LED reflection of radial-led-120 showed a windowed contrast of -5.5 to 33.8 grey levels at rest over seeds
0-15, the median pin's 45-50, and bounds of half and twice its measures lay above those measures
themselves, or left its area unbounded but for noise). So each bound reaches as far as that frame's noise
may have moved the measure it comes from (`bounds_at_rest`), by the contrast's scatter in the rest frame's
own noise (`contrast_noise`): crisp tips keep the bounds of their own measures; a tip too faint to show an
area at rest is bounded by its contrast alone.
"""

from __future__ import annotations

import numpy as np

from ._noise import noise_sigma
from ._rest import _NOISE_DRAWS, _standard_draws
from ._window import WindowCentroids

__all__ = ["bounds_at_rest", "contrast_noise"]

_AREA_RATIO = (0.5, 2.0)
_MIN_CONTRAST_RATIO = 0.5
_MIN_COMPACTNESS_RATIO = 0.6
# A tip's contrast later may lie this many times the contrast's scatter in noise (`contrast_noise`) below
# its contrast at rest, and its area and compactness, which are measured over the threshold-to-top height,
# scale by as much (`bounds_at_rest`). On radial-led-120 (noise 5.4 grey levels: the contrast's scatter
# 2.6), visible pins' windows at their rest positions over 10 still frames fail their bounds in 20/0/0
# pin-frames (reach 0, the bounds before / 4 / 5 scatters) on seeds 0-5, 101/3/0 on seeds 6-25 and
# 124/4/3 on seeds 26-45 (5 was chosen seeing seeds 6-25; 26-45 held out). Windows half-way between two
# tips (a window between neighbours: a swap) pass them in 0/8/9 of 2400 (seeds 6-25), against 97 with no
# bounds at all for tips below half the median pin's contrast; on tactip-331, dark-331, white-dark-331,
# radial-120, brown-127 and small-pad-100 (seeds 0-5) no window fails at any reach, none half-way passes,
# and no tip goes unjudged.
_NOISE_REACH = 5.0


def contrast_noise(windows: WindowCentroids, rest_crop: np.ndarray, points: np.ndarray) -> float:
    """The scatter of a window's contrast in the rest frame's own noise, grey levels: the median over the
    windows at `points` (N, 2), px, of the rms change of their contrast when noise of the crop's level
    (`noise_sigma`, the draws of `pins._rest`) is added to it; 0 in a noiseless frame.

    One figure for all windows (the contrast is the top's five pixels above the sides' darkest runs, the
    same pixels in every window): four draws of each of a hundred windows measure it to a few per cent.
    """
    sigma = noise_sigma(rest_crop)
    if not sigma > 0 or len(points) == 0:
        return 0.0
    base = windows.contrast(rest_crop, points)
    total = np.zeros(len(points))
    for draw in _standard_draws(rest_crop.shape):
        noisy = np.multiply(draw, sigma)
        noisy += rest_crop
        noisy = np.clip(noisy, 0, 255, out=noisy).astype(np.uint8)
        change = windows.contrast(noisy, points) - base
        total += change * change
    scatter = np.sqrt(total[np.isfinite(total)] / _NOISE_DRAWS)
    return float(np.median(scatter)) if scatter.size else 0.0


def bounds_at_rest(area: np.ndarray, contrast: np.ndarray, compactness: np.ndarray,
                   noise: float) -> tuple[np.ndarray, np.ndarray]:
    """Bounds on each pin's tip from its tip at rest: (area, contrast, compactness) from below (3, N), area
    above (N,), for a rest frame whose windows' contrast scatters by `noise` grey levels.

    The ratios of a tip's own measures at rest (`_AREA_RATIO`, `_MIN_CONTRAST_RATIO`,
    `_MIN_COMPACTNESS_RATIO`), applied to the measures that frame's noise may have hidden: the contrast
    down to `_NOISE_REACH` scatters below its own, the area and compactness (a mass over the
    threshold-to-top height) scaled by the contrast's reach either way. A tip whose contrast at rest lies
    within that reach of nothing (a faint tip beside a reflection: -5.5 to 33.8 grey levels over
    radial-led-120's seeds 0-15, the median tip's 45-50) shows no area or compactness at rest to be
    judged by: only its contrast bounds it (from below, at its own less the reach).
    """
    reach = _NOISE_REACH * noise
    judged = contrast > reach  # NaN compares False
    with np.errstate(divide="ignore", invalid="ignore"):
        low = np.where(judged, contrast / (contrast + reach), np.nan)  # the top was up to `reach` brighter
        high = np.where(judged, contrast / (contrast - reach), np.nan)  # ... or darker
    at_least = np.stack([np.where(judged, _AREA_RATIO[0] * area * low, -np.inf),
                         np.minimum(_MIN_CONTRAST_RATIO * contrast, contrast - reach),
                         np.where(judged, _MIN_COMPACTNESS_RATIO * compactness * low, -np.inf)])
    area_at_most = np.where(judged, _AREA_RATIO[1] * area * high, np.inf)
    return at_least, area_at_most
