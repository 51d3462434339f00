"""Sequences of contacts with short rests between them, and their ground truth (`ContactEvent`).

A stroke is a press (down, hold, lift) or a slide (down, drag the skin sideways, lift: the pad springs
back as it lifts). Phases are whole frames, so every rest frame is exactly at rest and every contact
frame has ``indentation_mm > 0``: a rest of 2 frames separates two contacts as surely as a long one.

>>> from tactip.sim import SyntheticTacTip
>>> run = SyntheticTacTip.from_preset("radial-led-120").slides([0, 90], distance_mm=4.0, rest_s=3 / 120)
>>> [(e.kind, e.direction_deg) for e in run.events]
[('slide', 0.0), ('slide', 90.0)]
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, replace

import numpy as np

from tactip.sim import _slide
from tactip.sim.contact import Contact, SyntheticFrame

__all__ = ["ContactEvent", "ContactSequence", "ContactSequences", "Stroke"]


@dataclass(frozen=True)
class Stroke:
    """One contact of a sequence: a press, or a slide when ``direction_deg`` is given.

    Attributes
    ----------
    indentation_mm : float
        Depth of the press, mm (> 0).
    direction_deg : float or None
        Direction of the slide, degrees from image x towards image y; None: a press.
    distance_mm : float
        How far the skin is dragged, mm of pad surface (>= 0; slides only).
    gap_width_mm : float
        Width of a gap in the plate, mm (0: flat).
    texture_mm : float
        A slide over a textured plate: how far its ridges (2 mm apart) move the pins in the contact
        patch back and forth along the slide, mm (0: a smooth plate; `Contact.texture_mm`).
    """

    indentation_mm: float
    direction_deg: float | None = None
    distance_mm: float = 0.0
    gap_width_mm: float = 0.0
    texture_mm: float = 0.0

    def __post_init__(self):
        if not (math.isfinite(self.indentation_mm) and self.indentation_mm > 0):
            raise ValueError(f"indentation_mm must be > 0, got {self.indentation_mm!r}")
        if not (math.isfinite(self.distance_mm) and self.distance_mm >= 0):
            raise ValueError(f"distance_mm must be >= 0, got {self.distance_mm!r}")
        if self.direction_deg is not None and not math.isfinite(self.direction_deg):
            raise ValueError(f"direction_deg must be finite or None, got {self.direction_deg!r}")

    @property
    def kind(self) -> str:
        """"slide" or "press"."""
        return "press" if self.direction_deg is None else "slide"


@dataclass(frozen=True)
class ContactEvent:
    """Ground truth of one contact in a sequence.

    Attributes
    ----------
    kind : {"press", "slide"}
    start_frame, stop_frame : int
        Frames ``start_frame <= k < stop_frame`` are in contact (indentation > 0); the frames just
        before and after are at rest.
    start_s, stop_s : float
        Time stamps of ``start_frame`` and ``stop_frame``, s.
    peak_indentation_mm : float
    direction_deg : float or None
        Direction of a slide, degrees from image x towards image y (None for a press).
    distance_mm : float
        Slide distance along the pad surface, mm (0 for a press).
    """

    kind: str
    start_frame: int
    stop_frame: int
    start_s: float
    stop_s: float
    peak_indentation_mm: float
    direction_deg: float | None = None
    distance_mm: float = 0.0


class ContactSequence:
    """Frames of a sequence of strokes, rendered on demand, with the contacts' ground truth.

    Attributes
    ----------
    contacts : tuple of Contact
        The contact state of every frame.
    timestamps_s : (T,) float64 ndarray
        ``k / frame_rate``, s.
    events : tuple of ContactEvent
        One per stroke, in order.
    frame_rate : float
        Frames per second.
    """

    def __init__(self, sensor, contacts, events, frame_rate: float):
        self._sensor = sensor
        self.contacts, self.events, self.frame_rate = tuple(contacts), tuple(events), float(frame_rate)
        self.timestamps_s = np.arange(len(self.contacts)) / self.frame_rate

    def __len__(self) -> int:
        return len(self.contacts)

    def __iter__(self) -> Iterator[SyntheticFrame]:
        for contact, t in zip(self.contacts, self.timestamps_s):
            yield self._sensor.render(contact, timestamp_s=float(t))

    def in_contact(self) -> np.ndarray:
        """(T,) bool: frames with the plate pressed in."""
        return np.array([c.indentation_mm > 0 for c in self.contacts])

    def displacements_px(self) -> np.ndarray:
        """(T, N, 2) float64, px: every pin's true displacement from its rest place in each frame (the
        renderer's ground truth), NaN where the pin is not visible."""
        rest, _ = self._sensor.pin_centres()
        frames = np.empty((len(self.contacts), len(rest), 2))
        for k, contact in enumerate(self.contacts):
            centres, visible = self._sensor.pin_centres(contact)
            frames[k] = np.where(visible[:, None], centres - rest, np.nan)
        return frames


