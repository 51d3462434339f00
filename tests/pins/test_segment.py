"""pins.segment: hysteresis tap segmentation of continuous recordings."""

import numpy as np
import pytest

from pins import PinTracker, converging_frames, displacement_from_rest, segment_taps, tap_signal
from tactip.sim import Contact
from tests.pins.conftest import sensor


def _signal(*bumps, length=60):
    signal = np.full(length, 0.05)
    for start, stop, height in bumps:
        signal[start:stop] = height
    return signal


def test_each_bump_is_a_tap():
    signal = _signal((5, 15, 3.0), (25, 31, 2.0), (40, 52, 8.0))
    assert segment_taps(signal, pad_frames=0) == [(5, 15), (25, 31), (40, 52)]
    assert segment_taps(signal, pad_frames=2) == [(3, 17), (23, 33), (38, 54)]


def test_hysteresis_low_and_high():
    # A bump that never reaches high_px is not a tap; a tap lasts while above low_px.
    signal = _signal((5, 15, 1.0), (30, 40, 0.8))
    signal[33:36] = 2.0
    assert segment_taps(signal, high_px=1.5, low_px=0.5, pad_frames=0) == [(30, 40)]


def test_short_dips_merge_and_short_runs_drop():
    signal = _signal((10, 20, 3.0), (21, 30, 3.0), (45, 47, 3.0))
    assert segment_taps(signal, merge_gap_frames=2, min_frames=3, pad_frames=0) == [(10, 30)]
    assert segment_taps(signal, merge_gap_frames=0, min_frames=3, pad_frames=0) == [(10, 20), (21, 30)]
    assert segment_taps(signal, merge_gap_frames=0, min_frames=1, pad_frames=0) == [(10, 20), (21, 30), (45, 47)]


def test_padding_never_overlaps():
    signal = _signal((10, 20, 3.0), (24, 30, 3.0))
    taps = segment_taps(signal, merge_gap_frames=1, pad_frames=3)
    assert taps[0][1] <= taps[1][0]


def test_quiet_recording_has_no_taps():
    assert segment_taps(np.zeros(30)) == []
    assert segment_taps(np.zeros((30, 5, 2))) == []


def test_signal_ignores_lost_pins():
    displacements = np.zeros((3, 10, 2))
    displacements[1, :, 0] = 4.0
    displacements[1, :3] = np.nan
    displacements[2] = np.nan
    assert np.allclose(tap_signal(displacements), [0.0, 4.0, 0.0])


def test_taps_of_a_tracked_recording_cover_the_contacts():
    s = sensor(331)
    frames = [s.render()] * 3
    for depth in (2.0, 3.5, 5.0):
        frames += list(s.tap(Contact(indentation_mm=depth, gap_width_mm=2.0)))
    tracker = PinTracker()
    rest = tracker.start(frames[0].image)
    positions = np.stack([rest] + [tracker.update(f.image) for f in frames[1:]])
    taps = segment_taps(displacement_from_rest(positions, rest))
    assert len(taps) == 3
    touching = np.array([f.contact.indentation_mm > 0.2 for f in frames])
    # Each segment is mostly contact, and together they hold every contact frame.
    for start, stop in taps:
        assert touching[start:stop].mean() > 0.5
    covered = np.zeros(len(frames), dtype=bool)
    for start, stop in taps:
        covered[start:stop] = True
    assert covered[touching].all()


@pytest.mark.parametrize("kwargs, name", [({"high_px": 0.3, "low_px": 0.5}, "low_px"),
                                          ({"min_frames": -1}, "min_frames"),
                                          ({"pad_frames": 1.5}, "pad_frames")])
def test_arguments_checked(kwargs, name):
    with pytest.raises(ValueError, match=name):
        segment_taps(np.zeros(10), **kwargs)


def test_signal_equals_nanpercentile_with_lost_pins(rng):
    displacements = rng.normal(size=(40, 25, 2))
    displacements[rng.random((40, 25)) < 0.3] = np.nan
    displacements[7] = np.nan  # a blank frame
    magnitude = np.hypot(displacements[..., 0], displacements[..., 1])
    with np.errstate(all="ignore"), pytest.warns(RuntimeWarning):
        expected = np.nan_to_num(np.nanpercentile(magnitude, 75, axis=1))
    assert np.allclose(tap_signal(displacements, percentile=75), expected, atol=1e-12)


def test_converging_frames_tell_a_pressed_reference():
    s = sensor(331)
    rest = s.rest_centres
    pressed = s.pin_centres(Contact(indentation_mm=4.0))[0]
    frames = np.stack([rest, pressed, rest, pressed, rest])
    # From the true rest frame the pins spread: nothing converges.
    assert converging_frames(displacement_from_rest(frames, rest), rest).size == 0
    # From the pressed frame, the frames at rest show the pins drawn together.
    assert converging_frames(displacement_from_rest(frames, pressed), pressed).tolist() == [0, 2, 4]


def test_nanmedian_rows_gives_numpys_nanmedian_exactly():
    """Replay's contact kinds and jitter floor take row medians by one sort (`nanmedian_rows`): the same
    values as `np.nanmedian`, with NaN rows, infinities and even counts."""
    import warnings

    from pins.segment import nanmedian_rows

    rng = np.random.default_rng(7)
    for trial in range(400):
        shape = (int(rng.integers(1, 20)), int(rng.integers(1, 12)))
        values = rng.normal(size=shape) * 10.0 ** rng.integers(-3, 3)
        values[rng.random(shape) < rng.random()] = np.nan
        values[rng.random(shape) < (0.1 if trial % 5 == 0 else 0.0)] = np.inf
        values[rng.random(shape) < (0.1 if trial % 7 == 0 else 0.0)] = -np.inf
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            expected = np.nanmedian(values, axis=1)
        assert np.array_equal(nanmedian_rows(values), expected, equal_nan=True)
    cube = rng.normal(size=(6, 40, 2))
    cube[rng.random(cube.shape) < 0.3] = np.nan
    assert np.array_equal(nanmedian_rows(np.moveaxis(cube, 1, -1)), np.nanmedian(cube, axis=1), equal_nan=True)
