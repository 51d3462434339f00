"""Detection and tracking under conditions nobody tuned on: one row per condition, preset and seed.

Issue 20's user judges on real recordings we do not have. Our renders are one frame size per preset, one
frame rate, one lighting; this bench varies, one at a time and then together, what a real recording
varies, and scores against the renderer's ground truth (`tactip.sim`):

- frame size: the same render filmed at 320x240, 1280x720, 1920x1080 (an exact affine warp of a
  noiseless render, anti-aliased when shrunk, then the preset's sensor noise at the final size), the
  pad off-centre, the pad cut by the frame edge (truth: the warped centres, visible inside the frame);
- lighting: exposure gain (x0.6, x1.5), a glare gradient, strong LED reflections, low-contrast tips,
  sensor noise sigma 2-10, JPEG (an MJPG webcam's frames) on top;
- presets: any of `tactip.sim.preset_names()` (layouts, 100-1000 pins, both polarities);
- frame rate: slides at 15, 20 and 30 frames/s (pins 8x, 6x and 4x farther per frame than at 120), also
  with the pad cut by the frame's edge (pins slide out of view and back).

Per row (``--checks``):

- detect:  `find_pin_field` on the rest frame, the polarity decided (what `tactip detect` runs): recall
           and precision against the visible truth (matched within 0.3 true pitch, one to one), the
           position RMSE of the matched pins (px), and the scale (`sensor_scale` with the preset named)
           against the preset's scale at 640x480 times the warp (``d scale``); met when recall and
           precision >= 0.97, RMSE <= 0.5 px and the scale within 2 %; ``warn S`` / ``warn F``: the field's
           warnings (`PinField.warnings`, which `tactip detect` and replay's start print): a saturated pad,
           faint (or small) tips;
- still:   replay's start (`PinTracker` with the field's parameters and disc) then 20 still frames (fresh
           noise, shimmer, JPEG): most pins lost in a frame, retired at the end; met when both are 0;
- slides:  8 slides of 3 pitches at the condition's frame rate with rests between and after: identity
           swaps after the return, and during the slides (``during``: pin-frames, every frame, a placed pin
           nearer another pin's true centre than its own; ``apart``: those two centres at least half a pitch
           apart, not one blob of squeezed tips), pins > 1 px from their true rest place after the return,
           lost then, and pin-frames placed
           on the replicated border beyond the frame (``on border``: within half a tip radius of the frame's
           edge, or beyond: tracked on what the frame cut); met when all 0 (``during`` but ``apart`` apart);
- cli:     `tactip detect FRAME --sensor NAME --json` and `tactip replay` (an MJPG .avi of the still frames)
           as a user runs them: exit status, pins, and replay's lost pins per frame (median/max).

Figures (session 17's audit10, 2-core VM; seeds 40-43, never tuned on; detect and still on tactip-331,
dark-331, radial-led-120, radial-120, brown-127, white-dark-331, tactip-127, small-pad-100, dense-1000 under
every condition; slides and cli on tactip-331, dark-331, radial-led-120, seed 42). Found and mended
(before -> after, `pins`):
- 1920x1080: `find_pin_field` took 11 GB (an MJPG frame) and 22 GB (tactip-331 seed 41): the lattice-hole
  probe tested ~32000 places of ~2200 px at once; killed by the OOM killer -> batches, 76 MB per 4000
  places. On the MJPG frame 39 of 331 true pins were rejected as flat tops (the membrane ring 1.5-3.5 px
  beyond 13 px tips caught their soft edge): 292 -> 331 found;
- white-dark-331 at 1920x1080: the gaps between the pins won the polarity (177 dark 'pins', recall 0) ->
  331/331 bright;
- noise sigma 10-12: radial-led-120 recall/precision 0.38-0.68/0.30-0.62 on 3-5 of 5 seeds, radial-120
  precision 0.85-0.94 -> recall 0.97-1.00, precision 0.99-1.00 (offsets above the blurred noise);
- pad cut by the frame edge: pins the frame cuts kept, then lost and retired on every still frame (12 of
  320 on tactip-331, dark-331) -> left out (`outside field`);
- (session 17, edge11) PinTracker on its own start frame lost whole pins whose tips lay 4-7 px inside the
  frame edge: their windows (half a spacing) did not fit in the crop, clipped to the frame -> the crop grows
  by replicated border beyond the frame (`pins.track`). Update on the start frame, then 3 still frames
  (lost at start, summed over seeds 40-49, never tuned on): tactip-127 and brown-127 cut-edge 80 of 1200 -> 0,
  dense-1000 cut-edge 78 of 9085 -> 0, cut-corner 54 of 9332 -> 0; tactip-331, radial-led-120 (cut-edge,
  cut-corner) and every preset off-centre 0 -> 0.
- (session 18, track12) a pin the frame edge cuts at the tracker's own threshold (its windows' tip radius, not
  detection's) flickered on still frames: dense-1000 cut+grad+noise8 seeds 44-45, 4 and 3 of 20 frames; held out
  (48-59) dense-1000 cut-edge seeds 49, 53, 59 (4 of 20), cut+grad+noise8 53 (2 of 20) and cut-corner 51 (kept by
  detection, lost in all 20) -> the tracker cuts by detection's rule and radius, with hysteresis (`pins._edge`): 0
  pins lost at the edge on dense-1000, tactip-127, tactip-331, radial-led-120 x cut-edge, cut-corner,
  cut+grad+noise8, seeds 40-47 and held out 48-59 (an interior radial-led-120 pin on 3 seeds, lost once or twice,
  old and new alike); slides with the pad cut (seeds 40-42): 0 pin-frames on the replicated border, old and new;
- (session 18, track12) slides at 15-20 frames/s (a cheap webcam; pins step 1.5-2 spacings a frame in the drag and
  the lift, tactip-127): pins came out of the slides on others' tips and stayed there through the rests
  (tactip-127 seeds 40-43: 20/s 2 of 4 seeds with 12-13 swaps and 109-115 of 127 lost at the end; 15/s and 20/s +
  JPEG 60 1 of 4) -> where the frame shows the rest frame again the pins are put back on their own tips
  (`pins._return`): every slides row met on tactip-127, tactip-331, radial-led-120, dense-1000 at 15, 20, 30
  frames/s, 20/s + JPEG 60 and cut at 20/s (but radial-led-120 + JPEG seed 41: one faint pin > 1 px, old and new),
  seeds 40-43; held out (48-51, with cut+grad+noise8) tactip-127 10 of 20 rows not met (up to 15 swaps, 109-127 of
  127 lost) -> 0, radial-led-120 cut+grad+noise8 3 rows with 1-2 pins > 1 px -> 2 with 1. Within the slides pins
  still swap: of the pins on their own tips in one frame (bench 20, 30, 60 frames/s, seeds 40-41), on another's in
  the next, by their own step (spacings) 0.1-0.25 / 0.25-0.4 / 0.4-0.5 / 0.8-1: tactip-127 0.5 / 6.6 / 15 / 42 %,
  tactip-331 0.4 / 4.7 / 10 / 47 %, radial-led-120 0.5 / 0.9 / 2.5 / 4.6 % (and 51 % lost), dense-1000 0.2 / 0.9 /
  0.4 / 39 % (and 4 / 20 / 22 / 56 % lost): the tracker follows about a quarter of a spacing a frame
  (radial-led-120 0.4); replay warns when pins came back to rest on others' tips (`PinTracker.motion_warning`:
  film faster).
- (session 18, slide13) the slides check counts swaps in every frame (``during``, ``apart``), not only after the
  return: seeds 0-1, main 6705663, 120 / 30 frames/s, apart (during): radial-led-120 4+2 (11+19) / 236+262
  (252+279), tactip-127 110+118 (129+150) / 865+801 (923+866), tactip-331 167+158 (338+370) / 1486+1467
  (1593+1569) pin-frames; no row is met any more, every one met after the return (0 swaps, 0 > 1 px, 0 lost).
- (session 19, slide14) where the apart swaps of the slides begin (120 frames/s, seeds 0-5, main 09118d1, by the
  stage that placed each swap's first frame): tactip-127 465 of 486 onsets in the lifts (50 ms: pins speed to about
  a spacing a frame), 376 placed by LK from constant-velocity guesses 0.25-0.6 spacings off; tactip-331 269 of 603 in
  the lifts, 334 in the drag (the follow passes in skin squeezed until tips merge), 184 by the pair fit. LK now starts
  from the frame's motion field fitted to the pins placed first (`pins._motion`), and placed pins half a spacing off
  it are looked for from it too. Seeds 0-1, apart, main -> now: 120 frames/s tactip-127 110+118 -> 8+16,
  tactip-331 167+158 -> 150+155, radial-led-120 4+2 -> 0+0 (both rows met); 30 frames/s 865+801 -> 956+992 (worse:
  pins step 1.5 spacings there), 1486+1467 -> 1215+1106, 236+262 -> 274+254. Held out (seeds 48-53, 120 frames/s):
  tactip-127 107/122/112/104/102/122 -> 56/19/24/18/18/26, tactip-331 871 -> 815 in all, radial-led-120
  1/3/2/1/7/1 -> 1/1/1/1/2/0. After the return every row as before: 0 swaps, 0 > 1 px, 0 lost.
- (session 19, slide15) the field's guesses made 30 frames/s worse: in the drag the skin under the plate steps a
  spacing a frame and the field fitted to the slow skin around it steps those pins by a fifth of that. It is now used
  only where its median step for the pins not placed is at least 0.3 spacings (a lift's spring-back). Apart
  pin-frames, constant velocity only / main 0a5c057 / now, seeds 0-5: 30 frames/s tactip-127 4893 / 5689 / 4988,
  radial-led-120 1507 / 1607 / 1509; 120 frames/s tactip-127 706 / 107 / 106; seeds 0-1: tactip-331 30 frames/s
  2953 / 2321 / 2349, 120 frames/s 325 / 305 / 305. Held out (seeds 48-53): 30 frames/s tactip-127 4829 / 5500 /
  5028 (still 4 % above constant velocity), radial-led-120 1418 / 1453 / 1418; 120 frames/s tactip-127
  669 / 161 / 154; tactip-331 at 30 frames/s (seeds 48-49) 2985 / 2389 / 2400.
  Given back: bench_slide_losses (radial-led-120, webcam at 120 frames/s, viscoelastic skin, seeds 0-5) lost
  9192 / 8475 / 8854, swaps (apart) 100 (62) / 85 (45) / 91 (53); a 0.2 gate keeps it (8495 lost) but leaves
  tactip-127 at 30 frames/s at 5393 (seeds 0-5).
- (session 18, detect13) a noisy webcam through JPEG (grad+noise8+jpeg75; bench_user_chain's camera): JPEG smooths
  the finest scale, where `noise_sigma` reads (1.5 for 8 grey levels), so the candidate offsets stayed at 5 and a
  lattice of noise blobs between radial-led-120's spokes won the vote; their short spacing made the pitch short
  (bench_user_chain seed 50: 136 pins, 18 of them noise, scale +39 %). The offsets are now floored at the noise
  read on 2 x 2 block means (`pins._noise.binned_noise_sigma`, about 8 there), and the central pitch leaves out
  crowded points (`pins.scale`). radial-led-120 seeds 40-43: 1 of 4 not met (131 pins, precision 0.85) -> recall
  0.96, precision 1.00; 320+noise8+jpeg precision 0.88-0.95 -> 0.96-0.98 (recall 0.67-0.79 either way: its tips
  are 1 px); held out (48-59 but 50) 7 of 11 not met (122-139 pins, precision 0.72-0.88, scale up to +18 %) -> 0;
  small-pad-100 loses a faint pin it kept on 3 of 11 (recall 1.00 -> 0.99); base and noise 6/10 and JPEG 60 on
  nine presets, seeds 40-47: 0 of 72 base rows changed, 4 of 216 others (noise 10: 0-2 more pins found, scale
  within 1.2 % either way).
- (session 19, detect14) webcam noise after detect13 (detect on rest frames, `find_pin_field` old against new on
  the same frames; development seeds): the lowest candidate offset kept the pins and a few noise blobs, more than
  97 % of any other set's pins, so it voted alone and its noise blobs were agreed (bench_user_chain radial-led-120
  seed 0: 122 pins, 3 noise blobs on the LED reflections, an offset-6.9 set; brown-127 seed 9: 131 of 127) ->
  the sets keeping the next most pins vote with a lone voter when they keep 0.9 of its pins
  (`pins._candidates._consensus`; 0.95-0.97 there, 0.85-0.89 at 320x240 where the extras are faint pins only
  the best set finds). small-pad-100 lost a rim pin under noise + JPEG: the flat-top test fitted the membrane
  round it through the bright surround -> the surround is no membrane, a ring the disc cuts is not judged, and a
  blob within a tip radius of the disc's edge is no pin (casing glare; `pins._tipprobe.flat_pins`). The noise
  floor of the offsets (`_NOISE_OFFSET`, 2 x the blurred noise) swept 1.5/2/2.5/3/3.5/4 on the user chain's rest
  frames (seeds 0-35, nine presets; missed/false pins, with the vote above and a first flat test: 57/24 at 2.0,
  66/34 at 2.5, 59/25 at 3.0; 73/33 before) and nine conditions (seeds 0-5 in part): 1.5 lets noise through (noise 10, webcam: 15-29 false), 3.0
  loses small-pad-100 at x1.5 (50 of 100), none is better than 2.0: kept. Figures, old -> new: user-chain rest
  frames (seeds 0-17, nine presets) missed 44 -> 34, false 17 -> 9 (radial-led-120 3 -> 0, brown-127 14 -> 9:
  glare on the casing round the rim, beyond the last ring; small-pad-100 missed 22 -> 12, but seed 14's scale
  -0.6 % -> -3.3 % with one pin more: its central pitch reads the nearest neighbours of 6-8 central 1 px tips); conditions base, 320x240, webcam, x1.5, x0.6, off-centre, cut-edge, noise 10,
  LED reflections x nine presets, seeds 0-2: missed 142 -> 135, false 24 -> 7, rows not met 11 -> 9 (webcam
  radial-led-120 false 17 -> 0); no row lost recall or precision, or moved its scale past 2 %, but two radial-led-120 rows (320x240 seed 2:
  scale -0.9 % -> +4.5 %, 1 px tips; webcam seed 2: one pin fewer, 7 noise blobs gone); bench_detect_seeds'
  frames (all eleven presets at rest and tapped, seeds 0-3): unchanged. Held out (seeds 48-59, looked at once, at
  the end): user-chain rest frames, nine presets, missed 26 -> 17, false 3 -> 3 (brown-127's casing glare),
  rows not met 1 -> 2 (small-pad-100 seed 54: one pin more, the scale -0.1 % -> +3.0 %: 6-8 central pins);
  seeds 48-51 x nine presets: base unchanged, noise 10 missed/false 4/3 -> 3/0, webcam 8/3 -> 8/2 (radial-led-120
  seed 50 one pin fewer: recall 0.975 -> 0.967).
Met after (detect, still): every size 320x240-1920x1080 (but radial-led-120 at 320x240), off-centre,
cut, exposure x0.6 (but radial-led-120: recall 0.97, 1-2 lost at rest), glare gradient 60, reflections,
noise 2-10, JPEG 60; slides at 30 and 120 frames/s: 0 swaps, 0 > 1 px, 0 lost.
Left (the tracker's, or the camera's limits):
- radial-led-120 x1.5 exposure: the veil saturates, the outer ring (255 on 220-250) is not found, recall
  0.87-0.89 (a camera setting); at 320x240 its tips are 1 px: recall 0.84-0.90; `tactip replay` of an
  MJPG still video at noise 10 or JPEG 60: 1 pin lost in some frames;
- low-contrast tips (pin level 95): brown-127 recall 0.76-0.91, precision 0.85-0.87; small-pad-100
  recall 0.92-0.94 (radial-led-120's pins then lie below its membrane level: dark, not a failure).

Session 18 (detect12): the camera's limits are now told, not silent (`pins._exposure`, thresholds set on
seeds 40-47, `bench` figures from the detect check): a saturated pad (over 0.5 % of the pin field off the
tips at 253-255, or a pin on membrane too bright to stand out) and faint tips (the faintest tenth's SNR,
contrast x sqrt(pi) x tip radius / noise, under 8, or contrast under 10 grey levels) each earn a warning
with what to do. Seeds 40-47: radial-led-120 x1.5 (recall 0.86-0.90) warned 8/8; 320x240 (0.84-0.90) 8/8;
x0.6 (0.97-1.00) 7/8; noise 10 (0.97-0.99) 8/8; brown-127 low-contrast (0.75-0.91) 8/8, small-pad-100
low-contrast (0.91-0.95) 8/8; every preset under base: none. Warned with no pin lost: small-pad-100 at
x0.6 and noise 10, brown-127 LED reflections (2/8), white-dark-331 and dark-331 glare or x1.5 (a
saturated membrane). The size limit is the tips' SNR, not their size alone: radial-led-120 (tips 31 grey
levels above its veil at 640x480) filmed 240/270/300/360/420 px high: recall 0.84-0.90/0.92-0.98/
0.97-0.98/0.97-1.00/0.99-1.00, warned at all but 420 (tips 1.25-1.5 px radius at half height; 1.75 at
420); radial-120 at 200 px (tips 1.0 px, pitch 3.5 px) 0.93-0.95 and at 160 px 0.63-0.69, warned;
tactip-532 at 160 px (tips 1.5 px, pitch 4.9 px, 34 grey levels) 1.00, not warned. Held out (seeds 48-59,
looked at once): base, every preset: no warning; radial-led-120 x1.5 warned 12/12, 320x240 12/12, x0.6
9/12 (the 3 not warned lose 1 pin each), noise 10 12/12; brown-127 low-contrast 11/12, small-pad-100
12/12; tactip-331, dense-1000, brown-127 at x1.5: no warning, all found. They showed radial-led-120 at
320x240 (seeds 48, 54) searched as a flat gel: 64-82 noise blobs in the near-saturated surround beyond
the pad made a whole-frame field of 155-161 (precision 0.49-0.58) -> the whole frame is refused when its
pins beyond the disc's are no lattice (`pins._flat._irregular_beyond`): 102 and 111 pins, precision
0.99/0.96; base, 320x240, cut-corner and noise 10 on every preset, seeds 40-47: 0 of 352 fields changed.

Run: .venv/bin/python bench/bench_conditions.py [--presets tactip-331,dark-331] [--seeds 40-44]
     [--conditions base,320x240,...] [--checks detect,still,slides,cli]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import pathlib
import sys
import tempfile
import time

import cv2
import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial import cKDTree

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from pins import NoSensorError, PinTracker, find_pin_field, sensor_scale  # noqa: E402
from tactip.sim import SyntheticTacTip, preset_names  # noqa: E402

STILL_FRAMES = 20

#: Each condition: renderer options (over the preset's) and the camera: ``size`` (w, h) of the frame (the
#: render scaled to its height, the pad centred), ``shift`` of the pad centre as a fraction
#: of the pad radius, ``gain`` (exposure), ``jpeg`` quality, ``noise`` (sigma after the warp: None keeps
#: the preset's), ``fps``.
CONDITIONS = {
    "base": {},
    "320x240": {"size": (320, 240)},
    "1280x720": {"size": (1280, 720)},
    "1920x1080": {"size": (1920, 1080)},
    "off-centre": {"shift": (0.35, -0.2)},
    "cut-edge": {"shift": (0.0, 0.45)},
    "cut-corner": {"shift": (0.4, 0.4)},
    "bright x1.5": {"gain": 1.5},
    "dim x0.6": {"gain": 0.6},
    "glare-grad 60": {"sim": {"glare_gradient": 60.0}},
    "reflections 4": {"sim": {"reflections": 4, "reflection_level": 90.0}},
    "low-contrast": {"sim": {"pin_level": 95.0}},
    "noise 2": {"noise": 2.0},
    "noise 6": {"noise": 6.0},
    "noise 10": {"noise": 10.0},
    "jpeg 60": {"jpeg": 60},
    "30fps": {"fps": 30.0},
    "120fps": {"fps": 120.0},
    "20fps": {"fps": 20.0},
    "20fps+jpeg": {"fps": 20.0, "jpeg": 60},
    "15fps": {"fps": 15.0},
    "cut-edge 20fps": {"shift": (0.0, 0.45), "fps": 20.0},
    "320+noise8+jpeg": {"size": (320, 240), "noise": 8.0, "jpeg": 60},
    "1080+dim+refl+jpeg": {"size": (1920, 1080), "gain": 0.7, "jpeg": 70,
                           "sim": {"reflections": 4, "reflection_level": 70.0}},
    "cut+grad+noise8": {"shift": (0.3, 0.4), "noise": 8.0, "sim": {"glare_gradient": 50.0}},
    "grad+noise8+jpeg75": {"noise": 8.0, "jpeg": 75, "sim": {"glare_gradient": 50.0}},
}


class Camera:
    """A preset's renderer filmed under one condition: frames and their ground truth, warped."""

    def __init__(self, preset: str, seed: int, condition: dict):
        options = {**condition.get("sim", {}), "noise_sigma": 0.0}
        if "fps" in condition:
            options["frame_rate"] = condition["fps"]
        self.base = SyntheticTacTip.from_preset(preset, seed=seed)
        self.sensor = SyntheticTacTip.from_preset(preset, seed=seed, **options)
        self.noise = condition.get("noise", self.base.noise_sigma)
        width, height = self.sensor.image_size
        self.size = condition.get("size", (width, height))
        self.zoom = self.size[1] / height  # the pad keeps its share of the frame height
        cx, cy, radius = self.sensor.disc
        dx, dy = condition.get("shift", (0.0, 0.0))
        # x' = zoom x + t: the pad centre to the frame centre, then shifted by a fraction of its radius
        self.t = np.array([(self.size[0] - 1) / 2 - self.zoom * cx + dx * self.zoom * radius,
                           (self.size[1] - 1) / 2 - self.zoom * cy + dy * self.zoom * radius])
        self.gain, self.jpeg = condition.get("gain", 1.0), condition.get("jpeg")
        self.rng = np.random.default_rng(seed + 1000)
        self.pitch_px = self.zoom * self.sensor.pin_spacing_mm / self.sensor.mm_per_px

    def film(self, frame) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(image, centres, visible, partial) of one rendered frame under the condition: a pin is visible
        when its whole tip (radius and 1 px edge ramp, plus half a px) is inside the frame, partial
        when the frame cuts it (as `tests.pins.conftest.cropped_frame` flags them)."""
        image = frame.image.astype(np.float32)
        if self.zoom < 1:  # anti-alias before shrinking
            image = cv2.GaussianBlur(image, (0, 0), 0.5 * np.sqrt(1 / self.zoom ** 2 - 1))
        matrix = np.array([[self.zoom, 0, self.t[0]], [0, self.zoom, self.t[1]]])
        image = cv2.warpAffine(image, matrix, self.size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        image = image * self.gain + self.rng.normal(0.0, self.noise, image.shape)
        image = np.clip(np.rint(image), 0, 255).astype(np.uint8)
        if self.jpeg is not None:
            image = cv2.imdecode(cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, self.jpeg])[1],
                                 cv2.IMREAD_UNCHANGED)
        centres = frame.centres * self.zoom + self.t
        reach = self.zoom * self.sensor.pin_radius_px + 1.5
        inside = np.all((centres >= reach) & (centres <= np.array(self.size) - 1 - reach), axis=1)
        near = np.all((centres >= -reach) & (centres <= np.array(self.size) - 1 + reach), axis=1)
        drawn = np.asarray(frame.visible, bool) | np.asarray(frame.partial, bool)
        return image, centres, frame.visible & inside, drawn & near & ~(frame.visible & inside)


def match(found: np.ndarray, truth: np.ndarray, reach_px: float) -> tuple[np.ndarray, np.ndarray]:
    """One-to-one matches (found index, truth index) within ``reach_px``."""
    if not len(found) or not len(truth):
        return np.zeros(0, int), np.zeros(0, int)
    cost = np.linalg.norm(found[:, None] - truth[None], axis=2)
    rows, cols = linear_sum_assignment(np.where(cost < reach_px, cost, 1e6))
    keep = cost[rows, cols] < reach_px
    return rows[keep], cols[keep]


def row(check: str, preset: str, condition: str, seed, figure: str, met: bool, cpu_s: float) -> None:
    """Print one row of the table."""
    print(f"{check:6s} {preset:15s} {condition:19s} {str(seed):>3s}  {figure:66s} {'yes' if met else 'NO':>3s} "
          f"{cpu_s:6.1f}", flush=True)


def check_detect(camera: Camera, preset: str, name: str, seed: int, image, centres, visible, partial):
    """`find_pin_field` on the rest frame against the truth (pins the frame cuts count neither for nor
    against); returns the field (None: no sensor)."""
    start = time.process_time()
    try:
        field = find_pin_field(image)
    except NoSensorError as exc:
        row("detect", preset, name, seed, f"no sensor: {exc}"[:66], False, time.process_time() - start)
        return None
    drawn = visible | partial
    truth, whole = centres[drawn], visible[drawn]
    found_i, truth_i = match(field.centres, truth, 0.3 * camera.pitch_px)
    on_whole = whole[truth_i]
    recall = int(on_whole.sum()) / max(int(visible.sum()), 1)
    precision = len(found_i) / max(len(field.centres), 1)
    errors = field.centres[found_i[on_whole]] - truth[truth_i[on_whole]]
    rmse = float(np.sqrt(np.mean(np.sum(errors ** 2, axis=1)))) if len(errors) else float("nan")
    try:
        mm_per_px = sensor_scale(field.centres, sensor=preset).mm_per_px
        reference = sensor_scale(camera.base.rest_centres, sensor=preset).mm_per_px / camera.zoom
        scale_off = mm_per_px / reference - 1
    except Exception:  # noqa: BLE001 - a refusal is a result here
        scale_off = float("nan")
    met = recall >= 0.97 and precision >= 0.97 and rmse <= 0.5 and abs(scale_off) <= 0.02
    polarity = "dark" if field.params.dark_pins else "bright"
    # The warnings `tactip detect` prints: S a saturated pad, F faint (or small) tips.
    warned = "".join("S" if w.startswith("the pad is saturated") else "F" for w in field.warnings)
    row("detect", preset, name, seed, f"{len(field.centres)}/{int(visible.sum())} rec {recall:.3f} prec {precision:.3f} "
        f"rmse {rmse:.2f} d scale {scale_off:+.1%} {polarity}" + (f" warn {warned}" if warned else ""), met,
        time.process_time() - start)
    return field


def check_still(camera: Camera, preset: str, name: str, seed: int, image, field) -> None:
    """Replay's start on the rest frame, then still frames: pins lost, retired."""
    start = time.process_time()
    tracker = PinTracker(detection=field.params, disc=field.disc)
    tracker.start(image, field.centres)
    lost = []
    for _ in range(STILL_FRAMES):
        tracker.update(camera.film(camera.sensor.render())[0])  # fresh noise and shimmer
        lost.append(int(np.sum(tracker.lost)))
    retired = int(np.sum(tracker.retired))
    row("still", preset, name, seed, f"lost max {max(lost)} median {int(np.median(lost))} of "
        f"{len(field.centres)}, retired {retired}", max(lost) == 0 and retired == 0, time.process_time() - start)


