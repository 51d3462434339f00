"""The skin's own rest between contacts (`skin_rest`): where a real elastomer rests after a slide.

Contacts are found on the displacements from the skin's rest before each frame rather than from the first
frame (`tactip.replay.contacts.find_contacts`): a skin that creeps back over a second or more, or keeps a
set, never looks at its first frame's rest between contacts.
"""

from __future__ import annotations

import numpy as np

from .errors import ShapeError
from .segment import tap_signal

__all__ = ["skin_rest"]

_AHEAD = 128  # most frames whose signal from a rest is measured at once (a rest frame moves it: the rest re-measured)
_FIRST = 8  # the fewest: after a rest frame the next often comes within a few frames (a rest creeping back)


def skin_rest(field: np.ndarray, *, low_px: float, high_px: float, share: float = 0.4,
              fill: np.ndarray | None = None, steady: np.ndarray | None = None,
              return_frames: bool = False) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """The skin's own rest before each frame: the displacements at the last frame where it was at rest, px.

    A real elastomer does not return to its first frame's rest between contacts: what a slide leaves in
    the skin creeps back over a second or more, and some of it may stay (a set). Measured from the first
    frame, the pad then never looks at rest between contacts: contacts merge, and a slide's direction and a
    press's field carry what the last slides left. This follows the skin where it rests instead. A frame
    is *still* when the pins moved since the frame before by no more than ``low_px`` (the tap signal of the
    frame-to-frame change, `tap_signal`). From the first frame with pins on, the rest is the displacements
    at the latest *rest frame*: a still frame that is

    - a lift: since the last rest frame the signal from it (`tap_signal` of the displacements less the
      rest's) rose to ``high_px`` or more (a contact), has fallen to at most ``share`` of that peak, has
      not risen again by ``high_px`` or more since its lowest after the peak (a press right after a slide
      holds still above what the slide left: no rest) and no longer falls (by half ``low_px`` or more from
      the frame before: a press whose skin relaxes under the plate falls to half its peak while held); what
      is left in the skin after the plate lifted is the next contact's rest. "Not risen again" is judged on the
      pins' own motion since the signal stopped falling (`tap_signal` of the change from that frame below
      ``high_px``), not on the signal: the signal is a percentile over the pins seen, and where what a slide left
      moves more pins than a press right after it, the press does not raise it (tactip-127's tours, retire23: a
      rest taken in the press's hold, the press merged into the slide), while pins found again after a lift raise
      it with nothing moving (a rest missed, slides merged); or
    - a lift stopped at once by the next contact (a rest of a frame, no still frame): the first frame where the
      signal, having fallen by ``high_px`` or more in the frame before, stops falling (by less than half
      ``low_px``) at ``share`` of the peak or less and not risen again: the next contact is measured from there; or
    - a rest that creeps back: the skin at the last rest frame was off its first rest (`tap_signal` of the
      displacements ``low_px`` or more), the signal from it has stayed below ``high_px`` since (no contact),
      the next two frames are still too (a contact's slow onset is not), and the pins displaced there (by
      ``low_px`` or more) have moved since mostly back towards the first rest (their motion against their
      displacement at least three quarters of its length, summed over them): a skin creeping back moves
      towards its first rest; a press spreads the pins across that, however slowly it presses in. A skin at
      its first rest (one that springs back) has no such rest frames: there the rest moves at lifts only.

    A press's hold is still too, but its signal is at its peak: it is no rest frame. A rest too short to be
    still (a lift followed at once by the next contact) leaves the rest where it was: `split_at_dips` splits
    those contacts. Each pin's rest is its displacement at the latest rest frame where it was seen; a pin unseen
    there and found again before the next contact (the pins with a rest there still within ``high_px`` of it)
    rests where it is, frame by frame, until that contact: a tracker that lost pins through a slide may find them
    only once the skin is at rest again, and their older rests are off by what the contacts since left.

    Parameters
    ----------
    field : (T, N, 2) ndarray
        Displacements from the first frame's rest, px (NaN where lost: a frame with no pin is never still).
    low_px, high_px : float
        `segment_taps`' thresholds, px (0 < low < high).
    share : float
        Highest share of a contact's peak signal left at a lift's rest frame, in (0, 1).
    fill : (T, N, 2) ndarray, optional
        A pin's rest where it is unseen at a rest frame, px (NaN: none), e.g. its neighbourhood's median
        (`pins.neighbour_median`): a pin lost at a lift and found again a frame later is at the skin's rest
        there, not at the rest where it was last seen (which, before a slide, is off by what the slide left).
        Used where it is off the first frame's rest by ``low_px`` or more (a skin back at its first rest keeps
        its rests as without it); without it (or where NaN or less), such a pin keeps its displacement at the
        latest rest frame where it was seen.
    steady : (T, N) ndarray of bool, optional
        The pins a creeping rest is judged by (default: all): e.g. those that agree with their neighbourhood
        (`tactip.replay.contacts.find_contacts` outvotes the others, replacing their displacement by their
        neighbours' median, which jumps when lost neighbours are found again: a step away from the first rest
        that outweighed a creep back for tens of frames on tactip-127's and white-dark-331's tours).
    return_frames : bool
        Also return the rest frames.

    Returns
    -------
    rest : (T, N, 2) ndarray of float64
        Each frame's rest, px: zeros up to the first frame with pins; NaN for a pin not yet seen at a rest
        frame nor found again after one. ``field - rest`` are the displacements from the skin's own rest.
    frames : (R,) ndarray of int, with ``return_frames``
        The rest frames, increasing: the first frame with pins (none: empty), then each lift's and creeping
        rest's. Frame t's rest is taken at the latest of them <= t (a pin unseen there: where it is found
        again before the next contact, else at the latest where it was seen).

    Examples
    --------
    >>> field = np.zeros((12, 20, 2)); field[2:5, :, 0] = [[2.0], [8.0], [3.0]]   # a slide that leaves 3 px
    >>> field[5:, :, 0] = 3.0; field[8:10, :, 1] = 2.0                     # at rest, then a press
    >>> rest = skin_rest(field, low_px=0.5, high_px=1.5)
    >>> from pins import segment_taps
    >>> rest[[1, 5, 9, 11], 0].tolist(), segment_taps(tap_signal(field - rest), pad_frames=0, min_frames=1)
    ([[0.0, 0.0], [3.0, 0.0], [3.0, 0.0], [3.0, 0.0]], [(2, 5), (8, 10)])
    """
    data = np.asarray(field, dtype=np.float64)
    if data.ndim != 3 or data.shape[2] != 2:
        raise ShapeError(f"field must have shape (T, N, 2), got {data.shape}")
    if not 0.0 < low_px < high_px:
        raise ValueError(f"need 0 < low_px < high_px, got low_px={low_px}, high_px={high_px}")
    if not 0.0 < share < 1.0:
        raise ValueError(f"share must be in (0, 1), got {share}")
    seen = np.isfinite(data[..., 0])
    rest = np.zeros_like(data)
    if not seen.any():
        return (rest, np.zeros(0, dtype=np.intp)) if return_frames else rest
    first = int(np.argmax(seen.any(axis=1)))
    motion = np.full(len(data), np.inf)
    motion[first + 1:] = tap_signal(data[first + 1:] - data[first:-1])
    motion[~seen.any(axis=1)] = np.inf
    still = motion <= low_px
    displaced: dict[int, float] = {}  # the signal from the first frame's rest, at the rest frames asked (a row of
    # `tap_signal` alone has its value in the whole recording's: its rows are independent)
    rests = [first]
    anchor = first  # the last rest frame
    peak = trough = 0.0  # the highest signal from the rest since it, and the lowest after that peak
    peak_at = first  # the peak's frame
    # Between still frames the rest cannot change: the signal from it is judged a run at a time, and measured
    # (`tap_signal`, row by row) for `_FIRST` frames at once after a rest frame, twice as many each time after
    # that up to `_AHEAD`, until the rest moves.
    breaks = np.flatnonzero(still[first + 1:]) + first + 1
    edges = np.concatenate([[first + 1], np.repeat(breaks, 2), [len(data)]]).reshape(-1, 2)
    signal, known, ahead = np.empty(len(data)), anchor, _FIRST          # signal[anchor:known]: from the rest
    for start, stop in edges:
        end = min(int(stop) + 1, len(data))
        if end > known:
            known, last, ahead = max(end, min(known + ahead, len(data))), known, min(2 * ahead, _AHEAD)
            signal[last:known] = tap_signal(data[last:known] - data[anchor])
        values = signal[start:end]                                        # the run, and the still frame after it
        if values.size:
            top = int(np.argmax(values))
            if values[top] > peak:
                peak_at = int(start) + top
            peak, trough = ((float(values[top]), float(values[top:].min())) if values[top] > peak
                            else (peak, min(trough, float(values.min()))))
        if peak >= high_px:  # a lift stopped at once by the next contact: no still frame between them
            stopped = _stopped_by_contact(signal, max(int(start), peak_at + 2, anchor + 2), min(int(stop), len(data)),
                                          peak * share, trough + high_px, low_px, high_px)
            if stopped is not None:
                rests.append(stopped)
                anchor, known, ahead = stopped, max(end, min(stopped + _FIRST, len(data))), _FIRST
                signal[anchor:known] = tap_signal(data[anchor:known] - data[anchor])
                after = signal[anchor + 1:end]
                peak, trough, peak_at = 0.0, 0.0, anchor
                if after.size:
                    top = int(np.argmax(after))
                    peak, trough, peak_at = float(after[top]), float(after[top:].min()), anchor + 1 + top
                values = signal[start:end]
        if stop >= len(data):
            break
        now = float(values[-1])                                           # the still frame's signal
        before = float(values[-2]) if values.size > 1 else 0.0            # the frame's before it
        lift = (peak >= high_px and now <= share * peak and before - now < 0.5 * low_px   # fallen, no longer falling,
                and _moved_since_fall(data, signal, peak_at, int(stop), share * peak, low_px) < high_px)  # no press
        if peak < high_px and anchor not in displaced:
            displaced[anchor] = float(tap_signal(data[anchor:anchor + 1])[0])
        creep = (peak < high_px and displaced[anchor] >= low_px and still[stop + 1:stop + 3].all()
                 and _back(data[stop], data[anchor], low_px, None if steady is None else steady[stop] & steady[anchor])
                 >= 0.75)
        if lift or creep:
            rests.append(int(stop))
            anchor, peak, trough, known, ahead = int(stop), 0.0, 0.0, int(stop), _FIRST
    rests = np.asarray(rests, dtype=np.intp)
    # each pin's rest: its displacement at the latest rest frame where it was seen (or filled)
    source = data[rests]                                                  # (R, N, 2)
    known = seen[rests]
    if fill is not None:
        filled = np.asarray(fill, dtype=np.float64)[rests]
        filled[np.hypot(filled[..., 0], filled[..., 1]) < low_px] = np.nan      # only what a contact left
        source = np.where(known[..., None], source, filled)
        known = known | np.isfinite(filled[..., 0])
    # A pin unseen at a rest frame and found again before the next contact (while the pins with a rest there moved
    # from it by less than ``high_px``) rests where it is, frame by frame, until that contact: the displacement it
    # kept from an older rest frame is off by what the contacts since left in the skin (radial-led-120's creeping
    # tours: retired pins back in a rest 1-3 px from their older rests held the signal at twice the high threshold
    # until the next slide ended), and where it is when first found may be too (a neighbourhood's median, one
    # neighbour found so far).
    marked = np.zeros(seen.shape, dtype=bool)                            # (T, N): the frames each pin's rest is from
    marked[rests] = known
    value = data.copy()
    value[rests] = source
    ends = np.append(rests[1:], len(data))
    for k, (at_rest, end) in enumerate(zip(rests, ends)):
        window = seen[at_rest + 1:end]
        back = window.any(axis=0) & ~known[k]
        if not back.any() or not known[k].any():
            continue
        moved = tap_signal(data[at_rest + 1:end][:, known[k]] - source[k][known[k]])
        before = int(np.argmax(moved >= high_px)) if (moved >= high_px).any() else len(moved)
        marked[at_rest + 1:at_rest + 1 + before, back] = window[:before, back]
    index = np.where(marked, np.arange(len(data))[:, None], -1)          # (T, N): latest frame its rest is from
    index = np.maximum.accumulate(index, axis=0)
    pins = np.arange(data.shape[1])
    rest = np.where((index >= 0)[..., None], value[np.maximum(index, 0), pins[None]], np.nan)
    rest[:first] = 0.0
    return (rest, rests) if return_frames else rest


