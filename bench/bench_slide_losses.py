"""Why visible pins are lost in slides on webcam-like video (issue 20, outcome 1): the split per cause.

The recording is `bench_user_chain`'s tour (9 slides of 3 pitches in eight directions, presses between some,
2.0 mm deep, 120 frames/s, rests of 1-3 frames and some of 0.5-1 s) filmed as its webcam films it
(`bench_conditions.Camera`: the pad off-centre, a glare gradient of 50, noise 4-8; each frame through JPEG at
MJPG's quality 75, in memory; `HIDDEN_PINS` central pins hidden during each contact), or ``--clean`` (no noise
or glare, JPEG quality 100, nothing hidden). The tracker starts as `tactip replay` starts it (`find_pin_field`
on the rest frame, `PinTracker` with its parameters and disc); the renderer's truth follows every frame.

Per preset and seed, over the frames in contact: visible pins (the renderer's ``visible``: drawn, whole in
the frame) reported lost per frame (median, max, sum of pin-frames), swapped pin-frames (placed nearer another
visible pin's true centre than their own and more than 0.3 true pitch from it; ``apart``: those two centres
at least half a pitch apart), and each lost visible pin-frame's cause:

- merged:   another visible tip's true centre within two tip radii (``touching``: within 2 radii + 1 px, the
            edge ramps): one blob in the image, lost as outcome 1 allows (occluded);
- pulled:   a window at the pin's true centre moves by more than the plausibility bound (a neighbour's tip
            inside it: nearly merged); ``+judged``: its tip also unlike at rest;
- judged:   the window at the true centre stays, but the tip is unlike the pin's own at rest (`pins._like`:
            contrast, area, compactness), which judgement is named;
- searched: the window at the true centre passes every judgement; the pin's prediction (`pins._predict`, from
            its neighbours placed in this frame) lies within the gate of the truth and is trusted
            (`Refiner._trusted`), yet the pin was not placed (the frame's search trusted it from the last
            frame's placements, or `pins._identity` unplaced it: another pin expected nearer);
- untrusted: as searched, but the prediction is not trusted (fewer than most neighbours placed);
- far:      the prediction lies beyond the gate from the truth.

Figures (session 18, slide13; main 6705663; radial-led-120; seeds 0-5 developed on, 48-50 held out; 4-9 s of
CPU a tour of 461-867 frames):
- webcam-like, seeds 0-5: 1387-1781 lost visible pin-frames a tour (median 0-2 a frame in contact, max 29-44;
  the 6 hidden pins not counted), 9377 in all: merged 49.1 %, touching 7.9 %, pulled 12.1 % (+judged 1.8 %),
  judged 0.7 %, searched 6.7 %, untrusted 13.3 %, far 8.5 %; swaps 14-35 pin-frames (apart 3-29);
- clean, seeds 0-5: 8394 in all (0/27-35 a frame): merged 61.6 %, touching 8.3 %, pulled 4.7 % (+1.0 %),
  judged 0.1 %, searched 7.1 %, untrusted 9.5 %, far 7.7 %: the camera's noise and glare add pulled windows
  (a noisy neighbour's foot in the window), not judgements;
- held out, webcam-like, seeds 48-50: 5062 in all: merged 46.2 %, touching 7.6 %, pulled 11.8 % (+3.7 %),
  judged 1.3 %, searched 8.5 %, untrusted 13.9 %, far 6.9 %.
So about 57 % of the lost visible pin-frames are tips merged in the squeezed skin (outcome 1 allows them),
14 % lie so near a neighbour that the window at the truth is pulled off (a two-tip fit, `pins._pairfit`, is off
for tips under 3 px), under 2 % are judged unlike at rest (contrast, area, compactness), and the tracker's own
share, a tip a window would place, is about 29 %: its prediction from neighbours off by more than the gate
(8 %), not trusted (its neighbours lost too: 13 %), or searched from the last frame's neighbours and missed or
unplaced by `pins._identity` (7 %). Searching those again from the frame's own placements (a second search,
gate x1 / x0.25) cut the lost pin-frames by 16 % / 9 % but raised swaps (tour: 132 -> 162 / 135; bench_slides'
two slides, seeds 0-5: any swap 38 -> 96, apart 0 -> 15 at gate x0.25): dropped.

Session 19 (slide14; main 09118d1 -> LK in frames where many pins are not placed starts from the frame's motion
field fitted to the pins placed, `pins._motion`), webcam-like, seeds 0-5: lost visible pin-frames 9192 -> 8475
(1631/1507/1387/1729/1566/1372 -> 1520/1351/1235/1654/1473/1242; max a frame 29-44 -> 20-27): merged 4611 -> 4554,
touching 750 -> 651, pulled 1094 -> 1066 (+judged 162 -> 146), judged 60 -> 54, searched 607 -> 471, untrusted 1196
-> 1064, far 712 -> 469 (the tracker's own share 2515 -> 2004); swaps 100 -> 85 (apart 62 -> 45).

Where identity swaps begin (``--onsets``, issue 20 outcome 2): `bench_conditions`' slides (8 slides of 3 pitches,
2 mm deep, at ``--fps``), tracked as its slides check tracks them; each onset of an apart swap (a visible pin placed
nearer another pin's true centre than its own, the two at least half a pitch apart, and not so in the frame before)
is split by the step of `pins.track.PinTracker` that placed the pin there (the last to move it: ``follow`` passes,
``LK`` from constant-velocity guesses or ``LK(field)`` from the motion field's, ``snap`` to rest, ``restore`` of
`pins._return`, ``pairfit``, ``recover`` from blobs, ``fit`` of sloped tips), by the slide's phase (press, drag,
lift, rest), by the pin's state in the frame before (``ok``, ``lost``, or ``merged``: nearer another's centre less
than half a pitch away, the two tips one blob) and by its guess's error (spacings from its true centre).
Session 20 (slide16; main 854fe70), 120 frames/s, seeds 0-5, apart pin-frames and onsets:
- tactip-331: 941 pin-frames (drag 550, lift 391), 528 onsets: follow 396 (drag 267, lift 129), pairfit 127
  (lift 81, drag 46), LK(field) 4, snap 1; by the state before: follow in the drag after ``merged`` 155, ``ok`` 66,
  ``lost`` 46; follow in the lift after ``lost`` 59, ``ok`` 57; pairfit in the lift after ``ok`` 51. The pair fit's
  onsets looked at (seed 0) are pins already lagging about 0.7 spacings, moved by about 1 px across the midpoint.
- tactip-127: 106 pin-frames (drag 21, lift 85), 76 onsets: follow 56 (lift 40, drag 16), LK 11 and LK(field) 5
  (lift), pairfit 3, recover 1.
So on the 331-pin pad the swaps begin in the follow passes, where a window in the skin squeezed ahead of the plate
settles on the merged blob of its tip and one approaching from behind (its missing neighbour expected where it
lagged, the window is wide enough to take that tip's side), and the constant-velocity guess carries that pull on
frame by frame (tactip-331 seed 0: a pin's window stepping 2.4-2.6 px a frame backwards for four frames while its tip
moved 0.1-3 px forwards); and in the lifts' first frames, where the skin springs back 0.65 spacings in one frame
and the motion field, fitted to the pins the follow passes placed (some on the tips that moved into their places),
steps the fast pins by a fifth of that.
Tried and dropped (session 20, apart pin-frames, 120 frames/s, seeds 0-5 unless said, main -> tried):
- a moving pin's step carried as its neighbours' median step where it runs against or across it (dot product <= 0)
  and lies farther from it than half of it plus 0.1 spacings, on frames the follow passes placed (no LK retry):
  tactip-331 941 -> 760, tactip-127 106 -> 69, dense-1000 (seeds 0-1) 303 -> 273, but dark-331 1148 -> 1219,
  radial-led-120 6 -> 8, and this bench's lost visible pin-frames (radial-led-120 webcam) 8994 -> 9325 (apart 53 ->
  51); at 30 frames/s unchanged (every such frame retries LK), without that gate tactip-127 4988 -> 5423. On the
  331-pin pads the median was the better guess (against the truth of the next frame) for 42 % (tactip-331) and 38 %
  (dark-331) of the pins changed, both about 0.25 spacings off (pins already lagging); 68 % on tactip-127. Variants
  (tactip-331 / tactip-127 / dark-331): no direction condition 808 / 57 / 1390, 0.2 spacings 935 / 89 / 1158, only
  pins still the frame before 745 / 73 / 1194;
- in frames that retry LK, a second look: the field refitted to every pin placed after LK, the pins placed more than
  half a spacing off it looked for again by LK from it: tactip-331 941 -> 944, dark-331 1148 -> 1152, tactip-127 106
  -> 94, radial-led-120 6 -> 7, tactip-127 at 30 frames/s 4988 -> 5082 (offline on tactip-331 seed 0's lifts the
  refit would take off 48 of 137 pins placed more than half a spacing off, and 14 placed right);
- follow windows no wider than 1.2 tip radii + 1 px for pins whose window neighbours are missing: tactip-331 941 ->
  1113, dark-331 1148 -> 1168, tactip-127 106 -> 176.
Not tried, for want of cases: a rule against folds (two neighbours at rest in inverted order): on tactip-331 seed 0,
2 of 150 apart pin-frames have a placed neighbour in inverted order; the pin whose tip is taken is mostly missing.
Kept (session 20, slide17): a re-centred follow window that holds two or more tips (local maxima of the crop blurred to
half a tip radius) has them assigned one-to-one to the pin's guess and its neighbours' expected places (missing ones at
their predictions), `pins._follow._Following._part_tips`. Apart pin-frames, seeds 0-5 (dense-1000 0-2 here, 0-5 in
`bench_conditions` --checks slides), 120 frames/s: tactip-331 941 -> 683 (onsets 528 -> 380), dark-331 1148 -> 985,
tactip-127 106 -> 79, dense-1000 426 -> 336 (0-5: 857 -> 638), radial-led-120 6 -> 7; 30 frames/s: 7309 -> 7324,
7174 -> 7046, 4988 -> 5071, 292 -> 272, 1509 -> 1542; held out 48-53 at 120: tactip-331 815 -> 723, dark-331 1068 ->
910. After the return, every row as before (0 swaps, 0 > 1 px, 0 lost). Lost visible pin-frames (webcam-like
radial-led-120) 8994 -> 8883, held out 48-50 4616 -> 4674 (merged 2190 -> 2237). Variants: every window with two
tips re-measured (as kept) against only those whose centroid lay more than 0.5 / 0.25 tip radii from the tip assigned
to it: tactip-331 683 against 779 / 699, dark-331 985 against 1045 / 1000, lost 8883 against 9029 / 9130.
Session 21 (part21): the same test compiled (`pins._jit_follow`: each window's own pixels, a first look over its
square, then the reference's test where two tips may be), the same figures: tactip-331 683 (onsets 380), dark-331 985
(497), tactip-127 (seeds 0-2) 43, radial-led-120 (0-2) 3, lost visible pin-frames 8849 (slide17 reported 8883 on its main).
Session 21 (swap21; main 2bcbdb2), onsets at 120 frames/s, tactip-331 + dark-331 seeds 0-2: 432 (185 + 247), drag 247
(follow 205, pairfit 42), lift 185 (follow 91, pairfit 82, LK(field) 7, snap 5). Of the drag's follow onsets 195 of
203 are pins on the tip of a pin lost the frame before and after, 92 of them placed in the first pass (their guesses
on that tip: a merged blob parted again). In the lift, where the field was fitted, the pins swapped lie where it puts
them (within 0.25 spacings) and it lies 0.5 spacings or more from their truth; fitted to the truth of the same pins it
is still 0.25-0.5 off for most: the field's form, not only the pins it is fitted to. Kept (swap21): first-pass pins
beside a missing pin (window neighbours) join `pins._follow._Following._part_tips` (tips >= 3 px). Apart pin-frames,
seeds 0-5: tactip-331 683 -> 540, dark-331 985 -> 844; held out 48-53: tactip-331 723 -> 557, dark-331 910 -> 816;
tactip-127 79 -> 109 (worse: its lifts, LK(field) and pairfit onsets, seed 4 12 -> 33); radial-led-120 (2 px tips, not
parted) unchanged. Tried: every tip size (radial-led-120 lost visible pin-frames 8555 -> 8634, main measured again
here: 8555, not part21's 8849; tracker CPU on `bench_replay.py --slides 8` +8-14 %; as kept, on tactip-331's slides
(`--preset tactip-331`, where it engages) 1.59-1.60 -> 1.72-1.73 ms/frame, +8 %); only pins whose missing neighbour is
expected within 0.5 / 1.0 spacings (seeds 0-2, tactip-331 306 / 269 against 249 for any, dark-331 501 / 435 against
423); first-pass pins left where they were when assigned no tip (268, 433, tactip-127 67 against 61: unplacing them
pays); only neighbours lost the frame before too (278, 415).

Session 22 (swap22; main fb192f9): swap21's rise on tactip-127 (seeds 0-5 79 -> 109) was no drift in the rule: the
onsets it added (LK, LK(field), pairfit in lifts' first frames, seeds 0 and 4) begin where the motion field, fitted to
the pins placed, flips on pins re-measured 0.2-0.5 px off two frames before (seed 0; `pins._motion`), and over seeds
6-23 swap21 lowered tactip-127 from 345 to 222. Kept (swap22): a first-pass pin the assignment gives no tip stays where
it is; one given another pin's tip (farther than a tip radius from where it is) is unplaced; one given its own is
re-measured there (that is what gains). Apart pin-frames, main -> swap22: seeds 0-5 tactip-331 683 -> 509, dark-331 985
-> 847, tactip-127 79 -> 107 (seeds 0 and 4: 15 -> 31, 12 -> 32; the others 52 -> 44), radial-led-120 7 -> 7 (2 px tips:
not engaged); seeds 6-23 2058 -> 1704, 2920 -> 2559, 345 -> 192; held out 48-53 723 -> 597, 910 -> 799, 87 -> 70 (swap21
there: 557, 816). Variants (seeds 0-5, tactip-127 / tactip-331 / dark-331, as separate calls): own tips not re-measured
77 / 667 / 921 (tactip-127 seeds 6-23: 303), with those given no tip unplaced 84 / 635 / 909, those given another's
unplaced 64 / 626 / 939; every first-pass pin kept placed (moved, never unplaced) 130 / 567 / 864.

Session 22 (retire22; main 4f5966d): retired pins are guessed every `check_every` frames at their rest positions moved
by the median displacement of the 8 placed pins nearest at rest, where those agree within 0.05 spacings
(`pins._motion.retired_guesses`), and followed from there. On the webcam-like tour (this bench's) 43 % of the lost
visible pin-frames are retired pins (seeds 0-2: 1788 of 4135; 288 with no neighbour placed), most of them merged; on
the same tour with `bench_tour_contacts`' creeping skin (residual 0.1, creep 1 s, set share 0.02) 91 % (seeds 3/11:
17001 of 18456, 7540 with no neighbour placed; far 54 %, untrusted 23 %). Main -> retire22, lost visible pin-frames
(apart pin-frames): webcam-like seeds 0-2 4135 (22) -> 4109 (22), held out 48-50 4669 (40) -> 4550 (40); creeping
skin seeds 3/5/7/11 33510 (6) -> 9575 (15; seed 3: 0 -> 12), held out 48-51 32428 (8) -> 12644 (20): the swaps rise
there. ``--onsets`` seeds 0-2 tactip-331 228 -> 231, dark-331 427 -> 384, tactip-127 63 -> 60; held out 48-50 331 ->
315, 394 -> 386, 44 -> 34. Agreement 0.1 / 0.25: onsets tactip-331 254 / 266; any retired pin, no agreement: 271, 454,
80; only pins with no neighbour placed: tours 5336 / 4050 (seeds 3 / 11), onsets 228, 437, 64.

Session 23 (swap23; main 43b3857): swap22's rise on tactip-127 seeds 0 and 4 (15 -> 31, 12 -> 32) lies in lifts'
first frames, where a fifth of the pins the follow passes placed (6 of 28-31, the field's fit) stepped 1-2 px while
their tips sprang back half a spacing; the affine field (5 x 2) fitted to them held, with -8 times the last step in x,
and stepped the pins needing LK by about 0.2 spacings (median), under `_LEAST_STEP`: LK started from constant velocity
(0.40 spacings off). Kept (swap23): the field as two scalars (displacement from rest, last step) and a shift
(`pins._motion.spring_steps`), refitted by least trimmed squares where no plain fit holds. Apart pin-frames, main ->
swap23: seeds 0-5 tactip-127 107 -> 71, tactip-331 509 -> 509, dark-331 847 -> 848, radial-led-120 7 -> 7; seeds 6-23
tactip-127 192 -> 190, tactip-331 1704 -> 1711, dark-331 2559 -> 2568; held out 48-53 tactip-127 70 -> 38, tactip-331
597 -> 595, dark-331 799 -> 803 (the 331-pin pads: a few lifts flipped either way, +0.1-0.4 %). Lost visible
pin-frames (webcam-like radial-led-120, seeds 0-2) 4135 -> 4138 (apart 22 -> 20). Tried: the scalar field alone (seeds
0-5: 91, 509, 848, radial-led-120 9); least trimmed squares always (a fifth of the pins, 6 refits: tactip-127 141, its
later lift frames lose their fast pins' steps) or whenever it holds more pins (74); an affine field with the trimmed
refit where no plain fit holds (107: the affine fit holds). Not yet: seeds 0, 6 and 7 each have a lift's first frame
whose plain fit holds but steps the pins under `_LEAST_STEP` (the trimmed fit there: 0.06-0.25 spacings off).

Run: .venv/bin/python bench/bench_slide_losses.py [--presets radial-led-120] [--seeds 0-5] [--clean]
     .venv/bin/python bench/bench_slide_losses.py --onsets [--presets tactip-331,tactip-127] [--fps 120]
"""

