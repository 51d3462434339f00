"""A replay's contacts, feature pins and scale, found in the tracked pins; and the rest-frame check.

Nothing here raises for lack of pins: every problem becomes a warning, so the tracking is always kept.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy import ndimage

from pins import (DEFAULT_PAD_DIAMETER_MM, PadScale, PinSelection, PinsError, contact_kinds, jitter_floor_px,
                  median_spacing_px, neighbour_median, segment_taps, select_feature_pins, sensor_scale, skin_rest,
                  tap_signal)

from tactip.pipeline import PinTrack
from tactip.replay._trim import drop_unmoved, trim_settled, trim_still
from tactip.replay._thresholds import REFERENCE_PITCH_PX, noise_limited, tap_thresholds_px

__all__ = ["DEFAULT_PAD_DIAMETER_MM", "REFERENCE_PITCH_PX", "analyse", "check_rest_frame", "feature_rests_of",
           "find_contacts", "local_maxima", "neighbour_medians_of", "noise_limited", "split_at_dips",
           "tap_thresholds_px"]


def check_rest_frame(displacements: np.ndarray, rest_positions: np.ndarray, *, rest_frame: int,
                     high_px: float = 1.5, signal: np.ndarray | None = None) -> str:
    """A warning when the rest frame looks taken during a tap (`pins.converging_frames`), else "".

    Parameters
    ----------
    displacements : (T, N, 2) ndarray
        Displacements from the rest frame, px (NaN where lost or not tracked).
    rest_positions : (N, 2) ndarray
        px.
    rest_frame : int
        The rest frame's index (named in the warning).
    high_px : float
        Smallest tap signal of a frame that counts, px.
    signal : (T,) ndarray, optional
        The tap signal (`pins.tap_signal`) when already computed, px.

    Returns
    -------
    warning : str
        Names the frames where the pins are drawn together (as at rest after a press, seen from
        a pressed reference) and suggests for ``--rest-frame`` the middle of the longest run of
        frames drawn together about the most (the pad still, at rest); "" when fewer than
        max(3, 5 % of the tracked frames) converge.
    """
    from pins import converging_frames

    if signal is None:
        signal = tap_signal(displacements)
    frames = converging_frames(displacements, rest_positions, high_px=high_px, signal=signal)
    tracked = int(np.isfinite(displacements[:, :, 0]).any(axis=1).sum())
    if len(frames) < max(3, 0.05 * tracked):
        return ""
    signal = np.where(np.isin(np.arange(len(displacements)), frames), signal, 0.0)
    # The pad at rest: the middle of the longest run of frames drawn together about the most.
    runs, count = ndimage.label(signal >= 0.9 * signal.max())
    longest = np.argmax(np.bincount(runs.ravel())[1:]) + 1
    suggested = int(np.median(np.flatnonzero(runs == longest)))
    return (f"the rest frame {rest_frame} looks taken during a tap: in {len(frames)} frames (e.g. {suggested}) "
            f"the pins are drawn together by up to {signal.max():.1f} px from it, as a pad at rest looks from a "
            f"pressed one; displacements and taps are measured from a deformed pad: give --rest-frame of a "
            f"frame off contact (frame {suggested} looks like one)")


def analyse(track: PinTrack, *, calibration, n_pins: int, min_separation_mm: float, sensor, pins_on_pad,
             pad_diameter_mm, mm_per_px, expected_pins, rest_frame: int, pitch_positions=None,
             neighbour_medians=None) -> dict:
    """Scale, feature pins, rest-frame check and contacts of a replay; every problem becomes a warning.

    Returns a dict: ``scale`` (`pins.PadScale` or None with a calibration), ``mm_per_px``,
    ``selection`` (`pins.PinSelection` or None), ``selected`` (P,) pin indices, ``bounds`` (the
    contacts, [start, stop) frames), ``kinds`` (a `pins.ContactKind` per contact: press or slide and
    its direction), ``warnings``, ``tap_thresholds_px`` (high, low), and per contact where its features are
    measured from (`feature_rests_of`): ``rest_frames`` (a frame each) and ``rests`` ((N, 2) px or None: the
    rest frame).

    Contacts separated by any rest are separate, however short the rest: no quiet frame is bridged.
    The pin pitch of the scale is measured on ``pitch_positions`` ((M, 2) px: the rest frame's pin field,
    as `tactip detect` and `tactip calibrate` measure it), else on the tracked rest positions.
    ``neighbour_medians`` (`pins.segment.NeighbourMedians`, optional) holds `find_contacts`' neighbourhood
    medians of the frames from the rest frame on, computed while they were tracked (`neighbour_medians_of`).
    """
    warnings = list(track.warnings)
    rest, disc, displacements = track.rest_positions, track.disc, track.displacements
    found = track.pins_detected
    if expected_pins and abs(found - expected_pins) > 0.1 * expected_pins:
        warnings.append(f"{found} pins found in the rest frame, {expected_pins} expected "
                        f"({(found - expected_pins) / expected_pins:+.0%}): check --expected-pins and the rest frame")
    scale = selection = None
    selected = np.zeros(0, dtype=np.intp)
    if calibration is not None:
        scale_mm_per_px, selected = float(calibration.mm_per_px), np.asarray(calibration.selected_pins)
    else:
        try:  # the rule detect and calibrate apply too
            scale = sensor_scale(rest if pitch_positions is None else pitch_positions, sensor=sensor, pins_on_pad=pins_on_pad, pad_diameter_mm=pad_diameter_mm,
                                 mm_per_px=mm_per_px, expected_pins=expected_pins)
        except (PinsError, ValueError) as exc:
            pad = pad_diameter_mm or DEFAULT_PAD_DIAMETER_MM
            scale = PadScale(pad / (2.0 * disc.radius_px), float("nan"), float("nan"),
                             f"pad diameter {pad:g} mm / disc diameter {2 * disc.radius_px:.1f} px",
                             {"pad_diameter_mm": pad})
            warnings.append(f"the scale could not come from the pin pitch ({exc}); the disc's diameter was used")
        scale_mm_per_px = scale.mm_per_px
        try:
            selection = _select(track, n_pins=n_pins, min_separation_mm=min_separation_mm, mm_per_px=scale_mm_per_px)
            selected = selection.indices
            if selection.warning:
                warnings.append(f"feature pins: {selection.warning}")
        except (PinsError, ValueError) as exc:
            warnings.append(f"no feature pins ({exc})")
    signal = tap_signal(displacements)  # per frame, px: for the rest-frame check, the thresholds and the taps
    try:
        spacing = track.tracker.spacing_px
        check = check_rest_frame(displacements, rest, rest_frame=rest_frame, signal=signal,
                                 high_px=1.5 * min(1.0, spacing / REFERENCE_PITCH_PX) if spacing > 0 else 1.5)
        if check:
            warnings.append(check)
    except (PinsError, ValueError) as exc:
        warnings.append(f"the rest frame could not be checked ({exc})")
    bounds, kinds, rests = [], [], []
    try:  # the neighbourhood medians: the thresholds' noise floor and find_contacts' field
        medians = neighbour_medians_of(track, neighbour_medians)
        medians = neighbour_median(displacements, rest) if medians is None else medians
    except (PinsError, ValueError):
        medians = None
    usable = track.tracked & ~track.blank
    jitter = jitter_floor_px(displacements, usable=usable)
    high_px, low_px = tap_thresholds_px(displacements, track.tracker.spacing_px, usable=usable, signal=signal,
                                        medians=medians, jitter_px=jitter)
    try:
        bounds, kinds, rests = find_contacts(displacements, signal=signal, blank=track.blank,
                                             thresholds_px=(high_px, low_px), rest_positions=rest,
                                             medians=medians, with_rests=True, jitter_px=jitter)
        if not bounds:
            warnings.append(f"no taps found (no frame moved the pins by {high_px:.2g} px): only the tracking "
                            f"was written")
    except (PinsError, ValueError) as exc:
        warnings.append(f"no tap features ({exc})")
    rest_frames, feature_rests = feature_rests_of(rests, np.asarray(selected, np.intp), low_px=low_px,
                                                  rest_frame=int(track.rest_frame))
    return dict(scale=scale, mm_per_px=scale_mm_per_px, selection=selection, selected=np.asarray(selected, np.intp),
                bounds=bounds, kinds=kinds, warnings=warnings, tap_thresholds_px=(high_px, low_px),
                rest_frames=rest_frames, rests=feature_rests)


def feature_rests_of(rests, selected: np.ndarray, *, low_px: float, rest_frame: int) -> tuple[list[int], list]:
    """Where each contact's features are measured from: ([its rest frame], [its rest, (N, 2) px, or None]).

    A contact's features are its feature pins' displacements from the skin's own rest before it (`find_contacts`'
    ``with_rests``) when that rest is off the rest frame's by ``low_px`` or more (`pins.tap_signal` of the feature
    pins' rest: what a slide left in a skin that creeps back or keeps a set, so a press right after a slide is
    measured as a press on a rested skin is, as a calibration's taps after a 1 s pause are, paper 000); else from
    the rest frame (None; ``rest_frame``), so a skin back at its first rest gives the features it always gave.
    A rest with a feature pin unseen (NaN) counts that pin as unmoved.
    """
    frames, chosen = [], []
    for frame, rest in rests:
        part = np.asarray(rest, dtype=np.float64)[selected]
        off = selected.size and tap_signal(part[None])[0] >= low_px
        frames.append(int(frame) if off else int(rest_frame))
        chosen.append(np.nan_to_num(np.asarray(rest, dtype=np.float64)) if off else None)
    return frames, chosen


def find_contacts(displacements: np.ndarray, *, signal: np.ndarray, blank: np.ndarray,
                  thresholds_px: tuple[float, float], rest_positions: np.ndarray | None = None,
                  medians: np.ndarray | None = None, with_rests: bool = False,
                  jitter_px: float | None = None) -> tuple:
    """The contacts of a replay and their kinds: ([start, stop) frames, a `pins.ContactKind` each), and with
    ``with_rests`` the skin's rest before each.

    Contacts are found (`pins.segment_taps`, no quiet frame bridged, then `split_at_dips`) on a tap
    signal where, given the rest positions, a pin whose displacement differs from its neighbourhood's
    median (`pins.segment.neighbour_median`) by more than the low threshold counts as that median: a
    contact moves patches of neighbouring pins together, while the pins a tracker loses and misplaces
    for a few frames after a slide's lift, or a few pins jumping in noise, move alone (on the pins' own
    tap signal they held it up at 0.6-3 px after a lift, a contact stopping 4 frames late or a slide
    2 frames after another starting 5 frames early, or made short contacts of their own). A pin that
    agrees with its neighbours within the noise keeps its own displacement, so a clean tap's onset
    and end are where they were. Where the pins' own noise reaches the low threshold (twice their jitter floor,
    `pins.jitter_floor_px`, above it: `tap_thresholds_px` then set it from the medians' lower noise), every pin
    counts as its neighbourhood's median: on radial-led-120's tours each pin jitters by its own 0.1-0.3 px
    (up to 1.7), a still pad's tap signal 0.55 px on the pins and 0.3 on the medians, while a press moves its
    patch together (1.0-1.8 px on both): the press-down before a slide's drag and a light press stood inside
    the pins' noise. Given the rest positions, the displacements are also measured from
    the skin's own rest before each frame (`pins.skin_rest`: the last still frame after a lift, or of
    a rest creeping back towards the first frame's), not the first frame's: a real elastomer creeps
    back over a second or more after a slide and may keep a set, and measured from the first frame it
    never looks at rest between contacts (they merged, and a slide's direction and a press's field
    carried what the last slides left). A contact's still ends are trimmed (`trim_still`: the pins did not
    move) and so is a settled tail after a lift (`trim_settled`: the signal flat at what the skin kept, while the
    tracked pins catch up); a contact whose pins never moved by the high threshold from the skin at rest before
    it is dropped (`drop_unmoved`: pins found again with a stale rest, a rest taken mid-release). Kinds are
    `pins.contact_kinds` with the rest positions (a press's field spreads out, a slide's shifts one way).

    Parameters
    ----------
    displacements : (T, N, 2) ndarray
        Displacements from the rest frame, px (NaN where lost or not tracked).
    signal : (T,) ndarray
        The pins' tap signal (`pins.tap_signal`), px.
    blank : (T,) ndarray of bool
        Frames where nothing was seen.
    thresholds_px : (float, float)
        `tap_thresholds_px`' (high, low), px.
    rest_positions : (N, 2) ndarray, optional
        The pins' rest positions, px; without them, contacts are found on ``signal`` and kinds by the
        drag alone.
    medians : (T, N, 2) ndarray, optional
        ``neighbour_median(displacements, rest_positions)`` when already computed, px (replay computes
        them as it tracks: `neighbour_medians_of`).
    with_rests : bool
        Also return, per contact, the skin's rest before it: a pair (frame, rest), the latest rest frame
        (`pins.skin_rest`) at or before the contact's start and the pins' displacements there ((N, 2) px, from
        the frames' own rest: a pin unseen there at the latest rest frame where it was seen, its neighbourhood's
        median where it disagreed with it); without ``rest_positions``, the first frame with pins and zeros.
    jitter_px : float, optional
        `pins.jitter_floor_px` of ``displacements`` when already computed, px.
    """
    high_px, low_px = thresholds_px
    coherent, relative, rest, frames, spacing = signal, None, None, None, float("nan")
    if rest_positions is not None:  # a pin differing from its neighbourhood by more than the noise is outvoted
        at_rest = np.asarray(rest_positions, dtype=np.float64)
        spacing = median_spacing_px(at_rest[np.isfinite(at_rest).all(axis=1)])
        local = neighbour_median(displacements, rest_positions) if medians is None else medians
        if jitter_px is None:
            jitter_px = jitter_floor_px(displacements, usable=~blank)
        settled_px = low_px
        if noise_limited(jitter_px, spacing):   # each pin's own noise: the neighbourhood's medians
            # (a settled tail within the pins' own noise: the tracked pins catching up after a lift move the
            # medians too)
            settled_px = max(low_px, 2.0 * jitter_px)
            field, alone = local, np.zeros(displacements.shape[:2], dtype=bool)
        else:
            alone = np.hypot(*np.moveaxis(displacements - local, -1, 0)) > low_px
            field = np.where(alone[..., None], local, displacements)
        # the skin's own rest before each frame
        rest, frames = skin_rest(field, low_px=low_px, high_px=high_px, fill=local, steady=~alone, return_frames=True)
        relative = field - rest
        coherent = tap_signal(relative)
        displacements = displacements - rest
        signal = tap_signal(displacements)
    bridged = _bridge_blank(coherent, blank)
    bounds = segment_taps(bridged, high_px=high_px, low_px=low_px, merge_gap_frames=0)
    bounds = split_at_dips(bridged, bounds, min_drop_px=high_px, field=relative)
    if relative is not None:
        bounds = trim_still(bounds, np.where(alone[..., None], np.nan, field), bridged, low_px=low_px,
                            high_px=high_px)
        bounds = trim_settled(bounds, bridged, low_px=settled_px)
        bounds = drop_unmoved(bounds, field, bridged, low_px=low_px, high_px=high_px)
    kinds = _kinds(displacements, bounds, signal, low_px, rest_positions,
                   field=None if rest_positions is None else field, spacing_px=spacing)
    if not with_rests:
        return bounds, kinds
    if rest is None:
        seen = np.isfinite(displacements[..., 0]).any(axis=1)
        first = int(np.argmax(seen)) if seen.any() else 0
        return bounds, kinds, [(first, np.zeros(displacements.shape[1:])) for _ in bounds]
    at = np.searchsorted(frames, [start for start, _ in bounds], side="right") - 1
    return bounds, kinds, [(int(frames[max(k, 0)]) if len(frames) else 0, rest[start])
                           for k, (start, _) in zip(at, bounds)]


def neighbour_medians_of(track: PinTrack, medians=None) -> np.ndarray | None:
    """`pins.neighbour_median` of the track's displacements from `medians` (`pins.segment.NeighbourMedians`
    fed, from the rest frame on, every frame's positions as the tracker placed them): (T, N, 2) px, NaN
    before the rest frame; None when `medians` does not cover exactly the tracked frames from the
    track's rest positions (`find_contacts` then computes them)."""
    if medians is None:
        return None
    before = int(track.rest_frame)
    rest = np.asarray(track.rest_positions, dtype=np.float64)
    if len(medians) != len(track.timestamps_s) - before or not np.array_equal(medians.rest_positions, rest):
        return None
    table = medians.table()
    return table if before == 0 else np.concatenate([np.full((before, *rest.shape), np.nan), table])


