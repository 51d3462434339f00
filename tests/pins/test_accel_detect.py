"""pins.accel_detect: batched adaptive-threshold detection (torch + kornia) against the NumPy/OpenCV path (CPU)."""

import cv2
import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("kornia")

from pins import DetectionParams, SensorDisc, detect_blobs, detect_pins, find_pin_field  # noqa: E402
from pins.accel_detect import BatchedDetector, detect_pins_batched, gaussian_kernel_fixed  # noqa: E402
from pins.detect import _filtered  # noqa: E402
from tactip.sim import GEL_PRESETS, PRESETS, Contact, SyntheticTacTip  # noqa: E402
from tactip.sim.gel import SyntheticGel  # noqa: E402

from .conftest import score  # noqa: E402


def _grey(image):
    return image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)


def _sensor(preset, seed):
    if preset in GEL_PRESETS:
        return SyntheticGel.from_preset(preset, seed=seed)
    return SyntheticTacTip.from_preset(preset, seed=seed)


@pytest.mark.parametrize("preset", [*PRESETS, *GEL_PRESETS])
def test_batched_detection_equals_the_numpy_path_on_every_preset(preset):
    """At rest, pressed and pressed hard, two sensor seeds: the same pins, within 0.01 px (in fact equal).

    Both paths detect with the parameters and disc of the pin field of the first seed's rest frame (the claim
    is that they agree for given parameters; a search per seed was half the file's CPU)."""
    field = None
    for seed in (0, 3):
        sensor = _sensor(preset, seed)
        frames = [sensor.render(Contact(depth, 2.0)) for depth in (0.0, 3.0, 5.0)]
        field = field or find_pin_field(_grey(frames[0].image))
        # BGR frames go in as they come from the camera; the batch converts them to grey as OpenCV does.
        # The blob stage on the tensors (default), and (first seed) on the CPU with pins.detect's code.
        for labelling in ("tensor", "cpu") if seed == 0 else ("tensor",):
            detector = BatchedDetector(field.disc, _grey(frames[0].image).shape, field.params, device="cpu",
                                       labelling=labelling)
            got = detector.detect_blobs([frame.image for frame in frames])
            for frame, blobs in zip(frames, got):
                expected = detect_blobs(frame.image, params=field.params, disc=field.disc)
                assert blobs.centres.shape == expected.centres.shape and len(expected.centres) > 0
                assert np.abs(blobs.centres - expected.centres).max() <= 0.01
                np.testing.assert_array_equal(blobs.areas, expected.areas)
                np.testing.assert_allclose(blobs.contrasts, expected.contrasts, rtol=1e-9)
                assert blobs.candidates == expected.candidates
        # And both are where the pins are drawn (the NumPy path's own bars are in test_detect.py).
        recall, precision, rmse = score(got[0].centres, frames[0])
        assert recall >= 0.9 and precision >= 0.9 and rmse < 0.5, (recall, precision, rmse)


@pytest.mark.parametrize("sigma_px", [0.6, 0.98, 1.2, 1.89, 3.3])
@pytest.mark.parametrize("shape", [(64, 64), (45, 61), (33, 7)])
def test_image_operations_are_opencvs_bit_for_bit(sigma_px, shape):
    """Blur and neighbourhood means of noisy images, any width (OpenCV's last width % 4 columns scale in double)."""
    rng = np.random.default_rng(int(10 * sigma_px) + shape[1])
    frames = rng.integers(0, 256, (3, *shape), dtype=np.uint8)
    frames[rng.random(frames.shape) < 0.3] = 0
    height, width = shape
    # A disc bigger than the frame: its box is the whole frame, whatever the width.
    disc = SensorDisc((width - 1) / 2, (height - 1) / 2, float(width + height))
    for block in (3, 11, 25):
        params = DetectionParams(blur_sigma_px=sigma_px, block_size_px=block)
        image, smooth, mean = BatchedDetector(disc, shape, params, device="cpu").filtered(frames)
        for k, frame in enumerate(frames):
            _, _, expected_image, expected_smooth, expected_mean = _filtered(frame, disc, params)
            np.testing.assert_array_equal(image[k].numpy(), expected_image)
            np.testing.assert_array_equal(smooth[k].numpy(), expected_smooth)
            np.testing.assert_array_equal(mean[k].numpy(), expected_mean)


