"""Pins at empty lattice sites, taken back from the other candidate sets (`pins.find_pin_field`, step 5b).

One candidate set (one blur, neighbourhood and offset) cannot suit every pin of a pad whose light
varies: a pin on an LED reflection inside the pad stands less above a brighter background (contrast
~35 against ~50), and at a low offset the reflection joins it into one large blob; a pin of the
outermost ring under the veil and the rim glare is faint, and at a high offset only a few pixels of
it pass. The winning set then leaves holes in the lattice that other sets fill.

A hole is a lattice site the kept pins predict and none occupies (`pins._sites`: the mirror image of a
kept pin through a linked neighbour, predicted from opposite sides or once outward at the end of a lone
row such as a radial spoke, or a gap in a curved row flanked on opposite sides). A blob of any
candidate set at a hole (within `_MIRROR` of the link length) fills it when it looks like a pin beside
the kept pins around the hole: an area within `_AREA_RANGE` of theirs (not a reflection merged with
its pins, nor a speck), at least `_MIN_CONTRAST` of their contrast and a box filled like a disc's
(beside pins large enough for a fill to tell a shape); of several, the one of the highest offset (the
most confident), then the nearest. Sites are predicted by the judged pins, and then by the pins taken
back (several pins missing in a row along a spoke that crosses a reflection), never farther from the
disc centre than the outermost judged pin plus `_BEYOND` pitches, so that no chain reaches the glare
on the rim.

Some pins make a blob in no candidate set (the outermost ring under the veil, -11 to +16 grey from
the membrane round them, noise sigma 5): `probe_lattice_holes` looks at the image itself at the holes
left, no farther out than the outermost pin plus `_PROBE_BEYOND` pitches, and takes a pin where a
matched test of an opaque tip over a quadratic membrane (`pins._tipprobe`) passes a bar set by a
false-alarm rate per hole. There the lattice prior is used harder than for blobs: a site predicted
towards the centre (two pins lost in a row along a spoke, a gap in a radial layout's innermost ring)
is a hole too, unless it lies in the empty zone round a radial layout's centre pin, whose own site is
probed when the ring round it is whole and it is missing; pins found predict again. A faint tip's
evidence may peak a pixel off it (its evidence there a few units above the truth's), so a pin found is
placed where the image and the lattice agree best: the most evidence less the log of the lattice's prior
(`pins._sites.site_prior`: the mirror site corrected by how the same prediction misses the pins that
are there, about 0.45 px per axis on ``radial-led-120``), and the tip fit weighs the same prior
(`pins._tipfit.fit_tip_centres`). On ``radial-led-120`` (seeds 0-35, rest and a 5 mm tap) the 102 tips
probed were placed 0.31-0.48 px (rms) from their truth without it, four more than a pixel off (1.16-1.76);
with it 0.24-0.28, none.

A kept blob that is no tip (an LED reflection's flat top at a lattice site) is told by
`pins._tipprobe.flat_pins`.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import Delaunay, cKDTree

from ._judge import _FILL_AREA, _MIRROR, _Neighbourhood, _row_median
from ._noise import noise_sigma
from ._sites import _empty_zone, _holes, site_prior
from ._tipfit import tip_shapes
from ._tipprobe import threshold, tip_evidence

# A blob at a hole: its area within this range of the median area of the kept pins round the hole
# (px added to both, as the judge does), and at least this fraction of their median contrast.
_AREA_RANGE = (0.35, 2.2)
_AREA_SLACK = 3.0
_MIN_CONTRAST = 0.35
# ... and fill its bounding box like a disc (0.785), not like a crescent of a reflection's edge: asked, as the
# judge asks it, only beside pins of `pins._judge._FILL_AREA` px or more (with the slack); a blob of a few
# pixels fills its box by where the grid cuts it (a 1-2 px tip: 0.44-0.56, bench_user_chain radial-led-120).
_MIN_FILL = 0.6
# No blob closer than this many local pitches to a kept pin fills a hole (a split pin, a speck).
_APART = 0.6
# Rounds of prediction: by the judged pins, then by the pins taken back in the round before (a
# spoke crossing a reflection loses several pins in a row).
_ROUNDS = 4
# Sites lie at most `_BEYOND` local pitches farther from the disc centre than the farthest judged pin
# (`pins._sites`).
_BEYOND = 0.3
# Probing the image at the holes no blob filled (`probe_lattice_holes`): bare membrane passes for a tip
# at a hole with probability `_FALSE_ALARM` (the bar: `pins._tipprobe.threshold`, from the noise, not
# fitted); the tip's place is searched on a `_PROBE_STEP_PX` grid within the hole's tolerance, its
# shape taken from the `_PROBE_NEIGHBOURS` pins round it; the holes no farther than `_PROBE_BEYOND`
# pitches past the outermost pin (as for blobs, `_BEYOND`: the rim glare lies a pitch past it).
# A tip is painted and lit like the pins round it: its level within `_LEVEL_RANGE` of their median
# level. Chosen on seeds 0-2 of brown-127 and 0-23 of radial-led-120: skin highlights on brown-127
# stand at 0.63-0.77 of the pins' level round them (and pass the evidence bar: skin is no quadratic
# membrane), the pins found on radial-led-120 at 0.76-1.25 (three of 62 below 0.8 are lost).
_FALSE_ALARM = 1e-3
_PROBE_STEP_PX = 0.5
_PROBE_NEIGHBOURS = 6
_PROBE_BEYOND = 0.3
_LEVEL_RANGE = (0.8, 1.5)
# ... and it stands out from the membrane round it as this very image shows it: its evidence at least
# `_NULL_FACTOR` times the median evidence at the `_NULL_SITES` lattice interstices nearest it (the
# centroids of the triangles of neighbouring pins, where skin between the pins and its highlights are
# seen), each searched as a hole is (`_membrane_evidence`). On a membrane the quadratic-plus-noise
# model fits, that median is 0-9 (radial-led-120) and the false-alarm bar (15) rules; through a webcam
# (bench_user_chain: noise 4-8, MJPG) it is 5-12 (5-95 %) and this rules (no bar there tells the outer
# tips missed, evidence 8-14, from holes with no pin, 10-23: session 21's detect21); on a textured skin
# bare membrane passes the bar everywhere (brown-127 by its rim: medians 38-54). Over seeds 0-35
# of radial-led-120 the 97 pins found stand 3.0-9.4 (median) x above that median; the two skin
# highlights of brown-127 (seeds 0-23, seed 5 at rest and tapped) that pass the level band 1.47-1.54x.
_NULL_SITES = 6
_NULL_FACTOR = 2.0
_MOST_FOUND = 0.1


def fill_lattice_holes(kept: np.ndarray, kept_areas: np.ndarray, kept_contrasts: np.ndarray,
                       candidates: list, centre: tuple[float, float]) -> list[tuple[int, int]]:
    """The blobs of the candidate sets that fill holes of the lattice of `kept`.

    Parameters
    ----------
    kept : (N, 2) ndarray of float64
        The judged pins (x, y), px.
    kept_areas, kept_contrasts : (N,) ndarray
        Their areas (px) and contrasts (grey levels).
    candidates : list of (centres (M, 2), areas (M,), fills (M,), contrasts (M,), offset)
        The blobs of every candidate set, with the set's threshold offset.
    centre : (float, float)
        The sensor disc's centre (x, y), px: no hole lies farther from it than the farthest judged
        pin plus `_BEYOND` local pitches.

    Returns
    -------
    taken : list of (int, int)
        (candidate set, blob) of each blob taken back, at most one per hole.
    """
    if len(kept) < 7 or not candidates:
        return []
    owner = np.concatenate([np.full(len(c[0]), s) for s, c in enumerate(candidates)])
    index = np.concatenate([np.arange(len(c[0])) for c in candidates])
    if not len(owner):
        return []
    centres = np.concatenate([c[0] for c in candidates])
    areas = np.concatenate([c[1] for c in candidates]).astype(np.float64)
    fills = np.concatenate([c[2] for c in candidates]).astype(np.float64)
    contrasts = np.concatenate([c[3] for c in candidates]).astype(np.float64)
    offsets = np.concatenate([np.full(len(c[0]), float(c[4])) for c in candidates])
    field_reach = float(np.max(np.hypot(kept[:, 0] - centre[0], kept[:, 1] - centre[1])))
    pool = cKDTree(centres)
    pins, pin_areas, pin_contrasts = kept, kept_areas.astype(np.float64), kept_contrasts.astype(np.float64)
    taken: list[tuple[int, int]] = []
    used = np.zeros(len(centres), bool)
    first_new = len(pins)
    for round_ in range(_ROUNDS):
        hood = _Neighbourhood(pins)
        if hood.near.shape[1] < 3:
            break
        area_ref, contrast_ref = _row_median(np.stack([pin_areas, pin_contrasts])[:, hood.near])
        # Only the pins taken back in the round before predict anew.
        sites, tolerance, through = _holes(pins, hood, centre, field_reach, _BEYOND,
                                           fresh=first_new if round_ > 0 else None)
        if not len(sites):
            break
        new = []
        for site, reach, near_pin in zip(sites, tolerance, through):
            if len(new) and np.min(np.hypot(*(np.array([centres[i] for i in new]) - site).T)) <= reach:
                continue  # a hole already filled (predicted from several pins)
            found = np.array(pool.query_ball_point(site, reach), dtype=int)
            if not len(found):
                continue
            found = found[~used[found]]
            ref_area, ref_contrast = area_ref[near_pin] + _AREA_SLACK, contrast_ref[near_pin]
            ratio = (areas[found] + _AREA_SLACK) / ref_area
            good = found[(ratio >= _AREA_RANGE[0]) & (ratio <= _AREA_RANGE[1])
                         & (contrasts[found] >= _MIN_CONTRAST * ref_contrast)
                         & ((fills[found] >= _MIN_FILL) | (ref_area < _FILL_AREA))]
            if not len(good):
                continue
            # Apart from every pin (a split pin or a speck beside one is no hole's pin).
            apart = cKDTree(pins).query(centres[good])[0] >= _APART * hood.pitch[near_pin]
            good = good[apart]
            if not len(good):
                continue
            best = max(good, key=lambda i: (offsets[i], -np.hypot(*(centres[i] - site))))
            new.append(best)
            # The same blob found by other sets is used up with it.
            used[pool.query_ball_point(centres[best], 0.5 * reach)] = True
        if not new:
            break
        filled = np.array(new)
        taken += [(int(owner[i]), int(index[i])) for i in filled]
        first_new = len(pins)
        pins = np.vstack([pins, centres[filled]])
        pin_areas = np.append(pin_areas, areas[filled])
        pin_contrasts = np.append(pin_contrasts, contrasts[filled])
    return taken


def probe_lattice_holes(grey: np.ndarray, pins: np.ndarray, centre: tuple[float, float], radius_px: float, *,
                        disc_radius_px: float = np.inf, dark_pins: bool = False, with_prior: bool = False):
    """Pins at lattice holes that no blob filled, found by looking at the image there.

    A faint pin (the outermost ring under the veil and the rim glare, -11 to +16 grey from the membrane
    round it, noise sigma 5) makes a blob in no candidate set, or one too small to judge. At each hole
    of the lattice of `pins` (`_holes`, reaching no farther than the farthest pin plus `_PROBE_BEYOND`
    pitches; with the sites predicted towards the centre and the centre pin's, `_empty_zone`) the
    place within the hole's tolerance with the most evidence for an opaque tip shaped like the pins
    round it (`pins._tipprobe.tip_evidence`) is a pin when that evidence passes the bar for a
    false-alarm rate of `_FALSE_ALARM` per hole (set from the noise: `pins._tipprobe.threshold`), its
    level is within `_LEVEL_RANGE` of theirs, it lies inside the disc and no closer than
    `_APART` local pitches to a pin; it is placed where evidence and the lattice's prior agree best
    (`_placed_by_prior`). Pins found predict again, for `_ROUNDS` rounds at most. A field
    the probe would grow by more than `_MOST_FOUND` of its pins, or with more predicted sites than
    pins, gets none (it is no lattice with holes: the wrong polarity's field of a white-on-dark pad).

    Parameters
    ----------
    grey : (H, W) ndarray of uint8
        Grey frame.
    pins : (N, 2) ndarray
        The pins found so far (x, y), px.
    centre : (float, float)
        The sensor disc's centre (x, y), px.
    radius_px : float
        Pin tip radius, px.
    disc_radius_px : float
        The sensor disc's radius, px: a pin's tip and the membrane just round it (1.5 px beyond the
        tip) lie inside it; beyond it is the surround, no membrane, which the tip test does not fit
        (`pins._tipprobe.tip_evidence`'s ``disc``).
    dark_pins : bool
        Dark markers on a light membrane (the image is inverted).
    with_prior : bool
        Also return the lattice's prior for each pin found (for its tip fit, `pins._tipfit.fit_tip_centres`).

    Returns
    -------
    found : (M, 2) ndarray of float64
        The pins found at holes (x, y), px (a `_PROBE_STEP_PX` grid's point: the tip fit places them);
        empty (0, 2) when there are none, fewer than 7 pins, or no radius.
    prior : (M, 2) ndarray of float64, with `with_prior`
        Where the lattice puts each (x, y), px: the product of the priors of the links that predict its hole.
    sigma : (M,) ndarray of float64, with `with_prior`
        Its uncertainty per axis, px (inf: none, such as a radial layout's centre pin).

    Examples
    --------
    >>> import numpy as np
    >>> pitch = 10.0
    >>> grid = pitch * np.array([(x, y) for y in range(-4, 5) for x in range(-4, 5)], float) + 50.0
    >>> yy, xx = np.mgrid[0:100, 0:100]
    >>> image = np.full((100, 100), 100.0)
    >>> for x, y in grid:
    ...     image += 40.0 * (np.hypot(xx - x, yy - y) <= 2.0)
    >>> kept = np.delete(grid, 40, axis=0)  # the centre pin, at (50, 50), not found
    >>> probe_lattice_holes(image.astype(np.uint8), kept, (50.0, 50.0), 2.0).round(1)
    array([[50., 50.]])
    """
    pins = np.asarray(pins, dtype=np.float64).reshape(-1, 2)
    none = np.zeros((0, 2))
    if len(pins) < 7 or not (np.isfinite(radius_px) and radius_px > 0):
        return (none, none.copy(), np.zeros(0)) if with_prior else none
    image = grey.astype(np.float32)
    if dark_pins:
        image = 255.0 - image
    pins0 = pins
    disc = (float(centre[0]), float(centre[1]), float(disc_radius_px)) if np.isfinite(disc_radius_px) else None
    field_reach = float(np.max(np.hypot(pins[:, 0] - centre[0], pins[:, 1] - centre[1])))
    inner, hub = _empty_zone(pins, centre)
    taken: list[np.ndarray] = []
    priors: list[tuple[np.ndarray, np.ndarray]] = []
    fresh = None
    for round_ in range(_ROUNDS):
        hood = _Neighbourhood(pins)
        sites, tolerance, through = _holes(pins, hood, centre, field_reach, _PROBE_BEYOND, fresh=fresh, inward_beyond=inner)
        centre_pin = np.zeros(len(sites), bool)
        if round_ == 0 and hub is not None:
            sites = np.vstack([sites, hub[:2]])
            tolerance = np.append(tolerance, hub[2])
            through = np.append(through, int(cKDTree(pins).query(hub[:2])[1]))
            centre_pin = np.append(centre_pin, True)
        # A site nearer a pin than a pin's own neighbours are is that pin's (an irregular patch of lattice).
        far = cKDTree(pins).query(sites)[0] >= _APART * hood.pitch[through]
        sites, tolerance, through, centre_pin = sites[far], tolerance[far], through[far], centre_pin[far]
        if not len(sites):
            break
        if len(sites) > len(pins0):
            taken.clear()  # more predicted sites than pins: no lattice with holes
            break
        position, evidence, bar, level, typical_level, expected = _measure_holes(
            grey, image, pins, sites, tolerance, radius_px, disc)
        with np.errstate(invalid="ignore"):
            good = ((evidence >= bar) & (level >= _LEVEL_RANGE[0] * typical_level)
                    & (level <= _LEVEL_RANGE[1] * typical_level)
                    & (np.hypot(position[:, 0] - centre[0], position[:, 1] - centre[1])
                       <= disc_radius_px - radius_px - 1.5)
                    & (cKDTree(pins).query(position)[0] >= _APART * hood.pitch[through]))
        if good.any():  # measured only where a pin would be taken: 6 interstices per site cost
            good[good] = evidence[good] >= _NULL_FACTOR * _membrane_evidence(grey, image, pins, position[good],
                                                                             radius_px, disc)
        # One pin per hole (several links predict it): the strongest evidence first.
        found: list[int] = []
        for i in np.flatnonzero(good)[np.argsort(-evidence[good], kind="stable")]:
            if not found or np.min(np.hypot(*(position[found] - position[i]).T)) >= _APART * hood.pitch[through[i]]:
                found.append(int(i))
        if not found:
            break
        found = np.sort(found)
        # Placed where the image and the lattice agree best (`_placed_by_prior`): a faint tip's evidence
        # alone may peak a pixel off it. Every link that predicts a found pin's hole (its site within the
        # link's tolerance of the pin) gives a prior (`pins._sites.site_prior`); together, their product.
        predicts = np.hypot(*(sites[None] - position[found][:, None]).transpose(2, 0, 1)) <= tolerance[None]  # (F, S)
        each, each_spread = sites.copy(), np.full(len(sites), np.inf)
        asked = predicts.any(axis=0) & ~centre_pin  # (the centre pin's site: no link predicts it)
        each[asked], each_spread[asked] = site_prior(pins, sites[asked], through[asked], centre)
        weight = np.where(predicts, 1.0 / np.square(each_spread)[None], 0.0)
        total = weight.sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            prior = np.where(total[:, None] > 0, (weight @ each) / total[:, None], sites[found])
            spread = np.where(total > 0, 1.0 / np.sqrt(total), np.inf)
        place = _placed_by_prior(image, sites[found], tolerance[found], expected[found], pins, noise_sigma(grey),
                                 prior, spread, disc, position[found])
        priors.append((prior, spread))
        # The pins found predict in the next round (a spoke that lost two pins in a row).
        fresh = len(pins)
        taken.append(place)
        if sum(map(len, taken)) > _MOST_FOUND * len(pins0):
            break
        pins = np.vstack([pins, taken[-1]])
    # Holes are the exception in a lattice: a field the probe would grow by more than `_MOST_FOUND` of
    # its pins is no lattice with holes (the wrong polarity's field of a white-on-dark pad: 24 + 37).
    if not taken or sum(map(len, taken)) > _MOST_FOUND * len(pins0):
        return (none, none.copy(), np.zeros(0)) if with_prior else none
    found_all = np.vstack(taken)
    if not with_prior:
        return found_all
    return found_all, np.vstack([p for p, _ in priors[:len(taken)]]), np.concatenate([q for _, q in priors[:len(taken)]])


def _measure_holes(grey: np.ndarray, image: np.ndarray, pins: np.ndarray, sites: np.ndarray, tolerance: np.ndarray,
                   radius_px: float, disc=None):
    """The best place for a tip within each site's tolerance and what it shows (`pins._tipprobe`).

    The tip's expected shape at a site is the median ellipse of the `_PROBE_NEIGHBOURS` pins nearest it
    (`pins._tipfit.tip_shapes`); its place, the point of a 1 px grid within the tolerance with the
    most evidence, refined on a `_PROBE_STEP_PX` grid round it; the bar, the evidence bare membrane
    reaches with probability `_FALSE_ALARM` over the tip-sized cells of that disc.

    `disc` (cx, cy, radius) px, when given: no membrane beyond it (`pins._tipprobe.tip_evidence`).

    Returns
    -------
    position (S, 2) px, evidence (S,), bar (S,), the tip's level (S,) grey levels, and the median
    level (S,) of the pins round each site, measured the same way.
    """
    sigma = noise_sigma(grey)
    _, near = cKDTree(pins).query(sites, min(_PROBE_NEIGHBOURS, len(pins)))
    near = near.reshape(len(sites), -1)
    # Only the pins round the sites are fitted (a pad of 532 pins with 5 holes: 30 of them).
    used = np.unique(near)
    shapes = np.full((len(pins), 2, 2), np.nan)
    shapes[used] = tip_shapes(image, pins, radius_px, which=used)
    expected = np.median(shapes[near], axis=1)  # (S, 2, 2)
    # The best place on a 1 px grid within the tolerance, then on a `_PROBE_STEP_PX` grid round it.
    position, evidence, level = _best_place(image, sites, sites, tolerance, expected, pins, sigma, 1.0, tolerance, disc)
    position, evidence, level = _best_place(image, sites, position, tolerance, expected, pins, sigma,
                                            _PROBE_STEP_PX, np.full(len(sites), _PROBE_STEP_PX), disc)
    tip_area = np.pi * np.sqrt(np.linalg.det(expected))
    bar = threshold(_FALSE_ALARM, 1.0 + np.pi * tolerance ** 2 / tip_area)
    pin_level = np.full(len(pins), np.nan)
    pin_level[used] = tip_evidence(image, pins[used], shapes[used], pins, sigma, disc=disc)[1]
    with np.errstate(invalid="ignore"):
        typical_level = np.nanmedian(pin_level[near], axis=1)
    return position, evidence, bar, level, typical_level, expected


def _placed_by_prior(image, sites, tolerance, expected, pins, sigma, prior, spread, disc, place):
    """Where each tip found at a site is placed: the point within the site's tolerance (a 1 px grid, then
    `_PROBE_STEP_PX` round the best) with the most evidence less ``|x - prior|^2 / spread^2``.

    The evidence is twice the log-likelihood ratio of a tip there (`pins._tipprobe`); the lattice's
    prior (`pins._sites.site_prior`: a Gaussian of `spread` px per axis round `prior`) adds twice its
    log. On a faint tip (evidence 15-30, noise 5) the evidence of a place a pixel off may beat the
    truth's by a few units, which a prior 0.5 px wide outweighs; on a clear tip the evidence falls
    by tens of units a pixel off, and the prior moves it a few hundredths of a px. Where there is no
    prior (`spread` inf), `place` (the most evidence) as it was.
    """
    weight = np.where(np.isfinite(spread), 1.0 / np.maximum(spread, 1e-3) ** 2, 0.0)
    if not np.any(weight > 0):
        return place
    position, _, _ = _best_place(image, sites, sites, tolerance, expected, pins, sigma, 1.0, tolerance, disc,
                                 prior=(prior, weight))
    position, _, _ = _best_place(image, sites, position, tolerance, expected, pins, sigma, _PROBE_STEP_PX,
                                 np.full(len(sites), _PROBE_STEP_PX), disc, prior=(prior, weight))
    return np.where(weight[:, None] > 0, position, place)


def _membrane_evidence(grey: np.ndarray, image: np.ndarray, pins: np.ndarray, points: np.ndarray,
                       radius_px: float, disc=None) -> np.ndarray:
    """The median evidence for a tip that bare membrane gives round each point (P,): at the
    `_NULL_SITES` interstices of the lattice of `pins` nearest it (the centroids of the Delaunay
    triangles whose longest side is within 1.6 nearest-pin distances of a corner's), each searched
    within `_MIRROR` of the local pitch as a hole is (`_measure_holes`, with the same `disc`); 0 where there
    are too few."""
    nearest = cKDTree(pins).query(pins, 2)[0][:, 1]
    corners = Delaunay(pins).simplices
    side = np.hypot(*(pins[corners] - pins[np.roll(corners, 1, axis=1)]).transpose(2, 0, 1))
    centroids = pins[corners[side.max(axis=1) <= 1.6 * nearest[corners].max(axis=1)]].mean(axis=1)
    if len(centroids) < _NULL_SITES:
        return np.zeros(len(points))
    _, near = cKDTree(centroids).query(points, _NULL_SITES)
    used, back = np.unique(near, return_inverse=True)
    tolerance = _MIRROR * nearest[cKDTree(pins).query(centroids[used])[1]]
    evidence = _measure_holes(grey, image, pins, centroids[used], tolerance, radius_px, disc)[1]
    evidence = np.where(np.isfinite(evidence), evidence, 0.0)  # no membrane to fit: no evidence
    return np.median(evidence[back.reshape(near.shape)], axis=1)


def _best_place(image, sites, around, tolerance, expected, pins, sigma, step, reach, disc=None, prior=None):
    """Per site, the point of a `step` px grid within `reach` of `around` and `tolerance` of the site
    with the most tip evidence (no membrane beyond `disc`, when given): (points (S, 2) px, evidence (S,), the
    tip's level (S,) grey levels)."""
    half = np.ceil(reach.max() / step)
    steps = np.arange(-half, half + 1) * step
    gx, gy = (a.ravel() for a in np.meshgrid(steps, steps))
    candidates = around[:, None, :] + np.stack([gx, gy], axis=1)[None]  # (S, G, 2)
    within = ((np.hypot(gx, gy)[None] <= reach[:, None] + 1e-9)
              & (np.hypot(*(candidates - sites[:, None, :]).transpose(2, 0, 1)) <= tolerance[:, None] + 1e-9))
    within[:, np.argmin(np.hypot(gx, gy))] = True  # `around` itself, always
    owner, cell = np.nonzero(within)
    found, level, _ = tip_evidence(image, candidates[owner, cell], expected[owner], pins, sigma, disc=disc)
    score = np.full(within.shape, -np.inf)
    score[owner, cell] = np.nan_to_num(found, nan=-np.inf)
    if prior is not None:
        score -= prior[1][:, None] * np.sum((candidates - prior[0][:, None, :]) ** 2, axis=2)
    best = np.argmax(score, axis=1)
    pick = np.full(within.shape, -1)
    pick[owner, cell] = np.arange(len(owner))
    chosen = pick[np.arange(len(sites)), best]
    return candidates[np.arange(len(sites)), best], score[np.arange(len(sites)), best], level[chosen]
