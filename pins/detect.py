"""Pin detection: where the pin tips are in one camera frame (paper 002, III-A.3).

The pipeline, all inside the sensor disc (`pins.disc`):

1. grey image (BGR converted once), pixels outside the disc left out (zeroed, and excluded from
   the neighbourhood means) so that the bright surround does not hide the pins near the rim;
2. Gaussian blur (`blur_sigma_px`) against sensor noise;
3. adaptive threshold: a pixel is a pin pixel when it is `offset` grey levels above the mean of
   its `block_size_px` neighbourhood (the mean follows the illumination gradient and glare);
4. connected components, kept when their area, bounding-box fill and aspect look like a pin tip
   (LED glare and merged blobs are too large or too elongated);
5. sub-pixel centres: the intensity-weighted centroid of each component grown by one pixel,
   weighting each pixel by its grey level above the component's local mean (one value per
   component), summed by label with `numpy.bincount`. A symmetric blob gives its geometric centre
   whatever the threshold cut.

Dark markers on a light membrane (`dark_pins=True`) are handled by inverting the grey image.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass

import cv2
import numpy as np
from scipy.spatial import cKDTree

from .disc import SensorDisc, as_grey, find_sensor_disc

__all__ = ["DetectionParams", "detect_pins", "detect_blobs", "Blobs"]

# Smallest eroded core that counts as a pin when splitting touching pins, px.
_MIN_CORE_PX = 4
# ... when the pins are too small to erode (a split radius below 1 px): the core of a tip of about a
# pixel's radius at half height has 2-4 pixels (small-pad-100, two tips pressed 3.6 px together).
_MIN_CORE_UNERODED_PX = 2
_GROW = np.ones((3, 3), np.uint8)

@dataclass(frozen=True)
class DetectionParams:
    """Parameters of `detect_pins`; defaults suit a 640x480 TacTip frame with 331-532 pins.

    Attributes
    ----------
    blur_sigma_px : float
        Standard deviation of the Gaussian blur, px (0 disables it).
    block_size_px : int
        Side of the square neighbourhood of the adaptive threshold, px; odd, >= 3. About two pin
        spacings works well.
    offset : float
        How far above its neighbourhood mean a pixel must be to count as a pin, grey levels.
    min_area_px, max_area_px : int
        Accepted component areas, px (pin tips of radius 4-6 px cover 50-115 px).
    min_fill : float
        Minimum component area over its bounding-box area (a disc fills 0.785), in (0, 1].
    max_aspect : float
        Maximum ratio of the longer to the shorter bounding-box side, >= 1.
    rim_margin_px : float
        Components whose centre is closer than this to the disc rim are ignored, px.
    split_radius_px : float
        Touching pins (pushed together at the edge of a contact) form one component with a
        narrow neck; eroding by a disc of this radius, px, separates them (0 disables). About
        0.4 of the pin radius.
    dark_pins : bool
        Dark markers on a light membrane instead of white pin tips on a dark membrane.
    """

    blur_sigma_px: float = 1.2
    block_size_px: int = 25
    offset: float = 12.0
    min_area_px: int = 10
    max_area_px: int = 250
    min_fill: float = 0.45
    max_aspect: float = 2.5
    rim_margin_px: float = 2.0
    split_radius_px: float = 2.0
    dark_pins: bool = False

    def __post_init__(self) -> None:
        if not (0.0 <= self.blur_sigma_px <= 20.0):
            raise ValueError(f"blur_sigma_px must be in [0, 20], got {self.blur_sigma_px}")
        if int(self.block_size_px) != self.block_size_px or self.block_size_px < 3 or self.block_size_px % 2 == 0:
            raise ValueError(f"block_size_px must be an odd integer >= 3, got {self.block_size_px}")
        if not np.isfinite(self.offset):
            raise ValueError(f"offset must be finite, got {self.offset}")
        if not (1 <= self.min_area_px <= self.max_area_px):
            raise ValueError(
                f"min_area_px and max_area_px must satisfy 1 <= min <= max, got {self.min_area_px}, {self.max_area_px}")
        if not (0.0 < self.min_fill <= 1.0):
            raise ValueError(f"min_fill must be in (0, 1], got {self.min_fill}")
        if not self.max_aspect >= 1.0:
            raise ValueError(f"max_aspect must be >= 1, got {self.max_aspect}")
        if not self.rim_margin_px >= 0.0:
            raise ValueError(f"rim_margin_px must be >= 0, got {self.rim_margin_px}")
        if not 0.0 <= self.split_radius_px <= 20.0:
            raise ValueError(f"split_radius_px must be in [0, 20], got {self.split_radius_px}")

    def replace(self, **changes) -> DetectionParams:
        """A copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict:
        """The parameters as a JSON-serialisable dict (inverse: ``DetectionParams(**d)``)."""
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class Blobs:
    """Accepted pin blobs of one frame, as returned by `detect_blobs`.

    Attributes
    ----------
    centres : (N, 2) ndarray of float64
        Intensity-weighted centres (x, y), px.
    areas : (N,) ndarray of int
        Component areas, px.
    fills : (N,) ndarray of float64
        Component area over bounding-box area.
    candidates : int
        Number of components before the area and shape filters.
    contrasts : (N,) ndarray of float64
        Summed grey level above the local background (the neighbourhood mean) of each blob grown
        by one pixel, over its area: about its mean contrast, grey levels (of the inverted image
        for dark pins).
    """

    centres: np.ndarray
    areas: np.ndarray
    fills: np.ndarray
    candidates: int
    contrasts: np.ndarray = dataclasses.field(default_factory=lambda: np.empty(0))


