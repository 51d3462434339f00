"""How well a camera shows the pins: a saturated pad, and pins too faint or too small for the noise.

`pins.find_pin_field` finds the pins a frame shows; a camera set too bright, too dark or too far away
shows fewer than the sensor has, and a user filming a sensor we have never seen must be told so
rather than get a silent shortfall (issue 20: `tactip detect` and replay's start print these).
Two conditions lose pins, and each earns a warning (`bench/bench_conditions.py`, seeds 40-47; the
thresholds were set on these, seeds 48-59 held out):

- a saturated pad: glare or a veil at the top grey level hides the bright tips on it (radial-led-120 at
  exposure x1.5: its veil at 255, 12-17 of 120 pins not found, and the pad's rim merges with the
  bright surround). Tips at the top level are no loss (tactip-331, dense-1000 at x1.5: all found), so
  the share of the pin field off the tips at 253-255 counts (over 0.5 %: radial-led-120 at x1.5 0.05-2.1 %,
  every preset at its own exposure 0 %), and so do pins whose membrane leaves them less than half the
  pins' median contrast below the top (0-2 on radial-led-120 at x1.5, none elsewhere): 8 of 8 seeds
  warned. Strong LED reflections (brown-127, 2 of 8 seeds) and a glare gradient (white-dark-331)
  saturating 0.5-0.7 % of the field are warned too, with no pin lost; a dark-marker membrane at 255
  (dark-331 at x1.5) is warned as clipped;
- faint pins: a tip's signal against the camera noise is its contrast times the square root of its
  area over the noise sigma (the matched filter's SNR of a disc, here of the faintest tenth of the
  pins); a frame too dark, a tip too small (filmed far off or at a low resolution, shrunk and blurred)
  or a noisy camera lowers it. Below 8, or a contrast below 10 grey levels whatever the noise reads (a
  codec smooths the noise it then fails to show): radial-led-120 at 320x240 (tips of 1.2 px radius 2-4
  grey levels above the veil, SNR 1.1-2.0, 12-18 of 120 missed) 8 of 8 seeds, at exposure x0.6 (SNR
  7.2-8.3, 0-2 missed) 7 of 8, at noise sigma 10 8 of 8; low-contrast tips on brown-127 (recall
  0.75-0.91) and small-pad-100 (0.91-0.95) 8 of 8. A warning may come before a loss: small-pad-100 at
  x0.6 and at noise 10 (SNR 4.6-7.9) is warned and loses 0-1 pin. Every preset at its own exposure:
  SNR 11-600, none.
"""

from __future__ import annotations

import cv2
import numpy as np

from ._flat import _pin_radius_px, _tip_contrasts
from ._noise import noise_sigma

__all__ = ["exposure_warnings", "pad_exposure"]

#: Grey level from which a pixel counts as saturated (`_noise` leaves out pixels from 253 as clipped).
SATURATED_LEVEL = 253
#: A share of the pin field off the tips at `SATURATED_LEVEL` or above that earns a warning (so does one
#: pin washed out: `pad_exposure`).
SATURATED_SHARE = 0.005
#: A tip SNR (the faint tenth of the pins') below this earns a warning, and so does a contrast below
#: `FAINT_CONTRAST` grey levels whatever the noise reads (a codec smooths the noise it then fails to show).
FAINT_SNR = 8.0
FAINT_CONTRAST = 10.0
#: Tips smaller than this radius, px, are called too small in the faint warning's advice.
SMALL_TIP_PX = 2.0


def pad_exposure(grey: np.ndarray, field) -> dict:
    """Measures of how a pin field's frame shows its pins.

    Parameters
    ----------
    grey : (H, W) ndarray of uint8
        The frame the field was found in.
    field : PinField
        Its pin field (`pins.find_pin_field`).

    Returns
    -------
    exposure : dict
        ``saturated`` (share of the pin field's pixels off the tips at `SATURATED_LEVEL` or above: glare or
        a veil at the top level, where a bright tip cannot show; saturated bright tips themselves show),
        ``washed_out`` (pins found whose membrane lies nearer the top grey level, or the bottom for dark
        markers, than half the pins' median contrast: on a veil or glare too bright for a pin to stand out;
        their neighbours there are lost), ``tip_radius_px`` (the tips' half-height radius), ``contrast`` (the faint tenth of the pins'
        contrast over the membrane round them, grey levels), ``noise_sigma`` (grey levels), ``snr``
        (``contrast`` x sqrt(pi) x ``tip_radius_px`` / ``noise_sigma``) and ``bright_level`` (the pad's
        99th percentile grey level); nan where a field of fewer than two pins leaves a measure undefined.
    """
    region = field.field_disc.mask(grey.shape[:2])
    measurable = field.count >= 2 and np.isfinite(field.pitch_px)
    radius_px = _pin_radius_px(grey, field.centres, field.pitch_px, field.params.dark_pins) if measurable \
        else float("nan")
    off_tips = region.copy()
    if measurable and radius_px > 0:
        # Each tip's disc (its radius and a 1.5 px edge): the centres' pixels dilated by a disc.
        tips = np.zeros(grey.shape[:2], np.uint8)
        x, y = (np.clip(np.rint(field.centres[:, k]).astype(int), 0, grey.shape[1 - k] - 1) for k in (0, 1))
        tips[y, x] = 1
        size = 2 * int(np.ceil(radius_px + 1.5)) + 1
        off_tips &= cv2.dilate(tips, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (size, size))) == 0
    membrane = grey[off_tips] if off_tips.any() else grey[region]
    saturated = float(np.mean(membrane >= SATURATED_LEVEL)) if membrane.size else 0.0
    contrasts = _tip_contrasts(grey, field) if measurable else np.full(1, np.nan)
    contrast = float(np.percentile(contrasts, 10))
    washed = _washed_out(grey, field, float(np.median(contrasts))) if measurable else 0
    sigma = noise_sigma(grey)
    snr = contrast * np.sqrt(np.pi) * radius_px / max(sigma, 0.5)
    bright = float(np.percentile(grey[region], 99)) if region.any() else float("nan")
    return {"saturated": saturated, "washed_out": washed, "tip_radius_px": radius_px, "contrast": contrast,
            "noise_sigma": sigma, "snr": float(snr), "bright_level": bright}


