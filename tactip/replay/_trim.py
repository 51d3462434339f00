"""A contact's frames where the plate was not on the skin, trimmed from its ends (`tactip.replay.contacts.find_contacts`).

Measured from the skin's own rest (`pins.skin_rest`), a contact on a skin that creeps back can begin before the
plate moves the pins and end after they settle: these trim such frames, and leave a clean tap's ends where they were.
"""

from __future__ import annotations

import numpy as np

from pins import tap_signal

__all__ = ["ONSET_STILL_FRAMES", "SETTLED_CREEP", "SETTLED_FRAMES", "SETTLED_SHARE", "drop_unmoved", "trim_settled",
           "trim_still"]
# Fewest frames of a settled tail (`trim_settled`): a tracker's catch-up after a lift lasts 2-3 frames.
SETTLED_FRAMES = 3
# Highest share of a contact's peak signal a settled tail sits at (a press's hold sits at its peak).
SETTLED_SHARE = 0.4
# Share of a settled tail's level it may fall by besides the noise: a skin creeping back with a time constant of
# 1 s (paper 000 waits 1 s between contacts) loses 3 % of what a slide left a frame at 30 frames/s.
SETTLED_CREEP = 0.1
# Fewest still frames in a row, before a contact's first frame at the high threshold, after which its onset is looked
# for (`trim_still`): the pins' motion before them is not the contact's.
ONSET_STILL_FRAMES = 5


def trim_still(bounds, field: np.ndarray, signal: np.ndarray, *, low_px: float, high_px: float) -> list:
    """Contacts without their still frames at either end: a frame whose pins moved since the frame before by at
    most half ``low_px`` (`pins.tap_signal` of the change of ``field``, (T, N, 2) px) and whose ``signal`` is below
    ``high_px``. A contact begins when the plate moves the pins and ends when they stop; measured from a rest the
    skin has crept away from since (a slow creep, a few tenths of a px in all), the signal can sit at the low
    threshold for tens of frames before a contact and after it (tactip-127's tours: slides starting 4-70 frames
    early). Only ends with a still frame at the low threshold or above are trimmed (a clean tap's ends, `segment_taps`'
    ``pad_frames`` included, stay where they were); a contact with no moving frame is kept whole. Where
    `ONSET_STILL_FRAMES` or more still frames in a row come between a moving frame and the contact's first frame at
    ``high_px``, the contact begins at the first moving frame after them (tactip-127's tour, seed 0: the skin at rest
    stepped 0.5 px in one frame, 44 frames before a slide, and the signal from its rest sat at 0.8-1.2 px, between
    the thresholds, until the slide: the slide began there)."""
    motion = np.full(len(field), np.inf)
    motion[1:] = tap_signal(field[1:] - field[:-1])
    still = (motion <= 0.5 * low_px) & (signal < high_px)
    trimmed = []
    for start, stop in bounds:
        moving = np.flatnonzero(~still[start:stop])
        if moving.size:  # only still frames the signal held at the low threshold or above (not segment_taps' pad)
            first, last = start + int(moving[0]), start + int(moving[-1]) + 1
            first = _after_still_runs(still, first, start + _first_at(signal[start:stop], high_px))
            start = first if (signal[start:first] >= low_px).any() else start
            stop = last if (signal[last:stop] >= low_px).any() else stop
        trimmed.append((start, stop))
    return trimmed


def trim_settled(bounds, signal: np.ndarray, *, low_px: float, frames: int = SETTLED_FRAMES,
                 share: float = SETTLED_SHARE) -> list:
    """Contacts without a settled tail: the frames at a contact's end (before `segment_taps`' pad, the frames
    below ``low_px``) whose ``signal`` (px) stays within half ``low_px`` plus `SETTLED_CREEP` of the last one's
    level of each other, at ``low_px`` or more and at most ``share`` of the contact's peak, ``frames`` of them or
    more (never the contact's first frame); the contact stops at the first of them.

    After a slide's lift on a skin that creeps back, the skin rests off the rest the slide was measured from by
    what the slide left, so the signal stays at the low threshold or above until `pins.skin_rest` takes the next
    rest; and the tracked pins keep catching up for 2-3 frames (0.3-0.7 px a frame on tactip-127's tours), so
    `trim_still`, which judges the pins' motion, keeps those frames (slides ending 4-7 frames late). The signal,
    a percentile over all pins, is flat there: the skin has settled. A press's release falls frame by frame, and
    its hold sits at its peak; a clean tap's end on a skin back at its rest falls below ``low_px`` (untouched).
    """
    trimmed = []
    for start, stop in bounds:
        part = np.asarray(signal[start:stop], dtype=np.float64)
        above = np.flatnonzero(part >= low_px)
        if above.size:
            last = int(above[-1])
            cap = share * part.max()
            # the tail: from `last` back while the signal stays within half low_px (max - min), at most cap
            head = part[:last + 1][::-1]
            spread = np.maximum.accumulate(head) - np.minimum.accumulate(head)
            flat = (spread <= 0.5 * low_px + SETTLED_CREEP * part[last]) & (head <= cap)
            run = int(np.argmin(flat)) if not flat.all() else len(flat) - 1   # never the contact's first frame
            if run >= frames:
                stop = start + last + 1 - run
        trimmed.append((start, stop))
    return trimmed


def drop_unmoved(bounds, field: np.ndarray, signal: np.ndarray, *, low_px: float, high_px: float) -> list:
    """Contacts whose pins moved: at some frame of the contact, `pins.tap_signal` of ``field`` ((T, N, 2) px, NaN
    where unseen) less its last frame with pins before the contact where ``signal`` (px) was below ``low_px`` (the
    skin at rest there; else its last frame with pins before the contact), over the pins seen in both, reaches
    ``high_px``.

    A contact moves the pins under it by as much as its signal rose. Measured from the skin's rest, the signal can
    also rise with no pin moving: pins found again with their rest from an earlier rest frame (before a slide), or
    a rest frame taken while a press's release went on slowly (radial-led-120's tours: such "presses" moved their
    pins by 0.34-0.85 of the high threshold; every rendered contact by 1.4 or more). A slow press's first frames
    trimmed (`trim_still`) moved the pins before the contact's start: measured from the rest before them.
    """
    seen = np.isfinite(field[..., 0]).any(axis=1)
    quiet = seen & (np.asarray(signal) < low_px)
    kept = []
    for start, stop in bounds:
        before = np.flatnonzero(quiet[:start])
        before = before if before.size else np.flatnonzero(seen[:start])
        if before.size:
            moved = tap_signal(field[start:stop] - field[before[-1]])
            if not (moved >= high_px).any():
                continue
        kept.append((start, stop))
    return kept


def _first_at(values: np.ndarray, level: float) -> int:
    """Index of the first of ``values`` at ``level`` or above (their length if none)."""
    above = np.flatnonzero(np.asarray(values) >= level)
    return int(above[0]) if above.size else len(values)


def _after_still_runs(still: np.ndarray, first: int, peak: int) -> int:
    """The first moving frame at or after ``first`` that follows the last run of `ONSET_STILL_FRAMES` or more still
    frames before ``peak`` (``first`` when there is none)."""
    part = still[first:peak]
    if part.size < ONSET_STILL_FRAMES:
        return first
    edges = np.diff(np.concatenate([[0], part.astype(np.int8), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    long = np.flatnonzero(ends - starts >= ONSET_STILL_FRAMES)
    if not long.size or ends[long[-1]] >= part.size:
        return first
    return first + int(ends[long[-1]])