def detect_pins(frame: np.ndarray, *, params: DetectionParams | None = None, disc: SensorDisc | None = None,
                **knobs) -> np.ndarray:
    """Sub-pixel centres of the pin tips in one frame.

    Parameters
    ----------
    frame : (H, W) or (H, W, 3) ndarray of uint8
        Grey or BGR camera frame.
    params : DetectionParams, optional
        Detection parameters (default ``DetectionParams()``).
    disc : SensorDisc, optional
        The sensor disc, if already known (a tracker finds it once); found with
        `find_sensor_disc` otherwise.
    **knobs
        Fields of `DetectionParams` overriding `params`, e.g. ``offset=8``.

    Returns
    -------
    pins : (N, 2) ndarray of float64
        (x, y) px, sorted by y then x; shape (0, 2) when there are none.

    Raises
    ------
    NoSensorError
        When `disc` is not given and the frame shows no sensor disc.

    Examples
    --------
    >>> from tactip.sim import SyntheticTacTip
    >>> frame = SyntheticTacTip(pins=331, seed=0).render().image
    >>> pins = detect_pins(frame)                 # dark markers: detect_pins(frame, dark_pins=True)
    >>> 300 <= len(pins) <= 331
    True
    """
    return detect_blobs(frame, params=params, disc=disc, **knobs).centres


def detect_blobs(frame: np.ndarray, *, params: DetectionParams | None = None, disc: SensorDisc | None = None,
                 **knobs) -> Blobs:
    """Like `detect_pins`, with the blob areas and fills that tuning uses to judge regularity.

    Parameters
    ----------
    frame : (H, W) or (H, W, 3) ndarray of uint8
        Grey or BGR camera frame.
    params : DetectionParams, optional
        Detection parameters (default ``DetectionParams()``).
    disc : SensorDisc, optional
        The sensor disc, found with `find_sensor_disc` when not given.
    **knobs
        Fields of `DetectionParams` overriding `params`.

    Returns
    -------
    blobs : Blobs
    """
    params = params or DetectionParams()
    if knobs:
        params = params.replace(**knobs)
    grey = as_grey(frame)
    if disc is None:
        disc = find_sensor_disc(grey, dark_pins=params.dark_pins)
    return _detect(grey, disc, params)


def _detect(grey: np.ndarray, disc: SensorDisc, params: DetectionParams, cache: dict | None = None) -> Blobs:
    """Detection on a grey uint8 image with a known disc (no validation: internal fast path).

    `cache` (one per image and disc) keeps the blurred disc and its neighbourhood means between
    parameter sets that share the blur, polarity and block (`pins.find_pin_field`'s candidates).
    """
    x0, y0, image, smooth, mean = _filtered(grey, disc, params, cache)
    return _blobs(image, smooth, mean, disc, params, x0, y0)