from __future__ import annotations

import argparse
import collections
import pathlib
import sys
import time

import cv2
import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

import bench_user_chain as chain  # noqa: E402
import pins.track  # noqa: E402
from bench_conditions import Camera  # noqa: E402
from pins import PinTracker, find_pin_field  # noqa: E402
from pins.disc import as_grey  # noqa: E402
from tactip.sim.sequence import ContactSequence, schedule  # noqa: E402

CAUSES = ("merged", "touching", "pulled", "pulled+judged", "judged", "searched", "untrusted", "far")


def tour(preset: str, seed: int, clean: bool):
    """The tour's frames as (image, true centres px, visible, in contact), and the camera."""
    condition = chain.condition(seed)
    if clean:
        condition = {"shift": condition["shift"], "noise": 0.0, "fps": 120.0}
    camera = Camera(preset, seed, condition)
    sensor = camera.sensor
    rng = np.random.default_rng(seed)
    strokes, rests_s = chain.tour_strokes(sensor.pin_spacing_mm, rng)
    contacts, events = schedule(strokes, frame_rate=sensor.frame_rate, rest_s=rests_s, press_s=0.05, hold_s=0.05,
                                slide_s=0.15, lift_s=0.05, **chain.SKIN)
    run = ContactSequence(sensor, contacts, events, sensor.frame_rate)
    rest, visible = sensor.pin_centres()
    central = np.flatnonzero(visible & (np.linalg.norm(rest - np.asarray(sensor.disc[:2]), axis=1)
                                        < 0.6 * sensor.disc[2]))
    event_of = np.full(len(contacts), -1)
    masks = []
    for number, event in enumerate(events):
        mask = np.zeros(sensor.n_pins, bool)
        if not clean:
            mask[rng.choice(central, chain.HIDDEN_PINS, replace=False)] = True
        masks.append(mask)
        event_of[event.start_frame:event.stop_frame] = number
    quality = 100 if clean else chain.MJPG_QUALITY
    for k, contact in enumerate(run.contacts):
        frame = sensor.render(contact, hidden=masks[event_of[k]] if event_of[k] >= 0 else None,
                              timestamp_s=float(run.timestamps_s[k]))
        image, centres, seen, _ = camera.film(frame)
        image = cv2.imdecode(cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, quality])[1],
                             cv2.IMREAD_UNCHANGED)
        yield camera, image, centres, seen, event_of[k] >= 0


