"""pins._jit_track: the tracker's compiled bookkeeping against its NumPy references, on awkward inputs (NaN
rows, all NaN, ties, one pin, one neighbour), bit for bit; and the follow passes and snap to rest through a
tracker on the kernels and on the reference."""

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial import cKDTree

import pins._kernels
from pins import DetectionParams, PinTracker, SensorDisc
from pins._identity import IDENTITY_NEIGHBOURS, MISSING_MARGIN, _keep_own_tips_numpy, keep_own_tips
from pins._kernels import compiled
from pins._noise import _JITTER_BOUND, _JITTER_FIRST, _JITTER_RATE
from pins._predict import _median, _Prediction
from pins._refine import _SAME_TIP_FRACTION, Refiner
from pins._rest import _AtRest
from pins._window import WindowCentroids
from pins.disc import as_grey
from tests.pins.conftest import slide_run

kernels = compiled()
pytestmark = pytest.mark.skipif(kernels is None, reason="Numba missing or TACTIP_KERNELS=numpy: no kernels to test")


def _same(got, want):
    """Equal bit for bit, NaN in the same places (and -0.0 equal to 0.0)."""
    np.testing.assert_array_equal(got, want)


def _lattice(rng, n, k):
    """`n` jittered points on a grid (spacing 10 px) and each one's `k` nearest others (N, k)."""
    side = int(np.ceil(np.sqrt(n)))
    points = np.stack(np.meshgrid(np.arange(side), np.arange(side)), axis=-1).reshape(-1, 2)[:n] * 10.0
    points = points + rng.uniform(-1.0, 1.0, points.shape)
    index = cKDTree(points).query(points, min(k + 1, n))[1][:, 1:]
    if index.ndim == 1:
        index = index[:, None]
    return points, np.ascontiguousarray(index)


def _awkward_values(rng, n, ties):
    """(N, 2) values with NaN rows, one NaN-x row with a finite y, and (`ties`) repeated values."""
    values = rng.normal(0.0, 2.0, (n, 2))
    if ties:
        values = np.round(values)  # many equal values
    values[rng.random(n) < 0.3] = np.nan
    values[0, 0] = np.nan  # x NaN, y finite: the reference counts x
    values[min(1, n - 1)] = [-0.0, 0.0]
    values[-1, 0] = np.inf  # not finite: not counted, sorted before NaN
    return values


@pytest.mark.parametrize("seed", range(4))
def test_neighbour_medians_are_the_references(seed):
    rng = np.random.default_rng(seed)
    for n, k in ((1, 1), (2, 1), (7, 6), (40, 6), (40, 5)):
        points, index = _lattice(rng, max(n, 2), k)
        index = index[:n] if n > 1 else np.zeros((1, 1), np.int64)
        for ties in (False, True):
            values = _awkward_values(rng, len(points), ties)
            _same(kernels.neighbour_median(values, index), _median(values[index]))
            rest = rng.normal(0.0, 5.0, values.shape)
            _same(kernels.displacement_median(values, rest, index), _median((values - rest)[index]))
        every = np.full((len(points), 2), np.nan)  # all NaN: NaN medians
        assert np.isnan(kernels.neighbour_median(every, index)).all()
        _same(kernels.neighbour_median(every, index), _median(every[index]))


def _predictor(rng, n, k):
    """A `_Prediction` with rest positions, neighbours and remembered displacements (some NaN)."""
    rest, index = _lattice(rng, n, k)
    then = rng.normal(0.0, 1.0, (n, index.shape[1], 2))
    then[rng.random(then.shape[:2]) < 0.3] = np.nan
    return SimpleNamespace(rest_positions=rest, _neighbour_index=index, _then=then)


