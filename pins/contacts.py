"""What kind of contact a tap is: a press (pins pushed apart) or a slide (pins dragged one way).

A press spreads the pins away from the contact, so their displacements point in all directions and
cancel in a mean; a slide drags the skin under the plate sideways, so they share one direction. For
each frame of a contact, among the pins the contact moves most (displaced by at least half the
frame's 90th percentile), the *drag ratio* is the length of their median displacement (per axis)
over their median displacement magnitude: about 0 for displacements that cancel, 1 for a rigid
translation. Medians, not means, so that a few pins tracked wrongly (a swap moves a pin by a
pitch) cannot make a press look like a slide or turn a slide. A contact is a slide when, at the
frame where that median displacement is longest (among the frames where the tap signal is at least
half its peak in the contact: after a lift, a few pins the tracker misplaced are not the contact),
the ratio reaches `slide_ratio` and the median is longer than `min_drag_px`; the slide's direction
is the median's, in degrees from image x towards image y (image y points down).

Given the pins' rest positions, the field's shape must say slide too. A skin that kept part of the
last slide's shear (a real elastomer creeps back over tens of frames) shows it again in the patch a
press right after puts down, so the press's moved pins share one direction (drag ratio 0.66-0.89 on
issue 20's webcam-like tours with a residual of 0.2) though the plate never moved. A press spreads
its pins outward about the patch's centre; a slide shifts the whole patch one way. In each frame at
half the peak signal or more, the *outward spread* is the median over the moved pins of their
displacement less the median one, along the direction away from the moved pins' centre at rest. A
slide's median displacement over that spread (the *shift*), the median over the later half of those
frames, is at least `shift_over_spread` and has grown since the earlier half (a slide's shift grows
against its spread while it drags; a shear the skin kept relaxes under a press), unless it is
`CLEAR_SHIFT` times that or more (a long drag, whose earlier frames may not spread at all). On those
tours presses gave 0.2-0.7 and slides of 3 pitches 12 or more; a press 2 frames after a slide fell
from 2.4 to 1.2 on tactip-127 and from 2.8 to 0.7 on small-pad-100, a slide of half a pitch on
tactip-331 rose from 0.35 to 1.9.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .errors import ShapeError
from .segment import nanmedian_rows, tap_signal

__all__ = ["ContactKind", "contact_kinds", "CLEAR_SHIFT"]

#: A shift this many times `contact_kinds`' ``shift_over_spread`` is a slide whatever its trend.
CLEAR_SHIFT = 4.0


@dataclass(frozen=True)
class ContactKind:
    """The kind of one contact.

    Attributes
    ----------
    kind : {"press", "slide"}
    direction_deg : float
        Direction of a slide in [0, 360), degrees from image x towards image y; NaN for a press.
    drag_ratio : float
        The drag ratio at the frame of longest drag, in [0, 1] (see the module docstring).
    drag_px : float
        Length of the moved pins' median displacement at that frame, px.
    """

    kind: str
    direction_deg: float
    drag_ratio: float
    drag_px: float


def contact_kinds(displacements: np.ndarray, bounds: Sequence[tuple[int, int]], *, slide_ratio: float = 0.6,
                  min_drag_px: float = 1.0, signal: np.ndarray | None = None,
                  rest_positions: np.ndarray | None = None, shift_over_spread: float = 1.0) -> list[ContactKind]:
    """Press or slide, and a slide's direction, for each contact of a recording.

    Parameters
    ----------
    displacements : (T, N, 2) ndarray
        Displacements from rest, px; NaN where lost (ignored).
    bounds : sequence of (start, stop)
        The contacts' frame ranges, stop exclusive (`pins.segment_taps`).
    slide_ratio : float
        Smallest drag ratio of a slide, in (0, 1].
    min_drag_px : float
        Shortest median displacement of a slide, px (>= 0): a contact that hardly moves the pins is
        a press.
    signal : (T,) ndarray, optional
        The recording's tap signal (`pins.tap_signal`, 90th percentile) when already computed, px.
    rest_positions : (N, 2) ndarray, optional
        The pins' rest positions, px: a slide's field must then shift more than it spreads (the module
        docstring); without them, the drag ratio and length alone decide.
    shift_over_spread : float
        Least shift (median displacement over outward spread, the module docstring) of a slide (> 0),
        with ``rest_positions``.

    Returns
    -------
    kinds : list of ContactKind
        One per contact, in order.

    Examples
    --------
    >>> rest = np.stack(np.meshgrid(np.arange(-3, 4), np.arange(-3, 4)), -1).reshape(-1, 2) * 10.0
    >>> press = 0.1 * rest[None] * np.linspace(0, 1, 5)[:, None, None]    # (5, 49, 2): pins pushed apart
    >>> slide = np.zeros_like(press); slide[..., 1] = np.linspace(0, 8, 5)[:, None]  # dragged along +y
    >>> [(k.kind, k.direction_deg) for k in contact_kinds(np.concatenate([press, slide]), [(0, 5), (5, 10)])]
    [('press', nan), ('slide', 90.0)]
    """
    data = np.asarray(displacements, dtype=np.float64)
    if data.ndim != 3 or data.shape[2] != 2:
        raise ShapeError(f"displacements must have shape (T, N, 2), got {data.shape}")
    if not 0.0 < slide_ratio <= 1.0:
        raise ValueError(f"slide_ratio must be in (0, 1], got {slide_ratio}")
    if not min_drag_px >= 0.0:
        raise ValueError(f"min_drag_px must be >= 0, got {min_drag_px}")
    if signal is None:
        signal = tap_signal(data)
    elif np.shape(signal) != (len(data),):
        raise ShapeError(f"signal must have shape ({len(data)},), got {np.shape(signal)}")
    if not shift_over_spread > 0.0:
        raise ValueError(f"shift_over_spread must be > 0, got {shift_over_spread}")
    if rest_positions is not None and np.shape(rest_positions) != data.shape[1:]:
        raise ShapeError(f"rest_positions must have shape {data.shape[1:]}, got {np.shape(rest_positions)}")
    kinds = []
    for start, stop in bounds:
        if not 0 <= start < stop <= len(data):
            raise ValueError(f"contact bounds ({start}, {stop}) outside the {len(data)} frames")
        part = data[start:stop]
        magnitude = np.hypot(part[..., 0], part[..., 1])            # (F, N) px, NaN where lost
        level = np.asarray(signal[start:stop], dtype=np.float64)     # (F,) px: the 90th percentile over pins
        moved = magnitude >= 0.5 * level[:, None]                   # the pins the contact moves most
        moved &= np.isfinite(magnitude) & (level[:, None] > 0)
        if not moved.any():
            kinds.append(ContactKind("press", float("nan"), 0.0, 0.0))
            continue
        # frames of the contact at half its peak signal or more: a few pins misplaced as the pad springs back
        # (the signal low, those pins far) must not outweigh the drag
        frames = np.flatnonzero(moved.any(axis=1) & (level >= 0.5 * np.nanmax(level)))
        chosen = np.where(moved[frames, :, None], part[frames], np.nan)
        drag = nanmedian_rows(np.moveaxis(chosen, 1, -1))           # (F', 2) px: the moved pins' median motion
        spread = nanmedian_rows(np.where(moved[frames], magnitude[frames], np.nan))
        length = np.hypot(drag[:, 0], drag[:, 1])
        peak = int(np.argmax(length))
        ratio = float(min(length[peak] / spread[peak], 1.0)) if spread[peak] > 0 else 0.0
        dragged = ratio >= slide_ratio and length[peak] > min_drag_px
        if dragged and rest_positions is not None:
            early, late = _shift_over_spread(part[frames], moved[frames], drag, np.asarray(rest_positions, np.float64))
            dragged = late >= shift_over_spread and (late > early or late >= CLEAR_SHIFT * shift_over_spread)
        if dragged:
            direction = float(np.degrees(np.arctan2(drag[peak, 1], drag[peak, 0])) % 360.0)
            kinds.append(ContactKind("slide", round(direction, 6) % 360.0, ratio, float(length[peak])))
        else:
            kinds.append(ContactKind("press", float("nan"), ratio, float(length[peak])))
    return kinds


def _shift_over_spread(part: np.ndarray, moved: np.ndarray, drag: np.ndarray, rest: np.ndarray) -> tuple[float, float]:
    """The moved pins' median displacement over their outward spread about it: the medians over the earlier
    and the later half of the frames.

    ``part`` (F, N, 2) px displacements, ``moved`` (F, N) bool, ``drag`` (F, 2) px their median, ``rest``
    (N, 2) px. A frame's spread is the median of the moved pins' displacement components, less the drag,
    away from their centre at rest; a frame that does not spread outward counts as infinite shift.
    """
    count = moved.sum(axis=1)
    centre = np.where(moved[..., None], rest[None], 0.0).sum(axis=1) / np.maximum(count, 1)[:, None]  # (F, 2)
    away = rest[None] - centre[:, None]                                          # (F, N, 2)
    away /= np.maximum(np.hypot(away[..., 0], away[..., 1]), 1e-9)[..., None]
    outward = np.einsum("fnk,fnk->fn", part - drag[:, None], away)
    spread = nanmedian_rows(np.where(moved, outward, np.nan))                   # (F,) px
    length = np.hypot(drag[:, 0], drag[:, 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(spread > 0, length / spread, np.inf)
    half = len(ratio) // 2
    return float(np.median(ratio[:half])) if half else float("nan"), float(np.median(ratio[half:]))
