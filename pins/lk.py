"""The Lucas-Kanade step of pin tracking: move pins from one frame to the next (paper 002, III-A.3).

Pyramidal Lucas-Kanade (`cv2.calcOpticalFlowPyrLK`) moves each pin from the previous frame to
the next one. A pin's new position is trusted only when LK converged (status flag), its
residual is small (the blob did not vanish), and tracking the result back to the previous frame
lands within `fb_threshold_px` of where it started (forward-backward check). A pin that fails is
*lost*: its position is NaN and `PinTracker.lost` says so; it is never frozen at an old place.

`track_pins` is that step alone, on two frames; `pins.track.PinTracker` runs it (`_track`, forward
from a guess, the backward check optional) inside its following, refinement and recovery.

Speed: OpenCV's Python binding cannot take the pyramids of `cv2.buildOpticalFlowPyramid`
(opencv/opencv#4777), so they are not reused between frames.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import cv2
import numpy as np

from ._recover import _as_points
from .disc import as_grey
from .errors import ShapeError

__all__ = ["LKParams", "track_pins"]

# Without the backward check, failed pins are tracked again with the pyramid only when more than
# this fraction of them failed on the full image alone; fewer are left to the windowed search.
_RETRY_FRACTION = 0.1


@dataclass(frozen=True)
class LKParams:
    """Lucas-Kanade settings shared by `track_pins` and `PinTracker`.

    Attributes
    ----------
    window_px : int
        Side of the LK window, px; odd, below the pin spacing so that a window sees one pin.
    levels : int
        Pyramid levels above the full image (0: no pyramid); each doubles the largest motion
        tracked between frames (about window/2 * 2**levels px).
    fb_threshold_px : float
        Largest forward-backward error accepted, px.
    max_error : float
        Largest LK residual accepted (mean absolute grey-level difference over the window); a pin
        that disappears between frames leaves a large residual.
    iterations : int
        LK iterations per pyramid level.
    """

    window_px: int = 11
    levels: int = 1
    fb_threshold_px: float = 0.5
    max_error: float = 25.0
    iterations: int = 10

    def __post_init__(self) -> None:
        if int(self.window_px) != self.window_px or self.window_px < 5 or self.window_px % 2 == 0:
            raise ValueError(f"window_px must be an odd integer >= 5, got {self.window_px}")
        if int(self.levels) != self.levels or not 0 <= self.levels <= 5:
            raise ValueError(f"levels must be an integer in [0, 5], got {self.levels}")
        if not self.fb_threshold_px > 0:
            raise ValueError(f"fb_threshold_px must be > 0, got {self.fb_threshold_px}")
        if not self.max_error > 0:
            raise ValueError(f"max_error must be > 0, got {self.max_error}")
        if int(self.iterations) != self.iterations or self.iterations < 1:
            raise ValueError(f"iterations must be a positive integer, got {self.iterations}")

    @property
    def _criteria(self) -> tuple[int, int, float]:
        return (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, int(self.iterations), 0.01)


def track_pins(prev_image: np.ndarray, next_image: np.ndarray, points: np.ndarray, *,
               params: LKParams | None = None, **knobs) -> tuple[np.ndarray, np.ndarray]:
    """Move pins from one frame to the next by pyramidal Lucas-Kanade with a forward-backward check.

    Parameters
    ----------
    prev_image, next_image : (H, W) or (H, W, 3) ndarray of uint8
        Consecutive grey or BGR frames.
    points : (N, 2) ndarray
        Pin positions (x, y) in `prev_image`, px; NaN rows are skipped (and stay NaN).
    params : LKParams, optional
        LK settings (default ``LKParams()``).
    **knobs
        Fields of `LKParams` overriding `params`, e.g. ``window_px=9``.

    Returns
    -------
    points : (N, 2) ndarray of float64
        Positions in `next_image`, px; NaN where tracking failed.
    ok : (N,) ndarray of bool
        True where the pin was tracked (finite result).

    Examples
    --------
    >>> from tactip.sim import Contact, SyntheticTacTip
    >>> sensor = SyntheticTacTip(pins=331, seed=0)
    >>> rest, pressed = sensor.render(), sensor.render(Contact(indentation_mm=3.0, gap_width_mm=2.0))
    >>> moved, ok = track_pins(rest.image, pressed.image, rest.centres)     # true centres as the pins
    >>> flow = moved[ok] - rest.centres[ok]          # (M, 2) px
    >>> flow.shape
    (331, 2)
    """
    params = replace(params or LKParams(), **knobs)
    points = _as_points(points, "points")
    prev_grey, next_grey = as_grey(prev_image), as_grey(next_image)
    if prev_grey.shape != next_grey.shape:
        raise ShapeError(f"prev_image and next_image must have the same size, got {prev_grey.shape} "
                         f"and {next_grey.shape}")
    return _track(prev_grey, next_grey, points, params)


def _track(prev_grey: np.ndarray, next_grey: np.ndarray, points: np.ndarray, params: LKParams,
           guess: np.ndarray | None = None, *, backward: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """LK forward (from `guess` if given), LK backward from the result, and the checks.

    From a guess, the forward pass first runs on the full image only (a good guess leaves little
    motion to find); the pins that then fail a check, or land more than a third of a window from
    the guess (about as far as LK reaches without the pyramid), are tracked again with it.
    Without `backward`, no pass runs the backward LK and its check (status and residual only:
    `PinTracker` checks each result by its windowed centroid instead, and searches for the pins
    that fail), and the pyramid runs only when more than `_RETRY_FRACTION` of all the points
    (NaN rows included) fail (the guess was poor for many: a sudden change of motion).
    """
    out = np.full_like(points, np.nan)
    ok = np.zeros(len(points), dtype=bool)
    live = np.flatnonzero(np.isfinite(points).all(axis=1))
    if live.size == 0:
        return out, ok
    start = points[live].astype(np.float32).reshape(-1, 1, 2)
    initial = None if guess is None else guess[live].astype(np.float32).reshape(-1, 1, 2)
    levels = params.levels if guess is None else 0
    forward, good = _forward_backward(prev_grey, next_grey, start, initial, params, levels,
                                      backward=backward or guess is None)
    if levels < params.levels:
        if backward:
            far = np.sum((forward - initial) ** 2, axis=2).ravel() > (0.35 * params.window_px) ** 2
            again = np.flatnonzero(~good | far)
        else:
            # Checked by their centroids, far pins need no retry; a few failed ones are searched for.
            again = np.flatnonzero(~good)
            if again.size <= _RETRY_FRACTION * len(points):
                again = again[:0]
        if again.size:
            forward[again], good[again] = _forward_backward(prev_grey, next_grey, start[again], initial[again],
                                                            params, params.levels, backward=backward)
    out[live[good]] = forward.reshape(-1, 2)[good]
    ok[live[good]] = True
    return out, ok


def _forward_backward(prev_grey: np.ndarray, next_grey: np.ndarray, start: np.ndarray, initial: np.ndarray | None,
                      params: LKParams, forward_levels: int, *, backward: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """LK forward with `forward_levels` pyramid levels, backward with all; (M, 1, 2) positions and the checks."""
    window = (params.window_px, params.window_px)
    if initial is None:
        forward, status_f, error = cv2.calcOpticalFlowPyrLK(
            prev_grey, next_grey, start, None, winSize=window, maxLevel=forward_levels, criteria=params._criteria)
    else:
        forward, status_f, error = cv2.calcOpticalFlowPyrLK(  # a copy: OpenCV writes into the guess
            prev_grey, next_grey, start, initial.copy(), winSize=window, maxLevel=forward_levels,
            criteria=params._criteria, flags=cv2.OPTFLOW_USE_INITIAL_FLOW)
    good = (status_f.ravel() == 1) & (error.ravel() <= params.max_error)
    if not backward:
        return forward, good
    backward_points, status_b, _ = cv2.calcOpticalFlowPyrLK(
        next_grey, prev_grey, forward, None, winSize=window, maxLevel=params.levels, criteria=params._criteria)
    fb_error = np.linalg.norm((backward_points - start).reshape(-1, 2), axis=1)
    return forward, good & (status_b.ravel() == 1) & (fb_error <= params.fb_threshold_px)