def split_at_dips(signal: np.ndarray, bounds, *, min_drop_px: float, share: float = 0.5,
                  field: np.ndarray | None = None) -> list[tuple[int, int]]:
    """Contacts split where the tap signal falls deep between two peaks: the plate lifted and came back
    before the skin had crept back to rest.

    A real elastomer does not spring back at once when a slide's plate lifts: what the slide left in
    the skin creeps back over tens of frames, so with a rest of a few frames the signal never falls
    below `segment_taps`' low threshold and two slides read as one contact. Within each contact, two
    peaks of the signal (median of 3 frames, so a one-frame jump of the tracker makes no peak) are
    two contacts when the signal between them falls to at most ``share`` of the lower peak and by at
    least ``min_drop_px`` below it; the contact is cut where the lift brought it a quarter of the way
    from the dip to the lower peak (the first contact's end, +- a frame). A press's plateau or
    a slide's drag never falls so far while the plate is down. Without ``field``, a press too weak to
    rise above what the last slide left stays merged with it; with it, a dip is also a lift where the
    signal fell to at most ``share`` of the earlier peak and the pins moved by ``min_drop_px`` or more
    (`pins.tap_signal` of the change) from the dip to the later peak: a press right after a slide, on
    the shear the slide left.

    Parameters
    ----------
    signal : (T,) ndarray
        The tap signal (`pins.tap_signal`), px.
    bounds : sequence of (start, stop)
        Contacts, stop exclusive (`pins.segment_taps`).
    min_drop_px : float
        Least fall from the lower peak to the dip, px (the tap threshold: above the tracking noise).
    share : float
        Highest dip, as a share of the lower peak, in (0, 1).
    field : (T, N, 2) ndarray, optional
        The displacements the signal was measured on, px.

    Returns
    -------
    list of (start, stop)
        The contacts, split, in order, not overlapping.

    Examples
    --------
    >>> slides = np.array([0, 5, 10, 20, 3, 2, 8, 16, 24, 4, 2, 0], float)   # two slides, a 2 px residual
    >>> split_at_dips(slides, [(1, 11)], min_drop_px=1.0)
    [(1, 4), (4, 11)]
    """
    from scipy.ndimage import median_filter

    smooth = median_filter(np.asarray(signal, dtype=np.float64), 3, mode="nearest")
    split = []
    for start, stop in bounds:
        part = smooth[start:stop]
        peaks = np.union1d(local_maxima(part), [int(np.argmax(part))])
        cuts, held = [], None
        for peak in peaks:
            if held is None:
                held = peak
                continue
            dip = held + int(np.argmin(part[held:peak]))
            lower = min(part[held], part[peak])
            apart = part[dip] <= share * lower and lower - part[dip] >= min_drop_px
            if not apart and field is not None and part[dip] <= share * part[held]:   # a press on what was left
                apart = tap_signal(field[start + peak][None] - field[start + dip][None])[0] >= min_drop_px
            if apart:
                # the lift: the first frame down to a quarter of the way from the dip to the lower peak (the
                # dip itself may lie in the next contact, whose drag can cancel what the last one left)
                cuts.append(held + int(np.argmax(part[held:dip + 1] <= part[dip] + 0.25 * (lower - part[dip]))))
                held = peak
            elif part[peak] > part[held]:
                held = peak
        edges = [start, *(start + c for c in cuts), stop]
        split += [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:])]
    return split