def _filtered(grey: np.ndarray, disc: SensorDisc, params: DetectionParams, cache: dict | None = None):
    """Steps 1-3 up to the threshold: the disc's box corner (x0, y0) px, its grey image (inverted for dark
    pins, zero outside the disc), the blurred image (uint8) and the neighbourhood means (float32).

    `pins.accel_detect` computes the same three arrays, bit for bit, for many frames at once.
    """
    x0, y0, roi_mask = _roi(disc, grey.shape)
    height, width = roi_mask.shape
    key = (params.dark_pins, params.blur_sigma_px)
    if cache is not None and key in cache:
        image, smooth = cache[key]
    else:
        image = grey[y0:y0 + height, x0:x0 + width]
        if params.dark_pins:
            image = 255 - image
        # Only the disc counts: the surround is zeroed and left out of the neighbourhood means
        # (normalised box filter), so it neither makes pins nor hides the pins near the rim.
        image = cv2.copyTo(image, roi_mask, np.zeros_like(image))
        if params.blur_sigma_px > 0:
            k = _blur_size_px(params.blur_sigma_px)
            smooth = cv2.GaussianBlur(image, (k, k), params.blur_sigma_px)
        else:
            smooth = image
        if cache is not None:
            cache[key] = image, smooth
    if cache is not None and key + (params.block_size_px,) in cache:
        mean = cache[key + (params.block_size_px,)]
    else:
        block = (params.block_size_px, params.block_size_px)
        mean = cv2.boxFilter(smooth, cv2.CV_32F, block, borderType=cv2.BORDER_CONSTANT)
        mean *= _inverse_coverage(disc, grey.shape, params.block_size_px)
        if cache is not None:
            cache[key + (params.block_size_px,)] = mean
    return x0, y0, image, smooth, mean


def _blur_size_px(sigma_px: float) -> int:
    """Side of the Gaussian blur's kernel for `sigma_px`, px (odd: 2.5 sigma each side)."""
    return 2 * int(np.ceil(2.5 * sigma_px)) + 1


def _blobs(image: np.ndarray, smooth: np.ndarray, mean: np.ndarray, disc: SensorDisc, params: DetectionParams,
           x0: int, y0: int) -> Blobs:
    """Steps 3-5 on `_filtered`'s arrays: threshold, components, split, sub-pixel centres (px in the frame)."""
    width = image.shape[1]
    foreground = smooth > mean + np.float32(params.offset)
    binary = foreground.view(np.uint8)
    count, labels, stats, _ = cv2.connectedComponentsWithStatsWithAlgorithm(binary, 8, cv2.CV_32S, cv2.CCL_GRANA)
    left, top, box_w, box_h, area = (column.astype(np.int64) for column in stats.T)
    # Each component grown by one pixel into the background (not into a neighbour): the threshold
    # cuts a pin's soft edge unevenly where the neighbourhood mean slopes, and the centroid must
    # see all of the pin above its background.
    # Distinct 8-connected components are at least two pixels apart, so the dilation keeps every
    # component pixel's own label and gives each background pixel next to a component its label.
    # uint16 labels dilate three times faster than float32 ones (a frame has far fewer components).
    grown = cv2.dilate(labels.astype(np.uint16 if count <= np.iinfo(np.uint16).max else np.float32), _GROW).ravel()
    index = np.flatnonzero(grown > 0)
    lab = grown[index].astype(np.intp)
    # Background of each blob: the neighbourhood mean at the middle of its bounding box, constant
    # per blob so that a sloping background does not tilt the weights.
    middle_x, middle_y = left + box_w // 2, top + box_h // 2
    suspect = _odd_shaped(area, box_w, box_h, params)
    if params.split_radius_px > 0 and suspect.any():
        split = _split_touching(smooth, mean, labels, count, suspect, index, lab, params.split_radius_px,
                                (left, top, box_w, box_h))
        if split is not None:
            lab, count, (left, top, box_w, box_h, area, middle_x, middle_y) = split[0], split[1], (
                np.concatenate([old, new]) for old, new in zip((left, top, box_w, box_h, area, middle_x, middle_y),
                                                               split[2]))
    background = mean[middle_y, middle_x].astype(np.float64)
    background[0] = np.inf
    # Intensity-weighted centroids of all components at once: sums by label.
    weight = np.maximum(image.ravel()[index] - background[lab], 0.0)
    total, sum_x, sum_y = _weighted_sums(index, lab, weight, width, count)
    return _kept(area, box_w, box_h, total, sum_x, sum_y, disc, params, x0, y0)


