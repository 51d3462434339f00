"""pins._rest's calm pins on a creeping skin (issue 20): a pin near rest is placed where its neighbours place it
only while they agree as a still membrane's do; the compiled judgement (`pins._jit_rest.rest_judge`) is its NumPy
reference bit for bit on patches that spread over px (faint tips among them)."""

import numpy as np
import pytest

import pins._kernels
from pins import DetectionParams, PinTracker, SensorDisc
from pins._kernels import compiled
from pins._rest import _CALM_BOUND, _ODD_NEIGHBOURS
from pins._window import _squared_norm
from tactip.sim import SyntheticTacTip

kernels = compiled("_jit_rest")


def _tracker(preset, seed):
    """A tracker started on the preset's rest frame from the true pins, a still frame's bright crop, and its refiner
    with a third of its tips made faint (its noise's reach raised) and scatters as a creeping tour leaves them."""
    sensor = SyntheticTacTip.from_preset(preset, seed=seed, frame_rate=120.0)
    rest = sensor.render()
    tracker = PinTracker(detection=DetectionParams(dark_pins=sensor.dark_pins), disc=SensorDisc(*sensor.disc))
    tracker.start(rest.image, pins=rest.centres[np.flatnonzero(rest.visible)])
    refiner = tracker._refiner
    measures = refiner._rest_for_noise[1]
    refiner.contrast_noise = float(np.nanpercentile(measures[1], 33)) / 10.0
    refiner._await_levels(measures)
    rng = np.random.default_rng(seed)
    n = len(refiner.rest_positions)
    refiner._jitter_sq = rng.uniform(0.0, 0.02, n)
    refiner._rest_scatter_sq = rng.uniform(0.0, 0.05, n)
    refiner._rest_scatter_seen = rng.integers(0, 8, n).astype(np.float64)
    refiner._guess_px = max(refiner._guess_px, 0.6)
    return tracker, tracker._bright(tracker._cropped(sensor.render().image)), rng


def _creeping(refiner, rng, amplitude_px):
    """Positions of a pad at rest but for a patch (a Gaussian of a spacing and a half round a random pin) shifted by
    up to `amplitude_px` along one direction, with jitter and a few pins lost."""
    rest = refiner.rest_positions
    n = len(rest)
    centre = rest[rng.integers(n)]
    angle = rng.uniform(0.0, 2.0 * np.pi)
    weight = np.exp(-_squared_norm(rest - centre) / (2.0 * (1.5 * refiner.spacing_px) ** 2))
    positions = rest + amplitude_px * weight[:, None] * np.array([np.cos(angle), np.sin(angle)])
    positions += rng.normal(0.0, 0.05, (n, 2))
    positions[rng.random(n) < 0.03] = np.nan
    return positions


def _agreeing(refiner, positions, look, noise_scatter_sq):
    """The rule as written out here: (L,) bool, the neighbours of `look` within the guess bound of their median or
    `_CALM_BOUND` scatters (or beyond the gate: on another tip), a faint tip's all but `_ODD_NEIGHBOURS`; and their
    median (L, 2)."""
    shift = refiner.displacement_median(positions, look)
    index = refiner._neighbour_index[look]
    noise = np.maximum(np.maximum(refiner._jitter_sq[index], noise_scatter_sq[index]), refiner._jitter_floor)
    moved = positions[index] - refiner.rest_positions[index]
    bound = np.maximum(refiner._guess_px ** 2, _CALM_BOUND ** 2 * noise)
    near = _squared_norm(moved) <= refiner.gate_px ** 2
    apart = np.sum((_squared_norm(moved - shift[:, None]) > bound) & near, axis=1)
    return apart <= np.where(np.isin(look, refiner._faint), _ODD_NEIGHBOURS, 0), shift


@pytest.mark.skipif(kernels is None, reason="Numba missing or TACTIP_KERNELS=numpy: no kernels to test")
@pytest.mark.parametrize("preset, seed", [("radial-led-120", 0), ("tactip-127", 1)])
def test_calm_judgement_on_a_creeping_patch_is_the_reference(preset, seed):
    tracker, crop, rng = _tracker(preset, seed)
    refiner = tracker._refiner
    noise = refiner._noise_scatter_sq
    split = calm = 0
    for trial in range(12):
        positions = _creeping(refiner, rng, refiner._guess_px * (1.0 + 0.5 * (trial % 4)))
        search = np.zeros(len(positions), dtype=bool)
        out, state = [], (refiner._rest_scatter_sq.copy(), refiner._rest_scatter_seen.copy())
        for numpy in (True, False):  # (each from the same learnt rest scatter)
            refiner._rest_scatter_sq, refiner._rest_scatter_seen = state[0].copy(), state[1].copy()
            pins._kernels.choose("numpy" if numpy else "compiled")
            try:
                placed = refiner._snap_to_rest(crop, positions, search, noise)
            finally:
                pins._kernels.choose("compiled")
            out.append((placed, refiner._rest_scatter_sq, refiner._rest_scatter_seen))
            refiner._rest_scatter_sq, refiner._rest_scatter_seen = state
        for got, want in zip(*out):
            assert np.array_equal(got, want, equal_nan=True)
        refiner._rest_scatter_sq, refiner._rest_scatter_seen = out[1][1], out[1][2]
        # The rule bit: pins whose neighbours' median lies near rest but which spread over more than the bound ...
        look = np.flatnonzero(_squared_norm(positions - refiner.rest_positions) > refiner._guess_px ** 2)
        agree, shift = _agreeing(refiner, positions, look, noise)
        near = _squared_norm(shift) <= refiner._guess_px ** 2
        split += np.count_nonzero(near & ~agree)
        # A pin whose neighbours disagree is never put at rest + their median.
        moved = ~np.all(out[0][0][look] == positions[look], axis=1) | np.isnan(positions[look, 0])
        at_median = np.all(np.abs(out[0][0][look] - (refiner.rest_positions[look] + shift)) < 1e-9, axis=1)
        assert not np.any(moved & at_median & near & ~agree)
        calm += np.count_nonzero(moved & at_median)
    assert split > 0 and calm > 0  # (the rule was put to the test, and calm pins were placed)

