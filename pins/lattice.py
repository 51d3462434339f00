"""The pin field: the blobs that form the pin lattice, told apart from everything else.

A TacTip frame shows more bright blobs than pins: LED glare and its reflections on a black rim
ring, specks of dust, light patches of skin between the shadows of the pins, skin texture. What
makes a pin a pin is that it belongs to the lattice: it sits at a lattice site, with neighbours at
the lattice pitch, and its size, contrast and sharpness are like its neighbours'. `find_pin_field`
finds that lattice without being told the pin count:

0. the search region: the sensor disc, or, when a black rim ring (the casing lip) lies between
   the pin field and the disc edge, the disc inside the ring's inner edge: an outer annulus whose
   dark grey level over nearly all azimuths is at most half the membrane's just inside it, and
   darker than the membrane's of the inner half of the disc. Like
   the surround, the ring neither makes candidate blobs (its LED glare, which in a radial layout
   sits where one more ring of pins would) nor darkens the threshold's neighbourhood means (the
   membrane along its edge would pass for pins);
1. pitch: blobs detected permissively (`pins.detect`) at parameters scaled to each possible pitch
   of the disc (a twentieth to a quarter of its radius: 1000 to 100 pins, radial layouts, small
   pads); the strongest lattice (most contrast x area kept) gives the pitch, measured as the median
   nearest-neighbour distance of its blobs;
2. candidates: a dozen parameter sets at that pitch (neighbourhood blocks of 1-2.2 pitches,
   offsets of 5-25 grey levels);
3. lattice consistency, per candidate set, iterated until nothing changes (removing an impostor
   changes its neighbours' statistics), each blob against the medians of its six nearest
   neighbours: ``size`` when its area is below 0.4 or above 2.2 of theirs (or its box poorly
   filled); ``contrast`` when fainter than half of theirs, or with edges much softer (glare and
   patches of skin are smooth, pin tips are discs with a sharp edge); ``off lattice`` when within
   0.6 local pitches of a stronger blob (a speck, a light patch between pins), or when it sits at no
   lattice site and does not look just like its neighbours. A lattice site is found by mirror
   images: a pin is the mirror of a neighbour through another neighbour (six times for interior
   pins, at least once at the rim or at the end of a radial spoke). The local pitch is the median
   nearest-neighbour distance around a blob, so radial layouts, whose spacing grows with the
   radius, and foreshortened rim pins work. Then the blobs rejected are judged again against the
   blobs kept, and those that pass rejoin (once each) and the iteration runs again: a pin first
   judged among impostors (skin highlights and specks round the spoke ends or the lone centre pin
   of a radial layout make it look unlike its neighbours) comes back once they are gone;
4. the field: blobs joined by lattice links (at most 1.3 times the local second-neighbour distance)
   form connected groups; the large groups are the pin field, a blob beyond their convex hull is
   ``outside field`` (so is every rejected blob half a pitch beyond it: glare round the rim), and
   an isolated blob inside it (the centre pin of a radial layout) stays; fewer than 10 pins make
   no field;
5. the winner: the candidate set that keeps the most pins that at least half of the good sets
   (those keeping 97 % of the most pins; both when there are two) also keep, and the fewest
   others, its centres nearest their consensus;
6. later frames: `PinField.params` are those of the highest offset that keeps (nearly) the same
   pins (it keeps pins pushed together by a contact apart), with the kept pins' area range and a
   rim margin that leaves out the membrane half a pitch beyond the outermost pin and the rim
   ring, so that the per-frame fast path `pins.detect_pins(frame, params=field.params,
   disc=field.disc)` does not detect the rim ring and its glare again.

A known pin count does not steer the search: it is compared with the result (`count_error`).
`draw_pin_field` pictures what was kept and what was rejected, coloured by reason.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import cv2
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from .detect import Blobs, DetectionParams, _detect
from .disc import SensorDisc, as_grey, find_sensor_disc
from .scale import central_spacing_px

__all__ = ["PinField", "find_pin_field", "REJECTION_REASONS", "draw_pin_field"]

#: Why a candidate blob was rejected, in `PinField.rejected_reason`.
REJECTION_REASONS = ("outside field", "off lattice", "size", "contrast")
_OUTSIDE, _OFF, _SIZE, _CONTRAST = range(4)
_KEPT = -1

# Possible pin pitches, as fractions of the disc radius (1000 pins on a hexagonal lattice filling
# the disc: 0.06; 100 pins: 0.19; radial layouts and small pads between).
_PITCH_FRACTIONS = (0.05, 0.075, 0.11, 0.165, 0.25)
_BLOCK_PITCHES = (1.0, 1.5, 2.2)
_OFFSETS = (5.0, 9.0, 15.0, 25.0)
_COARSE_BLOCK = (2.2,)
_COARSE_OFFSETS = (9.0,)
_NEIGHBOURS = 6
# Lattice consistency: fractions of the neighbours' medians (areas compared with `_AREA_SLACK` px
# added, fills only for areas of `_FILL_AREA` px or more) and of the local pitch.
_SIZE_RANGE = (0.4, 2.2)
_MIN_FILL = 0.6
_FILL_AREA = 15.0
_MIN_CONTRAST = 0.5
_MIN_SHARPNESS = 0.8
# Below this tip radius, px, the steepest slope depends on where the pixel grid cuts the tip.
_SHARP_RADIUS = 2.0
_TOO_CLOSE = 0.6
_LINK = 1.3
# Lattice sites: a mirror image within this fraction of the link length anchors a blob; a blob with
# fewer than `_MIN_ANCHORS` must have at least these contrast ratios and at most these area ratios
# to its neighbours' medians (with one anchor, with none).
_MIRROR = 0.25
_MIN_ANCHORS = 2
_WEAK_CONTRAST = (0.5, 0.8)
_WEAK_SIZE = (1.8, 1.4)
_MIN_PINS = 4
# Fewest pins that make a pin field (TacTips have 100-1000).
_MIN_FIELD = 10
_AREA_SLACK = 3.0
# Linked groups of at least this fraction of the largest make the field; isolated blobs within
# `_HULL_MARGIN` pitches of its hull stay.
_MIN_GROUP = 0.1
_HULL_MARGIN = 0.3
# Rejected blobs this many pitches beyond the field's hull are reported as outside the field.
_OUTSIDE_MARGIN = 0.5
# The search region of later frames reaches this many pitches beyond the outermost pin.
_FIELD_MARGIN = 0.5
# Area range of the final parameters around the kept pins' median area.
_AREA_RANGE = (0.25, 2.5)
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
# Candidate sets: a pin matches within this many pitches; 'the same pins' within this fraction.
_MATCH = 0.3
_SAME_PINS = 0.005
_VOTER = 0.97


@dataclass(frozen=True)
class PinField:
    """The pins of a frame that form the pin lattice, and the blobs rejected beside them.

    Attributes
    ----------
    centres : (N, 2) ndarray of float64
        Kept pins (x, y), px, sorted by y then x; (0, 2) when there are none.
    params : DetectionParams
        Detection parameters for later frames of this sensor (`pins.detect_pins` with
        ``disc=field.disc``): the kept pins' blur, threshold and area range, and a rim margin that
        leaves out the membrane beyond the pin field (a rim ring and its glare).
    disc : SensorDisc
        The sensor disc, px (the pins were searched inside it, or inside a black rim ring's inner
        edge when there is one).
    pitch_px : float
        The pin pitch, px: median nearest-neighbour distance of the kept pins near the field's centre
        (`pins.central_spacing_px`, the pitch the scale `pins.pad_scale` divides by; nan with fewer
        than two).
    rejected : (M, 2) ndarray of float64
        Centres of the candidate blobs rejected, px.
    rejected_reason : (M,) ndarray of str
        Why each was rejected: one of `REJECTION_REASONS` ("outside field": beyond the lattice, such
        as glare round the rim or pins a rim ring cuts; "off lattice": too close to a stronger pin,
        such as a speck or a light patch of skin between pins, or at no lattice site and unlike its
        neighbours; "size": much smaller or larger than its neighbours; "contrast": much fainter
        than its neighbours, or with a much softer edge).
    expected_pins : int or None
        The pin count given, if any.
    count_error : int or None
        Pins kept minus `expected_pins` (None without a count).
    """

    centres: np.ndarray
    params: DetectionParams
    disc: SensorDisc
    pitch_px: float
    rejected: np.ndarray
    rejected_reason: np.ndarray
    expected_pins: int | None = None
    count_error: int | None = None

    @property
    def count(self) -> int:
        """Number of pins kept."""
        return int(len(self.centres))

    @property
    def field_disc(self) -> SensorDisc:
        """The pin field's circle: `disc` less the rim margin of `params`, px."""
        return SensorDisc(self.disc.cx, self.disc.cy, max(self.disc.radius_px - self.params.rim_margin_px, 0.0))

    def rejected_counts(self) -> dict[str, int]:
        """How many blobs were rejected for each reason (every reason listed, zeros included)."""
        return {reason: int(np.count_nonzero(self.rejected_reason == reason)) for reason in REJECTION_REASONS}

    def summary(self, *, pitch: bool = True) -> str:
        """One line for a person: pins kept, pitch (unless `pitch` is False: a summary that prints the
        scale prints the pitch there), blobs rejected by reason, the count check."""
        rejected = ", ".join(f"{n} {reason}" for reason, n in self.rejected_counts().items() if n)
        pitch = f", pitch {self.pitch_px:.1f} px" if pitch and np.isfinite(self.pitch_px) else ""
        line = f"{self.count} pins{pitch}; rejected {len(self.rejected)}"
        line += f" ({rejected})" if rejected else ""
        if self.expected_pins is not None:
            error = self.count_error
            off = "exact" if error == 0 else f"{error:+d} ({error / self.expected_pins:+.1%})"
            line += f"; expected {self.expected_pins}: {off}"
        return line


