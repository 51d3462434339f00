"""pins._jit_follow's kernel of `pins._follow._Following._part_tips` (tips in re-centred follow windows that hold two,
assigned one-to-one) against its NumPy reference (OpenCV blur and morphology over the windows' part of the crop,
`scipy.optimize.linear_sum_assignment`): the same pins re-placed at the same positions, through slides on both
polarities and the radial pad, and on windows cut by the crop's edge. Ground truth from the synthetic TacTip."""

import numpy as np
import pytest

import pins._follow
from pins._follow import _Following
from pins._kernels import compiled
from tests.pins.conftest import preset_sensor, slide_run, tracker_on_rest

kernels = compiled("_jit_follow")
pytestmark = pytest.mark.skipif(kernels is None, reason="Numba missing or TACTIP_KERNELS=numpy: no kernel to test")


def _reference(monkeypatch):
    """From now on `_part_tips` runs its NumPy reference; returns a list that counts the pins it re-placed."""
    monkeypatch.setattr(pins._follow, "_part_kernels", lambda: None)
    moved = []
    numpy = _Following._part_tips_numpy

    def counted(self, *args):
        result = numpy(self, *args)
        moved.append(result[0].size)
        return result

    monkeypatch.setattr(_Following, "_part_tips_numpy", counted)
    return moved


def _tracked(preset, seed):
    """Positions (frames, N, 2) of a tracker through two diagonal slides of 3 pitches at 120 frames/s."""
    pitch = preset_sensor(preset, seed).pin_spacing_mm
    s, run, _ = slide_run(preset, seed, [45, 225], distance_mm=3 * pitch, indentation_mm=2.0,
                          rest_s=0.025, press_s=0.05, slide_s=0.15, lift_s=0.05)
    tracker, _ = tracker_on_rest(s, run[0])
    return np.array([tracker.update(f.image).copy() for f in run[1:]])


@pytest.mark.parametrize("preset", ["tactip-331", "dark-331", "radial-led-120"])
def test_kernel_places_the_pins_the_reference_places_through_slides(monkeypatch, preset):
    # The kernel blurs in another order (float32 sums) and reads the crop's own pixels where the reference reflects
    # them at the edge of its part of the crop (2 half beyond the outermost window): a peak at a threshold or near that
    # edge may fall the other way (radial-led-120, seed 1: 1 pin-frame of 8160, by 0.016 px).
    compiled_positions = _tracked(preset, 1)
    moved = _reference(monkeypatch)
    reference_positions = _tracked(preset, 1)
    assert sum(moved) >= 10  # (windows with two tips were met and re-placed)
    same = np.all((compiled_positions == reference_positions) | (np.isnan(compiled_positions)
                                                                 & np.isnan(reference_positions)), axis=2)
    assert np.count_nonzero(~same) <= 0.001 * same.size


def test_kernel_reads_windows_cut_by_the_crop_edge_as_the_reference(monkeypatch):
    # A tactip-331 slide's frames whose re-centred windows hold two tips, with the crop cut 8 px before each such
    # window (the window, 10 px, and its blur's reach, 11 px, past the cut): the kernel's windows at the crop's edge
    # (blurred one by one, reflected there as OpenCV reflects) against the reference.
    calls = []
    real = _Following._part_tips

    def recorded(self, crop, positions, pins_, start, filled, *held):
        calls.append((self, crop.copy(), positions.copy(), pins_.copy(), start.copy(), filled.copy(), held))
        return real(self, crop, positions, pins_, start, filled, *held)

    monkeypatch.setattr(_Following, "_part_tips", recorded)
    _tracked("tactip-331", 1)
    monkeypatch.setattr(_Following, "_part_tips", real)
    moved = _reference(monkeypatch)
    cases = []
    for refiner, crop, positions, pins_, start, filled, held in calls:
        reference = positions.copy()
        refiner._part_tips(crop, reference, pins_, start.copy(), filled, *held)
        changed = pins_[np.any(reference[pins_] != positions[pins_], axis=1)]
        if changed.size:
            cases.append((refiner, crop, positions, pins_, start, filled, held, changed[0]))
        if len(cases) == 8:
            break
    assert len(cases) == 8 and sum(moved) >= 8
    origin = cases[0][0].origin
    replaced = 0
    for refiner, crop, positions, pins_, start, filled, held, pin in cases:
        corner = np.rint(positions[pin] - origin).astype(int) - 8
        cut = np.ascontiguousarray(crop[corner[1]:, corner[0]:])
        monkeypatch.setattr(refiner, "origin", origin + corner)
        local = np.rint(positions[pins_] - origin - corner)
        inside = np.all((local >= 0) & (local < cut.shape[::-1]), axis=1)  # (or nan: placed pins only)
        pins_, start = pins_[inside], start[inside]
        held = tuple(int(np.count_nonzero(inside[:h])) for h in held)  # (first-pass rows from there on)
        answers = []
        for numpy in (True, False):
            monkeypatch.setattr(pins._follow, "_part_kernels", (lambda: None) if numpy else (lambda: kernels))
            answer = positions.copy()
            refiner._part_tips(cut, answer, pins_, start.copy(), filled, *held)
            answers.append(answer)
        assert np.array_equal(answers[0], answers[1], equal_nan=True)
        replaced += not np.array_equal(answers[1], positions, equal_nan=True)
        monkeypatch.setattr(refiner, "origin", origin)
    assert replaced >= 4  # (the windows at the edge still held two tips)
