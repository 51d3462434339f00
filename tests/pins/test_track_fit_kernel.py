"""pins._jit_fit: the tracker's fits of tips on slopes in one compiled call (`pins._recover._Recovery.fit_tips`),
bit for bit the steps it replaces (`_fit_tips_steps`: NumPy round the other kernels), through a tracker on
slides and on awkward positions; and its window disc, `pins._tipfit._disc_offsets`'."""

import numpy as np
import pytest

from pins import DetectionParams, PinTracker, SensorDisc
from pins._kernels import compiled
from pins._recover import _Recovery
from pins._tipfit import _disc_offsets
from pins.disc import as_grey
from tests.pins.conftest import slide_run

kernels = compiled("_jit_fit")
pytestmark = pytest.mark.skipif(kernels is None, reason="Numba missing or TACTIP_KERNELS=numpy: no kernels to test")


def _same(got, want):
    """Equal bit for bit, NaN in the same places."""
    np.testing.assert_array_equal(got, want)


def test_the_window_disc_is_the_references():
    for half in range(-2, 14):
        gx, gy = kernels.disc_offsets(half)
        want_x, want_y = _disc_offsets(half)
        _same(gx, want_x)
        _same(gy, want_y)


@pytest.mark.parametrize("name, seed", [("radial-led-120", 2), ("radial-led-120", 7)])
def test_a_tracker_fits_tips_as_the_steps_do(name, seed, monkeypatch):
    # Slides and their return to rest on a preset whose faint tips on LED reflections the fits place every
    # few frames: every frame's positions, lost and retired pins bit for bit those of the steps.
    s, run, drawn = slide_run(name, seed, [0, 135], distance_mm=6.0, rest_s=3 / 120,
                              press_s=0.08, slide_s=0.2, lift_s=0.05)
    placed = []
    fused = kernels.fit_tips

    def counted(*args):
        changed, out = fused(*args)
        placed.append(int(changed))
        return changed, out

    monkeypatch.setattr(kernels, "fit_tips", counted)
    tracks = []
    for steps in (False, True):
        if steps:
            monkeypatch.setattr(_Recovery, "fit_tips", _Recovery._fit_tips_steps)
        tracker = PinTracker(detection=DetectionParams(dark_pins=s.dark_pins), disc=SensorDisc(*s.disc))
        tracker.start(run[0].image, pins=run[0].centres[drawn])
        tracks.append([(tracker.update(f.image), tracker.lost.copy(), tracker.retired.copy()) for f in run[1:]])
    for got, want in zip(*tracks):
        for a, b in zip(got, want):
            _same(a, b)
    assert sum(placed) >= 3  # the kernel ran, and placed pins
    assert np.nanmax(np.abs(tracks[0][len(run) // 3][0] - tracks[0][0][0])) > 4.0  # the pins moved


@pytest.mark.parametrize("name, seed", [("radial-led-120", 3), ("small-pad-100", 2)])
def test_fits_from_awkward_positions_are_the_steps(name, seed):
    # Pins missing among placed, jittered, shifted or missing neighbours, looked for near and far from their
    # tips, or on a farther neighbour's tip (one pin per tip, kept own tips: dropping the latter from the kernel
    # fails here): the positions bit for bit the steps', and whether anything changed the same.
    s, run, drawn = slide_run(name, seed, [60], distance_mm=5.0, rest_s=2 / 120,
                              press_s=0.05, slide_s=0.1, lift_s=0.03)
    tracker = PinTracker(detection=DetectionParams(dark_pins=s.dark_pins), disc=SensorDisc(*s.disc))
    tracker.start(run[0].image, pins=run[0].centres[drawn])
    refiner = tracker._refiner
    rng = np.random.default_rng(seed)
    n = len(refiner.rest_positions)
    fittable = np.flatnonzero(refiner._fittable)
    changed = unchanged = 0
    for frame in run[1::3]:
        crop = tracker._bright(tracker._cropped(as_grey(frame.image)))
        truth = frame.centres[drawn]
        for spread in (0.0, 0.3, 1.0, 3.0, "between", "crowded"):
            if spread == "between":  # every pin missing, last seen half a spacing off: windows between tips
                positions, missing = np.full_like(truth, np.nan), np.ones(n, dtype=bool)
                last_seen = truth + [0.5 * refiner.spacing_px, 0.0]
            elif spread == "crowded":  # every pin missing, some last seen on a farther neighbour's tip
                positions, missing = np.full_like(truth, np.nan), np.ones(n, dtype=bool)
                last_seen = truth.copy()
                for pin in rng.choice(fittable, min(len(fittable), 8), replace=False):
                    other = refiner._identity_index[pin, rng.integers(6, 12)]
                    last_seen[pin] = truth[other] + rng.normal(0.0, 0.3, 2)
            else:
                positions = truth + rng.normal(0.0, spread, truth.shape) if spread else truth.copy()
                missing = rng.random(n) < 0.25
                last_seen = np.where(rng.random((n, 1)) < 0.5, truth, refiner.rest_positions)
            if len(fittable) and spread != "crowded":  # (tips on slopes among them)
                missing[rng.choice(fittable, min(len(fittable), 6), replace=False)] = True
            positions[missing] = np.nan
            which = np.flatnonzero(missing & (rng.random(n) < 0.8))
            got = refiner.fit_tips(crop, positions, last_seen, which)
            want = refiner._fit_tips_steps(crop, positions, last_seen, which)
            _same(got, want)
            assert (got is positions) == (want is positions)
            changed += got is not positions
            unchanged += got is positions
    assert changed >= 3 and unchanged >= 1