def find_pin_field(frame: np.ndarray, *, expected_pins: int | None = None, params: DetectionParams | None = None,
                   disc: SensorDisc | None = None, dark_pins: bool = False) -> PinField:
    """Find the pins of a frame as the blobs that form the pin lattice, without knowing their count.

    Parameters
    ----------
    frame : (H, W) or (H, W, 3) ndarray of uint8
        Grey or BGR frame, best a rest frame (nothing touching the pad).
    expected_pins : int, optional
        The sensor's pin count: checked against the result (`PinField.count_error`), never used
        to steer the search.
    params : DetectionParams, optional
        Starting parameters: tried among the candidates; their polarity is kept, and their rim
        margin at least (`PinField.params` widens it to leave out the membrane beyond the field).
    disc : SensorDisc, optional
        The membrane disc, found with `find_sensor_disc` when not given.
    dark_pins : bool
        Dark markers on a light membrane (also taken from ``params.dark_pins``).

    Returns
    -------
    field : PinField

    Raises
    ------
    NoSensorError
        When `disc` is not given and the frame shows no sensor disc.
    ValueError
        `expected_pins` is not a positive integer.

    Examples
    --------
    >>> from tactip.sim import SyntheticTacTip
    >>> sensor = SyntheticTacTip(pins=331, seed=0)
    >>> field = find_pin_field(sensor.render().image)
    >>> 300 <= field.count <= 331, round(field.pitch_px)
    (True, 18)

    Later frames are detected fast with the field's parameters and region:

    >>> from pins import detect_pins
    >>> pins = detect_pins(sensor.render().image, params=field.params, disc=field.disc)
    """
    if expected_pins is not None and (isinstance(expected_pins, bool) or int(expected_pins) != expected_pins
                                      or expected_pins < 1):
        raise ValueError(f"expected_pins must be a positive integer, got {expected_pins!r}")
    start = params or DetectionParams()
    if dark_pins and not start.dark_pins:
        start = start.replace(dark_pins=True)
    grey = as_grey(frame)
    if disc is None:
        disc = find_sensor_disc(grey, dark_pins=start.dark_pins)
    # The possible pitches scale with the sensor disc; the search stops at a black rim ring, which,
    # like the surround, must neither make blobs (its glare) nor darken the threshold's
    # neighbourhood means (the membrane along its edge would pass for pins).
    pitches = disc.radius_px * np.array(_PITCH_FRACTIONS)
    ring = _rim_ring_inner_px(grey, disc, start.dark_pins)
    search = disc if not np.isfinite(ring) else SensorDisc(disc.cx, disc.cy, max(ring - _RING_INSET_PX, 1.0))
    # The rim margin is measured from the sensor disc's rim (the ring's inner edge is sharp: the
    # pins next to it are whole).
    start = start.replace(rim_margin_px=max(start.rim_margin_px - (disc.radius_px - search.radius_px), 0.0))
    cache: dict = {}
    # Coarse: one permissive candidate set per possible pitch; the strongest lattice gives the pitch.
    coarse = _evaluate_all(grey, search, list(_candidates(pitches, start, _COARSE_BLOCK, _COARSE_OFFSETS)), cache)
    first = max(coarse, key=lambda run: run.strength)
    pitch = first.pitch if np.isfinite(first.pitch) else float(np.median(pitches))
    pitch = float(np.clip(pitch, 0.5 * pitches.min(), 1.5 * pitches.max()))
    # Fine: blocks and offsets at the measured pitch.
    fine = list(_candidates(np.array([pitch]), start, _BLOCK_PITCHES, _OFFSETS))
    runs = _evaluate_all(grey, search, fine + ([start] if params is not None else []), cache)
    # The pins are the blobs that most candidate sets agree on, where they agree on them: the run
    # that keeps the most of those (and the fewest others), with centres nearest the consensus.
    membership, deviation = _consensus(runs, pitch)
    best = max(range(len(runs)), key=lambda r: (membership[r], -deviation[r]))
    # Later frames: the highest threshold that keeps (nearly) the same pins, because it keeps pins
    # pushed together by a contact apart.
    close = membership >= membership[best] - max(1.0, _SAME_PINS * runs[best].kept.sum())
    later = max(np.flatnonzero(close), key=lambda r: (runs[r].params.offset, -deviation[r]))
    run = runs[best]
    centres = run.blobs.centres[run.kept]
    final = _final_params(runs[later], centres, disc, run.pitch, search.radius_px)
    count_error = None if expected_pins is None else len(centres) - int(expected_pins)
    return PinField(centres=centres, params=final, disc=disc,
                    pitch_px=central_spacing_px(centres), rejected=run.blobs.centres[~run.kept],
                    rejected_reason=np.array(REJECTION_REASONS, dtype=object)[run.reason[~run.kept]].astype(str),
                    expected_pins=None if expected_pins is None else int(expected_pins), count_error=count_error)