def _frames(duration_s: float, frame_rate: float, name: str, minimum: int) -> int:
    if not (math.isfinite(duration_s) and duration_s >= 0):
        raise ValueError(f"{name} must be >= 0, got {duration_s!r}")
    return max(minimum, int(round(duration_s * frame_rate)))


def schedule(strokes: Sequence[Stroke], *, frame_rate: float, rest_s: float, press_s: float, hold_s: float,
             slide_s: float, lift_s: float, gap_angle_deg: float = 0.0, residual: float = 0.0,
             creep_s: float = 0.1, final_rest_s: float | None = None, min_area: float | None = None,
             set_share: float = 0.0, set_s: float = math.inf):
    """The contact state of every frame of a sequence, and its events.

    Each phase lasts a whole number of frames (at least one; ``rest_s`` and ``hold_s`` may round to
    one): rest, then per stroke a raised-cosine press to full depth, a hold (press) or a raised-cosine
    slide (slide), a raised-cosine lift releasing depth and slide together (the pad springs back), and
    a rest (the last one ``final_rest_s`` long; None: ``rest_s``). Returns (contacts, events).
    ``rest_s`` may instead be a sequence of ``len(strokes) + 1`` rests, s: before the first stroke,
    between each two and after the last (uneven rests, as a hand leaves them; ``final_rest_s`` must
    then be None).

    ``residual`` > 0 (opt-in; 0 renders as before) makes the skin viscoelastic: a slide's lift
    releases the drag only down to that share of it, and the skin's shear then creeps back to rest
    exponentially with time constant ``creep_s`` s, through the rests and the strokes after (their
    drags add to what is left of it): a real elastomer relaxes over tens of frames, not at once.
    ``set_share`` > 0 (opt-in; 0 as before) is a second, slower term of that relaxation (a two-term Prony
    series, as a viscoelastic solid's is written): that share of each drag is also left at the lift and
    relaxes with time constant ``set_s`` s (infinite, the default: a set the skin keeps), so the skin is
    not back at its first frame's rest between contacts, nor at the end.
    ``min_area`` in (0, 1) (opt-in; None as before) squeezes the skin ahead of a slide to no less than
    that share of its area (where the pad's base leaves room: `tactip.sim._slide.decay_for_area_mm`).
    """
    if not (math.isfinite(frame_rate) and frame_rate > 0):
        raise ValueError(f"frame_rate must be > 0, got {frame_rate!r}")
    if np.ndim(rest_s) == 1:
        if len(rest_s) != len(strokes) + 1 or final_rest_s is not None:
            raise ValueError(f"rest_s: a sequence of rests needs one more than the {len(strokes)} strokes "
                             f"(got {len(rest_s)}) and final_rest_s None")
        rests = [_frames(float(r), frame_rate, "rest_s", 1) for r in rest_s]
    else:
        rests = [_frames(rest_s, frame_rate, "rest_s", 1)] * (len(strokes) + 1)
        if final_rest_s is not None:
            rests[-1] = _frames(final_rest_s, frame_rate, "final_rest_s", 1)
    n_rest = rests[0]
    n_press, n_lift = _frames(press_s, frame_rate, "press_s", 1), _frames(lift_s, frame_rate, "lift_s", 1)
    n_hold, n_slide = _frames(hold_s, frame_rate, "hold_s", 1), _frames(slide_s, frame_rate, "slide_s", 1)
    if not (math.isfinite(residual) and 0.0 <= residual < 1.0):
        raise ValueError(f"residual must be in [0, 1), got {residual!r}")
    if not (math.isfinite(creep_s) and creep_s > 0):
        raise ValueError(f"creep_s must be > 0, got {creep_s!r}")
    if min_area is not None and not (math.isfinite(min_area) and 0.0 < min_area < 1.0):
        raise ValueError(f"min_area must be None or in (0, 1), got {min_area!r}")
    if not (math.isfinite(set_share) and 0.0 <= set_share < 1.0 - residual):
        raise ValueError(f"set_share must be in [0, 1 - residual), got {set_share!r}")
    if not set_s > 0:
        raise ValueError(f"set_s must be > 0 (inf: a set kept), got {set_s!r}")
    left = residual + set_share  # the share of a slide's drag the lift leaves in the skin
    rest = Contact()
    contacts, events = [rest] * n_rest, []
    for number, stroke in enumerate(strokes):
        start = len(contacts)
        sx = sy = 0.0
        if stroke.kind == "slide":
            angle = math.radians(stroke.direction_deg)
            sx, sy = stroke.distance_mm * math.cos(angle), stroke.distance_mm * math.sin(angle)
        down = 0.5 * (1 - np.cos(np.pi * np.arange(1, n_press + 1) / n_press))  # (0, 1]
        middle = (np.ones(n_hold) if stroke.kind == "press" else np.ones(n_slide))
        along = (np.zeros(n_hold) if stroke.kind == "press"
                 else 0.5 * (1 - np.cos(np.pi * np.arange(1, n_slide + 1) / n_slide)))
        up = 0.5 * (1 + np.cos(np.pi * np.arange(1, n_lift + 1) / (n_lift + 1)))  # (1, 0): still touching
        depth = np.concatenate([down, middle, up])
        dragged = np.concatenate([np.zeros(n_press), along, left + (1.0 - left) * up])
        decay = 0.0 if min_area is None else _slide.decay_for_area_mm(stroke.distance_mm, min_area)
        if set_share > 0 and stroke.kind == "slide":  # the drag and what it leaves keep the whole slide's fall-off
            decay = max(decay, _slide.SLIDE_DECAY_MM, _slide.DECAY_PER_SLIDE * stroke.distance_mm)
        sliding = stroke.kind == "slide"
        for fraction, share in zip(depth, dragged):
            contacts.append(Contact(stroke.indentation_mm * float(fraction), stroke.gap_width_mm, 0.0, gap_angle_deg,
                                    sx * float(share), sy * float(share), slide_decay_mm=decay,
                                    texture_mm=stroke.texture_mm if sliding else 0.0))
        stop = len(contacts)
        events.append(ContactEvent(stroke.kind, start, stop, start / frame_rate, stop / frame_rate,
                                   stroke.indentation_mm, float(stroke.direction_deg) if sliding else None,
                                   float(stroke.distance_mm) if sliding else 0.0))
        contacts.extend([rest] * rests[number + 1])
    if left > 0:
        terms = [(residual, math.exp(-1.0 / (creep_s * frame_rate)))] if residual > 0 else []
        if set_share > 0:
            terms.append((set_share, math.exp(-1.0 / (set_s * frame_rate))))
        contacts = _creep(contacts, events, strokes, terms, laid_out=set_share > 0)
    return contacts, events


