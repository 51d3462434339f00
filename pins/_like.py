"""A tip like the pin's own at rest, for `pins._refine.Refiner` (paper 002, III-A.3): the bounds on a windowed
tip's area, contrast and compactness (`pins._window`) from the pin's tip in the rest frame.

A hidden pin has no contrast; a neighbour, glare or a speck in the window pulls the centroid, adds area and
spreads the mass: a tip is like at rest when its contrast and compactness are at least a share of its own at
rest, and its area within a factor of it. On renders and the sample video (5-6 mm taps) centroids stay
within 0.01 spacings of LK, area within 0.9-1.3 and compactness within 0.92-1.09 of rest.

The rest frame is one noisy frame: a faint tip's measures there are mostly noise (issue 20: a pin beside an
LED reflection of radial-led-120 showed a windowed contrast of -5.5 to 33.8 grey levels at rest over seeds
0-15, the median pin's 45-50, and bounds of half and twice its measures lay above those measures
themselves, or left its area unbounded but for noise). So a tip's contrast may fall later by as much as
that frame's noise may have raised it at rest (a few times the contrast's scatter in the rest frame's own
noise, `contrast_noise`; through a video codec, which hides most of that noise from one frame, the scatter
the first still frame shows instead, and sqrt 2 times that reach for a still tip judged by all three
measures: `pins._rest._AtRest.heed_camera_noise`), and a tip whose contrast at rest lies within that reach of nothing shows no area
or compactness to be judged by: its contrast alone bounds it (`bounds_at_rest`). Crisp tips keep the
bounds of their own measures. A faint tip's rest frame may have caught it well above its level (radial-led-120
seed 37: 22.6 grey levels at rest, 14.0 +- 2.3 over 40 still frames): over the still frames it learns that
level and has its bounds (`bounds_from_level`, `pins._rest._AtRest._learn_levels`).
"""

from __future__ import annotations

import numpy as np

from ._window import WindowCentroids

__all__ = ["bounds_at_rest", "bounds_from_level", "contrast_noise"]

_AREA_RATIO = (0.5, 2.0)
_MIN_CONTRAST_RATIO = 0.5
_MIN_COMPACTNESS_RATIO = 0.6
# A tip's contrast later may fall to its own at rest less this many times the contrast's scatter in noise
# (`contrast_noise`), when that is below half its own; a tip whose contrast at rest lies within that reach of
# nothing is judged by its contrast alone (`bounds_at_rest`). On radial-led-120 (noise 5.4 grey levels: the
# contrast's scatter 2.6), visible pins' windows at their rest positions, measured in the rest frame itself,
# fail their bounds on 3 of 20 seeds (6-25) before, on none now; over 10 still frames in 20/15, 101/31,
# 124/38 pin-frames (before/now; seeds 0-5, 6-25, 26-45; the tracker's other steps, such as snapping calm
# pins to rest, keep most of these); windows half-way between two tips (where a swap would sit) pass them
# in 0/1, 0/9, 0/9 of 720, 2400, 2400 (with no bounds at all below half the median pin's contrast: 38, 97,
# 83). On tactip-331, dark-331, white-dark-331, radial-120, brown-127 and small-pad-100 (seeds 0-5) no tip
# goes unjudged and no bound changes. The reach (5) was chosen on radial-led-120 seeds 0-25 (at 3 and 4
# still frames fail in 44/39 pin-frames on 6-25, and more tips' bounds change); seeds 26-45 held out.
# Such a tip is told from the membrane only where it rests: `pins._refine.Refiner` places it by its window
# only while it is still. bench/bench_slides.py, radial-led-120 seeds 0-5 (before -> now): lost visible pins
# per frame 3.41 -> 3.24 (model skin), 2.91 -> 2.77 (realistic, min_area 0.5); pin-frames on another pin's
# centre 277 -> 269 (apart 34 -> 34), 1 -> 1 (0 -> 0); but pin-frames > 3 px off 79 -> 80 and, on the
# realistic skin, 18 -> 87 (faint tips placed off their centres where the old bounds left them lost).
# Placed while moving too: apart 0 -> 9 and > 3 px 18 -> 202 there; and not fitted (`pins._recover`)
# either: apart 0, > 3 px 18 -> 360. tactip-331 and small-pad-100 unchanged. Tried and dropped: every tip's
# area and compactness bounds stretched by its contrast's reach (c / (c -+ reach)): still frames 0/0/3
# pin-frames, but crisp tips' bounds loosened by a third on
# radial-led-120 and two-slide runs swapped identities (`tests/pins/test_track_identity.py`: seeds 1, 2,
# 5; small-pad-100 23 > 20 pin-frames).
_NOISE_REACH = 5.0


