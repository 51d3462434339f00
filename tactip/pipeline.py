"""One path from frames to tap features, shared by the live station and by replay.

``frames -> track_pins -> contacts -> contact_features``, as pure functions of their inputs: no file
is read or written here (the station records taps in its results store; replay writes HDF5 and an
annotated video from the `PinTrack` it gets back).

- `track_pins` starts a `pins.PinTracker` on the rest frame and follows the pins through every later
  frame: positions, lost and retired masks, blank frames, time stamps.
- The contacts are the frame ranges ``[start, stop)`` whose features are wanted: the station's tap is
  one contact (every frame it captured between the arm's callbacks); replay finds them in the
  recording (`tactip.replay.contacts.find_contacts`).
- `contact_features` resamples each contact's displacements of the feature pins into a
  ``(samples, 2 P)`` array (`pins.tap_features`). A feature pin unseen for the whole contact leaves
  its two columns NaN (missing dimensions, which every likelihood model marginalises); the contact
  counts its seen pins, and is invalid, with the reason, only when fewer than half of them
  (`MIN_SEEN_FRACTION`) were seen, or it has a single frame.

`frames_to_features` runs the three steps in order.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable, Iterable, Sequence

import numpy as np

from pins import (DetectionParams, LostPinError, PinsError, PinTracker, SensorDisc, displacement_from_rest, seen_pins,
                  tap_features)

from tactip.errors import SourceError

__all__ = ["MIN_SEEN_FRACTION", "PinTrack", "Start", "contact_features", "frames_to_features", "track_pins"]

#: Fewest feature pins a valid contact has seen, as a fraction of the feature pins (20 of 40 is valid, 19 is not).
MIN_SEEN_FRACTION = 0.5

# start(image) -> (tracker, rest positions px, pins detected, detection parameters, pin-field summary,
#                  warnings)
Start = Callable[[np.ndarray], tuple]


@dataclass
class PinTrack:
    """Pins followed through a sequence of frames, with the contacts found in it and their features.

    Attributes
    ----------
    positions : (T, N, 2) ndarray of float64
        (x, y) px of every pin in every frame; NaN where lost, in blank frames and before the rest frame.
    lost, retired : (T, N) ndarray of bool
        Pin not found (all pins before the rest frame and in frames the tracker failed on); lost long
        enough to be searched for only now and then (a rim pin out of view).
    blank : (T,) ndarray of bool
        Nothing trackable in the frame (LEDs off, a dropped or black frame).
    tracked : (T,) ndarray of bool
        At or after the rest frame.
    timestamps_s : (T,) ndarray of float64
        Frame times, s.
    rest_positions : (N, 2) ndarray
        Pin positions in the rest frame, px.
    rest_frame : int
        Index of the rest frame.
    tracker : pins.PinTracker
        The tracker, as it ended (its spacing and settings describe the pins).
    detection : pins.DetectionParams
    pins_detected : int
        Pins found (or placed) in the rest frame.
    pin_field : str
        How the rest frame's pins were found (`pins.PinField.summary`, or the calibration's pins).
    warnings : list of str
        What did not go as asked: unreadable frames, frames the tracker failed on.
    contacts : list of (int, int)
        Frame ranges [start, stop) whose features were computed.
    features : (contacts, samples, 2 P) ndarray of float64, or None
        Columns 0..P-1 dx, P..2P-1 dy of the feature pins, px; NaN in the columns of a pin unseen
        for the whole contact, and everywhere for an invalid contact. None when no features were asked for.
    pins_seen : (contacts,) ndarray of int
        Feature pins seen in at least one frame of each contact other than the rest frame (of P).
    valid : (contacts,) ndarray of bool
    errors : list of (pins.PinsError or None)
        Why each invalid contact is invalid (None for a valid one).
    """

    positions: np.ndarray
    lost: np.ndarray
    retired: np.ndarray
    blank: np.ndarray
    tracked: np.ndarray
    timestamps_s: np.ndarray
    rest_positions: np.ndarray
    rest_frame: int
    tracker: PinTracker
    detection: DetectionParams
    pins_detected: int
    pin_field: str = ""
    warnings: list = field(default_factory=list)
    contacts: list = field(default_factory=list)
    features: np.ndarray | None = None
    pins_seen: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    valid: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    errors: list = field(default_factory=list)

    @cached_property
    def displacements(self) -> np.ndarray:
        """(T, N, 2) displacements from the rest frame, px (NaN where the positions are).

        Computed once: replay's contacts, features and both recorders read it.
        """
        return displacement_from_rest(self.positions, self.rest_positions)

    @property
    def disc(self) -> SensorDisc:
        """The sensor disc the tracker works in."""
        return self.tracker.disc


def track_pins(frames: Iterable, *, start: Start, rest_frame: int | None = None,
               progress: bool | Callable[[int], None] = False, total: int | None = None,
               each_row: Callable[[np.ndarray], None] | None = None) -> PinTrack:
    """Follow the pins through ``frames`` from their rest frame.

    Parameters
    ----------
    frames : iterable of tactip.sources.Frame
        In stream order (``index``, ``timestamp_s``, ``image``).
    start : callable
        ``start(image) -> (tracker, rest, detected, params, field, warnings)``: the tracker started on
        the rest frame, and what did not go as asked there. It raises `pins.PinsError` when the frame
        shows no pins.
    rest_frame : int, optional
        Index of the rest frame; its start's error propagates. None: the first frame ``start``
        succeeds on (a blank frame is skipped, as at the start of a live tap).
    progress : bool or callable
        Show a tqdm bar in frames (on stderr); or a callable, called with the number of frames read
        since its last call, every `_TICK_FRAMES` frames and at the end (a batch's workers report so).
    total : int, optional
        Frames expected, for the bar.
    each_row : callable, optional
        Called with each tracked frame's (N, 2) positions, px, as they are stored, from the rest frame on
        (its rest positions first; every pin NaN in a frame the tracker failed on): work that can follow the
        track frame by frame (replay's contacts' neighbourhood medians) is done while it is tracked.

    Returns
    -------
    PinTrack
        Without contacts or features.

    Raises
    ------
    SourceError
        No rest frame: the stream ended before it, or was unreadable before it.
    PinsError
        ``start`` failed on the given rest frame, or on every frame when ``rest_frame`` is None.
    """
    tracker = rest = None
    detected, params, summary = 0, None, ""
    before = 0  # frames before the rest frame: not tracked
    positions, lost, retired, blank, timestamps = [], [], [], [], []
    warnings: list[str] = []
    failed: list[tuple[int, str]] = []  # frames the tracker raised on: (index, message)
    start_error: PinsError | None = None
    iterator = iter(frames)
    bar_options = dict(total=total, unit="frame", desc="replay", mininterval=0.5)
    with _bar(progress, bar_options) as bar:
        while True:
            try:
                frame = next(iterator)
            except StopIteration:
                break
            except (SourceError, OSError) as exc:  # a damaged file: keep what was tracked before it
                if tracker is None:
                    raise
                warnings.append(f"the video could not be read after frame {len(timestamps) - 1} ({exc}); the "
                                f"frames before it are kept")
                break
            timestamps.append(frame.timestamp_s)
            if tracker is not None:
                try:
                    moved = tracker.update(frame.image)
                except (PinsError, ValueError) as exc:  # the tracking so far is kept; this frame is lost
                    failed.append((frame.index, f"{type(exc).__name__}: {exc}"))
                    moved = np.full((len(rest), 2), np.nan)
                    gone, away, dark = np.ones(len(rest), dtype=bool), np.zeros(len(rest), dtype=bool), False
                else:
                    gone = np.array(tracker.lost, dtype=bool)
                    away = np.array(tracker.retired, dtype=bool) & gone
                    dark = bool(tracker.blank)
                positions.append(moved)
                if each_row is not None:
                    each_row(moved)
                lost.append(gone)
                retired.append(away)
                blank.append(dark)
                if progress:
                    bar.update(1)
                continue
            if rest_frame is None or frame.index == rest_frame:
                try:
                    tracker, rest, detected, params, summary, started = start(frame.image)
                    warnings += started
                except PinsError as exc:
                    if rest_frame is not None:
                        raise
                    start_error = exc
            if tracker is None:
                before += 1
            else:
                rest = np.asarray(rest, dtype=np.float64)
                positions.append(rest)
                if each_row is not None:
                    each_row(rest)
                lost.append(np.zeros(len(rest), dtype=bool))
                retired.append(np.zeros(len(rest), dtype=bool))
                blank.append(False)
            if progress:
                bar.update(1)
    if tracker is None:
        if start_error is not None:
            raise start_error
        raise SourceError(f"the video has {len(timestamps)} frames, so there is no rest frame {rest_frame}")
    if failed:
        warnings.append(f"tracking failed in {len(failed)} frame(s), every pin lost there (first: frame "
                        f"{failed[0][0]}, {failed[0][1]})")
    if getattr(tracker, "motion_warning", ""):  # (pins back at rest on others' tips: too fast for the frame rate)
        warnings.append(tracker.motion_warning)
    pins = len(rest)
    stacked = np.concatenate([np.full((before, pins, 2), np.nan), np.stack(positions)])
    return PinTrack(positions=stacked,
                    lost=np.concatenate([np.ones((before, pins), bool), np.stack(lost)]),
                    retired=np.concatenate([np.zeros((before, pins), bool), np.stack(retired)]),
                    blank=np.concatenate([np.zeros(before, bool), np.asarray(blank, dtype=bool)]),
                    tracked=np.arange(len(stacked)) >= before,
                    timestamps_s=np.asarray(timestamps, dtype=np.float64),
                    rest_positions=np.asarray(tracker.rest_positions), rest_frame=before, tracker=tracker,
                    detection=params, pins_detected=int(detected), pin_field=summary, warnings=warnings)


def _bar(progress, options: dict):
    """`track_pins`' progress: `_Ticks` for a callable, a tqdm bar for True, none (tqdm not even imported: ~0.03 s of
    a process's first replay) for False."""
    if callable(progress):
        return _Ticks(progress)
    if not progress:
        return contextlib.nullcontext()
    from _shared.progress import progress_bar

    return progress_bar(**options)


# Frames between two calls of a callable progress (`track_pins`): few messages, a live count.
_TICK_FRAMES = 10


class _Ticks:
    """A stand-in for `track_pins`'s tqdm bar that passes frame counts to a callable, `_TICK_FRAMES` at a time."""

    def __init__(self, report: Callable[[int], None]) -> None:
        self.report, self.pending = report, 0

    def update(self, frames: int = 1) -> None:
        self.pending += frames
        if self.pending >= _TICK_FRAMES:
            self.report(self.pending)
            self.pending = 0

    def __enter__(self) -> _Ticks:
        return self

    def __exit__(self, *exc) -> None:
        if self.pending:  # the last frames, also those before an error
            self.report(self.pending)
            self.pending = 0


def contact_features(track: PinTrack, contacts: Sequence[tuple[int, int]], selected: np.ndarray, *,
                     n_samples: int = 40, rests: Sequence[np.ndarray | None] | None = None) -> PinTrack:
    """``track`` with the features of each contact's feature pins (`pins.tap_features`).

    A contact's frames are resampled on their time stamps, or frame by frame when the stamps are
    not strictly increasing (a decoder without them). A feature pin lost for the whole contact has
    NaN columns; a contact is invalid, its features all NaN, when fewer than `MIN_SEEN_FRACTION` of
    the feature pins were seen in it, or when it has a single frame.

    Parameters
    ----------
    track : PinTrack
    contacts : sequence of (start, stop)
        Frame ranges [start, stop).
    selected : (P,) ndarray of int
        Indices of the feature pins into the track's pins.
    n_samples : int
        Samples per contact (paper: 40).
    rests : sequence of ((N, 2) ndarray or None), optional
        Per contact, the rest its displacements are measured from, px from the rest frame (the skin's own rest
        before it: `tactip.replay.contacts.feature_rests_of`); None (each, or all): the rest frame.

    Returns
    -------
    PinTrack
        The same track, its ``contacts``, ``features``, ``pins_seen``, ``valid`` and ``errors`` set.
    """
    contacts = [(int(a), int(b)) for a, b in contacts]
    selected = np.asarray(selected, dtype=np.intp)
    features = np.full((len(contacts), int(n_samples), 2 * len(selected)), np.nan)
    seen = np.zeros(len(contacts), dtype=np.int64)
    valid = np.ones(len(contacts), dtype=bool)
    errors: list[PinsError | None] = [None] * len(contacts)
    displacements = track.displacements
    needed = int(np.ceil(MIN_SEEN_FRACTION * len(selected)))
    for k, (begin, end) in enumerate(contacts):
        times = track.timestamps_s[begin:end]
        if not np.all(np.diff(times) > 0):
            times = None
        window = displacements[begin:end, selected]
        if rests is not None and rests[k] is not None:
            window = window - np.asarray(rests[k], dtype=np.float64)[selected]
        # Seen = found in a frame of the contact other than the rest frame, whose displacement is 0 by
        # construction: a pin lost in every other frame has no displacement to report, not a still one.
        moving = np.arange(begin, begin + len(window)) != track.rest_frame
        found = seen_pins(window[moving])
        seen[k] = found.sum()
        try:
            if seen[k] < needed:
                raise LostPinError(f"only {seen[k]} of {len(selected)} feature pins were seen in the contact; "
                                   f"its features need at least {needed}")
            features[k] = tap_features(np.where(found[:, None], window, np.nan), n_samples=int(n_samples),
                                       timestamps_s=times)
        except PinsError as exc:  # too few pins seen, or a contact of a single frame
            valid[k], errors[k] = False, exc
    track.contacts, track.features, track.pins_seen, track.valid, track.errors = contacts, features, seen, valid, errors
    return track


def frames_to_features(frames: Iterable, *, start: Start, selected: np.ndarray | Callable[[PinTrack], np.ndarray],
                       contacts: Sequence[tuple[int, int]] | Callable[[PinTrack], Sequence[tuple[int, int]]] | None = None,
                       n_samples: int = 40, rest_frame: int | None = None,
                       progress: bool | Callable[[int], None] = False, total: int | None = None,
                       each_row: Callable[[np.ndarray], None] | None = None,
                       rests: Callable[[PinTrack], Sequence[np.ndarray | None]] | None = None) -> PinTrack:
    """Frames in, pins tracked, contacts and their features out: the station's and replay's one path.

    Parameters
    ----------
    frames, start, rest_frame, progress, total, each_row
        As `track_pins`.
    selected : (P,) ndarray of int, or callable
        The feature pins, or ``selected(track) -> indices`` to choose them among the tracked pins
        (asked before ``contacts``).
    contacts : sequence of (start, stop), or callable, optional
        The contacts, or ``contacts(track) -> bounds`` to find them in the track; None: all the
        frames are one contact (a station's tap).
    n_samples : int
        Samples per contact.
    rests : callable, optional
        ``rests(track)`` (asked after ``contacts``): `contact_features`' rests, one per contact.

    Returns
    -------
    PinTrack
    """
    track = track_pins(frames, start=start, rest_frame=rest_frame, progress=progress, total=total, each_row=each_row)
    if callable(selected):
        selected = selected(track)
    if contacts is None:
        contacts = [(0, len(track.timestamps_s))]
    elif callable(contacts):
        contacts = contacts(track)
    return contact_features(track, contacts, selected, n_samples=n_samples,
                            rests=None if rests is None else rests(track))