def _kept(area: np.ndarray, box_w: np.ndarray, box_h: np.ndarray, total: np.ndarray, sum_x: np.ndarray,
          sum_y: np.ndarray, disc: SensorDisc, params: DetectionParams, x0: int, y0: int) -> Blobs:
    """The components (label 0 the background) that look like pins, as Blobs: their weighted centres, px.

    `total`, `sum_x`, `sum_y` are each component's sums of weight, weight * x and weight * y (x, y in the
    disc's box, px); the box's corner (x0, y0) px moves the centres into the frame.
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        fill = area / (box_w * box_h)
        aspect = np.maximum(box_w, box_h) / np.minimum(box_w, box_h)
    keep = ((area >= params.min_area_px) & (area <= params.max_area_px)
            & (fill >= params.min_fill) & (aspect <= params.max_aspect) & (total > 0))
    keep[0] = False
    centres = np.column_stack([sum_x[keep] / total[keep] + x0, sum_y[keep] / total[keep] + y0])
    inside = disc.contains(centres, margin_px=params.rim_margin_px)
    keep[keep] = inside
    centres = centres[inside]
    order = np.lexsort((centres[:, 0], centres[:, 1]))
    areas = area[keep][order]
    return Blobs(centres=centres[order], areas=areas, fills=fill[keep][order], candidates=len(area) - 1,
                 contrasts=total[keep][order] / np.maximum(areas, 1))


def _odd_shaped(area: np.ndarray, box_w: np.ndarray, box_h: np.ndarray, params: DetectionParams) -> np.ndarray:
    """Components that may be several touching pins: large or poorly filled ones."""
    plausible = (area >= params.min_area_px) & (area <= params.max_area_px)
    plausible[0] = False
    if plausible.sum() < 10:  # too few to know a pin's area: any component may be a pair
        suspect = area >= 2 * params.min_area_px
        suspect[0] = False
        return suspect
    typical = np.median(area[plausible])
    # Two pins side by side cover about twice a pin's area; on a diagonal they also fill their
    # box poorly. Single foreshortened pins near the rim are smaller, and fill theirs well.
    fill = area / (box_w * box_h)
    suspect = (area >= 2 * params.min_area_px) & ((area > 1.4 * typical) | (fill < 0.55))
    suspect[0] = False
    return suspect


def _split_touching(smooth: np.ndarray, mean: np.ndarray, labels: np.ndarray, count: int, suspect: np.ndarray,
                    index: np.ndarray, lab: np.ndarray, radius_px: float,
                    boxes: tuple[np.ndarray, ...]):
    """Split odd-shaped components (`suspect`) made of several touching pins.

    The loose threshold makes blobs fat and the neck between two touching pins wide, so the cores
    are cut at half height first: pixels at least halfway from the neighbourhood mean to the
    component's peak. Eroding that by a disc of `radius_px` removes the neck but leaves one core
    in each convex pin. A component with several cores gives each of its pixels to the core with
    the nearest core pixel (a Voronoi partition by cores, which cuts along the neck). Works on the
    suspect components' pixels only, laid out side by side in a mosaic of their bounding boxes
    (`boxes`: left, top, width, height per label) so that the erosion and labelling cost does not
    grow with the distance between suspects. Returns the new per-pixel labels, the new label count and
    the stats (left, top, width, height, area, middle x, middle y) of the new labels (appended
    after the old ones, whose split components become empty), or None.
    """
    pixels = np.flatnonzero(suspect[lab])
    component = lab[pixels]
    flat = index[pixels]
    level = smooth.ravel()[flat].astype(np.float32)
    peak = np.zeros(count, np.float32)
    np.maximum.at(peak, component, level)
    # Half height, inside the thresholded component (not its one-pixel growth).
    core = (2.0 * level >= mean.ravel()[flat] + peak[component]) & (labels.ravel()[flat] > 0)
    py, px = np.divmod(flat, smooth.shape[1])
    # Mosaic: each suspect's box grown by one pixel (the grown pixels) and a margin of zeros that
    # keeps the erosion and the labelling of one tile from reaching the next.
    pad = int(np.ceil(radius_px)) + 1
    left, top, box_w, box_h = boxes
    tiles = np.flatnonzero(suspect)
    tile_w = box_w[tiles] + 2 + 2 * pad
    origin_x = np.zeros(count, np.int64)
    origin_x[tiles] = np.cumsum(tile_w) - tile_w + pad + 1 - left[tiles]
    origin_y = np.zeros(count, np.int64)
    origin_y[tiles] = pad + 1 - top[tiles]
    mx, my = px + origin_x[component], py + origin_y[component]
    mask = np.zeros((int(box_h[tiles].max()) + 2 + 2 * pad, int(tile_w.sum())), np.uint8)
    mask[my[core], mx[core]] = 255
    # A disc of `radius_px` below 1 px holds the centre pixel alone: no erosion (the half-height cut
    # parts the cores of tips of about a pixel's radius, which a 3 px cross would erase).
    size = 2 * int(np.ceil(radius_px)) + 1 if radius_px >= 1.0 else 1
    eroded = cv2.erode(mask, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (size, size)))
    # 4-connected cores: a diagonal one-pixel bridge left by the erosion does not join two pins.
    cores, core_labels = cv2.connectedComponents(eroded, connectivity=4, ltype=cv2.CV_32S)
    if cores <= 2:
        return None
    in_core = core_labels[my, mx]
    core_pixels = np.flatnonzero(in_core)
    core_of_pixel = in_core[core_pixels]
    core_size = np.bincount(core_of_pixel, minlength=cores)
    component_of_core = np.zeros(cores, dtype=np.int64)
    component_of_core[core_of_pixel] = component[core_pixels]
    # Crumbs of a bridge are not pins: cores need a few pixels to count.
    component_of_core[core_size < (_MIN_CORE_PX if size > 1 else _MIN_CORE_UNERODED_PX)] = 0
    multi = np.bincount(component_of_core[1:], minlength=count) >= 2
    multi[0] = False
    if not multi.any():
        return None
    split_cores = np.flatnonzero(multi[component_of_core])
    n_new = len(split_cores)
    new_label = np.full(cores, -1, dtype=np.int64)
    new_label[split_cores] = np.arange(n_new)
    seed = np.flatnonzero(new_label[core_of_pixel] >= 0)
    members = np.flatnonzero(multi[component])
    mx, my = px[members], py[members]
    seed_xy = np.column_stack([px[core_pixels[seed]], py[core_pixels[seed]]])
    _, nearest_seed = cKDTree(seed_xy).query(np.column_stack([mx, my]))
    nearest_core = core_of_pixel[seed[nearest_seed]]
    # A pixel nearer to another component's core than to one of its own is left out (label 0).
    own = component_of_core[nearest_core] == component[members]
    nearest = new_label[nearest_core]
    lab = lab.copy()
    lab[pixels[members]] = np.where(own, count + nearest, 0)
    mx, my, nearest = mx[own], my[own], nearest[own]
    area = np.bincount(nearest, minlength=n_new)
    left = np.full(n_new, np.iinfo(np.int64).max)
    top = left.copy()
    right = np.full(n_new, -1)
    bottom = right.copy()
    np.minimum.at(left, nearest, mx)
    np.minimum.at(top, nearest, my)
    np.maximum.at(right, nearest, mx)
    np.maximum.at(bottom, nearest, my)
    empty = area == 0
    left[empty] = top[empty] = right[empty] = bottom[empty] = 0
    cx = np.bincount(core_of_pixel, weights=px[core_pixels], minlength=cores) / np.maximum(core_size, 1)
    cy = np.bincount(core_of_pixel, weights=py[core_pixels], minlength=cores) / np.maximum(core_size, 1)
    middle_x = np.rint(cx[split_cores]).astype(np.int64)
    middle_y = np.rint(cy[split_cores]).astype(np.int64)
    stats = (left, top, right - left + 1, bottom - top + 1, area, middle_x, middle_y)
    return lab, count + n_new, stats


def _roi(disc: SensorDisc, shape: tuple[int, int]) -> tuple[int, int, np.ndarray]:
    """Top-left corner of the disc's bounding box and the disc mask (uint8) inside it; cached per disc."""
    return _roi_cached(*_disc_key(disc), shape[0], shape[1])


