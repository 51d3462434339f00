"""The frame's edge for `pins.track.PinTracker`: the crop it tracks on (`tracking_crop`), and which tips the edge cuts:
detection's rule, with hysteresis (`FrameEdge`; issue 20, outcome 1).

Detection leaves out a pin whose disc (the pins' radius from their mean radial profile, plus half a px of
edge) reaches more than half a px beyond the frame (`pins._flat._cut_by_frame`, ``outside field``): its
centroid would lean inwards. The tracker asks the same question of every pin in every frame, so it asks it
the same way: the same function, on the same radius (`pins._flat._pin_radius_px`, measured on the rest
frame), with one change, hysteresis. A pin kept whose tip lies at the threshold was lost in some still
frames and not in others, as its centroid jittered in camera noise across it (before: the tracker measured
its own radius, from its windows' tip areas, 4.9 px against detection's; dense-1000 cut by the frame edge,
glare gradient and noise 8, seeds 44-45: a pin 4.8 px from the edge lost in 4 of 20 still frames).

So each pin is *in* or *out* of the frame and changes state only across a band `HYSTERESIS_PX` wide:

- at start, the rule decides on the pins' given centres (detection's: the pins it kept are in); after, the
  tracker's own positions are measured (windowed centroids; next to the edge they lean towards it by up to
  0.7 px, pulled by the replicated border: tactip-127, a tip reaching 0.85 px beyond the frame);
- an *in* pin goes out where detection's rule cuts it, or, for a pin that rested within `HYSTERESIS_PX` of
  that, `HYSTERESIS_PX` nearer the edge than its rest place (a still pin at the threshold stays in, whatever
  the noise: the band is several times a still tip's centroid scatter in camera noise);
- an *out* pin comes back in `HYSTERESIS_PX` inside the rule's threshold, or, for a pin in at start, half a
  band nearer the edge than its rest place when that is nearer: a pin that slides out and back is in again
  at its rest place.

A lost pin (NaN) keeps its state. Out pins are reported lost, never placed on the replicated border
beyond the frame (`tracking_crop`). A tip the tracker keeps is cut no deeper than detection allows, but
for a pin resting at the threshold: by one band more, as the tracker measures it.
"""

from __future__ import annotations

import numpy as np

from ._flat import _CUT_TOLERANCE_PX, _pin_radius_px
from .detect import _roi

# Width of the band, px, a pin's room to the frame's edge crosses before its state (in or out) changes:
# several times a still tip's centroid scatter in camera noise.
HYSTERESIS_PX = 0.5