def causes(tracker: PinTracker, image, positions, own, truth, seen, lost: np.ndarray, tip_px: float) -> list[str]:
    """The cause of each lost visible pin (`lost`: their indices) in one frame (the module docstring's)."""
    refiner = tracker._refiner
    crop = tracker._bright(tracker._cropped(as_grey(image)))
    gap = cKDTree(truth[seen]).query(own[lost], k=2)[0][:, 1]
    filled = np.where(np.isnan(positions), own, positions)
    radius = refiner.window_radius(filled)
    centres, measures = refiner.windows.measure(crop, own[lost] - refiner.origin, radius[lost])
    step = np.linalg.norm(centres + refiner.origin - own[lost], axis=1)
    like = refiner._like_at_rest(measures, lost)
    predicted = refiner._predict(positions, lost, tracker._last_seen)
    trusted = refiner._trusted(positions, lost, tracker._last_seen, predicted)
    near = np.linalg.norm(predicted - own[lost], axis=1) <= refiner.gate_px
    named = []
    for j in range(lost.size):
        if gap[j] < 2 * tip_px:
            named.append("merged")
        elif gap[j] < 2 * tip_px + 1.0:
            named.append("touching")
        elif not step[j] <= refiner._max_shift_px:
            named.append("pulled" if like[j] else "pulled+judged")
        elif not like[j]:
            named.append("judged")
        else:
            named.append("far" if not near[j] else "searched" if trusted[j] else "untrusted")
    return named