def _disc_key(disc: SensorDisc) -> tuple[float, float, float]:
    return round(disc.cx, 3), round(disc.cy, 3), round(disc.radius_px, 3)


@functools.lru_cache(maxsize=8)
def _roi_cached(cx: float, cy: float, radius: float, height: int, width: int) -> tuple[int, int, np.ndarray]:
    x0 = max(int(np.floor(cx - radius)) - 1, 0)
    y0 = max(int(np.floor(cy - radius)) - 1, 0)
    x1 = min(int(np.ceil(cx + radius)) + 2, width)
    y1 = min(int(np.ceil(cy + radius)) + 2, height)
    # Sides that are multiples of 8 take OpenCV's fast labelling path (twice as fast at 433 px).
    x0, x1 = _round_span(x0, x1, width)
    y0, y1 = _round_span(y0, y1, height)
    mask = SensorDisc(cx - x0, cy - y0, radius).mask((y1 - y0, x1 - x0)).view(np.uint8)
    mask.setflags(write=False)
    return x0, y0, mask


def _inverse_coverage(disc: SensorDisc, shape: tuple[int, int], block_size: int) -> np.ndarray:
    """1 / (fraction of each pixel's neighbourhood inside the disc), for the normalised box filter."""
    return _inverse_coverage_cached(*_disc_key(disc), shape[0], shape[1], block_size)