@dataclass(frozen=True)
class _Run:
    """One candidate parameter set: its blobs, the lattice verdict on each, and their pitch, px."""

    params: DetectionParams
    blobs: Blobs
    reason: np.ndarray
    pitch: float

    @property
    def kept(self) -> np.ndarray:
        return self.reason == _KEPT

    @property
    def strength(self) -> float:
        """Summed contrast x area of the kept blobs: the strongest lattice is the pins'."""
        kept = self.kept
        return float(np.sum(self.blobs.contrasts[kept] * self.blobs.areas[kept]))


# OpenCV and NumPy release the GIL in the detection, so two candidate sets run at once on two cores.
_WORKERS = 2


def _evaluate_all(grey: np.ndarray, disc: SensorDisc, candidates: list, cache: dict) -> list:
    """`_evaluate` for each candidate parameter set, on `_WORKERS` threads."""
    with ThreadPoolExecutor(_WORKERS) as pool:
        return list(pool.map(lambda params: _evaluate(grey, disc, params, cache), candidates))


def _evaluate(grey: np.ndarray, disc: SensorDisc, params: DetectionParams, cache: dict) -> _Run:
    """Detect with one candidate parameter set and judge the blobs."""
    blobs = _detect(grey, disc, params, cache)
    reason, pitch = _judge_lattice(blobs, _sharpness(grey, blobs, params, cache))
    return _Run(params, blobs, reason, pitch)


