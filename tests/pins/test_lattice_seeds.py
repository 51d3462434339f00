"""pins.lattice over more seeds than seed 0: the pin field without a count meets the bar on every preset
(seeds 1-2, at rest and under the 5 mm tap; bench/bench_detect_seeds.py runs seeds 0-11), and the two
causes of failures found on other seeds stay fixed:

- the polarity of white pins on a dark membrane in a dark casing: under a tap the pressed pins darken
  and, with the dark gaps between the others, form a dark lattice that was neither sparse nor small,
  so it was taken for the sensor (white-dark-331 seed 2: 89 dark "pins" instead of 331 white ones);
- the sharpness of a blob just inside the casing's rim: the bright casing's blurred edge was taken
  for the blob's own edge, so a soft skin highlight at a hidden lattice site looked as sharp as a pin
  and was kept (brown-127 seeds 1-3, 5, 9, 11: one to three false pins).

Still failing beyond seed 2 (bench/bench_detect_seeds.py, seeds 0-11): brown-127 seed 3 tapped keeps two
soft highlights at hidden lattice sites by the rim (the blob stage); radial-led-120 places its pins to
0.10-0.15 px RMSE on 16 of 24 frames (the bench's bar is 0.1 px; its own test allows 0.14: the faint
outer-ring tips the lattice probe finds). Fixed here: brown-127 seed 5 (a rim highlight the lattice
probe took), small-pad-100 tapped seeds 4 and 10 (two tips pressed together read as one) and
radial-led-120 seed 14 at rest (noise in the surround taken for a flat gel's markers beyond the disc).
"""

import cv2
import numpy as np
import pytest
from scipy.spatial import cKDTree

from pins import find_pin_field
from pins._judge import _sharpness
from pins.detect import Blobs, DetectionParams
from pins.disc import SensorDisc
from pins.lattice import _other_keeps_more
from tactip.sim import preset_names
from tests.pins.conftest import TAP, preset_frame, preset_params, preset_sensor, score

CONTACTS = {"rest": None, "tap5mm": TAP}


def _grey(image: np.ndarray) -> np.ndarray:
    return image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)


def _gate_px(frame) -> float:
    """Matching gate: 3 px, or 0.4 of the true pitch on dense or small pads (as test_lattice)."""
    centres = frame.centres[frame.visible]
    distance, _ = cKDTree(centres).query(centres, 2)
    return min(3.0, 0.4 * float(np.median(distance[:, 1])))


@pytest.mark.parametrize("seed", [1, 2])
@pytest.mark.parametrize("contact", list(CONTACTS))
@pytest.mark.parametrize("name", preset_params(preset_names()))
def test_field_without_a_count_meets_the_bar_on_more_seeds(name, contact, seed):
    f = preset_frame(name, CONTACTS[contact], seed)
    field = find_pin_field(f.image)
    recall, precision, rmse = score(field.centres, f, gate_px=_gate_px(f))
    assert recall >= 0.99 and precision >= 0.99, (recall, precision, field.summary())
    assert rmse <= 0.1
    assert field.params.dark_pins == preset_sensor(name, seed).dark_pins


@pytest.mark.parametrize("seed", [0, 2])
def test_white_pins_darkened_by_a_tap_do_not_make_the_dark_lattice_the_sensor(seed):
    """White pins on a dark membrane in a dark casing, tapped: only the dark polarity shows a disc, and
    its lattice (pressed pins and gaps, at the pins' own pitch on these seeds) is outnumbered by the
    white pins at that pitch. (On other seeds it is the gaps' finer lattice, sparse in its disc.)"""
    f = preset_frame("white-dark-331", TAP, seed)
    dark = find_pin_field(f.image, dark_pins=True)
    assert dark.count < 0.5 * f.visible.sum()  # the dark lattice is not the pins ...
    assert _other_keeps_more(_grey(f.image), dark, DetectionParams())  # ... and the white pins outnumber it
    # (The polarity decided and the bar on these frames: test_lattice on seed 0, the sweep above on seed 2.)


# (That a sensor's own lattice is not outnumbered by its gaps, on seed 0: test_lattice.py, on its fields.)


