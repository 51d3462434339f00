"""The pin field: the blobs that form the pin lattice, told apart from everything else.

A TacTip frame shows more bright blobs than pins: LED glare and its reflections on a black rim
ring, specks of dust, light patches of skin between the shadows of the pins, skin texture. What
makes a pin a pin is that it belongs to the lattice: it sits at a lattice site, with neighbours at
the lattice pitch, and its size, contrast and sharpness are like its neighbours'. `find_pin_field`
finds that lattice without being told the pin count:

0. the search region: the sensor disc (or the whole frame, `pins.frame_region`, for a flat gel
   whose markers fill the view: see below), or, when a black rim ring (the casing lip) lies between
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
   offsets of 5-25 grey levels, each at least two standard deviations of the camera's noise after
   the candidate's blur, the noise read also on 2 x 2 block means, which JPEG leaves: a noisy camera's
   low offsets make a lattice of noise blobs);
3. lattice consistency, per candidate set, iterated until nothing changes (removing an impostor
   changes its neighbours' statistics), each blob against the medians of its six nearest
   neighbours: ``size`` when its area is below 0.4 or above 2.2 of theirs (or its box poorly
   filled); ``contrast`` when fainter than half of theirs, or with edges much softer (glare and
   patches of skin are smooth, pin tips are discs with a sharp edge; the casing's blurred edge
   next to a blob by the rim is not its edge); ``off lattice`` when within
   0.6 local pitches of a stronger blob (a speck, a light patch between pins), or when it sits at no
   lattice site and does not look just like its neighbours, or when it lies beyond the outer ring,
   linked to the field only from inside and from two directions, with less than 0.8 of its
   neighbours' contrast (a skin highlight the casing's glare brightens on a ring with no pins;
   `pins._judge`). A lattice site is found by mirror
   images: a pin is the mirror of a neighbour through another neighbour (six times for interior
   pins, at least once at the rim or at the end of a radial spoke), and a blob midway between two
   neighbours counts that line once (a reflection between two diverging radial spokes is not
   anchored twice by one pair). The local pitch is the median
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
   (those keeping 97 % of the most pins, or else the two keeping the most: one set's own blobs, such
   as the noise blobs only the lowest offset lets through, are no agreement; both when there are two)
   also keep, and the fewest others, its centres nearest their consensus;
5b. holes: a lattice site the winner's pins predict (a mirror image through a neighbour) from both
   sides, or once outward at the end of a lone row such as a radial spoke, that no pin occupies is
   filled with a pin-like blob another candidate set found there (`pins._rescue`): one threshold
   cannot suit every pin of a pad whose light varies, and a pin on an LED reflection inside the pad
   (a brighter background, less contrast) or a faint spoke end under the veil is lost by the
   winner's and found by another's; a kept pin whose core stands no higher than a quadratic fit of
   the membrane round it (an LED reflection's flat top; the surround beyond the disc is no membrane) is
   rejected (``contrast``), and at the holes
   still left (not on a flat gel) the image itself is probed for a faint tip;
5c. centres: each kept pin is placed by fitting its tip as an opaque ellipse over a quadratic
   background (`pins._tipfit`): the blobs' centroids lean towards the bright side of a sloped
   membrane (a reflection's flank, the veil, shading) by up to 0.7 px on small tips; a faint tip
   found by probing a hole also weighs where the lattice puts it (`pins._rescue`, `pins._sites.site_prior`);
6. later frames: `PinField.params` are those of the highest offset that keeps (nearly) the same
   pins (it keeps pins pushed together by a contact apart), with the kept pins' area range and a
   rim margin that leaves out the membrane half a pitch beyond the outermost pin and the rim
   ring, so that the per-frame fast path `pins.detect_pins(frame, params=field.params,
   disc=field.disc)` does not detect the rim ring and its glare again.

The polarity (bright pins on a dark membrane, or dark markers on a light one) is decided the same way
when it is not given: both are searched (each inside its own sensor disc) and the one whose lattice
keeps more pins wins (a polarity without a disc of its own, white pins on a dark membrane in a dark
casing, is searched in the other's disc when that one's lattice is small, sparse, or outnumbered at
its own pitch by one candidate set of the other polarity: under a tap the pressed white pins darken
and with the gaps between the others make a dark lattice at the pins' pitch); a frame where neither
keeps `MIN_SENSOR_PINS` shows no sensor (`NoSensorError`, saying why for each). `tactip detect` and `tactip replay` both decide so.

Sensors without a disc (a flat gel such as GelSight's: dark markers on a rectangular grid filling the
frame, on a colour gradient, no casing). When neither polarity shows a sensor disc, or the pins go on
beyond the disc found (pin-like blobs with the field's parameters beyond its circle: a gradient
across a gel can pass for a disc; a TacTip's casing holds none), both polarities are searched over
the whole frame (`pins.frame_region`, a `SensorDisc` with ``whole_frame=True`` that every caller
takes as a disc) and the one whose lattice stands out more (pins x their median contrast: the noise
of a bright gel makes a fine, faint lattice of its own) competes with the disc's by pin count. A
forced polarity with no disc is searched over the whole frame when the other polarity shows no disc
either. Over the whole frame, a sensor's pins must lie on a regular lattice: the median ratio of each
pin's second- to first-nearest-neighbour distance at most 1.15 (a gel's grid, pressed or sheared:
1.00-1.08; blobs of camera noise that pass the lattice judgement: 1.19-1.28). Steps 1-5 are the same: a square grid is a lattice of mirror images as hexagons are. Markers
cut by the frame's edge lean inwards (1.7 px for one cut through its centre): a pin whose disc (the
pins' radius from their mean radial profile, plus half a px of edge) reaches more than half a px
beyond the frame is left out (``outside field``), so those kept are measured within about 0.1 px.

A known pin count does not steer the search: it is compared with the result (`count_error`).
`draw_pin_field` pictures what was kept and what was rejected, coloured by reason.
The candidate parameter sets of steps 1, 2, 5 and 6 are generated, run, voted on and narrowed in
`pins._candidates`; the lattice judgement of steps 3 and 4 is `pins._judge`'s.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.spatial import cKDTree

from ._draw import draw_pin_field
from ._field import PinField
from ._exposure import exposure_warnings
from ._rescue import fill_lattice_holes, probe_lattice_holes
from ._tipfit import fit_tip_centres
from ._tipprobe import flat_pins
from ._candidates import (_MATCH, _SharedCache, _candidates, _consensus, _distinct, _evaluate_all, _final_params,
                          _keeps_more, _noise_floored, _strongest)
from ._judge import REJECTION_REASONS
from .detect import DetectionParams
from .disc import _RING_INSET_PX, SensorDisc, _rim_ring_inner_px, as_grey, find_sensor_disc, frame_region
from ._flat import _cut_by_frame, _irregular, _irregular_beyond, _median_contrast, _pin_radius_px, _spills_over
from .errors import NoSensorError
from .scale import central_spacing_px

__all__ = ["PinField", "find_pin_field", "REJECTION_REASONS", "draw_pin_field", "MIN_SENSOR_PINS"]

#: Fewest pins of a pin lattice that make a sensor when the polarity is decided
#: (`find_pin_field` with ``dark_pins=None``): TacTips have 100-1000 pins, and a rest frame shows
#: most of them; a handful of blobs of the other polarity (glare, the membrane between the pins)
#: is no sensor.
MIN_SENSOR_PINS = 40
_POLARITIES = {False: "bright pins on a dark membrane", True: "dark markers on a light membrane"}
# A polarity whose lattice fills less than `_SPARSE` of its disc's lattice sites, when the other
# polarity shows no disc, has the other searched in its disc grown by `_BORROW`.
_SPARSE = 0.2
_BORROW = 1.25


# Possible pin pitches, as fractions of the disc radius (1000 pins on a hexagonal lattice filling
# the disc: 0.06; 100 pins: 0.19; radial layouts and small pads between).
_PITCH_FRACTIONS = (0.05, 0.075, 0.11, 0.165, 0.25)
_BLOCK_PITCHES = (1.0, 1.5, 2.2)
_OFFSETS = (5.0, 9.0, 15.0, 25.0)
_COARSE_BLOCK = (2.2,)
_COARSE_OFFSETS = (9.0,)
# Candidate sets keep 'the same pins' within this fraction (a pin matches within `_MATCH` pitches).
_SAME_PINS = 0.005


def find_pin_field(frame: np.ndarray, *, expected_pins: int | None = None, params: DetectionParams | None = None,
                   disc: SensorDisc | None = None, dark_pins: bool | None = None) -> PinField:
    """Find the pins of a frame as the blobs that form the pin lattice, without knowing their count.

    Parameters
    ----------
    frame : (H, W) or (H, W, 3) ndarray of uint8
        Grey or BGR frame, best a rest frame (nothing touching the pad).
    expected_pins : int, optional
        The sensor's pin count: checked against the result (`PinField.count_error`), never used
        to steer the search.
    params : DetectionParams, optional
        Starting parameters: tried among the candidates; their polarity is kept (unless
        `dark_pins` says otherwise), and their rim margin at least (`PinField.params` widens it to
        leave out the membrane beyond the field).
    disc : SensorDisc, optional
        The membrane disc, found with `find_sensor_disc` when not given.
    dark_pins : bool, optional
        True: dark markers on a light membrane; False: bright pins on a dark membrane. None (the
        default, and without `params`): decided from the frame, as `tactip detect` and `tactip
        replay` do: both polarities are searched (those whose sensor disc `find_sensor_disc`
        finds, when `disc` is not given) and the one whose pin lattice keeps more pins wins; when
        only one polarity shows a disc and its lattice is no sensor's or fills little of it (the
        dark gaps between white pins in a dark casing), the other is searched in that disc too; a
        frame where neither forms a lattice of at least `MIN_SENSOR_PINS` pins shows no sensor.
        With `params` and no `dark_pins`, ``params.dark_pins`` is the polarity.

    Returns
    -------
    field : PinField
        ``field.params.dark_pins`` is the polarity searched (or decided); ``field.warnings`` says what in
        the frame may have hidden pins (a saturated pad, faint or small tips: `pins._exposure`).

    Raises
    ------
    NoSensorError
        When `disc` is not given and the frame shows no sensor disc of the polarity asked while the
        other polarity shows one, or neither shows one and no lattice of at least `MIN_SENSOR_PINS`
        pins fills the frame; or when deciding and no polarity forms a pin lattice of at least
        `MIN_SENSOR_PINS` pins, in a disc or over the whole frame. The message says why for each.
    ValueError
        `expected_pins` is not a positive integer.

    Examples
    --------
    >>> from tactip.sim import SyntheticTacTip
    >>> sensor = SyntheticTacTip(pins=331, seed=0)
    >>> field = find_pin_field(sensor.render().image)
    >>> 300 <= field.count <= 331, round(field.pitch_px)
    (True, 19)

    Later frames are detected fast with the field's parameters and region:

    >>> from pins import detect_pins
    >>> pins = detect_pins(sensor.render().image, params=field.params, disc=field.disc)
    """
    if expected_pins is not None and (isinstance(expected_pins, bool) or int(expected_pins) != expected_pins
                                      or expected_pins < 1):
        raise ValueError(f"expected_pins must be a positive integer, got {expected_pins!r}")
    grey = as_grey(frame)
    field = _find(grey, expected_pins, params, disc, dark_pins)
    return dataclasses.replace(field, warnings=exposure_warnings(grey, field))


def _find(grey: np.ndarray, expected_pins: int | None, params: DetectionParams | None, disc: SensorDisc | None,
          dark_pins: bool | None) -> PinField:
    """`find_pin_field` on a grey frame, without its warnings."""
    start = params or DetectionParams()
    if dark_pins is None and params is None:
        return _decide_polarity(grey, start, disc, expected_pins)
    if dark_pins is not None:
        start = start.replace(dark_pins=bool(dark_pins))
    if disc is not None:
        return _search(grey, disc, start, params is not None, expected_pins)
    try:
        disc = find_sensor_disc(grey, dark_pins=start.dark_pins)
    except NoSensorError as exc:
        # No disc of this polarity: a flat gel fills the frame when the other polarity shows none
        # either; a pad of the other polarity means these markers are not there, but for the case below.
        try:
            find_sensor_disc(grey, dark_pins=not start.dark_pins)
        except NoSensorError:
            field = _search(grey, frame_region(grey.shape), start, params is not None, expected_pins)
            if field.count >= MIN_SENSOR_PINS and not _irregular(field):
                return field
            raise NoSensorError(f"{exc}; nor a pin lattice filling the frame ({field.count} pins"
                                + (", not on a regular lattice" if field.count >= MIN_SENSOR_PINS else
                                   f", need {MIN_SENSOR_PINS}") + ")") from None
        if params is None:
            # White pins on a dark membrane in a dark casing frame no disc of their own: the polarity
            # decided as `_decide_polarity` decides it (in the other's disc, grown) is searched as
            # asked when it is this one; a pad of the other polarity refuses these markers.
            decided = _decide_polarity(grey, start, None, expected_pins)
            if decided.params.dark_pins == start.dark_pins:
                return decided
        raise
    return _search(grey, disc, start, params is not None, expected_pins)


def _decide_polarity(grey: np.ndarray, start: DetectionParams, disc: SensorDisc | None,
                     expected_pins: int | None) -> PinField:
    """The pin field of the polarity whose lattice keeps more pins; NoSensorError when neither
    polarity shows a sensor disc and a lattice of at least `MIN_SENSOR_PINS` pins.

    On a frame of either polarity the other one's disc is usually refused (the inverted surround
    is no disc), and where it is not, its blobs (the membrane between the pins, glare) form a
    lattice of far fewer pins, or none.
    """
    fields: list[PinField] = []
    why: list[str] = []
    for dark, name in ((False, _POLARITIES[False]), (True, _POLARITIES[True])):
        try:
            found = disc if disc is not None else find_sensor_disc(grey, dark_pins=dark)
        except NoSensorError as exc:
            why.append(f"{name}: {exc}")
            continue
        field = _search(grey, found, start.replace(dark_pins=dark), False, expected_pins)
        fields.append(field)
        why.append(f"{name}: {field.count} pins form a lattice")
    if len(fields) == 1 and disc is None and (fields[0].count < MIN_SENSOR_PINS or _sparse(fields[0])
                                              or _other_keeps_more(grey, fields[0], start)):
        # No disc of the other polarity (white pins on a dark membrane in a dark casing: no bright
        # surround frames the pad), and this one's lattice is no sensor's, fills little of its disc
        # (the dark gaps between white pins), or is outnumbered by the other polarity's at its own
        # pitch (white pins darkened by a tap form a patch of dark lattice among the gaps): the other
        # polarity is searched in this disc, grown.
        found = fields[0]
        other = not found.params.dark_pins
        grown = SensorDisc(found.disc.cx, found.disc.cy, _BORROW * found.disc.radius_px)
        field = _search(grey, grown, start.replace(dark_pins=other), False, expected_pins)
        if _irregular(field):
            # Borrowed, the disc frames no sensor of this polarity: on a bright-pin TacTip showing a
            # dozen pins, 58-154 specks of the dark membrane's noise passed the lattice judgement
            # (median second- over first-neighbour distance 1.32-1.40; white-dark-331's pins, at rest
            # and tapped: 1.02-1.06).
            why.append(f"{_POLARITIES[other]} in the other's disc: {field.count} blobs, but not on a regular lattice")
        else:
            fields.append(field)
            why.append(f"{_POLARITIES[other]} in the other's disc: {field.count} pins form a lattice")
    if disc is None and (not fields or _spills_over(grey, max(fields, key=lambda f: f.count))):
        # Neither polarity shows a disc, or the pins go on beyond the one found (a gradient across a
        # flat gel can pass for a disc): a flat gel whose markers fill the frame (no casing round
        # them) is searched over the whole frame, in both polarities.
        # Without a membrane's level to tell them apart, the polarity is the one whose lattice stands
        # out more (pins x their contrast): the noise of a bright gel forms a fine, faint lattice
        # of its own.
        region = frame_region(grey.shape)
        signal, in_disc = {}, max(fields, key=lambda f: f.count, default=None)
        for dark, name in ((False, _POLARITIES[False]), (True, _POLARITIES[True])):
            field = _search(grey, region, start.replace(dark_pins=dark), False, expected_pins)
            if _irregular(field) or (in_disc is not None and _irregular_beyond(field, in_disc)):
                why.append(f"{name} over the whole frame: {field.count} blobs, but not on a regular lattice")
                continue
            fields.append(field)
            signal[id(field)] = field.count * _median_contrast(grey, field)
            why.append(f"{name} over the whole frame: {field.count} pins form a lattice")
        if signal:
            whole = max((f for f in fields if id(f) in signal), key=lambda f: signal[id(f)])
            fields = [f for f in fields if id(f) not in signal] + [whole]
    best = max(fields, key=lambda f: f.count, default=None)
    if best is None or best.count < MIN_SENSOR_PINS:
        raise NoSensorError(f"no sensor in the frame: no pin lattice of at least {MIN_SENSOR_PINS} pins ("
                            + "; ".join(why) + ")")
    return best


def _other_keeps_more(grey: np.ndarray, field: PinField, start: DetectionParams) -> bool:
    """Whether one candidate set of the other polarity, at `field`'s pitch in its disc, keeps more
    lattice pins than `field` (one detection, a twentieth of a search).

    A lattice of one polarity that is really the other's (the gaps between white pins on a dark
    membrane, and the pins a tap darkens) is outnumbered there by the other's pins; a sensor's own
    lattice is not (the gaps between its pins and its glare, at its pitch, keep at most about 3/4 as
    many on every preset, at rest and tapped).
    """
    if field.count < 2 or not np.isfinite(field.pitch_px):
        return False
    other = start.replace(dark_pins=not field.params.dark_pins)
    # At the field's pitch, and at the pitch of the hexagonal lattice whose triangles' centres the
    # field's blobs would be (the gaps between pins lie 1/sqrt(3) pitch apart): on white-dark-331
    # filmed at 1920x1080 (tips of 13 px) a probe at the gaps' pitch, its blur and block too small for
    # the pins, kept 81 of them and the gaps (177 of them) won; at sqrt(3) of it, 331.
    cache: dict = {}
    for pitch in (field.pitch_px, np.sqrt(3.0) * field.pitch_px):
        probe = next(_candidates(np.array([pitch]), other, _COARSE_BLOCK, _COARSE_OFFSETS))
        # Touching blobs are not split: the other polarity's pins stand apart, and splitting the
        # network of a membrane seen the wrong way round costs more than the rest of the probe.
        probe = probe.replace(split_radius_px=0.0)
        if _keeps_more(grey, field.disc, probe, cache, field.count):
            return True
    return False


def _sparse(field: PinField) -> bool:
    """Whether a pin field fills less than `_SPARSE` of its disc with lattice sites (a hexagonal
    lattice at its pitch): radial layouts fill about a third, the gaps between another polarity's
    pins far less."""
    if field.count < 2 or not np.isfinite(field.pitch_px):
        return True
    sites = np.pi * field.field_disc.radius_px ** 2 / (0.866 * field.pitch_px ** 2)
    return field.count < _SPARSE * sites


def _search(grey: np.ndarray, disc: SensorDisc, start: DetectionParams, hinted: bool,
            expected_pins: int | None) -> PinField:
    """The pin field of one polarity (``start.dark_pins``) inside `disc`; `start` is a candidate when `hinted`."""
    # The possible pitches scale with the sensor disc; the search stops at a black rim ring, which,
    # like the surround, must neither make blobs (its glare) nor darken the threshold's
    # neighbourhood means (the membrane along its edge would pass for pins).
    pitches = disc.radius_px * np.array(_PITCH_FRACTIONS)
    ring = np.inf if disc.whole_frame else _rim_ring_inner_px(grey, disc, start.dark_pins)
    search = disc if not np.isfinite(ring) else SensorDisc(disc.cx, disc.cy, max(ring - _RING_INSET_PX, 1.0))
    # The rim margin is measured from the sensor disc's rim (the ring's inner edge is sharp: the
    # pins next to it are whole).
    start = start.replace(rim_margin_px=max(start.rim_margin_px - (disc.radius_px - search.radius_px), 0.0))
    cache = _SharedCache()
    # Coarse: one permissive candidate set per possible pitch; the strongest lattice gives the pitch.
    first = _strongest(grey, search, list(_candidates(pitches, start, _COARSE_BLOCK, _COARSE_OFFSETS)), cache)
    pitch = first.pitch if np.isfinite(first.pitch) else float(np.median(pitches))
    pitch = float(np.clip(pitch, 0.5 * pitches.min(), 1.5 * pitches.max()))
    # Fine: blocks and offsets at the measured pitch, no offset within the blurred noise's reach.
    fine = _distinct(_noise_floored(_candidates(np.array([pitch]), start, _BLOCK_PITCHES, _OFFSETS), grey))
    runs = _evaluate_all(grey, search, fine + ([start] if hinted else []), cache)
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
    rejected, reason = run.blobs.centres[~run.kept], run.reason[~run.kept]
    # Holes in the lattice (a pin on a reflection, a faint pin at a spoke's end) filled with the blobs
    # other candidate sets found there.
    taken = fill_lattice_holes(centres, run.blobs.areas[run.kept], run.blobs.contrasts[run.kept],
                               [(r.blobs.centres, r.blobs.areas, r.blobs.fills, r.blobs.contrasts, r.params.offset)
                                for r in runs],
                               (disc.cx, disc.cy))
    if taken:
        extra = np.array([runs[s].blobs.centres[i] for s, i in taken])
        centres = np.vstack([centres, extra])
        centres = centres[np.lexsort((centres[:, 0], centres[:, 1]))]
        apart = cKDTree(extra).query(rejected)[0] > _MATCH * pitch if len(rejected) else np.zeros(0, bool)
        rejected, reason = rejected[apart], reason[apart]
    placed = None  # the probed tips' lattice prior (centres, px per axis), aligned with `centres`
    if not disc.whole_frame and len(centres):
        radius_px = _pin_radius_px(grey, centres, run.pitch, start.dark_pins)
        # A reflection's flat top at a lattice site: no tip stands above the membrane round it.
        flat = flat_pins(grey, centres, radius_px, dark_pins=start.dark_pins,
                         disc=(disc.cx, disc.cy, disc.radius_px))
        if flat.any():
            rejected = np.vstack([rejected, centres[flat]])
            reason = np.concatenate([reason, np.full(int(flat.sum()), REJECTION_REASONS.index("contrast"))])
            centres = centres[~flat]
        # Holes no blob filled (a faint spoke end under the veil): the image itself, looked at there.
        probed, prior, prior_sigma = probe_lattice_holes(grey, centres, (disc.cx, disc.cy), radius_px,
                                                         disc_radius_px=search.radius_px, dark_pins=start.dark_pins,
                                                         with_prior=True)
        if len(probed):
            centres = np.vstack([centres, probed])
            order = np.lexsort((centres[:, 0], centres[:, 1]))
            centres = centres[order]
            # Where the lattice puts each probed tip: its fit weighs it (`pins._tipfit.fit_tip_centres`).
            placed = (np.vstack([np.zeros((len(centres) - len(probed), 2)), prior])[order],
                      np.concatenate([np.full(len(centres) - len(probed), np.inf), prior_sigma])[order])
            apart = cKDTree(probed).query(rejected)[0] > _MATCH * pitch if len(rejected) else np.zeros(0, bool)
            rejected, reason = rejected[apart], reason[apart]
    if len(centres):
        # Pins cut by the frame's edge (a gel's markers; a pad off-centre or filmed close): their
        # centroids lean inwards; only those with enough in view to measure stay (`_cut_by_frame`).
        # The tracker cannot follow a tip the frame cuts through: kept, they were lost on every still
        # frame and retired (12 of 320 on tactip-331 and dark-331 with the pad 0.45 radius low).
        cut = _cut_by_frame(centres, _pin_radius_px(grey, centres, run.pitch, start.dark_pins), grey.shape)
        rejected = np.vstack([rejected, centres[cut]])
        reason = np.concatenate([reason, np.full(int(cut.sum()), REJECTION_REASONS.index("outside field"))])
        centres = centres[~cut]
        placed = None if placed is None else (placed[0][~cut], placed[1][~cut])
    # The blobs' centroids lean towards the bright side of a sloped membrane (an LED reflection, a
    # veil, shading): each tip is placed by fitting it as an opaque ellipse over a curved background.
    if len(centres):
        centres = fit_tip_centres(grey, centres, _pin_radius_px(grey, centres, run.pitch, start.dark_pins),
                                  dark_pins=start.dark_pins, prior=placed)
    final = _final_params(runs[later], centres, disc, run.pitch, search.radius_px)
    count_error = None if expected_pins is None else len(centres) - int(expected_pins)
    return PinField(centres=centres, params=final, disc=disc,
                    pitch_px=central_spacing_px(centres), rejected=rejected,
                    rejected_reason=np.array(REJECTION_REASONS, dtype=object)[reason].astype(str),
                    expected_pins=None if expected_pins is None else int(expected_pins), count_error=count_error)