def _consensus(runs: list, pitch: float) -> tuple[np.ndarray, np.ndarray]:
    """Per run: kept pins the voters agree on minus the others; median distance to the consensus, px.

    Runs keeping fewer than `_VOTER` times the most pins kept neither vote nor win (-inf). The
    voters agree on a pin that at least half of them keep (both, when two vote).

    A kept pin is matched in another run by its nearest kept pin within `_MATCH` pitches; the
    consensus position of a pin is the mean of its matches.
    """
    kept = [run.blobs.centres[run.kept] for run in runs]
    # Only runs that keep nearly as many pins as the best one vote (on a small pad most candidate
    # sets lose pins, and pins that only the good ones find must not look like outliers).
    counts = np.array([len(c) for c in kept])
    voters = counts >= _VOTER * counts.max()
    gate = _MATCH * pitch if np.isfinite(pitch) else 1.0
    membership = np.full(len(runs), -np.inf)
    deviation = np.full(len(runs), np.inf)
    voting = [r for r in range(len(runs)) if voters[r] and len(kept[r])]
    if not voting:
        return membership, deviation
    # Every voter's kept centres matched in every voter's at once: the nearest centres of all of
    # them (one k-d tree), nearest first, so that a voter's first among them is its nearest.
    bounds = np.cumsum([0] + [len(kept[r]) for r in voting])
    every = np.concatenate([kept[r] for r in voting])
    voter_of = np.append(np.repeat(np.arange(len(voting)), np.diff(bounds)), -1)  # -1: no neighbour
    tree = cKDTree(every)
    reach = min(len(voting) + 2, len(every))
    distance, index = tree.query(every, k=reach, distance_upper_bound=gate)
    distance, index = distance.reshape(len(every), reach), index.reshape(len(every), reach)
    rows = np.arange(len(every))
    matched = np.full((len(voting) + 1, len(every)), -1)  # the extra row takes "no neighbour"
    for column in range(reach - 1, -1, -1):  # nearest last: it stays
        matched[voter_of[index[:, column]], rows] = index[:, column]
    crowded = np.flatnonzero(np.isfinite(distance[:, -1]))  # all of them within the gate: maybe more
    if crowded.size:
        for s, r in enumerate(voting):  # asked of each voter, as one at a time
            found, nearest = cKDTree(kept[r]).query(every[crowded], distance_upper_bound=gate)
            matched[s, crowded] = np.where(np.isfinite(found), bounds[s] + np.minimum(nearest, len(kept[r]) - 1), -1)
    matched = matched[:-1]
    support = (matched >= 0).sum(axis=0)
    # At least half: a strict majority of four voters would let the two least complete veto the
    # pins only the two most complete find. Two voters must both keep a pin (one run's own blobs
    # are no agreement).
    agreed = (2 * support >= voters.sum()) & (support >= min(2, voters.sum()))
    # The mean of each centre's matches (the row past the end of `every` is zeros: no match).
    with np.errstate(invalid="ignore"):  # centres no voter matched: averaged, never used
        consensus = np.append(every, [[0.0, 0.0]], axis=0)[matched].sum(axis=0) / support[:, None]
    for s, r in enumerate(voting):
        mine = slice(bounds[s], bounds[s + 1])
        membership[r] = agreed[mine].sum() - (~agreed[mine]).sum()
        if agreed[mine].any():
            offset = kept[r][agreed[mine]] - consensus[mine][agreed[mine]]
            deviation[r] = float(np.median(np.hypot(*offset.T)))
    return membership, deviation


