"""Flat gels for `pins.find_pin_field`: checks of a pin field whose sensing region is the whole frame.

A flat gel (GelSight and its kind) films dark markers on a rectangular grid filling the frame: no
disc, no casing. These helpers say whether the pins go on beyond a disc found (a false disc), whether
a whole-frame field lies on a regular lattice (not camera noise), how strongly it stands out (to
choose the polarity), and which markers the frame's edge cuts too deeply to measure. ``field``
arguments are `pins.PinField` s (not imported: `pins.lattice` imports this module).
"""

from __future__ import annotations

from types import SimpleNamespace

import cv2
import numpy as np
from scipy.spatial import cKDTree

from ._judge import _MIN_PINS
from .detect import _detect
from .disc import frame_region


# A sensor disc whose pins go on beyond it: at least this many pin-like blobs outside its pin field,
# and this share of the pins inside, each with two others outside within `_SPILL_LINK` pitches (the
# markers of a flat gel go on as a lattice: on a grid each has two to four neighbours one pitch away).
# Camera noise in a near-saturated surround makes blobs too (radial-led-120 seed 14: 38-48 of them,
# a median 3.5 pitches apart, 4-7 within 1.5 pitches of another), scattered, not in rows.
_SPILL_MIN = 10
_SPILL_SHARE = 0.25
_SPILL_LINK = 1.3


def _spills_over(grey: np.ndarray, field) -> bool:
    """Whether the frame holds many pin-like blobs (the field's parameters, over the whole frame)
    beyond the field's circle grown by a pitch, each with two others there within `_SPILL_LINK`
    pitches: the markers of a flat gel go on past a false disc as a lattice, while a TacTip's casing
    round its disc holds none (at most scattered blobs of noise)."""
    if field.count < _MIN_PINS or not np.isfinite(field.pitch_px):
        return False
    blobs = _detect(grey, frame_region(grey.shape), field.params.replace(rim_margin_px=0.0))
    reach = field.field_disc.radius_px + field.pitch_px
    outside = blobs.centres[np.hypot(blobs.centres[:, 0] - field.disc.cx, blobs.centres[:, 1] - field.disc.cy) > reach]
    if len(outside) < 3:
        return False
    rowed = cKDTree(outside).query(outside, 3)[0][:, 2] <= _SPILL_LINK * field.pitch_px
    return int(rowed.sum()) >= max(_SPILL_MIN, _SPILL_SHARE * field.count)


# A whole frame's pins whose median ratio of second- to first-nearest-neighbour distance exceeds
# this are no lattice: a grid gives about 1 (1.00-1.08 on a pressed or sheared gel), blobs of camera
# noise that pass the lattice judgement 1.19-1.28.
_MAX_NEIGHBOUR_RATIO = 1.15


def _irregular(field) -> bool:
    """Whether a field searched over the whole frame is not on a regular lattice (noise, texture):
    its pins' second-nearest neighbours are not as near as their nearest (`_MAX_NEIGHBOUR_RATIO`)."""
    if field.count < 3:
        return False
    distance = cKDTree(field.centres).query(field.centres, k=3)[0]
    return float(np.median(distance[:, 2] / np.maximum(distance[:, 1], 1e-9))) > _MAX_NEIGHBOUR_RATIO


def _irregular_beyond(whole, field) -> bool:
    """Whether the pins of a whole-frame field `whole` beyond a disc field's pins (its circle grown by a
    pitch) are no lattice: blobs of camera noise in a near-saturated surround, not a flat gel's markers
    going on past a false disc (radial-led-120 filmed at 320x240, seeds 48 and 54: 64-82 noise blobs
    beyond the pad made a whole-frame field of 155-161 'pins' that won over the pad's 102-111)."""
    if field.count < 2 or not np.isfinite(field.pitch_px):
        return False
    reach = field.field_disc.radius_px + field.pitch_px
    beyond = whole.centres[np.hypot(whole.centres[:, 0] - field.disc.cx, whole.centres[:, 1] - field.disc.cy) > reach]
    return len(beyond) >= 3 and _irregular(SimpleNamespace(count=len(beyond), centres=beyond))


