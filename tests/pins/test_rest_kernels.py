"""pins._jit_rest's kernels of the still pad's faint tips and of the rest frame's probe against their NumPy
references (`pins._rest._AtRest`, `pins._return.RestMatch`): the same bounds, steadiness, readings and answers,
bit for bit, on a tracker's own state with many faint tips and on awkward frames."""

import numpy as np
import pytest

import pins._kernels
from pins import DetectionParams, PinTracker, SensorDisc
from pins._kernels import compiled
from tactip.sim import SyntheticTacTip

kernels = compiled("_jit_rest")
pytestmark = pytest.mark.skipif(kernels is None, reason="Numba missing or TACTIP_KERNELS=numpy: no kernels to test")


def _tracker(seed):
    """A tracker started on a radial-led-120 rest frame (given the true pins), a third of its tips made faint
    (its noise's reach raised), and a still frame of the same pad."""
    sensor = SyntheticTacTip.from_preset("radial-led-120", seed=seed, frame_rate=120.0)
    rest = sensor.render()
    tracker = PinTracker(detection=DetectionParams(dark_pins=sensor.dark_pins), disc=SensorDisc(*sensor.disc))
    tracker.start(rest.image, pins=rest.centres[np.flatnonzero(rest.visible)])
    refiner = tracker._refiner
    measures = refiner._rest_for_noise[1]
    refiner.contrast_noise = float(np.nanpercentile(measures[1], 33)) / 10.0  # (faint: below twice 5 scatters)
    refiner._await_levels(measures)
    assert 0.2 * len(measures[1]) < refiner._faint.size < 0.5 * len(measures[1])
    return tracker, sensor.render().image


def _both(call, state, names):
    """`call()` on the NumPy reference and on the kernels, each from a copy of `state`'s attributes `names`:
    the two results and the two states after."""
    saved = {name: np.copy(getattr(state, name)) for name in names}
    out = []
    for numpy in (True, False):
        for name, value in saved.items():
            setattr(state, name, value.copy())
        pins._kernels.choose("numpy" if numpy else "compiled")
        try:
            result = call()
        finally:
            pins._kernels.choose("compiled")
        out.append((result, {name: np.copy(getattr(state, name)) for name in names}))
    return out


def _same(a, b):
    assert np.array_equal(a, b, equal_nan=True)


@pytest.mark.parametrize("seed", [0, 1])
def test_faint_tips_bounds_steadiness_and_levels_are_the_reference(seed):
    tracker, still_frame = _tracker(seed)
    refiner = tracker._refiner
    rng = np.random.default_rng(seed)
    n = len(refiner.rest_positions)
    crop = tracker._bright(tracker._cropped(still_frame))
    steady = learnt = 0
    for pair in (False, True):
        if pair:  # (a codec's still pair seen: still and moving pins' contrast bounds differ)
            refiner._contrast_moving = refiner._rest_least[1].copy()
            refiner._contrast_still = refiner._rest_least[1] - 3.0
            refiner._learnt_least = refiner._still_least(refiner._learnt_least)
        for trial in range(6):
            # Positions: the pad at rest with jitter, some pins lost, some moved off (a contact's edge) ...
            positions = refiner.rest_positions + rng.normal(0.0, 0.01 * refiner.spacing_px * (trial % 3), (n, 2))
            positions[rng.random(n) < 0.05] = np.nan
            if trial == 5:
                positions += 0.5 * refiner.spacing_px  # (no pad at rest: nothing read, none here)
            names = ["_level_sum", "_level_seen", "_learnt_least", "_learnt_most", "_at_rest_here"]
            (_, numpy), (_, kernel) = _both(lambda: refiner._learn_levels(crop, positions), refiner, names)
            for name in names:
                _same(kernel[name], numpy[name])
            for name, value in kernel.items():
                setattr(refiner, name, value)
            if trial < 5:
                assert refiner._at_rest_here[refiner._faint].any() and numpy["_level_seen"][1].max() > 1
            # ... steps: still, jittering within the settling bound, moved, lost ...
            steps = rng.normal(0.0, refiner._settled_px * (0.2 + 0.4 * (trial % 3)), (n, 2))
            steps[rng.random(n) < 0.05] = np.nan
            names = ["_steady", "_jitter_sq", "_jitter_seen", "_at_least", "_area_at_most"]
            (still_numpy, numpy), (still_kernel, kernel) = _both(lambda: refiner.observe_still(steps), refiner, names)
            _same(still_kernel, still_numpy)
            for name in names:
                _same(kernel[name], numpy[name])
            for name, value in kernel.items():
                setattr(refiner, name, value)
            steady += np.count_nonzero(refiner._steady)
            # ... and the bounds drawn for random still pins.
            refiner._still = rng.random(n) < 0.6
            names = ["_at_least", "_area_at_most"]
            (_, numpy), (_, kernel) = _both(refiner._draw_bounds, refiner, names)
            for name in names:
                _same(kernel[name], numpy[name])
            learnt += np.count_nonzero(numpy["_at_least"][:, refiner._faint] != refiner._rest_least[:, refiner._faint])
    assert steady > 0 and learnt > 0  # (faint tips were steady, and had learnt bounds drawn)


def test_the_rest_frame_probe_is_the_reference(monkeypatch):
    # Frames that match the rest frame at every probe, at none, and at exactly as many as it takes (or one fewer).
    tracker, still_frame = _tracker(2)
    match = tracker._rest_match
    rest = match._rest
    probes = len(match._probe_index)
    need = int(np.ceil(0.9 * probes - 1))
    rng = np.random.default_rng(2)
    answers = []
    for matching in (probes, 0, need, need - 1, need + 1):
        frame = rest.copy().ravel()
        off = rng.permutation(probes)[:probes - matching]
        for p in off:  # (a window far from the rest frame: well beyond the match bound)
            frame[match._probe_index[p]] = np.where(match._probe_rest[p] < 128, match._probe_rest[p] + 60,
                                                    match._probe_rest[p] - 60).astype(np.uint8)
        frame = frame.reshape(rest.shape)
        match.level = 2.0
        got = match._probe_matches(frame)
        monkeypatch.setattr(pins._kernels, "_NUMPY", True)
        want = match._probe_matches(frame)
        monkeypatch.setattr(pins._kernels, "_NUMPY", False)
        assert got == want
        answers.append(got)
    assert answers == [True, False, True, False, True]
    # A still frame's own noise: mean differences near the bound, the two agree at any level.
    crop = tracker._bright(tracker._cropped(still_frame))
    answers = []
    for level in np.linspace(0.5, 6.0, 23):
        match.level = level
        answers.append(match._probe_matches(crop))
        monkeypatch.setattr(pins._kernels, "_NUMPY", True)
        assert answers[-1] == match._probe_matches(crop), level
        monkeypatch.setattr(pins._kernels, "_NUMPY", False)
    assert not answers[0] and answers[-1]  # (the levels span the bound: MATCH_LEVELS times the level)