def one(preset: str, seed: int, clean: bool) -> collections.Counter:
    """Track one tour and print its row; returns the causes' counts."""
    start = time.process_time()
    frames = tour(preset, seed, clean)
    camera, image, truth, seen, _ = next(frames)
    field = find_pin_field(image)
    tracker = PinTracker(detection=field.params, disc=field.disc)
    rest = tracker.start(image, field.centres)
    distance, identity = cKDTree(truth).query(rest)
    real = (distance < 2.0) & seen[identity]
    tip_px = camera.zoom * camera.sensor.pin_radius_px
    counted, per_frame, swapped, apart = collections.Counter(), [], 0, 0
    for _, image, truth, seen, contact in frames:
        positions = tracker.update(image)
        if not contact:
            continue
        own = truth[identity]
        lost = np.flatnonzero(np.isnan(positions[:, 0]) & seen[identity] & real)
        per_frame.append(lost.size)
        placed = np.flatnonzero(np.isfinite(positions[:, 0]) & real)
        nearest = np.flatnonzero(seen)[cKDTree(truth[seen]).query(positions[placed])[1]]
        off = np.linalg.norm(positions[placed] - own[placed], axis=1) > 0.3 * camera.pitch_px
        other = (nearest != identity[placed]) & off
        swapped += int(np.count_nonzero(other))
        apart += int(np.count_nonzero(np.linalg.norm(truth[nearest[other]] - own[placed[other]], axis=1)
                                      >= 0.5 * camera.pitch_px))
        if lost.size:
            counted.update(causes(tracker, image, positions, own, truth, seen, lost, tip_px))
    total = max(sum(counted.values()), 1)
    split = " ".join(f"{c} {counted[c] / total:.0%}" for c in CAUSES)
    print(f"{preset:15s} {seed:3d} {'clean' if clean else 'webcam':6s} lost {int(np.median(per_frame)):2d}/"
          f"{max(per_frame):2d}/{sum(per_frame):5d}  swaps {swapped:3d} (apart {apart:3d})  {split}  "
          f"{time.process_time() - start:5.1f} s", flush=True)
    return counted