def check_slides(camera: Camera, preset: str, name: str, seed: int, image, centres, visible, field) -> None:
    """8 slides of 3 pitches at the condition's frame rate, then rest: swaps, off rest, lost."""
    start = time.process_time()
    sensor = camera.sensor
    tracker = PinTracker(detection=field.params, disc=field.disc)
    rest = tracker.start(image, field.centres)
    distance, identity = cKDTree(centres).query(rest)
    real = (distance < 2.0 * camera.zoom) & visible[identity]
    fps = sensor.frame_rate
    slides = sensor.slides(range(0, 360, 45), distance_mm=3 * sensor.pin_spacing_mm, indentation_mm=2.0,
                           rest_s=max(3 / fps, 0.025), press_s=0.05, slide_s=0.15, lift_s=0.05)
    frames = on_cut = 0
    during = np.zeros(2, int)
    half = 0.5 * camera.zoom * sensor.pin_radius_px
    height, width = camera.size[1], camera.size[0]
    for frame in slides:
        filmed, truth, _, _ = camera.film(frame)
        positions = tracker.update(filmed)
        frames += 1
        during += swapped(positions, truth, identity, real, camera.pitch_px)
        # Pins placed within half a tip radius of the frame's edge, or beyond it: on the replicated border.
        room = np.minimum(np.minimum(positions[:, 0] + 0.5, width - 0.5 - positions[:, 0]),
                          np.minimum(positions[:, 1] + 0.5, height - 0.5 - positions[:, 1]))
        on_cut += int(np.count_nonzero(room < half))
    error = np.linalg.norm(positions - truth[identity], axis=1)[real]
    seen = ~np.isnan(positions[:, 0]) & real
    _, nearest = cKDTree(truth).query(positions[seen]) if seen.any() else (None, identity[seen])
    swaps = int((nearest != identity[seen]).sum())
    over = int((error > 1.0 * camera.zoom).sum())
    lost = int(np.isnan(error).sum())
    row("slides", preset, name, seed, f"{frames} frames at {fps:g}/s: swaps {swaps} (during {during[0]}, apart {during[1]}), >1px {over}, "
        f"lost {lost} of {int(real.sum())}, on border {on_cut}",
        swaps == 0 and during[1] == 0 and over == 0 and lost == 0 and on_cut == 0, time.process_time() - start)