@functools.lru_cache(maxsize=32)
def _inverse_coverage_cached(cx: float, cy: float, radius: float, height: int, width: int,
                             block_size: int) -> np.ndarray:
    mask = _roi_cached(cx, cy, radius, height, width)[2]
    coverage = cv2.boxFilter(mask.astype(np.float32), cv2.CV_32F, (block_size, block_size),
                             borderType=cv2.BORDER_CONSTANT)
    inverse = 1.0 / np.maximum(coverage, 1e-3)
    inverse.setflags(write=False)
    return inverse


def _weighted_sums(index: np.ndarray, lab: np.ndarray, weight: np.ndarray, width: int,
                   count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sums of weight, weight * x and weight * y by label, (count,) each.

    `index` holds raster indices (increasing) of pixels in an image `width` px wide, `lab` their
    labels. The pixels come in runs along a row with one label (a blob's row), so the sums are
    taken per run first (`numpy.add.reduceat`) and then by label: ten times fewer elements for
    `numpy.bincount`, which is slow on repeated consecutive labels.
    """
    if len(index) == 0:
        return (np.zeros(count),) * 3
    boundary = np.empty(len(index), bool)
    boundary[0] = True
    np.not_equal(np.diff(index), 1, out=boundary[1:])
    boundary[1:] |= lab[1:] != lab[:-1]
    # A run also ends with its row (a blob touching both sides of the image would wrap around).
    row_start = np.arange(0, index[-1] + 1, width)
    at = np.searchsorted(index, row_start)
    boundary[at[index[at] == row_start]] = True
    starts = np.flatnonzero(boundary)
    run_lab = lab[starts]
    run_y = index[starts] // width
    run_w = np.add.reduceat(weight, starts)
    # Sum over a run of w * x = w * (index - y * width); float64 keeps it exact to ~1e-7 px.
    run_wx = np.add.reduceat(weight * index, starts) - run_w * (run_y * width)
    total = np.bincount(run_lab, weights=run_w, minlength=count)
    sum_x = np.bincount(run_lab, weights=run_wx, minlength=count)
    sum_y = np.bincount(run_lab, weights=run_w * run_y, minlength=count)
    return total, sum_x, sum_y


def _round_span(start: int, stop: int, size: int, multiple: int = 8) -> tuple[int, int]:
    """Grow [start, stop) to a length that is a multiple of `multiple`, staying inside [0, size)."""
    length = min(-(-(stop - start) // multiple) * multiple, size)
    stop = min(start + length, size)
    return stop - length, stop