def _candidates(pitches: np.ndarray, start: DetectionParams, blocks, offsets):
    """Permissive parameter sets scaled to each pitch (px)."""
    for pitch in pitches:
        blur = float(np.clip(0.07 * pitch, 0.6, 2.5))
        loose = dict(blur_sigma_px=round(blur, 2), min_area_px=2, max_area_px=max(int(1.2 * pitch**2), 8),
                     min_fill=0.3, max_aspect=4.0, split_radius_px=round(min(0.12 * pitch, 20.0), 2))
        for block in blocks:
            size = max(2 * int(round(block * pitch / 2.0)) + 1, 3)
            for offset in offsets:
                yield start.replace(block_size_px=size, offset=offset, **loose)


def _sharpness(grey: np.ndarray, blobs: Blobs, params: DetectionParams, cache: dict | None = None) -> np.ndarray:
    """Steepest grey-level slope near each blob over its contrast, 1/px.

    A pin tip is a disc with a sharp edge; glare, light patches of skin and shadows are smooth. On
    tips smaller than `_SHARP_RADIUS` the slope depends on where the pixel grid cuts the tip: all ones.
    `cache` keeps the slope image per blur between candidate sets.
    """
    n = len(blobs.centres)
    radius = float(np.sqrt(np.median(blobs.areas) / np.pi)) if n else 0.0
    if radius < _SHARP_RADIUS:
        return np.ones(n)
    sigma = max(params.blur_sigma_px, 0.5)
    cache = {} if cache is None else cache
    if sigma not in cache:
        smooth = cv2.GaussianBlur(grey, (0, 0), sigma).astype(np.float32)
        gx = cv2.Sobel(smooth, cv2.CV_32F, 1, 0, ksize=3, scale=0.125)
        gy = cv2.Sobel(smooth, cv2.CV_32F, 0, 1, ksize=3, scale=0.125)
        cache[sigma] = cv2.magnitude(gx, gy)
    slope = cache[sigma]
    # The steepest slope within the tip radius (plus a pixel and a half) of each centre.
    reach = int(np.ceil(radius + 1.5))
    dy, dx = np.mgrid[-reach:reach + 1, -reach:reach + 1]
    inside = dx**2 + dy**2 <= (radius + 1.5) ** 2
    x = np.rint(blobs.centres[:, 0]).astype(np.intp)
    y = np.rint(blobs.centres[:, 1]).astype(np.intp)
    height, width = grey.shape
    if n and x.min() >= reach and y.min() >= reach and x.max() < width - reach and y.max() < height - reach:
        # Every disc of pixels inside the image: one flat gather (no clipping).
        steepest = slope.ravel().take((y * width + x)[:, None] + (dy * width + dx)[inside]).max(axis=1)
    else:
        steepest = slope[np.clip(y[:, None] + dy[inside], 0, height - 1),
                         np.clip(x[:, None] + dx[inside], 0, width - 1)].max(axis=1)
    return steepest / np.maximum(blobs.contrasts, 1e-6)