def swapped(positions: np.ndarray, truth: np.ndarray, identity: np.ndarray, real: np.ndarray,
            pitch_px: float) -> np.ndarray:
    """Swapped pin-frames in one frame, (all, apart): pins placed (finite `positions`, px) among the `real` ones
    whose nearest true centre (`truth`, px, every pin's, hidden or not) is another pin's than their own
    (`identity`); apart: those two centres at least half a pitch (`pitch_px`) apart (nearer, a slide squeezed
    the two tips into one blob that no image parts: `bench_slides`' ``apart``)."""
    placed = np.flatnonzero(real & np.isfinite(positions[:, 0]))
    if not placed.size:
        return np.zeros(2, int)
    nearest = cKDTree(truth).query(positions[placed])[1]
    other = nearest != identity[placed]
    gap = np.linalg.norm(truth[nearest[other]] - truth[identity[placed[other]]], axis=1)
    return np.array([np.count_nonzero(other), np.count_nonzero(gap >= 0.5 * pitch_px)])


def _cli(argv: list[str]) -> tuple[int, str, str]:
    from tactip.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(argv)
    return status, out.getvalue(), err.getvalue()


def check_cli(camera: Camera, preset: str, name: str, seed: int, image, folder: pathlib.Path) -> None:
    """`tactip detect` and `tactip replay` (MJPG .avi of still frames) as a user runs them."""
    import h5py

    start = time.process_time()
    folder.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(folder / "frame.png"), image)
    status, out, err = _cli(["detect", str(folder / "frame.png"), "--sensor", preset, "--json"])
    count = len(np.asarray(json.loads(out)["pins"], float).reshape(-1, 2)) if status == 0 else None
    detected = f"detect {count if status == 0 else 'exit ' + str(status)}"
    if status != 0:
        detected += f" ({err.strip()[-40:]})"
    path = folder / "still.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), camera.sensor.frame_rate, camera.size, True)
    for k in range(10):
        frame = image if k == 0 else camera.film(camera.sensor.render())[0]
        writer.write(cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR) if frame.ndim == 2 else frame)
    writer.release()
    status_r, _, err_r = _cli(["replay", str(path), "--out", str(folder / "r.h5"), "--sensor", preset, "--quiet",
                               "--overwrite"])
    if status_r != 0:
        row("cli", preset, name, seed, f"{detected}; replay exit {status_r}: {err_r.strip()[-40:]}", False,
            time.process_time() - start)
        return
    with h5py.File(folder / "r.h5") as h5:
        positions = h5["positions"][()]
    lost = np.isnan(positions[:, :, 0]).sum(axis=1)
    met = status == 0 and lost.max() == 0 and positions.shape[1] == count
    row("cli", preset, name, seed, f"{detected}; replay {positions.shape[1]} pins, lost median "
        f"{int(np.median(lost))} max {int(lost.max())}", met, time.process_time() - start)