STAGES = ("follow", "LK", "snap", "restore", "pairfit", "recover", "fit")


class StageLog:
    """The positions each step of `PinTracker._refine` leaves in one frame (wrapping the steps of one tracker and,
    while in use, the module functions `pins.track` calls): ``log[stage]`` (N, 2) px, ``log["guess"]`` the
    constant-velocity guesses and ``log["field"]`` the guesses after `pins._motion.field_guesses`."""

    def __init__(self, tracker: PinTracker):
        self.log: dict = {}
        refiner, log = tracker._refiner, self.log

        def wrap(owner, name, stage, take=lambda out: out, before=None):
            inner = getattr(owner, name)

            def step(*args, **kwargs):
                out = inner(*args, **kwargs)
                if before is not None:
                    before(args)
                log[stage(log) if callable(stage) else stage] = np.array(take(out), copy=True)
                return out
            setattr(owner, name, step)

        wrap(refiner, "follow", "follow", lambda out: out[0], lambda args: log.__setitem__("guess", args[1].copy()))
        wrap(refiner, "refine", "LK")
        wrap(refiner, "fit_tips", "fit")
        wrap(tracker._rest_match, "restore", "restore")
        self._module = {name: getattr(pins.track, name) for name in ("field_guesses", "kept_on_own_tips",
                                                                     "part_overlapping")}
        wrap(pins.track, "field_guesses", "field", lambda out: out[0])
        wrap(pins.track, "kept_on_own_tips", lambda log: "recover" if "snap" in log else "snap")
        wrap(pins.track, "part_overlapping", "pairfit")

    def close(self) -> None:
        """Put `pins.track`'s functions back."""
        for name, function in self._module.items():
            setattr(pins.track, name, function)

    def placed_by(self, pin: int, position: np.ndarray) -> str:
        """The first step whose output holds the pin where it ended (the last step to move it)."""
        for stage in STAGES:
            if stage in self.log and np.array_equal(self.log[stage][pin], position):
                if stage == "LK" and "field" in self.log and not np.array_equal(self.log["field"][pin],
                                                                                self.log["guess"][pin]):
                    return "LK(field)"
                return stage
        return "?"