def _judge_lattice(blobs: Blobs, sharpness: np.ndarray) -> tuple[np.ndarray, float]:
    """Which blobs form a lattice: (reason per blob, -1 for kept; median pitch of the kept, px)."""
    n = len(blobs.centres)
    reason = np.full(n, _KEPT, dtype=np.int64)
    if n < _MIN_PINS:
        reason[:] = _OFF
        return reason, np.nan
    # Photometry and spacing, iterated: removing an impostor changes its neighbours' medians. Then
    # the blobs rejected are judged again against the blobs kept, because a pin first judged among
    # impostors (skin highlights and specks round the spoke ends or the lone centre pin of a radial
    # layout make it look unlike its neighbours) must come back once they are gone; those that pass
    # rejoin and the iteration runs again, each blob rejoining at most once (else pairs of blobs
    # could take turns).
    centres = blobs.centres
    active = np.ones(n, bool)
    rejoined = np.zeros(n, bool)
    while True:
        for _ in range(8):
            if active.sum() < _MIN_PINS:
                break
            verdict = _verdicts(blobs, sharpness, active)
            out = active & (verdict != _KEPT)
            if not out.any():
                break
            reason[out] = verdict[out]
            active &= ~out
        else:
            verdict = _verdicts(blobs, sharpness, active)
        if active.sum() < _MIN_PINS:
            break
        back = ~active & ~rejoined & (verdict == _KEPT)
        if not back.any():
            break
        reason[back] = _KEPT
        active |= back
        rejoined |= back
    index = np.flatnonzero(active)
    if len(index) < _MIN_PINS:
        reason[index] = _OFF
        return reason, np.nan
    # The field: groups of blobs joined by lattice links; blobs beyond their hull are outside.
    hood = _Neighbourhood(centres[index])
    groups, label = connected_components(hood.graph(), directed=False)
    sizes = np.bincount(label, minlength=groups)
    core = (sizes >= max(_MIN_PINS, _MIN_GROUP * sizes.max()))[label]
    if core.sum() < _MIN_FIELD:
        # A handful of blobs (glare round the rim of a pad without pins) is no pin field.
        reason[index] = _OFF
        return reason, np.nan
    hull = cv2.convexHull(centres[index[core]].astype(np.float32))
    pitch = float(np.median(hood.pitch[core]))
    loose = index[~core]
    reason[loose[_beyond(hull, centres[loose], _HULL_MARGIN * pitch)]] = _OUTSIDE
    # Whatever else was rejected beyond the field (glare round the rim) is outside it, first of all.
    kept = reason == _KEPT
    rejected = np.flatnonzero(~kept)
    reason[rejected[_beyond(hull, centres[rejected], _OUTSIDE_MARGIN * pitch)]] = _OUTSIDE
    return reason, float(_median_nn(centres[reason == _KEPT]))


def _verdicts(blobs: Blobs, sharpness: np.ndarray, members: np.ndarray) -> np.ndarray:
    """Each blob judged against its nearest `members` (bool per blob): -1 (a lattice site) or why not."""
    n = len(blobs.centres)
    areas = blobs.areas.astype(np.float64)
    fills = blobs.fills
    contrasts = np.maximum(blobs.contrasts, 1e-6)
    strength = contrasts * areas
    hood = _Neighbourhood(blobs.centres, members)
    # Medians over the blob and its neighbours. Areas compared with a little slack: a 1 px tip
    # covers 3-7 px.
    near = hood.near
    area_ref, contrast_ref, fill_ref, sharp_ref = _row_median(np.stack([areas, contrasts, fills, sharpness])[:, near])
    area_ref = area_ref + _AREA_SLACK
    area = areas + _AREA_SLACK
    verdict = np.full(n, _KEPT)
    # Of two blobs much closer than the local pitch, the weaker is not a lattice site.
    close = (hood.dist[:, 1:] < _TOO_CLOSE * hood.pitch[:, None]) & (strength[near[:, 1:]] > strength[:, None])
    verdict[close.any(axis=1)] = _OFF
    verdict[(contrasts < _MIN_CONTRAST * contrast_ref) | (sharpness < _MIN_SHARPNESS * sharp_ref)] = _CONTRAST
    # (The fill of a blob of a few pixels says nothing of its shape.)
    verdict[(area < _SIZE_RANGE[0] * area_ref) | (area > _SIZE_RANGE[1] * area_ref)
            | ((fills < _MIN_FILL * fill_ref) & (area_ref >= _FILL_AREA))] = _SIZE
    # Lattice sites: a blob on the lattice is a mirror image of a neighbour through another one
    # (interior pins have six such pairs, rim pins and the ends of radial spokes at least one). A
    # blob with fewer than two must look just like its neighbours to stay.
    anchors = hood.anchors()
    strict = np.clip(_MIN_ANCHORS - anchors, 0, _MIN_ANCHORS) / _MIN_ANCHORS
    ratio = contrasts / contrast_ref
    unlike = ((ratio < _WEAK_CONTRAST[0] + strict * (_WEAK_CONTRAST[1] - _WEAK_CONTRAST[0]))
              | (np.abs(np.log(area / area_ref)) > np.log(_WEAK_SIZE[0]) + strict * np.log(_WEAK_SIZE[1] / _WEAK_SIZE[0])))
    verdict[(anchors < _MIN_ANCHORS) & unlike & (verdict == _KEPT)] = _OFF
    return verdict


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
    polar = cv2.warpPolar(grey, (steps, _RING_AZIMUTHS), (disc.cx, disc.cy), disc.radius_px,
                          cv2.WARP_POLAR_LINEAR + cv2.INTER_LINEAR)
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