def contrast_noise(windows: WindowCentroids, rest_crop: np.ndarray, noisy: tuple, points: np.ndarray) -> float:
    """The scatter of a window's contrast in the rest frame's own noise, grey levels: the median over the
    windows at `points` (N, 2), px, of the rms change of their contrast from `rest_crop` to its `noisy`
    copies (`pins._rest.noisy_copies`); 0 without copies (a noiseless frame) or points.

    One figure for all windows (the contrast is the top's five pixels above the sides' darkest runs, the
    same pixels in every window): four draws of each of a hundred windows measure it to a few per cent.
    """
    if not noisy or len(points) == 0:
        return 0.0
    base = windows.contrast(rest_crop, points)
    total = np.zeros(len(points))
    for copy in noisy:
        change = windows.contrast(copy, points) - base
        total += change * change
    scatter = np.sqrt(total[np.isfinite(total)] / len(noisy))
    return float(np.median(scatter)) if scatter.size else 0.0


def bounds_at_rest(area: np.ndarray, contrast: np.ndarray, compactness: np.ndarray,
                   noise: float, fall: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Bounds on each pin's tip from its tip at rest: (area, contrast, compactness) from below (3, N), area
    above (N,), for a rest frame whose windows' contrast scatters by `noise` grey levels.

    The ratios of a tip's own measures at rest (`_AREA_RATIO`, `_MIN_CONTRAST_RATIO`,
    `_MIN_COMPACTNESS_RATIO`), but that its contrast may fall to its own less `_NOISE_REACH` scatters of the
    noise where that is lower (a tip of less than twice that reach). A tip whose contrast at rest lies within
    that reach of nothing (a faint tip beside a reflection: -5.5 to 33.8 grey levels over radial-led-120's
    seeds 0-15, the median tip's 45-50) shows no area or compactness at rest to be judged by: only its
    contrast bounds it (NaN at rest: nothing is like it). A judged tip's contrast may fall by `fall` reaches
    (`pins._rest._PAIR_REACH`: a still tip through a codec).
    """
    reach = _NOISE_REACH * noise
    judged = contrast > reach  # NaN compares False
    at_least = np.stack([np.where(judged, _AREA_RATIO[0] * area, -np.inf),
                         np.minimum(_MIN_CONTRAST_RATIO * contrast,
                                    contrast - np.where(judged, fall * reach, reach)),
                         np.where(judged, _MIN_COMPACTNESS_RATIO * compactness, -np.inf)])
    area_at_most = np.where(judged, _AREA_RATIO[1] * area, np.inf)
    return at_least, area_at_most


def bounds_from_level(level: np.ndarray, readings: np.ndarray, judged: np.ndarray,
                      noise: float) -> tuple[np.ndarray, np.ndarray]:
    """Bounds on faint tips from their level: the mean (area, contrast, compactness), (3, F), of `readings`
    (3, F) frames of each (its rest frame's and its still frames', `pins._rest._AtRest`), for tips `judged`
    (F,) by all three measures at rest or by their contrast alone; (3, F) from below and (F,) area above.

    `bounds_at_rest` of that level, but that the contrast's reach is that of a new frame's difference from
    a mean of n frames, sqrt((1 + 1/n) / 2) times `_NOISE_REACH` scatters of `noise` (the rest frame's reach
    at n = 1: one frame against another; 0.71 of it for a level learnt from many), and that a tip keeps how
    it was judged at rest (its level decides no more of that than its bounds).
    """
    reach = _NOISE_REACH * noise * np.sqrt(0.5 * (1.0 + 1.0 / np.maximum(readings[1], 1.0)))
    area, contrast, compactness = level
    at_least = np.stack([np.where(judged, _AREA_RATIO[0] * area, -np.inf),
                         np.where(judged, np.minimum(_MIN_CONTRAST_RATIO * contrast, contrast - reach),
                                  contrast - reach),
                         np.where(judged, _MIN_COMPACTNESS_RATIO * compactness, -np.inf)])
    return at_least, np.where(judged, _AREA_RATIO[1] * area, np.inf)