def _highlights(rim_gap_px: float):
    """A dark disc in a bright casing with two like soft Gaussian highlights (skin texture), one deep
    inside and one whose centre is `rim_gap_px` inside the rim: (image, disc, blobs)."""
    height, width = 240, 320
    disc = SensorDisc(160.0, 120.0, 100.0)
    y, x = np.mgrid[:height, :width]
    image = np.where(np.hypot(x - disc.cx, y - disc.cy) <= disc.radius_px, 70.0, 220.0)
    spots = np.array([(130.0, 120.0), (disc.cx + disc.radius_px - rim_gap_px, 120.0)])
    for sx, sy in spots:
        image += 40.0 * np.exp(-((x - sx) ** 2 + (y - sy) ** 2) / (2 * 4.5 ** 2))
    image = cv2.GaussianBlur(np.clip(image, 0, 255).astype(np.uint8), (0, 0), 1.0)
    blobs = Blobs(centres=spots, areas=np.array([113, 113]), fills=np.array([0.78, 0.78]), candidates=2,
                  contrasts=np.array([20.0, 20.0]))
    return image, disc, blobs


def test_the_casings_edge_does_not_sharpen_a_soft_highlight_by_the_rim():
    image, disc, blobs = _highlights(rim_gap_px=8.0)
    params = DetectionParams(blur_sigma_px=2.0)
    inside, by_the_rim = _sharpness(image, blobs, params, disc=disc)
    assert by_the_rim == pytest.approx(inside, rel=0.1)  # its own slope, as far from the rim
    # Without the disc the bright casing's blurred edge, within reach of the highlight, is taken for its own.
    inside_blind, by_the_rim_blind = _sharpness(image, blobs, params)
    assert inside_blind == pytest.approx(inside) and by_the_rim_blind > 2 * inside_blind


@pytest.mark.parametrize("contact", list(CONTACTS))
def test_a_skin_highlight_at_a_hidden_rim_site_is_not_probed_for_a_pin(contact):
    """brown-127 seed 5: by the rim, where the lattice predicts sites whose pins are hidden, textured skin
    passes the lattice probe's false-alarm bar (evidence 58-79 against 15) with a tip level 0.84-0.94 of
    its neighbours'; the probe took it for a pin, at rest and tapped (two false pins with the blob
    stage's one: precision 0.984). Bare skin at the interstices round it reaches a median evidence of
    38-54, and the probe now asks twice that (`pins._rescue._NULL_FACTOR`)."""
    f = preset_frame("brown-127", CONTACTS[contact], 5)
    field = find_pin_field(f.image)
    recall, precision, rmse = score(field.centres, f, gate_px=_gate_px(f))
    assert recall >= 0.99 and precision >= 0.99 and rmse <= 0.1, (recall, precision, rmse)
    false = cKDTree(f.centres[f.visible | f.partial]).query(field.centres)[0] > _gate_px(f)
    assert false.sum() <= 1, field.centres[false]


def test_noise_blobs_in_a_bright_surround_do_not_make_the_disc_a_flat_gels():
    """radial-led-120 seed 14 at rest: in the near-saturated surround (245, noise 5) the field's parameters
    make 38 blobs of noise beyond the disc, which passed for a flat gel's markers going on past a false
    disc: the whole frame was searched and 216 pins found (102 false). Scattered, a median 3.5 pitches
    apart and not in rows, they no longer count (`pins._flat._SPILL_LINK`): the disc holds, 120 of 120."""
    f = preset_frame("radial-led-120", None, 14)
    field = find_pin_field(f.image)
    recall, precision, _ = score(field.centres, f, gate_px=_gate_px(f))
    assert not field.disc.whole_frame and recall >= 0.99 and precision >= 0.99, field.summary()


@pytest.mark.parametrize("seed", [4, 10])
def test_tips_of_a_pixel_pressed_together_are_split(seed):
    """small-pad-100 tapped (tips about 1 px in radius, pitch 5.4 px): two tips pressed 3.6 px apart join
    into one blob through a bridge of a pixel or two. Splitting eroded the half-height cores by a 3 px
    cross, which left nothing of a 3-pixel core, so the pair was one pin (recall 0.98, one false): a
    split radius below 1 px now erodes nothing (`pins.detect._split_touching`), and both are found."""
    f = preset_frame("small-pad-100", TAP, seed)
    field = find_pin_field(f.image)
    recall, precision, rmse = score(field.centres, f, gate_px=_gate_px(f))
    assert recall == 1.0 and precision == 1.0 and rmse <= 0.1, (recall, precision, rmse)