def exposure_warnings(grey: np.ndarray, field) -> tuple[str, ...]:
    """Warnings for a person about the frame a pin field was found in (none when it shows its pins well).

    A saturated pad (the top grey levels over at least `HIDDEN_SITES` pin site off the pins found): lower
    the exposure. Faint pins (the faint tenth's SNR below `FAINT_SNR`, or contrast below `FAINT_CONTRAST`):
    film the pad larger when the tips are small, raise the exposure or the light when the pad is dark,
    less gain when the noise hides them, else pins that stand out more.

    >>> from tactip.sim import SyntheticTacTip
    >>> from pins import find_pin_field
    >>> frame = SyntheticTacTip.from_preset("tactip-331", seed=0).render().image
    >>> exposure_warnings(frame, find_pin_field(frame))
    ()
    """
    if field.count < 2:
        return ()
    measure = pad_exposure(grey, field)
    warnings = []
    if measure["saturated"] > SATURATED_SHARE or measure["washed_out"]:
        where = ("the membrane round the markers is clipped" if field.params.dark_pins else
                 "bright pins on it cannot be seen, and the pad's rim may pass for the bright surround")
        washed = f", {measure['washed_out']} pins on membrane too bright to stand out" if measure["washed_out"] else ""
        warnings.append(f"the pad is saturated: {measure['saturated']:.1%} of the pin field (off the pins) is at the "
                        f"top grey levels ({SATURATED_LEVEL}-255){washed}: {where}; lower the exposure or the gain "
                        "(or dim the light)")
    if measure["snr"] < FAINT_SNR or measure["contrast"] < FAINT_CONTRAST:
        radius, bright = measure["tip_radius_px"], measure["bright_level"]
        if radius < SMALL_TIP_PX:
            advice = "film the pad larger (closer, or at a higher resolution)"
        elif bright < 128:
            advice = "raise the exposure or the light"
        elif measure["contrast"] >= FAINT_CONTRAST:
            advice = "less gain and more light (less noise)"
        else:
            advice = "the pins barely differ from the membrane: light that shows them, or pins of more contrast"
        warnings.append(f"the pins are faint: the faintest tenth stand {measure['contrast']:.0f} grey levels from "
                        f"the membrane, tips of {radius:.1f} px radius, noise {measure['noise_sigma']:.1f} (SNR "
                        f"{measure['snr']:.1f}; under {FAINT_SNR:g}, or under {FAINT_CONTRAST:g} grey levels, pins "
                        f"are missed or lost); {advice}")
    return tuple(warnings)


def _washed_out(grey: np.ndarray, field, typical_contrast: float) -> int:
    """How many pins sit on membrane (the median of a ring 0.35-0.45 pitch round each) nearer the top grey
    level (bright pins; the bottom for dark markers) than half `typical_contrast`, grey levels."""
    if not np.isfinite(typical_contrast) or typical_contrast <= 0:
        return 0
    theta = np.linspace(0.0, 2 * np.pi, 16, endpoint=False)
    radii = np.array([0.35, 0.4, 0.45]) * field.pitch_px
    xs = field.centres[:, 0, None, None] + radii * np.cos(theta)[:, None]
    ys = field.centres[:, 1, None, None] + radii * np.sin(theta)[:, None]
    ring = cv2.remap(grey.astype(np.float32), xs.reshape(len(xs), -1).astype(np.float32),
                     ys.reshape(len(ys), -1).astype(np.float32), cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    level = np.median(ring, axis=1)
    room = level if field.params.dark_pins else 255.0 - level
    return int(np.sum(room < 0.5 * typical_contrast))