def _beyond(hull: np.ndarray, points: np.ndarray, margin: float) -> np.ndarray:
    """Which points lie farther than `margin` (px) outside a convex hull."""
    return np.array([cv2.pointPolygonTest(hull, (float(x), float(y)), True) < -margin for x, y in points],
                    dtype=bool)


class _Neighbourhood:
    """Nearest neighbours among member points (each point first), local pitch, links and mirror anchors.

    Every point, member or not, gets its nearest members as neighbours (a point is never its own
    neighbour), so that blobs rejected so far can be judged against the blobs kept.
    """

    def __init__(self, points: np.ndarray, members: np.ndarray | None = None):
        self.points = points
        index = np.arange(len(points)) if members is None else np.flatnonzero(members)
        self.tree = cKDTree(points[index])
        k = min(_NEIGHBOURS + 1, len(index))
        dist, near = self.tree.query(points, k)
        dist, near = dist.reshape(len(points), k), index[near.reshape(len(points), k)]
        if members is not None and not members.all():
            # A point outside the members is not found first: put it first, before its k - 1 nearest.
            outside = ~members
            dist[outside] = np.column_stack([np.zeros(outside.sum()), dist[outside, :-1]])
            near[outside] = np.column_stack([np.flatnonzero(outside), near[outside, :-1]])
        self.dist, self.near = dist, near
        # Local pitch: median nearest-neighbour distance of the point and its neighbours. Links
        # reach a little beyond the second-nearest distance instead: near the rim of a hemispherical
        # pad the pins are foreshortened towards the centre, closer in the radial direction than
        # along the rim.
        self.pitch, reach = _row_median(self.dist[:, [1, min(2, k - 1)]].T[:, self.near])
        self.link = self.dist[:, 1:] <= _LINK * np.maximum(reach[:, None], reach[self.near[:, 1:]])

    def anchors(self) -> np.ndarray:
        """Per point: linked neighbours j with a point at the mirror image through j, or beyond the point."""
        points, neighbours = self.points, self.near[:, 1:]
        n, k = neighbours.shape
        others = points[neighbours]
        tolerance = _MIRROR * self.dist[:, 1:]
        bound = float(tolerance.max()) if tolerance.size else 0.0
        # Mirror images of the point through each neighbour j (2 j - p) ...
        through = self.tree.query((2.0 * others - points[:, None, :]).reshape(-1, 2), distance_upper_bound=bound)[0]
        through = through.reshape(n, k)
        # ... and of each neighbour j through the point (2 p - j): the first kind seen from j, when p is
        # one of j's neighbours (the same numbers: looked up, not queried again).
        back = neighbours[neighbours] == np.arange(n)[:, None, None]  # (n, k, k): p among j's neighbours
        mutual = back.any(axis=2)
        beyond = np.empty((n, k))
        beyond[mutual] = through[neighbours[mutual], back.argmax(axis=2)[mutual]]
        if not mutual.all():
            lone = ~mutual
            beyond[lone] = self.tree.query(2.0 * np.broadcast_to(points[:, None, :], others.shape)[lone] - others[lone],
                                           distance_upper_bound=bound)[0]
        return np.sum(self.link & (through < tolerance), axis=1) + np.sum(self.link & (beyond < tolerance), axis=1)

    def graph(self) -> coo_matrix:
        """Sparse adjacency of the lattice links."""
        n, k = self.near.shape
        rows = np.repeat(np.arange(n), k - 1)[self.link.ravel()]
        cols = self.near[:, 1:].ravel()[self.link.ravel()]
        return coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))