def test_a_pixel_between_two_blobs_goes_to_opencvs_higher_label():
    """OpenCV numbers components by their first 2x2 block; the growth gives a pixel between two blobs to the higher.

    The tall blob starts first (label 1) but ends last (the highest raster index, which label propagation
    keeps); the short one starts later (label 2). The pixels between them weigh on the short one's centre.
    """
    image = np.full((48, 48), 20, np.uint8)
    image[2:11, 5:10] = 200    # tall: rows 2-10
    image[4:8, 11:14] = 200    # short: rows 4-7, one column apart
    image[3:9, 10] = 110       # the column between: below the threshold, above the background
    disc = SensorDisc(23.5, 23.5, 40.0)
    params = DetectionParams(blur_sigma_px=0.0, block_size_px=15, offset=60.0, split_radius_px=0.0, rim_margin_px=0.0)
    expected = detect_blobs(image, params=params, disc=disc)
    got = BatchedDetector(disc, image.shape, params, device="cpu", labelling="tensor").detect_blobs(image[None])[0]
    assert len(expected.centres) == 2
    np.testing.assert_allclose(got.centres, expected.centres, rtol=0, atol=1e-9)
    # The short blob's centre is pulled towards the column (x < 12, its middle), as OpenCV's numbering says.
    short, tall = expected.centres[np.argmin(expected.areas)], expected.centres[np.argmax(expected.areas)]
    assert short[0] < 11.9 and tall[0] == 7.0


def test_fixed_point_kernel():
    """OpenCV's 1/256 kernel: symmetric, sums to 256, peaks at the centre, and blurs an impulse as OpenCV does."""
    for sigma_px in (0.6, 1.2, 2.5):
        size = 2 * int(np.ceil(2.5 * sigma_px)) + 1
        kernel = gaussian_kernel_fixed(sigma_px, size)
        assert kernel.sum() == 256 and np.array_equal(kernel, kernel[::-1]) and kernel.argmax() == size // 2
        impulse = np.zeros((31, 31), np.uint8)
        impulse[15, 15] = 255
        expected = cv2.GaussianBlur(impulse, (size, size), sigma_px)
        outer = np.outer(kernel, kernel) * 255
        mine = np.zeros((31, 31), np.int64)
        half = size // 2
        mine[15 - half:16 + half, 15 - half:16 + half] = (outer + 32768) >> 16
        np.testing.assert_array_equal(mine, expected)
    with pytest.raises(ValueError, match="odd size"):
        gaussian_kernel_fixed(1.0, 4)


def test_many_frames_in_batches_with_progress_and_empty_frames():
    """detect_pins_batched gives detect_pins's pins frame by frame; a blank frame gives (0, 2); progress counts frames."""
    sensor = SyntheticTacTip.from_preset("tactip-127", seed=1)
    frames = [_grey(sensor.render(Contact(depth, 2.0)).image) for depth in np.linspace(0, 5, 4)]
    field = find_pin_field(frames[0])
    frames.append(np.zeros_like(frames[0]))  # the camera went dark
    counts = []
    got = detect_pins_batched(frames, params=field.params, disc=field.disc, device="cpu", together=2,
                              progress=counts.append)
    assert counts == [2, 2, 1] and len(got) == 5
    for frame, pins in zip(frames, got):
        np.testing.assert_array_equal(pins, detect_pins(frame, params=field.params, disc=field.disc))
    assert got[-1].shape == (0, 2)
    # The disc found in the first frame when not given, as detect_pins finds it.
    np.testing.assert_array_equal(detect_pins_batched(frames[:1], params=field.params, device="cpu")[0],
                                  detect_pins(frames[0], params=field.params))
    assert detect_pins_batched([], device="cpu") == []


def test_shapes_and_settings_are_checked():
    disc = SensorDisc(30.0, 30.0, 25.0)
    detector = BatchedDetector(disc, (60, 64), device="cpu")
    # On the CPU the blobs are labelled by OpenCV unless asked (label propagation is for a GPU).
    assert "BatchedDetector(" in repr(detector) and "device='cpu'" in repr(detector) and "labelling='cpu'" in \
        repr(detector)
    on_tensors = BatchedDetector(disc, (60, 64), device="cpu", labelling="tensor")
    assert on_tensors.labelling == "tensor"
    # Nothing above the threshold, and no frames: empty answers.
    blank = on_tensors.detect_blobs(np.full((2, 60, 64), 90, np.uint8))
    assert [b.centres.shape for b in blank] == [(0, 2), (0, 2)] and [b.candidates for b in blank] == [0, 0]
    assert on_tensors.detect_pins(np.zeros((0, 60, 64), np.uint8)) == []
    with pytest.raises(ValueError, match="unknown labelling"):
        BatchedDetector(disc, (60, 64), device="cpu", labelling="gpu")
    with pytest.raises(ValueError, match=r"\(B, 60, 64\) uint8, got \(2, 60, 65\)"):
        detector.filtered(np.zeros((2, 60, 65), np.uint8))
    with pytest.raises(ValueError, match="uint8"):
        detector.filtered(torch.zeros((2, 60, 64), dtype=torch.float32))
    assert detector.detect_pins(np.zeros((0, 60, 64), np.uint8)) == []
    with pytest.raises(ValueError, match="together"):
        detect_pins_batched([np.zeros((60, 64), np.uint8)], disc=disc, device="cpu", together=0)
