"""The sensor disc: where the TacTip membrane is in a camera frame.

A TacTip camera sees the dark membrane of the pad as a disc, surrounded by the bright inside of
the casing; LED glare spots sit on the rim of the disc. Pin detection only looks inside the disc,
so that neither the bright surround nor the glare is mistaken for pins.

The disc is found on a reduced, heavily blurred copy of the frame, where the pins average out
with the membrane around them: Otsu's threshold splits dark (membrane) from bright (surround),
the largest dark region is filled by its convex hull (which closes the notches glare cuts into
the rim), and the circle of equal area centred on the hull's centroid is the disc. A membrane cut
by the frame edge (a pad filling the view, no casing in sight) is a disc whose visible rim is an
arc: when the dark region touches the frame edge, the disc is the circle fitted to the rest of its
outline, accepted when the region fills the circle's part inside the frame and lies in it. Either
way the rim is then refined to a sub-pixel circle on rays from the centre (again, for a cut disc,
until it settles).

A flat gel (GelSight: markers on a gel filling the frame, no casing) shows no disc: its sensing
region is the whole frame, `frame_region`, a `SensorDisc` holding every pixel (``whole_frame``);
`pins.find_pin_field` falls back to it when no disc is found.

Inside the disc a black rim ring (the casing lip) may lie between the pin field and the disc edge;
`pins.find_pin_field` searches for pins inside its inner edge (`_rim_ring_inner_px`, here with the
rest of the pad's outline).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from .errors import NoSensorError, ShapeError

__all__ = ["SensorDisc", "find_sensor_disc", "frame_region", "as_grey"]

# Grey-level difference between membrane and surround below which there is no disc to see.
_MIN_CONTRAST = 30.0
# The disc must cover at least this fraction of the shorter image side, as radius.
_MIN_RADIUS_FRACTION = 0.08
# Hull area over its enclosing circle's area: 1 for a disc, ~0.61 for a full 4:3 frame.
_MIN_CIRCULARITY = 0.8
# A disc cut by the frame edge: its visible rim spans at least this fraction of a turn, fits its
# circle within this fraction of the radius (median), and the dark region fills the circle's part
# inside the frame to this fraction.
_CUT_MIN_ARC = 0.25
_CUT_MAX_RESIDUAL = 0.04
_CUT_MIN_FILL = 0.85
# Fewest rays from the centre that must cross the rim for it to be refined.
_MIN_RIM_RAYS = 12


@dataclass(frozen=True)
class SensorDisc:
    """The membrane disc in a frame, in px (x to the right, y down, pixel centres at integers).

    Attributes
    ----------
    cx, cy : float
        Centre of the disc, px.
    radius_px : float
        Radius of the disc, px.
    whole_frame : bool
        The sensing region is the whole frame (a flat gel filling the view, `frame_region`): the
        disc is the circle about the frame's centre that holds every pixel, and no casing frames it.
    """

    cx: float
    cy: float
    radius_px: float
    whole_frame: bool = False

    def mask(self, shape: tuple[int, int], *, margin_px: float = 0.0) -> np.ndarray:
        """Boolean image that is True inside the disc shrunk by `margin_px`.

        Parameters
        ----------
        shape : (height, width)
            Shape of the mask, px.
        margin_px : float
            Distance from the rim left out of the mask, px (negative grows the disc).

        Returns
        -------
        mask : (height, width) ndarray of bool
        """
        height, width = shape[:2]
        ys, xs = np.ogrid[:height, :width]
        radius = max(self.radius_px - margin_px, 0.0)
        return (xs - self.cx) ** 2 + (ys - self.cy) ** 2 <= radius**2

    def contains(self, points: np.ndarray, *, margin_px: float = 0.0) -> np.ndarray:
        """Which (x, y) points lie inside the disc shrunk by `margin_px`.

        Parameters
        ----------
        points : (N, 2) ndarray of (x, y) px
        margin_px : float
            Distance from the rim counted as outside, px.

        Returns
        -------
        inside : (N,) ndarray of bool
        """
        points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        radius = max(self.radius_px - margin_px, 0.0)
        return np.hypot(points[:, 0] - self.cx, points[:, 1] - self.cy) <= radius


def frame_region(shape: tuple[int, ...]) -> SensorDisc:
    """The whole frame as the sensing region, for a flat gel whose markers fill the view (no disc, no casing).

    Parameters
    ----------
    shape : (height, width[, channels])
        Shape of the frame, px.

    Returns
    -------
    region : SensorDisc
        The circle about the frame's centre through its corners, grown by 1 px, with
        ``whole_frame=True``: its mask is every pixel, so every caller that takes a disc searches,
        tracks and draws over the whole frame.

    Examples
    --------
    >>> region = frame_region((240, 320))
    >>> bool(region.mask((240, 320)).all()), region.whole_frame
    (True, True)
    """
    height, width = shape[:2]
    return SensorDisc((width - 1) / 2.0, (height - 1) / 2.0, math.hypot(width, height) / 2.0 + 1.0, whole_frame=True)


def as_grey(frame: np.ndarray) -> np.ndarray:
    """A frame as a 2-D uint8 grey image (converting BGR or BGRA once; grey passes through).

    Parameters
    ----------
    frame : (H, W) or (H, W, 1|3|4) ndarray
        Grey or BGR(A) image, uint8 (other dtypes are clipped to 0..255).

    Returns
    -------
    grey : (H, W) ndarray of uint8
    """
    image = np.asarray(frame)
    if image.ndim == 3 and image.shape[2] == 1:
        image = image[:, :, 0]
    if image.ndim == 3 and image.shape[2] in (3, 4):
        code = cv2.COLOR_BGR2GRAY if image.shape[2] == 3 else cv2.COLOR_BGRA2GRAY
        image = cv2.cvtColor(_as_uint8(image), code)
    if image.ndim != 2:
        raise ShapeError(f"frame must be a grey (H, W) or BGR (H, W, 3) image, got shape {image.shape}")
    if min(image.shape) < 8:
        raise ShapeError(f"frame of {image.shape[1]}x{image.shape[0]} px is too small: at least 8x8 px")
    return _as_uint8(image)


def _as_uint8(image: np.ndarray) -> np.ndarray:
    if image.dtype == np.uint8:
        return image
    return np.clip(np.rint(image), 0, 255).astype(np.uint8)


def find_sensor_disc(frame: np.ndarray, *, dark_pins: bool = False, scale: float = 0.5) -> SensorDisc:
    """Locate the membrane disc of a TacTip frame.

    Parameters
    ----------
    frame : (H, W) or (H, W, 3) ndarray
        Grey or BGR camera frame, uint8.
    dark_pins : bool
        Dark markers on a light membrane seen against a dark surround: the polarity of the whole
        image is reversed (see `DetectionParams.dark_pins`).
    scale : float
        Resolution at which the disc is searched, as a fraction of the frame (0 < scale <= 1);
        0.5 locates the rim to about one px at a quarter of the cost.

    Returns
    -------
    disc : SensorDisc
        Centre and radius in px of the full frame.

    Raises
    ------
    NoSensorError
        The frame shows no dark disc against a brighter surround (lens cap on, camera pointing
        elsewhere, blank image).

    Examples
    --------
    >>> from tactip.sim import SyntheticTacTip
    >>> sensor = SyntheticTacTip(pins=331, seed=0)
    >>> disc = find_sensor_disc(sensor.render().image)
    >>> abs(disc.radius_px - sensor.disc[2]) < 1.0       # sensor.disc: the drawn (cx, cy, radius), px
    True
    """
    if not 0.0 < scale <= 1.0:
        raise ValueError(f"scale must be in (0, 1], got {scale}")
    grey = as_grey(frame)
    if dark_pins:
        grey = 255 - grey
    small = grey if scale == 1.0 else cv2.resize(grey, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
    # Blur over a few pin spacings so that pins and membrane average to one dark level.
    sigma = max(small.shape) / 80.0
    smooth = cv2.GaussianBlur(small, (0, 0), sigma)
    level, bright = cv2.threshold(smooth, 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    dark = bright == 0
    if not dark.any() or dark.all():
        raise NoSensorError("no sensor disc in the frame: the image has no dark membrane against a bright surround")
    contrast = float(smooth[~dark].mean()) - float(smooth[dark].mean())
    if contrast < _MIN_CONTRAST:
        raise NoSensorError(
            f"no sensor disc in the frame: membrane and surround differ by {contrast:.0f} grey levels "
            f"(need {_MIN_CONTRAST:.0f}); is the lens covered or the camera pointing elsewhere?")
    count, labels, stats, _ = cv2.connectedComponentsWithStats(dark.view(np.uint8), connectivity=8)
    largest = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    region = (labels == largest).view(np.uint8)
    contours, _ = cv2.findContours(region, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    contour = max(contours, key=cv2.contourArea)
    hull = cv2.convexHull(contour)
    moments = cv2.moments(hull)
    area = moments["m00"]
    (_, _), enclosing = cv2.minEnclosingCircle(hull)
    circularity = area / (np.pi * enclosing**2) if enclosing > 0 else 0.0
    # The contour runs through boundary pixel centres: half a pixel inside the true rim.
    radius = np.sqrt(area / np.pi) + 0.5
    # A membrane cut by the frame edge (a pad filling the view, no casing in sight) is a disc whose
    # visible rim is an arc: its circle is fitted to the arc (the region's centroid and area would
    # make it small and off-centre).
    x, y, w, h = cv2.boundingRect(contour)
    touches = x <= 0 or y <= 0 or x + w >= small.shape[1] or y + h >= small.shape[0]
    cut = _cut_disc(contour, labels == largest) if touches else None
    if cut is not None:
        cx, cy, radius = cut
    elif radius < _MIN_RADIUS_FRACTION * min(small.shape) or circularity < _MIN_CIRCULARITY:
        raise NoSensorError(
            f"no sensor disc in the frame: the dark region is not a disc (radius {radius / scale:.0f} px, "
            f"circularity {circularity:.2f})" + (", nor a disc cut by the frame edge" if touches else ""))
    else:
        cx, cy = moments["m10"] / area, moments["m01"] / area
    # Pixel centres are at integer coordinates at both scales: x_full = (x_small + 0.5) / scale - 0.5.
    cx, cy = (cx + 0.5) / scale - 0.5, (cy + 0.5) / scale - 0.5
    disc = _refine_rim(grey, cx, cy, radius / scale)
    # The arc of a cut disc gives a rougher first circle (a few px off on a 200 px pad): refined
    # again from the refined one until it settles.
    for _ in range(3 if cut is not None else 0):
        before, disc = disc, _refine_rim(grey, disc.cx, disc.cy, disc.radius_px)
        if np.hypot(disc.cx - before.cx, disc.cy - before.cy) < 0.1 and abs(disc.radius_px - before.radius_px) < 0.1:
            break
    return disc


def _cut_disc(contour: np.ndarray, region: np.ndarray) -> tuple[float, float, float] | None:
    """(cx, cy, radius) px of a disc cut by the frame edge, from the dark region (bool image) and its
    outline, or None.

    The outline away from the frame edge is the visible rim: a circle fitted to it (robustly: glare
    notches pull some of it inwards) must fit it closely, span at least `_CUT_MIN_ARC` of a turn and
    have its centre in the frame; the dark region must fill the part of that circle inside the frame
    and lie in it (`_CUT_MIN_FILL` each): a pad, not a dark corner, a shadow or the surround of a
    bright pad (whose inner outline is a circle too).
    """
    shape = region.shape
    height, width = shape
    points = contour.reshape(-1, 2).astype(np.float64)
    rim = points[(points[:, 0] > 1) & (points[:, 0] < width - 2) & (points[:, 1] > 1) & (points[:, 1] < height - 2)]
    if len(rim) < 20 or len(rim) == len(points):
        return None
    keep = np.ones(len(rim), bool)
    for _ in range(4):
        cx, cy, radius = _fit_circle(rim[keep, 0], rim[keep, 1])
        residual = np.abs(np.hypot(rim[:, 0] - cx, rim[:, 1] - cy) - radius)
        keep = residual < max(3.0 * 1.4826 * np.median(residual[keep]), 1.0)
    if not (np.isfinite(radius) and 0 <= cx < width and 0 <= cy < height):
        return None
    angles = np.sort(np.arctan2(rim[keep, 1] - cy, rim[keep, 0] - cx))
    gaps = np.diff(np.append(angles, angles[0] + 2 * np.pi))
    arc = 2 * np.pi - gaps.max()  # the rim's span: the turn less the largest gap (where the frame cuts it)
    inside = np.zeros(shape, np.uint8)
    cv2.circle(inside, (int(round(cx * 16)), int(round(cy * 16))), int(round(radius * 16)), 1, -1, cv2.LINE_8, 4)
    inside = inside.view(bool)
    common = float(np.count_nonzero(inside & region))
    fill = common / max(float(np.count_nonzero(inside)), 1.0)
    within = common / max(float(np.count_nonzero(region)), 1.0)
    if (np.median(residual[keep]) > _CUT_MAX_RESIDUAL * radius or arc < _CUT_MIN_ARC * 2 * np.pi
            or min(fill, within) < _CUT_MIN_FILL or radius < _MIN_RADIUS_FRACTION * min(shape)):
        return None
    return float(cx), float(cy), float(radius) + 0.5


def _refine_rim(grey: np.ndarray, cx: float, cy: float, radius: float, *, rays: int = 180) -> SensorDisc:
    """Sub-pixel rim: the outermost dark-to-bright crossing on rays from the rough centre, fitted by a circle."""
    smooth = cv2.GaussianBlur(grey, (0, 0), 1.5)
    theta = np.linspace(0.0, 2.0 * np.pi, rays, endpoint=False)[:, None]
    step = 0.5
    r = radius * np.arange(0.85, 1.15, step / radius)[None, :]
    map_x = (cx + r * np.cos(theta)).astype(np.float32)
    map_y = (cy + r * np.sin(theta)).astype(np.float32)
    profile = cv2.remap(smooth, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE).astype(np.float64)
    inner = r[0] < 0.95 * radius
    outer = r[0] > 1.08 * radius
    dark_level = np.percentile(profile[:, inner], 10, axis=1)
    bright_level = np.median(profile[:, outer], axis=1)
    mid = 0.5 * (dark_level + bright_level)
    below = profile < mid[:, None]
    # Index of the last sample below the midpoint on each ray; the rim lies between it and the next.
    last = below.shape[1] - 1 - np.argmax(below[:, ::-1], axis=1)
    good = (bright_level - dark_level > _MIN_CONTRAST) & below.any(axis=1) & (last < below.shape[1] - 1)
    rows = np.flatnonzero(good)
    if len(rows) < _MIN_RIM_RAYS:
        raise NoSensorError(f"no sensor disc in the frame: the dark region has no sharp rim ({len(rows)} of {rays} "
                            "rays cross one)")
    i = last[rows]
    p0, p1 = profile[rows, i], profile[rows, i + 1]
    frac = np.clip((mid[rows] - p0) / np.maximum(p1 - p0, 1e-9), 0.0, 1.0)
    rim_r = r[0, i] + frac * step
    xs = cx + rim_r * np.cos(theta[rows, 0])
    ys = cy + rim_r * np.sin(theta[rows, 0])
    # LED glare lights the membrane inside the rim and pulls the crossing inwards on its rays:
    # keep rays near the median rim radius, then those near the fitted circle.
    keep = np.abs(rim_r - np.median(rim_r)) < max(4.0, 0.02 * radius)
    fr = np.nan
    for _ in range(3):
        if keep.sum() < 3:  # no circle through the crossings (a frame without a rim: a flat gel)
            fr = np.nan
            break
        fx, fy, fr = _fit_circle(xs[keep], ys[keep])
        residual = np.abs(np.hypot(xs - fx, ys - fy) - fr)
        keep = residual < max(3.0 * 1.4826 * np.median(residual[keep]), 0.3)
    if not (np.isfinite(fr) and fr >= _MIN_RADIUS_FRACTION * min(grey.shape)):
        raise NoSensorError(f"no sensor disc in the frame: the rim fits no circle (radius {fr:.0f} px)")
    return SensorDisc(cx=float(fx), cy=float(fy), radius_px=float(fr))


def _fit_circle(xs: np.ndarray, ys: np.ndarray) -> tuple[float, float, float]:
    """Least-squares (Kasa) circle through points: x^2 + y^2 = 2 a x + 2 b y + c."""
    design = np.column_stack([2.0 * xs, 2.0 * ys, np.ones_like(xs)])
    (a, b, c), *_ = np.linalg.lstsq(design, xs**2 + ys**2, rcond=None)
    return a, b, np.sqrt(c + a * a + b * b)


# A black rim ring (the casing lip) between the pin field and the disc edge: an annulus reaching the
# disc edge (less `_RING_EDGE_PX`, its anti-aliased rim) at least `_RING_MIN_PX` wide, in which the
# dark grey level of nearly every azimuth (`_RING_PERCENTILE`, so that LED glare on the ring and
# pins on the membrane do not count) is at most `_RING_DARK` of the membrane's just inside it (over
# `_RING_INSIDE_PX` px after a `_RING_STEP_PX` px edge) and below the same percentile of the inner
# half of the disc. The pins are searched inside its inner edge less `_RING_INSET_PX` (its
# anti-aliased edge).
_RING_PERCENTILE = 5.0
_RING_DARK = 0.5
_RING_EDGE_PX = 2
_RING_MIN_PX = 3
_RING_STEP_PX = 2
_RING_INSIDE_PX = 4
_RING_AZIMUTHS = 720
_RING_INSET_PX = 1.0


def _rim_ring_inner_px(grey: np.ndarray, disc: SensorDisc, dark_pins: bool) -> float:
    """Radius of the inner edge of a black rim ring round the pin field, px from the disc centre.

    The grey levels on circles about the disc centre (1 px apart, `_RING_AZIMUTHS` samples each)
    give a dark level per radius, a low percentile over the azimuths, which neither the pins nor
    glare covering most of the ring raise. The ring is the widest outer annulus whose dark level
    stays at most `_RING_DARK` of the membrane's just inside its edge, and below the dark level of
    the inner half of the disc, out to the disc's rim. Only bright pins are looked for on such a
    ring (inf for dark pins, and when there is none).
    """
    if dark_pins:
        # A black ring has the polarity of dark pins: neither its glare nor the pins it hides make
        # candidate blobs.
        return np.inf
    steps = int(np.ceil(disc.radius_px))
    # WARP_FILL_OUTLIERS: without it, OpenCV leaves the samples beyond the frame as the new array's
    # memory held them (BORDER_TRANSPARENT). In a long-running process that is an earlier array's
    # bytes: rays leaving the frame then passed for whole, and the black beyond the frame for a ring.
    polar = cv2.warpPolar(grey, (steps, _RING_AZIMUTHS), (disc.cx, disc.cy), disc.radius_px,
                          cv2.WARP_POLAR_LINEAR + cv2.INTER_LINEAR + cv2.WARP_FILL_OUTLIERS)
    # A disc cut by the frame edge: only the azimuths whose ray stays in the frame see a ring (the
    # samples beyond the frame are black).
    seen = cv2.warpPolar(np.full(grey.shape, 255, np.uint8), (steps, _RING_AZIMUTHS), (disc.cx, disc.cy),
                         disc.radius_px, cv2.WARP_POLAR_LINEAR + cv2.INTER_NEAREST + cv2.WARP_FILL_OUTLIERS)
    whole = (seen == 255).all(axis=1)
    if whole.sum() < _RING_AZIMUTHS // 4:
        return np.inf
    polar = polar[whole]
    dark = np.percentile(polar, _RING_PERCENTILE, axis=0)
    end = steps - 1 - _RING_EDGE_PX
    first = max(steps // 2, _RING_STEP_PX + _RING_INSIDE_PX)
    if end - _RING_MIN_PX + 1 < first:
        return np.inf
    # Brightest dark level from each radius out to the rim, and the membrane's just inside it.
    outward = np.maximum.accumulate(dark[end::-1])[::-1]
    radii = np.arange(first, end - _RING_MIN_PX + 2)
    inside = np.stack([dark[radii - _RING_STEP_PX - k] for k in range(1, _RING_INSIDE_PX + 1)])
    # At most half as bright as the membrane next to it, and darker than the darkest membrane of
    # the inner half of the disc (the same percentile of all its pixels): a black lip, not the
    # membrane beyond a dense cluster of pins.
    inner = np.percentile(polar[:, :steps // 2], _RING_PERCENTILE)
    ring = (outward[radii] <= _RING_DARK * np.median(inside, axis=0)) & (outward[radii] <= inner)
    if not ring.any():
        return np.inf
    return float(radii[np.argmax(ring)] * disc.radius_px / steps)
