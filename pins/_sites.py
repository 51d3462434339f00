"""Lattice sites the pins predict and none occupies: the holes `pins._rescue` fills and probes.

A hole is a lattice site the pins predict and none occupies: the mirror image of a pin through a
linked neighbour (the next pin along a radial spoke or a lattice row, the spoke's end included), with
no pin within `pins._judge._MIRROR` of the link length, and either predicted from opposite sides
(inside the lattice) or predicted once, outward from the disc centre (the outer end of a lone row,
such as a radial spoke: not the next row of a hexagonal lattice, predicted twice from one side, nor
the inner end of a spoke, which points into the empty zone round the lone centre pin). Links are
about one pitch long (at most `_SHORT_LINK` local pitches), and no site lies farther from the disc
centre than the outermost pin plus a few tenths of a pitch (the caller's ``beyond``), so that no chain
reaches the glare on the rim. A gap in a curved row (a radial layout's innermost ring, where a mirror
image through a neighbour misses the next site by 0.4 pitch) is a hole too when two pins within a pitch
flank it on opposite sides. Where the image is probed (`pins._rescue.probe_lattice_holes`) a site
predicted towards the centre is a hole too, unless it lies in the empty zone round a radial layout's
centre pin (`_empty_zone`), whose own site is a hole when the ring round it is whole and it is missing.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ._judge import _MIRROR, _Neighbourhood

# Links that predict a site are at most this many local pitches long.
_SHORT_LINK = 1.3
# Two predictions of a site come from opposite sides when their directions' cosine is below this.
_OPPOSITE = -0.5
# The outer end of a lone row has one pin (the row's) within this many link lengths.
_LONE = 1.3
# At most this many pins lie within `_LONE` link lengths of a site.
_CLOSE_PINS = 8
# A radial layout's centre pin is a site when at least this many pins ring it within this fraction
# of one radius (`_empty_zone`).
_HUB_RING = 5
_HUB_SPREAD = 0.25
# A site's prior (`site_prior`): from the `_PRIOR_PINS` pins nearest it predicted by links like its own
# (turned from the radial direction by at most `_PRIOR_TURN` rad more or less); none from fewer than
# `_PRIOR_LEAST`.
_PRIOR_PINS = 6
_PRIOR_TURN = np.deg2rad(20.0)
_PRIOR_LEAST = 3
# ... and no surer than this, px per axis (a drawn lattice with no scatter: the pins' own places are
# measured no better than about a tenth of a px).
_PRIOR_FLOOR_PX = 0.1


def _holes(pins: np.ndarray, hood: _Neighbourhood, centre: tuple[float, float], field_reach: float, beyond: float,
           fresh: int | None = None, inward_beyond: float = np.inf) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The lattice sites `pins` predict and none occupies (the module docstring).

    Parameters
    ----------
    pins : (N, 2) ndarray of float64
        The pins (x, y), px; `hood` is their `_Neighbourhood`.
    centre : (float, float)
        The sensor disc's centre (x, y), px.
    field_reach : float
        Distance from `centre` of the farthest pin that may predict, px: no site lies farther than
        this plus `beyond` local pitches.
    fresh : int or None
        Only links with a pin of index `fresh` or more predict (the pins taken back in the round before).

    Returns
    -------
    sites : (H, 2) ndarray of float64
        Predicted sites (x, y), px, one per prediction (a hole predicted from several pins appears
        several times).
    tolerance : (H,) ndarray of float64
        How far from its site a hole's pin may lie, px (`_MIRROR` of the link length).
    through : (H,) ndarray of int
        The pin next to each site (the one the link runs through).
    """
    empty = np.zeros((0, 2)), np.zeros(0), np.zeros(0, dtype=int)
    k = hood.near.shape[1] - 1
    if k < 2:
        return empty
    source = np.repeat(np.arange(len(pins)), k)
    through = hood.near[:, 1:].ravel()
    length = hood.dist[:, 1:].ravel()
    # Links about a pitch long (not the long links of a radial layout's lone centre pin).
    link = hood.link.ravel() & (length <= _SHORT_LINK * hood.pitch[source])
    if fresh is not None:
        link &= (source >= fresh) | (through >= fresh)
    source, through, length = source[link], through[link], length[link]
    sites = 2.0 * pins[through] - pins[source]
    tolerance = _MIRROR * length
    # Never beyond the field: glare on the rim lies a pitch past the outermost pins, the next row
    # of a hexagonal lattice 0.87 pitch past the judged pins' hull, the end of a radial spoke whose
    # outermost pin is missing about half a pitch past it.
    inside = np.hypot(sites[:, 0] - centre[0], sites[:, 1] - centre[1]) <= field_reach + beyond * hood.pitch[through]
    sites, tolerance, through = sites[inside], tolerance[inside], through[inside]
    if not len(sites):
        return empty
    # Holes: sites no pin occupies.
    tree = cKDTree(pins)
    hole = tree.query(sites)[0] > tolerance
    sites, tolerance, through = sites[hole], tolerance[hole], through[hole]
    if not len(sites):
        return empty
    # A hole inside the lattice has pins on opposite sides along a row (predicted from both
    # directions, or with a pin beyond it); the outer end of a lone row (a radial spoke whose rim pin
    # is under the veil) is predicted once, from inside. Not the next row of a hexagonal lattice
    # (predicted twice, from one side: skin and glare beyond the field), nor the inner end of a radial
    # spoke (the empty zone round the lone centre pin).
    ahead = sites - pins[through]
    ahead /= np.maximum(np.hypot(*ahead.T), 1e-9)[:, None]
    groups = cKDTree(sites).query_ball_point(sites, tolerance)
    predictions = np.array([len(g) for g in groups])
    opposite = np.array([np.min(ahead[g] @ ahead[i]) < _OPPOSITE for i, g in enumerate(groups)])
    # ... or a pin beyond it along the row (the next one, whose own predictor is missing).
    opposite |= tree.query(2.0 * sites - pins[through])[0] <= tolerance
    outward = (np.hypot(sites[:, 0] - centre[0], sites[:, 1] - centre[1])
               > np.hypot(pins[through, 0] - centre[0], pins[through, 1] - centre[1]))
    # A lone row's end has one pin within a pitch (the next along the row); the next row of a
    # hexagonal lattice has two.
    k = min(_CLOSE_PINS, len(pins))
    gap, close = tree.query(sites, k, distance_upper_bound=float(np.max(_LONE * tolerance / _MIRROR)))
    gap, close = gap.reshape(len(sites), k), close.reshape(len(sites), k)
    within = gap <= (_LONE * tolerance / _MIRROR)[:, None]
    lone = within.sum(axis=1) == 1
    # A gap in a curved row (a radial layout's innermost ring, whose mirror images through a
    # neighbour miss the next site by 0.4 pitch): two pins within a pitch, on opposite sides.
    unit = (pins[np.minimum(close, len(pins) - 1)] - sites[:, None]) / np.maximum(gap, 1e-9)[..., None]
    cosine = np.where(within[:, :, None] & within[:, None, :], unit @ unit.transpose(0, 2, 1), 1.0)
    flanked = cosine.min(axis=(1, 2)) < _OPPOSITE
    plausible = opposite | flanked | ((predictions == 1) & outward & lone)
    # ... or, where its image is looked at (`probe_lattice_holes`), a site predicted towards the
    # centre from outside, not in the empty zone round a radial layout's centre pin (two pins lost in
    # a row along a spoke, a gap in the innermost ring).
    plausible |= ~outward & (np.hypot(sites[:, 0] - centre[0], sites[:, 1] - centre[1]) >= inward_beyond)
    return sites[plausible], tolerance[plausible], through[plausible]