def phase(frame: int, events, fps: float) -> str:
    """The slide's phase of a frame (`bench_conditions`' timing: 50 ms press, 150 ms drag, 50 ms lift)."""
    for event in events:
        if event.start_frame <= frame < event.stop_frame:
            into, press = frame - event.start_frame, max(1, round(0.05 * fps))
            return "press" if into < press else "drag" if into < press + max(1, round(0.15 * fps)) else "lift"
    return "rest"


def onsets(preset: str, seed: int, fps: float) -> tuple[int, collections.Counter]:
    """Apart swapped pin-frames through `bench_conditions`' slides and their onsets' split (module docstring)."""
    camera = Camera(preset, seed, {"fps": fps})
    image, centres, visible, _ = camera.film(camera.sensor.render())
    field = find_pin_field(image)
    tracker = PinTracker(detection=field.params, disc=field.disc)
    rest = tracker.start(image, field.centres)
    stages = StageLog(tracker)
    distance, identity = cKDTree(centres).query(rest)
    real = (distance < 2.0 * camera.zoom) & visible[identity]
    sensor = camera.sensor
    run = sensor.slides(range(0, 360, 45), distance_mm=3 * sensor.pin_spacing_mm, indentation_mm=2.0,
                        rest_s=max(3 / fps, 0.025), press_s=0.05, slide_s=0.15, lift_s=0.05)
    counted, apart = collections.Counter(), 0
    before = np.zeros((3, len(rest)), bool)  # apart, merged (any other) swap, lost in the frame before
    try:
        for k, frame in enumerate(run, start=1):
            stages.log.clear()
            filmed, truth, _, _ = camera.film(frame)
            positions = tracker.update(filmed)
            now = np.zeros_like(before)
            placed = np.flatnonzero(real & np.isfinite(positions[:, 0]))
            nearest = cKDTree(truth).query(positions[placed])[1]
            other = nearest != identity[placed]
            gap = np.linalg.norm(truth[nearest] - truth[identity[placed]], axis=1)
            now[0, placed[other & (gap >= 0.5 * camera.pitch_px)]] = True
            now[1, placed[other]] = True
            now[2] = real & np.isnan(positions[:, 0])
            apart += int(np.count_nonzero(now[0]))
            where = phase(k, run.events, fps)
            for pin in np.flatnonzero(now[0] & ~before[0]):
                guess = stages.log.get("field", stages.log["guess"])[pin]
                error = np.linalg.norm(guess - truth[identity[pin]]) / tracker.spacing_px
                state = "lost" if before[2, pin] else "merged" if before[1, pin] else "ok"
                band = next((f"<{b:g}" for b in (0.25, 0.5, 0.75) if error < b), ">=0.75")
                counted[(stages.placed_by(pin, positions[pin]), where, state, band)] += 1
            before = now
    finally:
        stages.close()
    return apart, counted