def _row_median(values: np.ndarray) -> np.ndarray:
    """Median along the last axis, as `numpy.median` gives it (a partition alone for an odd count, 5x faster)."""
    k = values.shape[-1]
    if k % 2 == 0 or np.isnan(values).any():
        return np.median(values, axis=-1)
    return np.partition(values, k // 2, axis=-1)[..., k // 2]


def _median_nn(centres: np.ndarray) -> float:
    if len(centres) < 2:
        return np.nan
    dist, _ = cKDTree(centres).query(centres, 2)
    return float(np.median(dist[:, 1]))


def _final_params(run: _Run, centres: np.ndarray, disc: SensorDisc, pitch: float, reach_px: float) -> DetectionParams:
    """Parameters for later frames: `run`'s, with the area range of its kept blobs and a rim margin
    that leaves out the membrane beyond `centres` (the pins, px) and whatever lies beyond `reach_px`
    from the disc centre (a rim ring)."""
    kept = run.kept
    if kept.sum() < _MIN_PINS or len(centres) < _MIN_PINS or not np.isfinite(pitch):
        return run.params
    median_area = float(np.median(run.blobs.areas[kept]))
    radius = np.sqrt(median_area / np.pi)
    params = run.params.replace(min_area_px=max(int(_AREA_RANGE[0] * median_area), 1),
                                max_area_px=max(int(np.ceil(_AREA_RANGE[1] * median_area)), 2),
                                min_fill=0.4, max_aspect=3.0, split_radius_px=round(float(min(0.4 * radius, 20.0)), 2))
    reach = float(np.max(np.hypot(centres[:, 0] - disc.cx, centres[:, 1] - disc.cy)))
    margin = disc.radius_px - min(reach + _FIELD_MARGIN * pitch, reach_px)
    return params.replace(rim_margin_px=round(float(max(params.rim_margin_px, margin)), 2))


# `draw_pin_field` enlarges frames to this shorter side, px, and scales its marks to it.
_LEGIBLE_PX = 480

#: Colours (B, G, R) of `draw_pin_field`: kept pins, then each rejection reason.
COLOURS = {"kept": (0, 200, 0), "outside field": (255, 80, 255), "off lattice": (0, 160, 255),
           "size": (255, 160, 0), "contrast": (0, 0, 255)}


def draw_pin_field(frame: np.ndarray, field: PinField, *, legend: bool = True) -> np.ndarray:
    """A colour picture of what `find_pin_field` kept and rejected, and why.

    Kept pins are green circles; rejected blobs are crosses coloured by reason (`COLOURS`); the
    pin field's circle (`PinField.field_disc`) is a thin yellow circle; a legend with the counts
    sits top left. Frames whose shorter side is under 480 px are enlarged by a whole factor (pixels
    repeated) so that the marks and the legend can be read.

    Parameters
    ----------
    frame : (H, W) or (H, W, 3) ndarray of uint8
        The frame the field was found in.
    field : PinField
    legend : bool
        Draw the legend.

    Returns
    -------
    picture : (k H, k W, 3) ndarray of uint8
        BGR; k = 1 for frames of 480 px or more (shorter side), else ceil(480 / shorter side).
    """
    grey = as_grey(frame)
    image = np.asarray(frame)
    picture = image.copy() if image.ndim == 3 and image.shape[2] == 3 else cv2.cvtColor(grey, cv2.COLOR_GRAY2BGR)
    zoom = max(int(np.ceil(_LEGIBLE_PX / min(grey.shape))), 1)
    if zoom > 1:
        picture = cv2.resize(picture, None, fx=zoom, fy=zoom, interpolation=cv2.INTER_NEAREST)
    scale = max(min(picture.shape[:2]) / _LEGIBLE_PX, 1.0)
    thick = max(int(round(scale)), 1)
    pitch = field.pitch_px if np.isfinite(field.pitch_px) else 10.0
    radius = max(0.3 * pitch * zoom, 2.0)

    def at(x: float, y: float) -> tuple[int, int]:
        # Pixel centres sit at integers in the frame and in the enlarged picture; 4 fractional bits.
        return int(round(((x + 0.5) * zoom - 0.5) * 16)), int(round(((y + 0.5) * zoom - 0.5) * 16))

    d = field.field_disc
    cv2.circle(picture, at(d.cx, d.cy), int(round(d.radius_px * zoom * 16)), (0, 230, 230), thick, cv2.LINE_AA, 4)
    for x, y in field.centres:
        cv2.circle(picture, at(x, y), int(round(radius * 16)), COLOURS["kept"], thick, cv2.LINE_AA, 4)
    half = radius / zoom
    for (x, y), reason in zip(field.rejected, field.rejected_reason):
        colour = COLOURS[str(reason)]
        cv2.line(picture, at(x - half, y - half), at(x + half, y + half), colour, thick, cv2.LINE_AA, 4)
        cv2.line(picture, at(x - half, y + half), at(x + half, y - half), colour, thick, cv2.LINE_AA, 4)
    if legend:
        counts = field.rejected_counts()
        lines = [("kept", f"kept {field.count}")] + [(r, f"{r} {n}") for r, n in counts.items()]
        step = int(round(18 * scale))
        cv2.rectangle(picture, (0, 0), (int(round(150 * scale)), step * len(lines) + step // 2), (0, 0, 0), -1)
        for i, (key, text) in enumerate(lines):
            cv2.putText(picture, text, (int(round(6 * scale)), step * (i + 1)), cv2.FONT_HERSHEY_SIMPLEX, 0.45 * scale,
                        COLOURS[key], thick, cv2.LINE_AA)
    return picture