def _stopped_by_contact(signal: np.ndarray, first: int, stop: int, fallen: float, below: float, low_px: float,
                        high_px: float) -> int | None:
    """The first frame in [first, stop) where a lift's signal (px, from the rest) that fell by ``high_px`` or more in
    the frame before stopped at once (by less than half ``low_px``), at most ``fallen`` and below ``below``: the
    plate came off and the next contact held the skin there (a rest of a frame or two, no still frame); else None."""
    if stop <= first:
        return None
    now, last, earlier = signal[first:stop], signal[first - 1:stop - 1], signal[first - 2:stop - 2]
    hits = np.flatnonzero((now <= fallen) & (now < below) & (last - now < 0.5 * low_px) & (earlier - last >= high_px))
    return first + int(hits[0]) if hits.size else None


def _moved_since_fall(data: np.ndarray, signal: np.ndarray, peak_at: int, stop: int, fallen: float,
                      low_px: float) -> float:
    """How far the pins moved (`tap_signal` of the change, px) from where the signal after the peak at ``peak_at``
    stopped falling at ``fallen`` px or below, to frame ``stop``: a press right after a slide moves them from there,
    while the signal from the rest, a percentile over pins that come and go (those found again after a lift), may not
    show it."""
    fall = signal[peak_at:stop] - signal[peak_at + 1:stop + 1]
    ended = (fall < 0.5 * low_px) & (signal[peak_at + 1:stop + 1] <= fallen)
    if not ended.any():
        return 0.0
    return float(tap_signal((data[stop] - data[peak_at + 1 + int(np.argmax(ended))])[None])[0])


def _back(now: np.ndarray, then: np.ndarray, level_px: float, pins: np.ndarray | None = None) -> float:
    """How much of the pins' motion from ``then`` to ``now`` ((N, 2) px each, displacements from the first rest)
    points back towards the first rest, in [-1, 1]: the sum over the pins displaced by ``level_px`` or more in
    ``then`` (seen in both) of their motion against their displacement, over the sum of their motion's length
    (1: all straight back, 0: across or noise; 0 without any such pin)."""
    both = np.isfinite(now[:, 0]) & np.isfinite(then[:, 0])
    if pins is not None:  # only these pins ((N,) bool)
        both &= pins
    length = np.hypot(then[:, 0], then[:, 1])
    pins = both & (length >= level_px)
    if not pins.any():
        return 0.0
    motion = now[pins] - then[pins]
    total = np.hypot(motion[:, 0], motion[:, 1]).sum()
    against = -np.einsum("nk,nk->n", motion, then[pins] / length[pins, None]).sum()
    return float(against / total) if total > 0 else 0.0