def _empty_zone(pins: np.ndarray, centre: tuple[float, float]) -> tuple[float, np.ndarray | None]:
    """The empty zone round a radial layout's lone centre pin, and the centre pin's site if it is missing.

    A radial layout's spokes start a ring away from the centre: their inner ends point into an empty
    zone, where no site lies. Its radius is that of the innermost ring (the pins nearest the disc
    centre but for the centre pin, within half a pitch of it) less half a pitch. When the pins
    nearest the centre form a ring round it (at least `_HUB_RING` of them within `_HUB_SPREAD` of
    one radius, no gap between them wider than a third of the turn) and none sits at their centroid,
    the centre pin's site is that centroid (its tolerance `_MIRROR` of the ring's radius... at most
    a pitch's). A hexagonal lattice has pins at every radius: no zone (0) and no such site.

    Returns
    -------
    inward_beyond : float
        Sites predicted towards the centre lie farther from `centre` than this, px.
    hub : (3,) ndarray or None
        The missing centre pin's site (x, y) and tolerance, px.
    """
    offset = pins - np.asarray(centre, dtype=np.float64)
    radius = np.hypot(*offset.T)
    pitch = float(np.median(cKDTree(pins).query(pins, 2)[0][:, 1]))
    ring = np.sort(radius[radius > 0.5 * pitch])
    if not len(ring):
        return 0.0, None
    inner = float(ring[0])
    within = (radius > 0.5 * pitch) & (radius <= (1.0 + _HUB_SPREAD) * inner)
    hub = None
    if within.sum() >= _HUB_RING and inner > 1.5 * pitch:
        angles = np.sort(np.arctan2(offset[within, 1], offset[within, 0]))
        gaps = np.diff(np.append(angles, angles[0] + 2.0 * np.pi))
        site = pins[within].mean(axis=0)
        if gaps.max() <= 2.0 * np.pi / 3.0 and cKDTree(pins).query(site)[0] > 0.5 * inner:
            hub = np.array([site[0], site[1], _MIRROR * min(inner, pitch)])
    return max(inner - 0.5 * pitch, 0.0), hub