def seed_range(text: str) -> list[int]:
    """'40-44', '40,42' or '0-2,48-50' to a list of seeds."""
    seeds = []
    for part in text.split(","):
        first, _, last = part.partition("-")
        seeds += list(range(int(first), int(last or first) + 1))
    return seeds


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--presets", default="tactip-331,dark-331,radial-led-120")
    parser.add_argument("--seeds", default="40-42")
    parser.add_argument("--conditions", default=",".join(CONDITIONS))
    parser.add_argument("--checks", default="detect,still")
    args = parser.parse_args(argv)
    checks = set(args.checks.split(","))
    os.environ.setdefault("TACTIP_SIM_WORKERS", "1")
    unknown = set(args.presets.split(",")) - set(preset_names())
    if unknown:
        parser.error(f"unknown presets {sorted(unknown)}")
    print(f"{'check':6s} {'preset':15s} {'condition':19s} {'sd':>3s}  {'figure':66s} {'met':>3s} {'cpu s':>6s}")
    with tempfile.TemporaryDirectory() as tmp:
        for preset in args.presets.split(","):
            for name in args.conditions.split(","):
                for seed in seed_range(args.seeds):
                    camera = Camera(preset, seed, CONDITIONS[name])
                    image, centres, visible, partial = camera.film(camera.sensor.render())
                    field = check_detect(camera, preset, name, seed, image, centres, visible, partial)
                    if field is None:
                        continue
                    if "still" in checks:
                        check_still(camera, preset, name, seed, image, field)
                    if "slides" in checks:
                        check_slides(camera, preset, name, seed, image, centres, visible, field)
                    if "cli" in checks:
                        check_cli(camera, preset, name, seed, image, pathlib.Path(tmp) / f"{preset}-{seed}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