def local_maxima(values: np.ndarray) -> np.ndarray:
    """Indices of the local maxima of a 1-D signal, as `scipy.signal.find_peaks` finds them with no condition:
    a sample (or the middle of a run of equal samples, rounded down) higher than the samples on both sides;
    never the first or last sample, NaN never a maximum. NumPy, not `scipy.signal`: importing that takes about
    0.3 s of CPU, as long as replaying a short video (issue 20, outcome 9).

    >>> local_maxima(np.array([0, 2, 1, 3, 3, 3, 0, 5, 5]))
    array([1, 4])
    """
    x = np.asarray(values, dtype=np.float64)
    if x.ndim != 1:
        raise ValueError(f"values must be 1-D, got shape {x.shape}")
    if len(x) < 3:
        return np.zeros(0, dtype=np.intp)
    starts = np.flatnonzero(np.concatenate([[True], ~(x[1:] == x[:-1])]))    # runs of equal samples (NaN: each alone)
    ends = np.concatenate([starts[1:], [len(x)]]) - 1
    level = x[starts]
    inner = np.arange(1, len(starts) - 1)
    peak = (level[inner - 1] < level[inner]) & (level[inner + 1] < level[inner])
    return ((starts[inner] + ends[inner]) // 2)[peak].astype(np.intp)


def _kinds(displacements: np.ndarray, bounds, signal: np.ndarray, low_px: float, rest_positions=None,
           field: np.ndarray | None = None, spacing_px: float = float("nan")) -> list:
    """`pins.contact_kinds` of each contact (with ``rest_positions``, (N, 2) px, when given), measured from its
    first frame where the pad was not back at rest there (the signal above ``low_px``: what the last slide left
    in the skin, creeping back, would otherwise turn this contact's drag towards that slide's direction); from
    the rest frame elsewhere. Given ``field`` ((T, N, 2) px, from the first frame's rest), a slide that only
    gives back what the skin kept (`_gives_back`) is a press; a slide drags its patch `MIN_DRAG_PITCH` of the pins'
    spacing (``spacing_px``, `pins.median_spacing_px` at rest) and 1 px or more."""
    kinds = []
    min_drag_px = max(1.0, MIN_DRAG_PITCH * spacing_px) if np.isfinite(spacing_px) else 1.0
    for start, stop in bounds:
        if signal[start] > low_px:
            moved = displacements[start:stop] - displacements[start]  # NaN where lost at the start: left out
            kind, = contact_kinds(moved, [(0, stop - start)], rest_positions=rest_positions, min_drag_px=min_drag_px)
        else:
            kind, = contact_kinds(displacements, [(start, stop)], signal=signal, rest_positions=rest_positions,
                                  min_drag_px=min_drag_px)
        if kind.kind == "slide" and field is not None and _gives_back(field[start:stop], low_px):
            kind = dataclasses.replace(kind, kind="press", direction_deg=float("nan"))
        kinds.append(kind)
    return kinds


#: A slide drags its patch at least this share of the pins' spacing (and 1 px): `_kinds`' ``min_drag_px``.
MIN_DRAG_PITCH = 0.1


def _gives_back(part: np.ndarray, low_px: float) -> bool:
    """Whether a contact's pins only went back towards the first frame's rest: ``part`` (F, N, 2) px, its frames'
    displacements from there.

    A press put down right after a slide, on the shear the slide left in the skin (creeping back, or kept as a
    set), holds the patch under the plate and lets it go part of the way back: its pins share one direction,
    back towards their first rest, and read as a slide. A slide drags its patch on, away from where the skin
    rested before it, by its length. So when the pins the contact moves most (at its peak tap signal from its
    first frame, at least half of it) rested off the first frame's rest at its start (their median displacement
    ``low_px`` or more) and at that peak their median displacement from the first rest is no longer than at the
    start, the contact only gave back what the skin kept. On the tours (issue 20's, residual 0.1, creep 1 s, set
    2 %), such presses ended at 0.49-0.97 of their start's leftover; slides at 5.9 or more. A slide shorter than
    twice the leftover and against it (a tenth of the slide before it, on those tours) reads so too.
    """
    moved_by = part - part[0]
    signal = tap_signal(moved_by)
    peak = int(np.argmax(signal))
    moved = np.hypot(moved_by[peak, :, 0], moved_by[peak, :, 1]) >= 0.5 * signal[peak]
    moved &= np.isfinite(part[0, :, 0]) & np.isfinite(part[peak, :, 0])
    if signal[peak] <= 0 or not moved.any():
        return False
    before, after = (np.hypot(*np.median(part[frame][moved], axis=0)) for frame in (0, peak))
    return bool(before >= low_px and after <= before)


def _bridge_blank(signal: np.ndarray, blank: np.ndarray) -> np.ndarray:
    """The tap signal with blank frames (nothing seen: no rest either) interpolated from their neighbours, px."""
    seen = np.flatnonzero(~blank)
    if not blank.any() or not seen.size:
        return signal
    bridged = signal.copy()
    bridged[blank] = np.interp(np.flatnonzero(blank), seen, signal[seen])
    return bridged


def _select(track: PinTrack, *, n_pins: int, min_separation_mm: float, mm_per_px: float) -> PinSelection:
    """Feature pins among the pins seen in at least half the tracked frames (all pins if too few are)."""
    rest = track.rest_positions
    usable = track.tracked & ~track.blank
    seen = (~track.lost[usable]).mean(axis=0) >= 0.5 if usable.any() else np.ones(len(rest), bool)
    candidates = np.flatnonzero(seen) if seen.sum() >= min(n_pins, len(rest)) else np.arange(len(rest))
    selection = select_feature_pins(rest[candidates], n_pins=n_pins, min_separation_mm=min_separation_mm,
                                    mm_per_px=mm_per_px, centre=tuple(rest.mean(axis=0)))
    return dataclasses.replace(selection, indices=candidates[selection.indices])