def room_px(positions: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """Each (N, 2) position's distance to the nearest edge of a frame of `shape` (the pixel grid's outer
    border), px (N,); NaN where the position is.

    >>> room_px(np.array([[2.0, 50.0], [np.nan, np.nan]]), (100, 100))
    array([2.5, nan])
    """
    height, width = shape[:2]
    x, y = positions[:, 0], positions[:, 1]
    return np.minimum(np.minimum(x + 0.5, width - 0.5 - x), np.minimum(y + 0.5, height - 0.5 - y))


class FrameEdge:
    """The pins the frame's edge cuts, frame after frame: detection's rule (`pins._flat._cut_by_frame`) with
    hysteresis (module docstring).

    Parameters
    ----------
    grey : (H, W) ndarray of uint8
        The rest frame (the pins' radius is measured on it, as detection measures it).
    given : (N, 2) ndarray
        The pins as given to the tracker (detection's centres), px: those detection's rule cuts are out.
    rest_positions : (N, 2) ndarray
        The pins at rest as the tracker measures them (its windows' centroids), px.
    spacing_px : float
        Their median nearest-neighbour spacing, px.
    dark_pins : bool
        Dark markers on a bright membrane.
    fallback_radius_px : float
        The pins' radius when their profile gives none (fewer than one pin half a spacing inside the frame).

    Attributes
    ----------
    reach_px : float
        Detection's threshold: a pin whose room to the edge is below it is cut, px.
    inside : (N,) ndarray of bool
        Whether each pin is in the frame (after the last `cut`).
    """

    def __init__(self, grey: np.ndarray, given: np.ndarray, rest_positions: np.ndarray, spacing_px: float,
                 dark_pins: bool, fallback_radius_px: float = 0.0) -> None:
        self.shape = grey.shape[:2]
        radius = _pin_radius_px(grey, given, spacing_px, dark_pins)
        if not radius > 0 and np.isfinite(fallback_radius_px):
            radius = fallback_radius_px
        #: (`_cut_by_frame`'s: the disc plus half a px of edge may reach `_CUT_TOLERANCE_PX` beyond the frame.)
        self.reach_px = float(radius + 0.5 - _CUT_TOLERANCE_PX)
        # Decided once, on the given centres (detection's, as detection decides); after, on the tracker's own.
        self.inside = room_px(given, self.shape) >= self.reach_px
        # Where an in pin goes out, and an out pin comes back in, px of room.
        rest_room = room_px(rest_positions, self.shape)
        self._leave = np.where(self.inside, np.minimum(self.reach_px, rest_room - HYSTERESIS_PX), self.reach_px)
        self._enter = np.where(self.inside, np.minimum(self.reach_px + HYSTERESIS_PX, rest_room - 0.5 * HYSTERESIS_PX),
                               self.reach_px + HYSTERESIS_PX)

    def cut(self, positions: np.ndarray) -> np.ndarray:
        """(N, 2) `positions`, px, with the pins the frame's edge cuts lost (NaN; a copy when any is), and
        `inside` updated: an in pin leaves below its leaving room, an out pin enters at its entering room."""
        room = room_px(positions, self.shape)
        with np.errstate(invalid="ignore"):
            inside = np.where(np.isnan(room), self.inside, room >= np.where(self.inside, self._leave, self._enter))
        self.inside = inside
        out = ~inside & np.isfinite(room)
        if not out.any():
            return positions
        positions = positions.copy()
        positions[out] = np.nan
        return positions


def tracking_crop(shape: tuple[int, ...], pins: np.ndarray, spacing_px: float, lk, disc, refine: bool):
    """The part of a frame of `shape` that LK works on: (borders, crop, origin).

    The part the (N, 2) `pins`, px, can reach (the `disc`, else the pins' box, with LK's margin: `lk`, an
    `pins.lk.LKParams`), grown beyond the frame by up to a spacing of replicated border where pins' windows reach,
    with refinement (a flat gel's whole frame, a pad cut by the edge; plain LK, as `track_pins`, keeps to the
    frame): whole tips next to the edge are measured (their windows clipped: tactip-127 cut lost 8 of 120 on its
    start frame), cut ones lost (`FrameEdge`). ``borders``: px of replicated border beyond the frame (top,
    bottom, left, right); ``crop``: (rows, columns) slices of the frame; ``origin``: the crop's (x, y) in the
    frame, px (negative by the border).
    """
    margin = lk.window_px * 2 ** lk.levels + 2
    reach = int(np.ceil(spacing_px)) + 2  # a window (half a spacing) and its search round a pin
    height, width = shape[:2]
    if disc is not None and disc.whole_frame:
        x0, y0, x1, y1 = -reach, -reach, width + reach, height + reach
    else:
        reach *= refine
        low, high = pins.min(axis=0), pins.max(axis=0)
        if disc is not None:
            low, high = np.array([disc.cx, disc.cy]) + [[-disc.radius_px], [disc.radius_px]]
        x0, y0 = np.maximum(np.floor(low).astype(int) - margin, np.minimum(np.floor(pins.min(axis=0)) - reach, 0))
        x1, y1 = np.minimum(np.ceil(high).astype(int) + margin + 1,
                            np.maximum(np.ceil(pins.max(axis=0)) + reach + 1, (width, height)))
        x0, y0, x1, y1 = int(x0), int(y0), int(x1), int(y1)
    borders = (max(-y0, 0), max(y1 - height, 0), max(-x0, 0), max(x1 - width, 0))  # top, bottom, left, right
    crop = (slice(max(y0, 0), min(y1, height)), slice(max(x0, 0), min(x1, width)))
    origin = np.array([max(x0, 0) - borders[2], max(y0, 0) - borders[0]], dtype=np.float64)
    return borders, crop, origin


def read_region(shape: tuple[int, ...], crop: tuple[slice, slice], disc) -> tuple[slice, slice]:
    """The (rows, columns) slices of a frame of `shape` that a tracker on `crop` (`tracking_crop`'s) reads: the
    crop, and the `disc`'s box (recovery's blob detection, `pins.detect`, reads no pixel beyond the disc)."""
    if disc is None:
        return crop
    (rows, columns), (x0, y0, mask) = crop, _roi(disc, shape[:2])
    return (slice(min(rows.start, y0), max(rows.stop, y0 + mask.shape[0])),
            slice(min(columns.start, x0), max(columns.stop, x0 + mask.shape[1])))