def _creep(contacts, events, strokes, terms, laid_out: bool = False) -> list:
    """``contacts`` with what each slide's drag leaves in the skin after it (``Contact.shear_x_mm``,
    ``shear_y_mm``): for each (share, decay) of ``terms``, that share of it at its last frame, shrinking by
    the factor ``decay`` per frame after. ``laid_out``: the frames after a slide keep its fall-off as the
    shear's (``Contact.shear_decay_mm``, until the next slide ends): what is left relaxes in the shape the
    drag had, whatever presses on it."""
    if laid_out:
        falloff = np.zeros(len(contacts))
        for event in events:
            if event.kind == "slide":
                falloff[event.stop_frame:] = contacts[event.stop_frame - 1].slide_decay_mm
        contacts = [replace(c, shear_decay_mm=float(f)) if f else c for c, f in zip(contacts, falloff)]
    left = np.zeros((len(contacts), 2))
    for event, stroke in zip(events, strokes):
        if stroke.kind == "slide":
            angle = math.radians(stroke.direction_deg)
            frames = np.arange(1, len(contacts) - event.stop_frame + 1)
            for share, decay in terms:
                left[event.stop_frame:] += (share * stroke.distance_mm * np.array([math.cos(angle), math.sin(angle)])
                                            * decay ** frames[:, None])
    return [replace(c, shear_x_mm=float(dx), shear_y_mm=float(dy)) if dx or dy else c
            for c, (dx, dy) in zip(contacts, left)]