def _tip_contrasts(grey: np.ndarray, field) -> np.ndarray:
    """Each pin's contrast, grey levels: the lightly blurred frame at its centre less the mean over a
    square of 1.5 pitches round it (the polarity's sign: dark markers below the membrane count positive)."""
    smooth = cv2.GaussianBlur(grey, (0, 0), 1.0).astype(np.float32)
    size = max(2 * int(round(0.75 * field.pitch_px)) + 1, 3)
    mean = cv2.boxFilter(smooth, cv2.CV_32F, (size, size), borderType=cv2.BORDER_REFLECT)
    x, y = (np.clip(np.rint(field.centres[:, k]).astype(int), 0, grey.shape[1 - k] - 1) for k in (0, 1))
    contrast = smooth[y, x] - mean[y, x]
    return -contrast if field.params.dark_pins else contrast


def _median_contrast(grey: np.ndarray, field) -> float:
    """Median contrast of a field's pins, grey levels (`_tip_contrasts`); 0 without pins."""
    if field.count < 2 or not np.isfinite(field.pitch_px):
        return 0.0
    return float(max(np.median(_tip_contrasts(grey, field)), 0.0))


# A marker whose disc reaches this far (px) beyond the frame's edge is still measured: its centroid
# leans inwards by at most about 0.1 px.
_CUT_TOLERANCE_PX = 0.5


def _pin_radius_px(grey: np.ndarray, centres: np.ndarray, pitch_px: float, dark_pins: bool) -> float:
    """Radius of the pins, px: where the mean radial profile of up to 40 pins well inside the frame
    crosses halfway from their core (within 1 px of the centre) to their surround (0.35-0.45 pitch)."""
    height, width = grey.shape[:2]
    inner = centres[(centres[:, 0] > 0.5 * pitch_px) & (centres[:, 0] < width - 1 - 0.5 * pitch_px)
                    & (centres[:, 1] > 0.5 * pitch_px) & (centres[:, 1] < height - 1 - 0.5 * pitch_px)][:40]
    if len(inner) == 0 or not np.isfinite(pitch_px):
        return 0.0
    radii = np.arange(0.0, 0.45 * pitch_px, 0.25)
    theta = np.linspace(0.0, 2 * np.pi, 16, endpoint=False)
    xs = inner[:, 0, None, None] + radii[None, None, :] * np.cos(theta)[None, :, None]
    ys = inner[:, 1, None, None] + radii[None, None, :] * np.sin(theta)[None, :, None]
    samples = cv2.remap(grey.astype(np.float32), xs.reshape(len(inner), -1).astype(np.float32),
                        ys.reshape(len(inner), -1).astype(np.float32), cv2.INTER_LINEAR)
    profile = samples.reshape(len(inner), len(theta), len(radii)).mean(axis=(0, 1))
    profile = -profile if dark_pins else profile
    core, surround = profile[radii <= 1.0].mean(), profile[radii >= 0.35 * pitch_px].mean()
    below = np.flatnonzero(profile < 0.5 * (core + surround))
    return float(radii[below[0]]) if len(below) else 0.0


def _cut_by_frame(centres: np.ndarray, radius_px: float, shape: tuple[int, ...]) -> np.ndarray:
    """Which pins (N,) bool are cut by the frame's edge too deeply to measure.

    A pin's disc (`_pin_radius_px`, plus half a px of its soft edge) may reach at most
    `_CUT_TOLERANCE_PX` beyond the frame's outer pixel edge: a deeper cut pulls the
    intensity-weighted centroid inwards by more than about 0.1 px (1.7 px for a marker cut through
    its centre), so such a marker is left out rather than measured wrongly.
    """
    height, width = shape[:2]
    reach = radius_px + 0.5 - _CUT_TOLERANCE_PX
    room = np.minimum(np.minimum(centres[:, 0] + 0.5, width - 0.5 - centres[:, 0]),
                      np.minimum(centres[:, 1] + 0.5, height - 0.5 - centres[:, 1]))
    return room < reach
