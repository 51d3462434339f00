"""The surround of a small pad: pixels beyond the sensor disc that a pin's window can reach.

A bright surround (the casing, a lit frame edge) next to the rim pins of a small pad would pull
their windowed centroids and make them look unlike at rest. `PinTracker` replaces those pixels in
every crop by the membrane's grey level (`surround_pixels` finds them once, at `start`).
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy.spatial import cKDTree

from ._noise import median_uint8
from .disc import SensorDisc

# The sensor disc's rim is blurred over this many px inside its fitted radius: the surround's light
# reaches that far (the crop's surround is replaced up to here, where pins' windows reach it).
DISC_EDGE_PX = 2.0


def surround_pixels(rest_crop: np.ndarray, pins: np.ndarray, disc: SensorDisc, origin: np.ndarray,
                    spacing_px: float, dark_pins: bool):
    """(flat indices, grey level): the rest crop's pixels beyond the disc (less its rim) within a pin's reach.

    `pins` are in frame px, `origin` is the crop's top-left corner in the frame (px), `spacing_px`
    the median pin spacing. A pin's reach: a window (half the spacing) plus a spacing of motion.
    The level is the median inside the disc (the membrane's, bright-pin polarity: dark markers'
    crops are inverted first). None when no pin reaches beyond the disc.
    """
    x0, y0 = origin
    reach = 1.5 * spacing_px + 2.0
    outermost = np.hypot(*(pins - (disc.cx, disc.cy)).T).max() + reach   # px from the centre
    if outermost <= disc.radius_px - DISC_EDGE_PX:
        return None  # no pin reaches the rim (most pads): no need to look at every pixel
    height, width = rest_crop.shape[:2]  # distances: a row against a column, broadcast (no pixel grids)
    from_centre = np.hypot(np.arange(width) + x0 - disc.cx, (np.arange(height) + y0 - disc.cy)[:, None])
    beyond = from_centre > disc.radius_px - DISC_EDGE_PX
    if not beyond.any() or beyond.all():
        return None
    # Only pixels no farther out than the outermost pin's reach can be in reach (triangle inequality).
    candidates = np.flatnonzero(beyond & (from_centre <= outermost + 1.0))
    rows, columns = np.divmod(candidates, width)
    near = cKDTree(pins - origin).query(np.column_stack([columns, rows]), distance_upper_bound=reach)[0] <= reach
    if not near.any():
        return None
    bright = cv2.bitwise_not(rest_crop) if dark_pins else rest_crop
    return candidates[near], np.uint8(median_uint8(bright[~beyond]))
