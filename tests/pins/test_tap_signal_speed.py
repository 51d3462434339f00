"""`pins.tap_signal` ranks the pins by their squared lengths and measures only the pins at the ranks it needs
(`pins.segment._ranked_length`): the same bits as sorting every pin's `np.hypot` length, as it did before."""

import numpy as np
import pytest

import pins.segment
from pins import skin_rest, tap_signal
from pins.displacement import displacement_magnitude


def _by_every_length(displacements, percentile=90.0):
    """The signal as `tap_signal` computed it until session 22: every pin's np.hypot, sorted (NaN last)."""
    ordered = np.sort(displacement_magnitude(np.asarray(displacements, dtype=np.float64)), axis=1)
    if ordered.shape[1] == 0:
        return np.zeros(len(ordered))
    count = np.count_nonzero(np.isfinite(ordered), axis=1)
    rank = percentile / 100.0 * np.maximum(count - 1, 0)
    low = np.floor(rank).astype(np.intp)
    high = np.minimum(low + 1, np.maximum(count - 1, 0))
    rows = np.arange(len(ordered))
    with np.errstate(invalid="ignore"):
        value = ordered[rows, low] + (ordered[rows, high] - ordered[rows, low]) * (rank - low)
    return np.where(count > 0, value, 0.0)


def _fields(seed: int, count: int):
    """Displacement fields (T, N, 2) px with what could make two rankings differ: exact ties, equal lengths from
    other components, zeros, lost pins, lost components, infinities, squares that overflow or underflow."""
    rng = np.random.default_rng(seed)
    for k in range(count):
        frames, pins = int(rng.integers(1, 30)), int(rng.integers(0, 25))
        field = rng.normal(size=(frames, pins, 2)) * 10.0 ** float(rng.integers(-3, 4))
        if k % 3 == 0:
            field = np.round(field, int(rng.integers(0, 3)))                      # exact ties
        if k % 4 == 1:
            field[:, ::2] = field[:, ::2, ::-1]                                   # (a, b) beside (b, a)
            field[:, 1::2] = field[:, ::2][:, : field[:, 1::2].shape[1]]
        if k % 5 == 0:
            field[rng.random((frames, pins)) < 0.3] = np.nan
        if k % 7 == 0:
            field[rng.random((frames, pins)) < 0.3] = 0.0
        if k % 11 == 0:
            field[rng.random((frames, pins)) < 0.2, 0] = np.nan
        if pins and k % 13 == 0:
            field[0, 0, 0] = np.inf
        if pins and k % 17 == 0:
            field[-1, 0] = (-np.inf, np.nan)                                      # np.hypot: inf
        if pins and k % 19 == 0:
            field[-1, -1, 1] = 1e-200                                             # squares to 0
        if pins and k % 23 == 0:
            field[0, -1, 0] = 1e200                                               # squares to inf
        yield field


@pytest.fixture
def ranked(monkeypatch):
    """The ranking by squared lengths on fields of any size (on its own, from `_RANKED_FROM` pin-frames)."""
    monkeypatch.setattr(pins.segment, "_RANKED_FROM", 0)


@pytest.mark.parametrize("percentile", [90.0, 0.0, 50.0, 100.0, 37.5])
def test_the_signal_is_every_length_sorted_bit_for_bit(percentile, ranked):
    for field in _fields(0, 160):
        with np.errstate(over="ignore", invalid="ignore"):
            assert tap_signal(field, percentile=percentile).tobytes() == _by_every_length(field, percentile).tobytes()


def test_a_replayed_slide_field_gives_the_same_bits():
    """Pins drifting, a slide, pins lost through it, the rest frame's zeros, float32 as replay stores them."""
    rng = np.random.default_rng(5)
    field = np.cumsum(rng.normal(0.0, 0.1, (300, 120, 2)), axis=0)
    field[0] = 0.0
    field[100:140] += np.linspace(0.0, 30.0, 40)[:, None, None]
    field[rng.random((300, 120)) < 0.05] = np.nan
    assert field[..., 0].size >= pins.segment._RANKED_FROM                      # ranked by squared lengths
    for data in (field, field.astype(np.float32), field[::-1] - field[7]):
        assert tap_signal(data).tobytes() == _by_every_length(data).tobytes()


def test_each_frame_alone_has_its_value_in_the_whole_signal(ranked):
    """`pins.skin_rest` measures the signal from the first rest at a rest frame alone: frames are independent."""
    for field in _fields(1, 40):
        with np.errstate(over="ignore", invalid="ignore"):
            whole = tap_signal(field)
            assert all(tap_signal(field[t:t + 1]).tobytes() == whole[t:t + 1].tobytes() for t in range(len(field)))


def test_a_set_creeping_back_is_a_new_rest():
    """A slide lifted leaves a 2 px set, which then creeps back to 1.4 px: the skin's rest follows it down (the
    creep is judged on the signal from the first rest at the lift's rest frame, `pins.skin_rest`)."""
    field = np.zeros((40, 30, 2))
    field[3:9, :, 0] = np.linspace(1.0, 6.0, 6)[:, None]       # the slide
    field[9:12, :, 0] = np.array([4.0, 2.6, 2.1])[:, None]      # its lift
    field[12:, :, 0] = 2.0                                      # the set it left
    field[20:25, :, 0] = np.linspace(1.85, 1.4, 5)[:, None]     # creeping back, slowly
    field[25:, :, 0] = 1.4
    rest, frames = skin_rest(field, low_px=0.5, high_px=1.5, return_frames=True)
    assert frames[0] == 0 and any(12 <= f < 20 for f in frames)   # the lift's rest
    assert any(f >= 20 for f in frames) and np.allclose(rest[-1, :, 0], 1.4)