def site_prior(pins: np.ndarray, sites: np.ndarray, through: np.ndarray, centre: tuple[float, float]
               ) -> tuple[np.ndarray, np.ndarray]:
    """Where the lattice puts each hole's pin, and how sure it is: the mirror site corrected by how the
    same prediction misses the pins that are there.

    A site is the mirror image ``2 t - s`` of a pin `s` through its neighbour `t` (`_holes`). On a dome
    the pitch shrinks towards the rim (foreshortening) and rows curve, and pins sit a little off their
    ideal places: the mirror site of a radial spoke's outer end lies 0.77 px (median) from its pin on
    ``radial-led-120``. The pins that are there show how such a prediction misses: each pin `p` that is
    the mirror of a neighbour's neighbour (``p ~ 2 t - s`` within `pins._judge._MIRROR` of the link) has
    a residual ``p - (2 t - s)``, in its link's frame (along and across ``t - s``, in link lengths). The
    `_PRIOR_PINS` such pins nearest a site whose links are like its own (about as far from `centre`,
    within half a link; pointing the same way relative to the radial direction, within
    `_PRIOR_TURN`; 0.7-1.4 times as long) give the correction (their median residual) and the
    uncertainty (their scatter about it, plus the median's own, per axis).

    Parameters
    ----------
    pins : (N, 2) ndarray
        The pins (x, y), px.
    sites : (S, 2) ndarray
        Mirror sites ``2 pins[through] - pins[source]`` (x, y), px.
    through : (S,) ndarray of int
        The pin each site's link runs through.
    centre : (float, float)
        The sensor disc's centre (x, y), px.

    Returns
    -------
    prior : (S, 2) ndarray of float64
        The corrected sites (x, y), px.
    sigma : (S,) ndarray of float64
        Their uncertainty per axis, px (at least `_PRIOR_FLOOR_PX`); inf where fewer than `_PRIOR_LEAST`
        pins are like it (no prior).
    """
    pins = np.asarray(pins, dtype=np.float64).reshape(-1, 2)
    sites = np.asarray(sites, dtype=np.float64).reshape(-1, 2)
    prior, sigma = sites.copy(), np.full(len(sites), np.inf)
    k = min(7, len(pins))
    if not len(sites) or k < 3:
        return prior, sigma
    centre = np.asarray(centre, dtype=np.float64)
    tree = cKDTree(pins)
    # Every chain s -> t -> p among the pins: p's neighbour t, and s the pin nearest the mirror of p through t.
    _, near = tree.query(pins, k)
    p = np.repeat(np.arange(len(pins)), k - 1)
    t = near[:, 1:].ravel()
    mirror = 2.0 * pins[t] - pins[p]
    gap, s = tree.query(mirror)
    link = np.hypot(*(pins[t] - pins[p]).T)
    chain = (gap <= _MIRROR * link) & (s != p) & (s != t)
    p, t, s = p[chain], t[chain], s[chain]
    residual = pins[s] - mirror[chain]  # p - (2 t - s)
    chain_frame = _link_frame(pins[s], pins[t], centre)
    chain_radius = np.hypot(*(pins[p] - centre).T)
    # Each site's own link.
    source = 2.0 * pins[through] - sites
    step, turn, length = _link_frame(source, pins[through], centre)
    radius = np.hypot(*(sites - centre).T)
    c_step, c_turn, c_length = chain_frame
    unit = c_step / c_length[:, None]
    along = np.sum(residual * unit, axis=1) / c_length
    across = (unit[:, 0] * residual[:, 1] - unit[:, 1] * residual[:, 0]) / c_length
    like = ((np.abs(chain_radius[None] - radius[:, None]) <= 0.5 * length[:, None])
            & (np.abs(np.angle(np.exp(1j * (c_turn[None] - turn[:, None])))) <= _PRIOR_TURN)
            & (c_length[None] >= 0.7 * length[:, None]) & (c_length[None] <= 1.4 * length[:, None]))
    distance = np.hypot(*(pins[p][None] - sites[:, None]).transpose(2, 0, 1))
    distance = np.where(like, distance, np.inf)
    order = np.argsort(distance, axis=1)[:, :_PRIOR_PINS]
    counted = np.isfinite(np.take_along_axis(distance, order, axis=1))
    for i in np.flatnonzero(counted.sum(axis=1) >= _PRIOR_LEAST):
        chosen = order[i][counted[i]]
        offsets = np.column_stack([along[chosen], across[chosen]]) * length[i]  # px, in the site's link frame
        middle = np.median(offsets, axis=0)
        u = step[i] / length[i]
        prior[i] = sites[i] + middle[0] * u + middle[1] * np.array([-u[1], u[0]])
        # Per axis: their scatter about their median (over n - 1: the median is fitted to them), and the
        # median's own variance (pi / 2n of theirs).
        spread = np.sum((offsets - middle) ** 2) / (2.0 * (len(chosen) - 1))
        sigma[i] = max(np.sqrt(spread * (1.0 + np.pi / (2.0 * len(chosen)))), _PRIOR_FLOOR_PX)
    return prior, sigma


def _link_frame(source: np.ndarray, through: np.ndarray, centre: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Links ``through - source`` (L, 2) px, their turn from the radial direction at `through` (L,) rad,
    and their lengths (L,) px."""
    step = through - source
    outward = through - centre
    turn = np.arctan2(step[:, 1], step[:, 0]) - np.arctan2(outward[:, 1], outward[:, 0])
    return step, turn, np.hypot(*step.T)
