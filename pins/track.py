"""Pin tracking: follow every pin from frame to frame (paper 002, III-A.3).

Each pin is moved from the previous frame to the next one by the Lucas-Kanade step of `pins.lk`
(`track_pins`, `LKParams`: pyramidal LK with convergence, residual and forward-backward checks).
A pin that fails is *lost*: its position is NaN and `PinTracker.lost` says so; never frozen at an old place.

`PinTracker` adds, on top of the pure `track_pins` (`pins._refine` says how):

- following and refinement: each pin's position is the intensity-weighted centroid of its tip,
  measured in a small window that stays inside the pin's own Voronoi cell, for all pins at once.
  Each frame the windows start at the pins' constant-velocity guesses and are re-centred once
  (`Refiner.follow`); a pin whose window settles within a few tenths of a px near its guess
  needs nothing else. The others are moved by LK forward from the guess (the frame's motion field, `pins._motion`,
  where many fail; the pyramid only then), and LK's answer is checked by its windowed centroid instead of a backward
  LK pass (`Refiner.refine`: near the LK estimate; tip area, contrast and compactness like at
  rest). Displacements come from one estimator at rest and after, so they carry none of its bias,
  and LK errors never add up: after a tap the pins are back at rest to a few hundredths of a px;
- search: a lost pin is looked for in a window around its prediction (its rest position moved
  by the median displacement of its tracked neighbours), re-centred once, and taken when it
  settles on a tip like the pin's own at rest, inside a gate below half the pin spacing, with no
  other pin on that tip: identities are kept without blob detection. Only pins whose predictions
  can be trusted are searched for (most neighbours placed, or a few that are still: `Refiner._trusted`),
  and a pin found keeps its tip only when no other pin is expected nearer to it (`pins._identity`):
  through slides that squeeze the skin ahead of them, a pin is rather lost than on another's tip;
- retirement: a pin lost for more than `retire_after` frames (a rim pin leaving view) is retired:
  searched for once in `check_every` frames, and followed from where the still placed pins around put it;
- recovery at a bounded rate: when a pin that is not retired is still missing, the frame's blobs are detected
  (`pins.detect`, a few ms), at most once in `detect_every` frames: implausible pins take the blob they landed
  on, and free blobs are assigned to lost pins one-to-one (Hungarian method) within the gate around their predictions;
- the surround: pixels of the crop beyond the sensor disc (less its blurred rim; `pins._surround`)
  that a pin's window can reach take the membrane's grey level, so a bright surround next to the
  pins at the rim of a small pad neither pulls their centroids nor makes them look unlike at rest;
- blank frames: a frame where fewer than a tenth of the expected pins are found (LEDs off, a
  black or dropped USB frame, the disc gone) is marked (`blank`, all NaN) and does not replace
  the last good frame as LK's reference, so the next good frame recovers the pins.

Limit: frame-to-frame motion must stay below about half the pin spacing (8 px at 331 pins in a
640x480 frame; a 250 ms tap rise at 20 frames/s moves pins at most ~7 px per frame). Beyond it
the lattice of identical pins aliases: LK and the windows agree on the neighbouring pin. Record
faster taps at a higher frame rate. Where a frame shows the rest frame again, pins are put back on their
own tips whatever the frames between did (`pins._return`: slides filmed at 15-20 frames/s step pins by
1-2 spacings), and `motion_warning` says how often a pin had to be taken off another's (replay lists it).

Speed: everything runs on the disc's crop (LK's pyramids are not reused between frames: `pins.lk`).
`bench/bench_tracking.py` measures one update against a plain 11x11 one-level LK step over the
same pins on a video with rim pins coming and going (`bench/bench_pins.py`: clean taps).
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy.spatial import cKDTree

from ._edge import FrameEdge, read_region, tracking_crop
from ._identity import kept_on_own_tips
from ._motion import field_guesses, retired_guesses
from ._pairfit import part_overlapping
from ._predict import settle
from ._recover import _as_points, match_to_blobs
from ._return import RestMatch, motion_warning, taken_off
from ._refine import Refiner
from ._surround import surround_pixels
from ._window import _squared_norm
from .detect import DetectionParams, _detect
from .disc import SensorDisc, as_grey, find_sensor_disc
from .errors import PinsError, ShapeError
from .lattice import find_pin_field
from .lk import _RETRY_FRACTION, LKParams, _track, track_pins

__all__ = ["LKParams", "track_pins", "match_to_blobs", "PinTracker"]

# A frame in which fewer than this fraction of the expected (not retired) pins are found is blank.
_BLANK_FRACTION = 0.1


class PinTracker:
    """Track a fixed set of pins through a stream of frames, flagging, searching for and recovering lost pins.

    Each `update` (with refinement, the default; `pins._refine` says how):

    1. following (`Refiner.follow`): windows at every pin's constant-velocity guess, re-centred
       up to three times, all pins in one array per pass; a pin whose window settles on a tip like
       its own at rest near its guess is placed. In the same passes the lost pins, and a pin whose
       guess alone failed among neighbours whose guesses held (it vanished, or moved unlike its
       guess near a contact), are searched for around their predictions (rest position moved by
       the median displacement of their placed neighbours) and found inside a gate below half the
       pin spacing, one pin per tip: identities are kept without blob detection;
    2. only when more than a tenth of the pins are not placed (a sudden change of motion: a slide's
       lift): LK forward from the last good frame for them (`_track`, no backward pass: each answer is
       checked by its windowed centroid, `Refiner.refine`), from where the frame's motion field fitted
       to the pins placed puts them (`pins._motion`), and a search for those that fail;
    3. retirement: a pin lost for more than `retire_after` frames (a rim pin out of view) is
       *retired*: searched for only once in `check_every` frames (pins take turns, so a frame
       searches about 1/`check_every` of the retired pins) until it comes back with its identity;
    4. full blob detection with recovery (`Refiner.recover`), only when a pin that is not retired
       is still missing, and at most once every `detect_every` frames: blob detection (a few ms)
       costs at most 1/`detect_every` of it per frame on average, whatever the video. A blob is
       kept only when its window holds a tip like the pin's own at rest (not LED glare).

    A frame in which fewer than a tenth of the expected (not retired) pins are found is *blank*
    (LEDs off, a dropped or black USB frame, the disc gone): all positions are NaN, `blank` is
    True, nothing is detected, no pin counts as lost for longer, and the last good frame stays
    the reference, so the next good frame recovers the pins from their last good positions (by
    windows, LK from the last good frame, and search).

    Parameters
    ----------
    lk : LKParams, optional
        Lucas-Kanade settings; by default a window of about 0.6 pin spacings (measured at
        `start`) and one pyramid level.
    detection : DetectionParams, optional
        Blob detection used for recovery (and for the pins at start when `start` is not given them).
        When not given and `start` is not given the pins, the pins, their polarity (bright pins or
        dark markers), the detection parameters and the disc are found in the rest frame by
        `pins.find_pin_field`, as `tactip detect` and `tactip replay` do; when `start` is given the
        pins, the defaults (`DetectionParams()`, bright pins).
    refine : bool
        Move tracked pins onto their tips' windowed centroids and search for and recover lost pins
        (default). Without it the tracker is plain LK with checks, equal to `track_pins` (but for
        blank frames), and lost pins stay lost.
    gate_fraction : float
        Gate of search and recovery as a fraction of the median nearest-neighbour pin spacing at start, in (0, 0.5).
    neighbours : int
        Tracked neighbours whose median displacement predicts where a lost pin is.
    retire_after : int
        Frames a pin may stay lost before it is retired, >= 1.
    check_every : int
        A retired pin is searched for once in this many frames, >= 1.
    detect_every : int
        At most one frame in this many detects blobs, >= 1 (1: any frame with a missing pin).
    disc : SensorDisc, optional
        The sensor disc; found in the first frame when not given.
    part_overlaps : bool
        With refinement: each frame, a placed pin whose tip overlaps a neighbour's (expected within two tip
        radii: skin squeezed ahead of a slide) is moved onto a fit of the two tips as two discs
        (`pins._pairfit`, compiled: `pins._jit_pairs`), where a window settles between them. On by default, for
        tips of 3 px or more only (`pins._pairfit._SMALLEST_TIP_PX`): on tactip-331 slides (bench/bench_slides.py,
        seeds 0-5; 6-11 held out alike) pin-frames on another pin's tip fall 4735 -> 1154 (model skin) and
        20 -> 0 (realistic);
        radial-led-120's 2 px tips are not fitted (fitted, they lost more visible pins: 2.91 -> 3.08 a frame).
        While tips overlap on a 331-pin pad the tracker's CPU rises ~40 %; with no pair to fit, nothing.

    Attributes
    ----------
    rest_positions, positions : (N, 2) ndarray of float64
        Pins at `start` and after the last `update`, px (NaN where lost).
    lost : (N,) ndarray of bool
        Pins lost in the last frame, retired pins included (all of them in a blank frame).
    retired : (N,) ndarray of bool
        Pins lost for more than `retire_after` frames and not found since.
    blank : bool
        Whether the last frame was blank (nothing trackable).
    frames : int
        Frames seen since `start`, the rest frame included.
    detection_frames : int
        Updates that detected blobs (bounded by `detect_every`).
    blank_frames : int
        Updates whose frame was blank.
    spacing_px : float
        Median nearest-neighbour pin spacing at `start`, px.
    frame_region : (slice, slice) or None
        The (rows, columns) of a frame that `update` reads (the crop, the disc's box), None before `start`.

    Examples
    --------
    >>> from tactip.sim import Contact, SyntheticTacTip
    >>> tap = SyntheticTacTip(pins=331, seed=0).tap(Contact(indentation_mm=3.0, gap_width_mm=2.0), frame_rate=20)
    >>> tracker = PinTracker()
    >>> rest = tracker.start(next(tap).image)
    >>> for frame in tap:
    ...     displacement = tracker.update(frame.image) - rest     # (N, 2) px, NaN where lost
    >>> int(tracker.lost.sum()), tracker.frames
    (0, 20)
    """

    def __init__(self, *, lk: LKParams | None = None, detection: DetectionParams | None = None,
                 refine: bool = True, gate_fraction: float = 0.4, neighbours: int = 6,
                 retire_after: int = 5, check_every: int = 5, detect_every: int = 30,
                 disc: SensorDisc | None = None, part_overlaps: bool = True) -> None:
        if not 0.0 < gate_fraction < 0.5:
            raise ValueError(f"gate_fraction must be in (0, 0.5), got {gate_fraction}")
        for name, value in (("neighbours", neighbours), ("retire_after", retire_after),
                            ("check_every", check_every), ("detect_every", detect_every)):
            if int(value) != value or value < 1:
                raise ValueError(f"{name} must be a positive integer, got {value}")
        self.lk = lk
        self._auto_lk = lk is None
        self._auto_detection = detection is None
        self.detection = detection or DetectionParams()
        self.refine = bool(refine)
        self.gate_fraction = float(gate_fraction)
        self.neighbours = int(neighbours)
        self.retire_after = int(retire_after)
        self.check_every = int(check_every)
        self.detect_every = int(detect_every)
        self.disc = disc
        self.part_overlaps = bool(part_overlaps)
        self.rest_positions: np.ndarray | None = None
        self.positions: np.ndarray | None = None
        self.lost: np.ndarray | None = None
        self.retired: np.ndarray | None = None
        self.blank = False
        self.frames = 0
        self.detection_frames = self.blank_frames = 0
        self.spacing_px = float("nan")
        self.frame_region: tuple[slice, slice] | None = None
        self._previous: np.ndarray | None = None      # crop of the last good frame (the LK reference)
        self._reference: np.ndarray | None = None     # pin positions in it, px (NaN where lost there)
        self._velocity: np.ndarray | None = None
        self._step: np.ndarray | None = None          # the last frame's steps as measured, px (NaN where unknown)
        self._since_good = 1                          # frames from the reference to the next frame
        self._since_detection = 0
        self._lost_run: np.ndarray | None = None
        self._origin = np.zeros(2)
        self._crop = (slice(None), slice(None))
        self._borders = (0, 0, 0, 0)                  # px of replicated border beyond the frame, each side
        self._last_seen: np.ndarray | None = None
        self._refiner: Refiner | None = None
        self._surround = None                         # (flat indices, membrane level) in the crop
        self._edge: FrameEdge | None = None           # which tips the frame's edge cuts (`pins._edge`)
        self._rest_match: RestMatch | None = None     # the rest frame seen again (`pins._return`)
        self._restored = (0, 0, 0)                    # pins it took off others' tips: pin-frames, frames, first

    def __repr__(self) -> str:
        state = "not started" if self.positions is None else (
            f"{len(self.positions)} pins, {int(self.lost.sum())} lost, {int(self.retired.sum())} retired, "
            f"{self.frames} frames")
        return (f"PinTracker(lk={self.lk!r}, detection={self.detection!r}, refine={self.refine}, "
                f"gate_fraction={self.gate_fraction}, neighbours={self.neighbours}, "
                f"retire_after={self.retire_after}, check_every={self.check_every}, "
                f"detect_every={self.detect_every}, part_overlaps={self.part_overlaps}) [{state}]")

    @property
    def windows(self):
        """The refiner's windowed centroids (`pins._window.WindowCentroids`), None before `start` or without refinement.

        Settable after `start`, to a stand-in with the same interface: `pins.accel.WindowBatcher.wrap`'s
        measures the windows of many trackers' frames together (a GPU); positions are the same.
        """
        refiner = getattr(self, "_refiner", None)
        return None if refiner is None else refiner.windows

    @windows.setter
    def windows(self, windows) -> None:
        """Replace the refiner's windowed centroids (after `start`; `ValueError` before)."""
        if getattr(self, "_refiner", None) is None:
            raise ValueError("the tracker has no windows to replace: start it first (with refinement)")
        self._refiner.windows = windows

    @property
    def motion_warning(self) -> str:
        """Since `start`: a warning when pins came back to rest on other pins' tips (the motion between frames
        went beyond what the tracker follows: slides filmed at 15-20 frames/s), naming how often; else ""
        (`pins._return`)."""
        return motion_warning(*self._restored, self.spacing_px)

    @property
    def gate_px(self) -> float:
        """Gate of search and recovery, px (fraction of the pin spacing at start)."""
        return self.gate_fraction * self.spacing_px

    def start(self, frame: np.ndarray, pins: np.ndarray | None = None) -> np.ndarray:
        """Begin tracking from a rest frame.

        Parameters
        ----------
        frame : (H, W) or (H, W, 3) ndarray of uint8
            The first (rest) frame.
        pins : (N, 2) ndarray, optional
            Pin positions in `frame`, px; detected in `frame` when not given (with `detection`, or
            by `pins.find_pin_field` when the tracker was made without it).

        Returns
        -------
        positions : (N, 2) ndarray of float64
            The starting positions (also `rest_positions`), px. With refinement, each pin is moved
            onto its tip's windowed centroid in `frame` (when that lies within the plausibility
            bound of the given position), so that rest and later positions come from the same
            estimator and displacements carry none of its bias.

        Raises
        ------
        NoSensorError
            The frame shows no sensor disc (when the disc is needed and not given), or, searched by
            `pins.find_pin_field`, no pin lattice of a sensor.
        PinsError
            Fewer than two pins to track, or (with refinement) a blank rest frame: fewer than a tenth
            of the pins show a tip where they are given.
        """
        grey = as_grey(frame)
        if pins is None and self._auto_detection:
            field = find_pin_field(grey, disc=self.disc)     # polarity, parameters and disc from the frame
            self.detection, self.disc, pins = field.params, field.disc, field.centres
        if self.disc is None and (self.refine or pins is None):
            self.disc = find_sensor_disc(grey, dark_pins=self.detection.dark_pins)
        if pins is None:
            pins = _detect(grey, self.disc, self.detection).centres
        pins = _as_points(pins, "pins")
        if len(pins) < 2 or not np.isfinite(pins).all():
            raise PinsError(f"need at least two finite pin positions to track, got {len(pins)}")
        self.spacing_px = float(np.median(cKDTree(pins).query(pins, k=2)[0][:, 1]))
        if self._auto_lk:
            # A window a little wider than a pin and narrower than the spacing sees one pin.
            self.lk = LKParams(window_px=int(np.clip(2 * round(0.3 * self.spacing_px) + 1, 7, 31)))
        # The part of the frame LK works on, grown by replicated border beyond it where pins' windows reach.
        self._borders, self._crop, self._origin = tracking_crop(grey.shape, pins, self.spacing_px, self.lk, self.disc,
                                                                self.refine)
        self.frame_region = read_region(grey.shape, self._crop, self.disc)  # (replay maps luma there alone)
        self._previous = self._cropped(grey)
        self._surround = None
        if self.refine and self.disc is not None:
            self._surround = surround_pixels(self._previous, pins, self.disc, self._origin, self.spacing_px,
                                             self.detection.dark_pins)
        if self.refine:
            refiner = Refiner(self._bright(self._previous), pins, self._origin,
                              spacing_px=self.spacing_px, gate_px=self.gate_px, neighbours=self.neighbours,
                              detection=self.detection, disc=self.disc)
            if refiner.settled_share < _BLANK_FRACTION:
                raise PinsError(f"the rest frame is blank: only {refiner.settled_share:.0%} of the pins show a tip "
                                f"where they are given")
            self._refiner = refiner
            given, pins = pins, refiner.rest_positions
            self._rest_match = RestMatch(self._bright(self._previous.copy()), pins, self._origin, self.spacing_px)
        # Tips the frame's edge cuts are lost, by detection's rule with hysteresis (`pins._edge`).
        self._edge = None if not (self.refine and any(self._borders)) else FrameEdge(
            grey, given, pins, self.spacing_px, self.detection.dark_pins, self._refiner.tip_radius_px)
        self.rest_positions = pins.copy()
        self.positions = pins.copy()
        self._reference = pins.copy()
        self._last_seen = pins.copy()
        self._velocity = np.zeros_like(pins)
        self._step = np.zeros_like(pins)
        self.lost = np.zeros(len(pins), dtype=bool)
        self.retired = np.zeros(len(pins), dtype=bool)
        self._lost_run = np.zeros(len(pins), dtype=np.int64)
        self._index = np.arange(len(pins))
        self._everyone = np.ones(len(pins), dtype=bool)  # (every missing pin looked for at rest: `_refine`)
        self.blank = False
        self.frames = 1
        self.detection_frames = self.blank_frames = 0
        self._since_good = 1
        self._since_detection = self.detect_every
        self._restored = (0, 0, 0)
        return self.positions.copy()

    def _cropped(self, grey: np.ndarray) -> np.ndarray:
        """The crop of a grey frame that tracking works on (a copy)."""
        if any(self._borders):
            return cv2.copyMakeBorder(grey[self._crop], *self._borders, cv2.BORDER_REPLICATE)
        return grey[self._crop].copy()

    def update(self, frame: np.ndarray) -> np.ndarray:
        """Track the pins into the next frame.

        Parameters
        ----------
        frame : (H, W) or (H, W, 3) ndarray of uint8
            The next frame, same size as the first.

        Returns
        -------
        positions : (N, 2) ndarray of float64
            Pin positions, px, NaN where lost (see `lost`, `retired`; all NaN when `blank`).
        """
        if self._previous is None:
            raise PinsError("PinTracker.update called before start()")
        grey = as_grey(frame)
        current = self._cropped(grey)
        if current.shape != self._previous.shape:
            raise ShapeError(f"frame size changed: expected the crop {self._previous.shape}, got {current.shape}")
        origin = self._origin
        # Constant velocity over one frame; after blank frames, from where the pins were last seen.
        guess = self._reference + self._velocity if self._since_good == 1 else self._reference
        if self.refine and self._since_good == 1 and self.frames % self.check_every == 0 and self.retired.any():
            # (Where the placed pins around them agree and did not move: not mid-slide, `retired_guesses`.)
            guess[self.retired] = retired_guesses(self._refiner.rest_positions, self._reference, self.retired,
                                                  self.spacing_px, self._refiner.still)
        detected = False
        if self.refine:
            positions, blank, detected = self._refine(grey, current, guess)
        else:
            moved, _ = _track(self._previous, current, self._reference - origin, self.lk, guess=guess - origin)
            positions = moved + origin
            blank = self._too_few(positions)
        if self._edge is not None:
            positions = self._edge.cut(positions)
        self.frames += 1
        self.blank = blank
        if blank:
            self.blank_frames += 1
            self._since_good += 1
            self._since_detection += 1
            positions = np.full_like(positions, np.nan)
            self.positions, self.lost = positions, np.ones(len(positions), dtype=bool)
            return positions.copy()
        self.detection_frames += detected
        self._since_detection = 0 if detected else self._since_detection + 1
        # Constant-velocity guess for the next frame; a pin just found moves like its neighbours.
        velocity = (positions - self._reference) / self._since_good
        if self.refine:
            fresh = (np.isnan(velocity[:, 0]) & np.isfinite(positions[:, 0])).nonzero()[0]
            if fresh.size:
                velocity[fresh] = self._refiner.neighbour_median(velocity, fresh)
            self._step = velocity.copy()  # (the steps as measured: the motion field's regressor, `pins._motion`)
        # A step within the search's settling bound is no motion to carry on (a faint tip's centroid jitters by a few
        # tenths of a px in noise; extrapolated, the jitter would walk the guesses off a still pad), unless the pin's
        # neighbourhood moves beyond its noise (`carried_velocity`).
        if self.refine:
            # (Still for `Refiner._trusted`: moved by no more than a window settles on its guess.)
            self._refiner.still = _squared_norm(velocity) <= self._refiner._guess_px ** 2
            velocity = self._refiner.carried_velocity(velocity, self._refiner.observe_still(velocity))
            self._refiner.remember(positions)  # (where lost pins' neighbours were: `pins._predict`)
            if self._rest_match.matched is not None:  # (the frame shows the rest frame there: no motion)
                velocity[self._rest_match.matched] = 0.0
        self._since_good = 1
        self._previous = current
        self._reference = positions
        self.positions = positions
        # Steps carried (NaN: none), pins lost and retired, where each was last seen (one call: `pins._predict`).
        self._velocity, self.lost, self._lost_run, self.retired = settle(positions, velocity, self._lost_run,
                                                                         self.retire_after, self._last_seen)
        return positions.copy()

    def _refine(self, grey: np.ndarray, current: np.ndarray, guess: np.ndarray) -> tuple[np.ndarray, bool, bool]:
        """Windowed following, LK where needed, search and bounded-rate detection: positions, blank?, detected?"""
        refiner, origin = self._refiner, self._origin
        crop = self._bright(current)
        # Retired pins take turns: each is searched for once in `check_every` frames.
        search = ~self.retired | ((self._index + self.frames) % self.check_every == 0)
        positions, filled = refiner.follow(crop, guess, self._last_seen, search)
        need = np.isnan(positions[:, 0]) & np.isfinite(self._reference[:, 0])  # (not retired pins guessed)
        tracked = positions
        # A few pins not found (searched for from their predictions too) have vanished; when many are not (a sudden
        # change of motion), LK looks for them from the last good frame, each answer checked by its windowed centroid.
        if np.count_nonzero(need) > _RETRY_FRACTION * len(need):
            if self._since_good == 1:
                # From where the frame's motion field, fitted to the pins just placed, puts them (`pins._motion`).
                guess, positions, need = field_guesses(refiner.rest_positions, self._reference, self._step, guess,
                                                       positions, need, self.spacing_px)
            start = np.where(need[:, None], self._reference, np.nan)
            moved, _ = _track(self._previous, current, start - origin, self.lk, guess=guess - origin, backward=False)
            tracked = np.where(need[:, None], moved + origin, positions)
            positions = refiner.refine(crop, tracked, self._last_seen, need, ~need & np.isfinite(positions[:, 0]),
                                       filled=np.where(need[:, None], tracked, filled))
        # On a pad back at rest, pins far from rest (carried onto another tip by a stale guess) and missing ones,
        # retired too (a slide's return: 3-9 left lost 3 frames after it), at their rest positions.
        # (Each pin it moves keeps the tip only where no other pin is expected nearer: issue 20's slides.)
        before = positions
        positions = kept_on_own_tips(positions, refiner.snap_to_rest(crop, positions, self._everyone),
                                     refiner.rest_positions, guess, refiner._identity_index)
        # Pins where the frame shows the rest frame again, whatever the frames between did (`pins._return`).
        positions = self._rest_match.restore(refiner, crop, positions)
        if positions is not before:  # (pins taken off others' tips, by either: `motion_warning`)
            restored = taken_off(before, positions, refiner.rest_positions, self.gate_px)
            if restored:
                self._restored = (self._restored[0] + restored, self._restored[1] + 1, self._restored[2] or self.frames)
        if self.part_overlaps:
            # Placed pins whose tips overlap a neighbour's (squeezed skin ahead of a slide): a fit of both tips.
            positions = part_overlapping(refiner, crop, positions, filled)
        missing = np.isnan(positions[:, 0])
        if not np.count_nonzero(missing):  # (count_nonzero: `ndarray.any` costs 4x more on a few hundred pins)
            return positions, False, False
        if self._too_few(positions):
            return positions, True, False
        wanted = missing & ~self.retired
        detected = bool(self._since_detection + 1 >= self.detect_every and np.count_nonzero(wanted))
        if detected:
            # Blobs only around pins not retired (spread along the rim, they would widen it to most of the disc).
            before = positions
            positions = refiner.recover(grey, tracked, positions, self._last_seen, crop, around=wanted)
            # (A missing pin is expected at its guess, or where lost at its prediction: `filled`.)
            positions = kept_on_own_tips(before, positions, np.where(np.isfinite(tracked), tracked, filled), filled,
                                         refiner._identity_index)
        # Pins just seen, on a sloped background at rest (a veil's or a reflection's flank, which their windows
        # weigh as tip), and missing now: fitted as opaque ellipses where their tips show (not those lost longer).
        fit = (np.isnan(positions[:, 0]) & (self._lost_run == 0) & refiner.sloped).nonzero()[0]
        if fit.size:
            positions = refiner.fit_tips(crop, positions, self._last_seen, fit)
        return positions, False, detected

    def _too_few(self, positions: np.ndarray) -> bool:
        """Whether fewer than a tenth of the pins expected (not retired) were found: a blank frame."""
        expected = int(np.count_nonzero(~self.retired))
        found = int(np.count_nonzero(np.isfinite(positions[:, 0])))
        return found < max(1, _BLANK_FRACTION * expected)

    def _bright(self, crop: np.ndarray) -> np.ndarray:
        """The crop with bright pins (dark markers inverted) and the surround near pins at the membrane's level.

        In place for bright pins: LK then sees the same surround in every frame.
        """
        bright = cv2.bitwise_not(crop) if self.detection.dark_pins else crop
        if self._surround is not None:
            if bright.flags.c_contiguous:  # (a store into the flat view: `ndarray.put` costs 2.4x more)
                bright.reshape(-1)[self._surround[0]] = self._surround[1]
            else:
                bright.put(*self._surround)
        return bright