@pytest.mark.parametrize("seed", range(4))
def test_predictions_are_the_references(seed, monkeypatch):
    rng = np.random.default_rng(seed)
    for n, k in ((2, 1), (12, 6), (60, 6)):
        state = _predictor(rng, n, k)
        positions = state.rest_positions + rng.normal(0.0, 2.0, state.rest_positions.shape)
        positions[rng.random(n) < 0.4] = np.nan
        positions[: max(1, n // 6)] = np.nan
        positions[-1, 0] = np.inf  # a neighbour neither placed nor missing
        last_seen = state.rest_positions + rng.normal(0.0, 1.0, state.rest_positions.shape)
        which = np.flatnonzero(np.isnan(positions[:, 0]))
        if n > 2:
            positions[state._neighbour_index[0]] = np.nan  # pin 0: no neighbour placed (where last seen)
        got = _Prediction._predict(state, positions, which, last_seen)
        monkeypatch.setattr(pins._kernels, "_NUMPY", True)
        want = _Prediction._predict(state, positions, which, last_seen)
        monkeypatch.setattr(pins._kernels, "_NUMPY", False)
        _same(got, want)
        if n > 2:
            _same(got[0], last_seen[0])
        # Whether to search there: most neighbours placed, or a few still ones and the prediction near.
        state.still, state.gate_px = rng.random(n) < 0.7, 3.0
        predicted = last_seen[which] + rng.normal(0.0, 3.0, (len(which), 2))
        got = _Prediction._trusted(state, positions, which, last_seen, predicted)
        monkeypatch.setattr(pins._kernels, "_NUMPY", True)
        want = _Prediction._trusted(state, positions, which, last_seen, predicted)
        monkeypatch.setattr(pins._kernels, "_NUMPY", False)
        _same(got, want)
        state._then[:] = 0.0  # `remember` against its reference
        _Prediction.remember(state, positions)
        got = state._then.copy()
        monkeypatch.setattr(pins._kernels, "_NUMPY", True)
        state._then[:] = 0.0
        _Prediction.remember(state, positions)
        monkeypatch.setattr(pins._kernels, "_NUMPY", False)
        _same(got, state._then)


@pytest.mark.parametrize("seed", range(4))
def test_kept_own_tips_are_the_references(seed):
    # Found pins on their own tips, on a neighbour's, on a missing pin's prediction (within and beyond the
    # margin), unplaced found pins, a pin expected nowhere, duplicates, one pin.
    rng = np.random.default_rng(seed)
    for n in (1, 2, 30, 120):
        expected, near = _lattice(rng, max(n, 2), IDENTITY_NEIGHBOURS)
        expected, near = expected[:n], near[:n] if n > 1 else np.zeros((1, 1), np.int64)
        for trial in range(5):
            positions = expected + rng.normal(0.0, 2.5, expected.shape)
            positions[rng.random(n) < 0.2] = np.nan
            if n > 2:
                positions[2, 0] = np.inf  # neither placed nor missing
            found = rng.choice(n, size=max(1, n // 3), replace=False)
            if n > 2 and trial == 1:
                found = np.concatenate([found, found[:1]])  # a duplicate
            start = expected[found] + rng.normal(0.0, 1.0, (len(found), 2))
            guess = expected.copy()
            guess[rng.random(n) < 0.1] = np.nan  # expected nowhere
            got, want = positions.copy(), positions.copy()
            kernels.keep_own_tips(got, found, start, guess, near, MISSING_MARGIN ** 2)
            _keep_own_tips_numpy(want, found, start, guess, near)
            _same(got, want)
            keep_own_tips(got, found[:0], start[:0], guess, near)  # none found: nothing changes
            _same(got, want)
    # The reference's own example: a tip where a missing pin is expected is not the found pin's.
    positions = np.array([[0.0, 0.0], [19.0, 0.0], [np.nan, np.nan]])
    kernels.keep_own_tips(positions, np.array([1]), np.array([[12.0, 0.0]]),
                          np.array([[0.0, 0.0], [10.0, 0.0], [20.0, 0.0]]), np.array([[1, 2], [0, 2], [1, 0]]), 16.0)
    assert np.isnan(positions[1]).all() and (positions[0] == 0.0).all()


@pytest.mark.parametrize("seed", range(4))
def test_one_pin_per_tip_is_the_reference(seed):
    # Found pins on one tip with a placed pin, with another found pin (the one farther from its prediction
    # yields; ties: both), NaN found pins, one pin.
    rng = np.random.default_rng(seed)
    for n in (1, 3, 50):
        points, near = _lattice(rng, max(n, 2), IDENTITY_NEIGHBOURS)
        points, near = points[:n], near[:n] if n > 1 else np.zeros((1, 1), np.int64)
        state = SimpleNamespace(_identity_index=near, spacing_px=10.0)
        for _ in range(5):
            positions = points.copy()
            positions[rng.random(n) < 0.2] = np.nan
            found = rng.choice(n, size=max(1, n // 2), replace=False)
            onto = near[found, 0]
            moved = rng.random(len(found)) < 0.5
            positions[found[moved]] = points[onto[moved]] + rng.normal(0.0, 1.0, (int(moved.sum()), 2))
            error = np.round(rng.uniform(0.0, 4.0, len(found)))  # ties
            got, want = positions.copy(), positions.copy()
            kernels.one_pin_per_tip(got, found, error, near, (_SAME_TIP_FRACTION * 10.0) ** 2)
            Refiner._one_pin_per_tip_numpy(state, want, found, error)
            _same(got, want)


class _Steps(_Prediction, _AtRest):
    """The prediction and rest sides of `Refiner` with only the state they read."""

    def __init__(self, **state):
        self.__dict__.update(state)


def _stepper(rng, n, k):
    """A `_Prediction`/`_AtRest` stand-in with neighbours, scatters and learnt state."""
    rest, index = _lattice(rng, n, k)
    return _Steps(rest_positions=rest, _neighbour_index=index, _noise_scatter_sq=rng.uniform(0.0, 0.05, n),
                           _guess_px=0.24, _settled_px=1.0, _jitter_sq=rng.uniform(0.0, 0.1, n),
                           _jitter_seen=rng.integers(0, 6, n).astype(np.float64), _observed=0, _jitter_floor=0.0)


@pytest.mark.parametrize("seed", range(4))
def test_carried_steps_and_still_steps_are_the_references(seed, monkeypatch):
    # Still pads (nothing carried), a neighbourhood moving slowly (own steps agreeing with the median and
    # not), NaN steps (lost pins), inf, one pin with one neighbour.
    rng = np.random.default_rng(seed)
    for n, k in ((2, 1), (30, 6), (120, 6)):
        for scale in (0.05, 0.6, 3.0):
            state = _stepper(rng, n, k)
            velocity = rng.normal(0.0, scale, (n, 2))
            velocity[rng.random(n) < 0.15] = np.nan
            if n > 2:
                velocity[2] = [np.inf, 0.0]
            results = []
            for choice in ("numba", "numpy"):
                monkeypatch.setattr(pins._kernels, "_NUMPY", choice == "numpy")
                copy = _Steps(**{key: (value.copy() if isinstance(value, np.ndarray) else value)
                                 for key, value in vars(state).items()})
                still = copy.observe_still(velocity)
                carried = copy.carried_velocity(velocity.copy(), still)
                results.append((still, carried, copy._jitter_sq, copy._jitter_seen))
            monkeypatch.setattr(pins._kernels, "_NUMPY", False)
            for got, want in zip(*results):
                _same(got, want)


def test_still_steps_learn_as_the_reference():
    rng = np.random.default_rng(5)
    mean_sq, seen = rng.uniform(0.0, 0.1, 50), rng.integers(0, 6, 50).astype(np.float64)
    steps = rng.normal(0.0, 0.4, (50, 2))
    steps[:5] = np.nan
    got_sq, got_seen = mean_sq.copy(), seen.copy()
    still = kernels.observe_still(steps, 1.0, got_sq, got_seen, _JITTER_FIRST, _JITTER_BOUND ** 2, _JITTER_RATE)
    assert not still[:5].any() and still[5:].mean() > 0.9
    from pins._noise import _learn_mean_square
    half = 0.5 * (steps ** 2).sum(axis=1)
    _learn_mean_square(mean_sq, seen, slice(None), half, still)
    _same(got_sq, mean_sq)
    _same(got_seen, seen)


@pytest.mark.parametrize("name, seed", [("radial-led-120", 2), ("small-pad-100", 0)])
def test_follow_and_snap_to_rest_agree_with_the_reference(name, seed, monkeypatch):
    # The follow passes and snap to rest on their kernels and on their references, the same window
    # measurements: a press and a slide and their return to rest, every frame's positions bit for bit.
    s, run, drawn = slide_run(name, seed, [0, 135], distance_mm=6.0, rest_s=3 / 120,
                              press_s=0.08, slide_s=0.2, lift_s=0.05)
    calls = {"rest_judge": 0, "follow_passes": 0}
    for label in calls:
        def counted(*args, _kernel=getattr(kernels, label), _label=label):
            calls[_label] += 1
            return _kernel(*args)
        monkeypatch.setattr(kernels, label, counted)
    tracks = []
    for bookkeeping in (True, False):
        tracker = PinTracker(detection=DetectionParams(dark_pins=s.dark_pins), disc=SensorDisc(*s.disc))
        tracker.start(run[0].image, pins=run[0].centres[drawn])
        if not bookkeeping:  # the NumPy passes, with the same compiled window measurements
            monkeypatch.setattr(Refiner, "_follow_compiled", None)
            monkeypatch.setattr(Refiner, "_snap_to_rest_compiled", None)
            monkeypatch.setattr("pins._follow.compiled", lambda: None)
            monkeypatch.setattr("pins._rest.compiled", lambda *module: None)
        tracks.append([(tracker.update(f.image), tracker.lost.copy()) for f in run[1:]])
    for (positions, lost), (want, want_lost) in zip(*tracks):
        _same(positions, want)
        _same(lost, want_lost)
    assert calls["follow_passes"] > len(run) // 2 and calls["rest_judge"] > 5  # the kernels' passes ran
    assert np.nanmax(np.abs(tracks[0][len(run) // 3][0] - tracks[0][0][0])) > 4.0  # the pins moved


def _refiner_and_frames(name, seed):
    """A tracker's refiner started on a preset's rest frame, and the bright crops of a press and slide."""
    s, run, drawn = slide_run(name, seed, [60], distance_mm=5.0, rest_s=2 / 120,
                              press_s=0.05, slide_s=0.1, lift_s=0.03)
    tracker = PinTracker(detection=DetectionParams(dark_pins=s.dark_pins), disc=SensorDisc(*s.disc))
    tracker.start(run[0].image, pins=run[0].centres[drawn])
    crops = [tracker._bright(tracker._cropped(as_grey(f.image))) for f in run[1::4]]
    truths = [f.centres[drawn] for f in run[1::4]]
    return tracker._refiner, crops, truths


class _StandIn(WindowCentroids):
    """Windowed centroids that are not `WindowCentroids` itself: the follow passes measure them pass by pass."""


@pytest.mark.parametrize("name, seed", [("radial-led-120", 3), ("tactip-331", 1)])
def test_follow_passes_are_the_reference_from_awkward_guesses(name, seed, monkeypatch):
    # Guesses on the tips, a fraction of a spacing off (re-centred), most of a spacing off (no tip near
    # them: searched for from their predictions), lost pins searched for or not: positions and the
    # filled guesses bit for bit the NumPy passes'.
    refiner, crops, truths = _refiner_and_frames(name, seed)
    rng = np.random.default_rng(seed)
    spacing = refiner.spacing_px
    far_pins = 0
    for k, (crop, truth) in enumerate(zip(crops, truths)):
        for spread in (0.02, 0.2, 0.45, None, "stale"):
            if spread == "stale":  # guesses from another frame of the slide: stale by up to px
                truth = truths[(k + 1) % len(truths)]
            guess = truth + rng.normal(0.0, (0.02 if spread in (None, "stale") else spread) * spacing, truth.shape)
            if spread in (None, "stale"):  # a few pins far off among placed neighbours: trusted searches
                off = rng.random(len(guess)) < 0.15
                angle = rng.uniform(0, 2 * np.pi, off.sum())
                guess[off] += rng.uniform(0.45, 0.9, off.sum())[:, None] * spacing * np.stack(
                    [np.cos(angle), np.sin(angle)], axis=1)
            guess[rng.random(len(guess)) < 0.1] = np.nan
            # Pins that moved in the last frame: a tip judged by its contrast alone is like at rest only while still.
            refiner.still = rng.random(len(guess)) < 0.5
            last_seen = np.where(np.isnan(guess), refiner.rest_positions, guess)
            search = rng.random(len(guess)) < 0.7
            got = refiner.follow(crop, guess, last_seen, search)
            # The passes judged by the kernels round a stand-in's window measurements (`pins.accel`'s).
            windows, refiner.windows = refiner.windows, _StandIn.__new__(_StandIn)
            refiner.windows.__dict__.update(windows.__dict__)  # (its settings)
            passes = refiner.follow(crop, guess, last_seen, search)
            refiner.windows = windows
            monkeypatch.setattr("pins._follow.compiled", lambda: None)
            want = refiner.follow(crop, guess, last_seen, search)
            monkeypatch.undo()
            for result in (got, passes):
                _same(result[0], want[0])
                _same(result[1], want[1])
            far_pins += int(np.count_nonzero(np.isnan(got[0][:, 0]) & np.isfinite(guess[:, 0])))
    assert far_pins > 10  # some guesses found no tip: the searches from predictions ran
    if name == "radial-led-120":  # (seed 3: two faint tips by LED reflections, judged by their contrast alone)
        assert np.count_nonzero(~refiner._judged) >= 1


@pytest.mark.parametrize("name, seed", [("radial-led-120", 4), ("small-pad-100", 2)])
def test_snap_to_rest_is_the_reference_on_awkward_positions(name, seed, monkeypatch):
    # A pad at rest with pins jittered, drifted, on a neighbour's tip, missing (searched for or not), and
    # the pad moving: the positions and the learnt rest scatter bit for bit the reference's.
    refiner, crops, _ = _refiner_and_frames(name, seed)
    rng = np.random.default_rng(seed)
    rest, n = refiner.rest_positions, len(refiner.rest_positions)
    snapped = 0
    for trial in range(12):
        positions = rest + rng.normal(0.0, (0.02, 0.1, 0.3)[trial % 3], rest.shape)
        swapped = rng.choice(n, 3, replace=False)
        positions[swapped] = rest[refiner._neighbour_index[swapped, 0]]
        positions[rng.random(n) < 0.1] = np.nan
        if trial == 11:
            positions = positions + 2.0  # a moving pad: nothing moves
        search = rng.random(n) < 0.6
        state = (refiner._rest_scatter_sq.copy(), refiner._rest_scatter_seen.copy())
        got = refiner.snap_to_rest(crops[0], positions, search)
        learnt = (refiner._rest_scatter_sq.copy(), refiner._rest_scatter_seen.copy())
        refiner._rest_scatter_sq, refiner._rest_scatter_seen = state
        monkeypatch.setattr("pins._rest.compiled", lambda *module: None)
        want = refiner.snap_to_rest(crops[0], positions, search)
        monkeypatch.undo()
        _same(got, want)
        _same(learnt[0], refiner._rest_scatter_sq)
        _same(learnt[1], refiner._rest_scatter_seen)
        snapped += got is not positions
    assert snapped >= 3  # pins were put back at rest