class ContactSequences:
    """Sequences of presses and slides for `SyntheticTacTip` (it inherits these methods)."""

    def sequence(self, strokes: Sequence[Stroke], *, rest_s: float = 0.25, press_s: float = 0.2,
                 hold_s: float = 0.1, slide_s: float = 0.4, lift_s: float = 0.2,
                 frame_rate: float | None = None, residual: float = 0.0, creep_s: float = 0.1,
                 final_rest_s: float | None = None, min_area: float | None = None, set_share: float = 0.0,
                 set_s: float = math.inf) -> ContactSequence:
        """Frames of presses and slides separated by rests, with the contacts' ground truth.

        Parameters
        ----------
        strokes : sequence of Stroke
            The contacts, in order.
        rest_s : float or sequence of float
            Rest before the first stroke, between strokes and after the last, s (at least one frame:
            a rest of 2-5 frames is a short rest); or one rest per place, ``len(strokes) + 1`` of them
            (uneven rests; `schedule`).
        press_s, hold_s, slide_s, lift_s : float
            Durations of pressing down, holding (presses), dragging (slides) and lifting, s (each at
            least one frame).
        frame_rate : float or None
            Frames per second; None: the sensor's `frame_rate`.
        residual, creep_s, final_rest_s : float
            Opt-in viscoelastic skin (`schedule`): the share of each slide's drag left when the plate
            lifts (0: none, the default), its creep back to rest's time constant, s, and the last
            rest's length, s (None: ``rest_s``).
        set_share, set_s : float
            Opt-in slower relaxation (`schedule`): the share of each slide's drag also left when the plate
            lifts (0: none, the default), relaxing with time constant ``set_s``, s (inf: a set the skin keeps).
        min_area : float or None
            Opt-in stiffer skin (`schedule`): the least share of its area the skin ahead of a slide
            is squeezed to (None: the default model, down to 21 %).

        Returns
        -------
        ContactSequence
            Iterate it for the `SyntheticFrame` s; ``events`` lists the contacts (frame bounds, kind,
            direction, peak indentation).

        Examples
        --------
        >>> from tactip.sim import SyntheticTacTip
        >>> run = SyntheticTacTip(pins=127).sequence([Stroke(3.0), Stroke(3.0, 45.0, 2.0)], rest_s=0.1)
        >>> [e.kind for e in run.events], len(run) == sum(1 for _ in run)
        (['press', 'slide'], True)
        """
        frame_rate = self.frame_rate if frame_rate is None else frame_rate
        contacts, events = schedule(list(strokes), frame_rate=frame_rate, rest_s=rest_s, press_s=press_s,
                                    hold_s=hold_s, slide_s=slide_s, lift_s=lift_s, residual=residual,
                                    creep_s=creep_s, final_rest_s=final_rest_s, min_area=min_area,
                                    set_share=set_share, set_s=set_s)
        return ContactSequence(self, contacts, events, frame_rate)

    def slides(self, directions_deg, *, distance_mm: float = 3.0, indentation_mm: float = 2.0,
               **timing) -> ContactSequence:
        """Frames of slides in the given directions, each a press, a drag and a lift, with rests between.

        Parameters
        ----------
        directions_deg : sequence of float
            Direction of each slide, degrees from image x towards image y.
        distance_mm : float
            How far each slide drags the skin, mm of pad surface (about 3 pitches of a 120-pin pad at 8 mm).
        indentation_mm : float
            Depth of each press, mm.
        **timing
            ``rest_s``, ``press_s``, ``slide_s``, ``lift_s``, ``frame_rate`` and the opt-in residual
            shear (``residual``, ``creep_s``, ``set_share``, ``set_s``, ``final_rest_s``) and stiffer skin
            (``min_area``) as in `sequence`.

        Returns
        -------
        ContactSequence

        Examples
        --------
        >>> from tactip.sim import SyntheticTacTip
        >>> run = SyntheticTacTip(pins=127).slides(range(0, 360, 45), rest_s=0.02, frame_rate=120.0)
        >>> len(run.events), run.events[1].direction_deg
        (8, 45.0)
        """
        return self.sequence([Stroke(indentation_mm, float(a), distance_mm) for a in directions_deg], **timing)

    def taps(self, count: int, *, indentation_mm: float = 3.0, gap_width_mm: float = 0.0,
             **timing) -> ContactSequence:
        """Frames of ``count`` plain presses (taps) with rests between them.

        Parameters
        ----------
        count : int
            Number of taps (>= 1).
        indentation_mm, gap_width_mm : float
            Depth of each tap and width of the gap under it, mm.
        **timing
            ``rest_s``, ``press_s``, ``hold_s``, ``lift_s``, ``frame_rate`` as in `sequence`.

        Returns
        -------
        ContactSequence
        """
        if int(count) != count or count < 1:
            raise ValueError(f"count must be an integer >= 1, got {count!r}")
        return self.sequence([Stroke(indentation_mm, gap_width_mm=gap_width_mm)] * int(count), **timing)