def print_onsets(presets: list[str], seeds: list[int], fps: float) -> None:
    """One block per preset: apart pin-frames per seed and the onsets' split by step, phase, state, guess error."""
    for preset in presets:
        start, total, counts = time.process_time(), collections.Counter(), {}
        for seed in seeds:
            counts[seed], split = onsets(preset, seed, fps)
            total += split
        print(f"{preset} {fps:g} frames/s: apart pin-frames {sum(counts.values())} "
              f"({' '.join(f'{s}:{n}' for s, n in counts.items())}), {sum(total.values())} onsets, "
              f"{time.process_time() - start:.0f} s", flush=True)
        for depth, name in ((1, "step"), (2, "step, phase"), (3, "step, phase, state before"), (4, "and guess error")):
            merged = collections.Counter()
            for key, n in total.items():
                merged[key[:depth]] += n
            print(f"  by {name}: " + ", ".join(f"{'/'.join(key)} {n}" for key, n in merged.most_common(12)))


def main(argv: list[str] | None = None) -> int:
    """Print one row per preset and seed, and the split over all of them."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--presets", help="presets (default radial-led-120; --onsets: tactip-331,tactip-127)")
    parser.add_argument("--seeds", default="0-5")
    parser.add_argument("--clean", action="store_true", help="no noise, glare, JPEG loss or hidden pins")
    parser.add_argument("--onsets", action="store_true", help="where apart swaps begin in bench_conditions' slides")
    parser.add_argument("--fps", type=float, default=120.0, help="frame rate of the slides (--onsets)")
    args = parser.parse_args(argv)
    if args.onsets:
        print_onsets((args.presets or "tactip-331,tactip-127").split(","), chain.seed_range(args.seeds), args.fps)
        return 0
    args.presets = args.presets or "radial-led-120"
    print("preset          seed video  lost median/max/sum  swaps (apart)  causes (module docstring)  cpu")
    total = collections.Counter()
    for preset in args.presets.split(","):
        for seed in chain.seed_range(args.seeds):
            total += one(preset, seed, args.clean)
    count = max(sum(total.values()), 1)
    print(f"all: {sum(total.values())} lost visible pin-frames: "
          + ", ".join(f"{c} {total[c]} ({total[c] / count:.1%})" for c in CAUSES))
    return 0


if __name__ == "__main__":
    sys.exit(main())
