"""pins.accel: the batched torch windowed centroids against the NumPy path, within 0.01 px, on every preset (CPU)."""

import cv2
import numpy as np
import pytest
from scipy.spatial import cKDTree

torch = pytest.importorskip("torch")

from pins import PinTracker, find_pin_field  # noqa: E402
from pins._window import WindowCentroids  # noqa: E402
from pins.accel import BatchedWindowCentroids, WindowBatcher, pick_device  # noqa: E402
from tactip.sim import PRESETS, Contact, SyntheticTacTip  # noqa: E402


def _compare(windows, frames, frame_index, points, radius):
    """The batched measure against `WindowCentroids.measure` frame by frame: (largest centre difference, px, count)."""
    centres, measures = BatchedWindowCentroids(windows, device="cpu").measure(frames, frame_index, points, radius)
    for k, frame in enumerate(frames):
        mine = frame_index == k
        expected_centres, expected_measures = windows.measure(frame, points[mine], radius[mine])
        assert np.array_equal(np.isnan(centres[mine]), np.isnan(expected_centres))
        np.testing.assert_allclose(measures[:, mine], expected_measures, rtol=1e-4, atol=1e-3, equal_nan=True)
        finite = np.isfinite(expected_centres)
        yield np.abs(centres[mine][finite] - expected_centres[finite]).max(initial=0.0), int(finite.all(axis=1).sum())


@pytest.mark.parametrize("preset", list(PRESETS))
def test_batched_centroids_equal_the_numpy_path_on_every_preset(preset):
    sensor = SyntheticTacTip.from_preset(preset, seed=2)
    rest, pressed = sensor.render(), sensor.render(Contact(3.5, 2.0))
    grey = [f.image if f.image.ndim == 2 else cv2.cvtColor(f.image, cv2.COLOR_BGR2GRAY) for f in (rest, pressed)]
    field = find_pin_field(grey[0])
    tracker = PinTracker(detection=field.params, disc=field.disc)
    tracker.start(grey[0], field.centres)
    refiner, origin = tracker._refiner, tracker._origin
    # The tracker's own windows (half side, above-mean rule, least contrast) on its own bright crops.
    frames = np.stack([tracker._bright(np.ascontiguousarray(image[tracker._crop])) for image in grey])
    rng = np.random.default_rng(5)
    pins = cKDTree(rest.centres).query(tracker.rest_positions)[1]  # each tracked pin's true centres
    truth = np.concatenate([rest.centres[pins], pressed.centres[pins]]) - origin
    points = truth + rng.normal(0.0, 0.4, truth.shape)  # guesses a tracker would make
    frame_index = np.repeat([0, 1], len(pins))
    radius = np.concatenate([refiner.window_radius(points[frame_index == k] + origin) for k in (0, 1)])
    order = rng.permutation(len(points))  # the frames' windows interleaved in one batch
    points, frame_index, radius = points[order], frame_index[order], radius[order]
    for above_mean in (refiner.windows.above_mean, not refiner.windows.above_mean):
        windows = WindowCentroids(refiner.windows.half_px, above_mean=above_mean)
        windows.least_contrast = refiner.windows.least_contrast
        for difference, measured in _compare(windows, frames, frame_index, points, radius):
            assert difference <= 0.01 and measured >= 0.8 * len(pins)


def test_windows_on_a_slope_at_the_edges_and_empty():
    """A tip on a bright ramp (the tilted threshold plane), windows off the frame (NaN), and no windows."""
    height, width = 40, 60
    y, x = np.mgrid[0:height, 0:width]
    ramp = 20 + 2.5 * x
    frames = []
    for cx, cy in ((20.3, 20.6), (31.8, 18.2)):
        tip = 120 * np.exp(-((x - cx) ** 2 + (y - cy) ** 2) / (2 * 1.5 ** 2))
        frames.append(np.clip(np.rint(ramp + tip), 0, 255).astype(np.uint8))
    frames = np.stack(frames)
    points = np.array([[20.0, 21.0], [32.0, 18.0], [2.0, 20.0], [58.5, 39.0], [30.0, 3.0]])
    frame_index = np.array([0, 1, 0, 1, 1])
    windows = WindowCentroids(5, threshold_fraction=0.3)
    radius = np.array([4.0, 3.5, 4.0, np.nan, 4.0])
    differences = list(_compare(windows, frames, frame_index, points, radius))
    assert max(d for d, _ in differences) <= 0.01 and sum(n for _, n in differences) == 2
    centres, _ = BatchedWindowCentroids(windows, device="cpu").measure(frames, frame_index, points, radius)
    assert np.isnan(centres[2:]).all()
    assert np.abs(centres[0] - [20.3, 20.6]).max() < 0.3  # the ramp does not pull the tip's centroid
    empty = BatchedWindowCentroids(windows, device="cpu").measure(frames, np.zeros(0, int), np.zeros((0, 2)),
                                                                  np.zeros(0))
    assert empty[0].shape == (0, 2) and empty[1].shape == (3, 0)


def test_devices_and_shapes_are_checked():
    assert pick_device("cpu").type == "cpu"
    assert pick_device("auto").type == ("cuda" if torch.cuda.is_available() else "cpu")
    if not torch.cuda.is_available():
        with pytest.raises(ValueError, match="no GPU"):
            pick_device("cuda")
    with pytest.raises(ValueError, match="unknown device"):
        pick_device("tpu")
    batched = BatchedWindowCentroids(WindowCentroids(3), device="cpu")
    assert "half_px=3" in repr(batched) and "cpu" in repr(batched)
    with pytest.raises(ValueError, match=r"frames must be \(B, H, W\) uint8"):
        batched.measure(np.zeros((8, 8), np.uint8), [0], [[4.0, 4.0]], [2.0])
    with pytest.raises(ValueError, match=r"frame_index must be \(1,\)"):
        batched.measure(np.zeros((1, 8, 8), np.uint8), [0, 0], [[4.0, 4.0]], [2.0])


def _tap_frames(preset: str, seed: int):
    sensor = SyntheticTacTip.from_preset(preset, seed=seed)
    frames = [f.image for f in sensor.tap(Contact(4.0, 2.0), frame_rate=20.0, rest_before_s=0.1, rest_after_s=0.1)]
    return [f if f.ndim == 2 else cv2.cvtColor(f, cv2.COLOR_BGR2GRAY) for f in frames]


def _track(frames, wrap=None):
    field = find_pin_field(frames[0])
    tracker = PinTracker(detection=field.params, disc=field.disc)
    positions = [tracker.start(frames[0], field.centres)]
    if wrap is not None:
        tracker.windows = wrap(tracker.windows)
    positions += [tracker.update(frame) for frame in frames[1:]]
    return np.array(positions)


def test_trackers_in_lockstep_measure_together_and_track_as_alone():
    """Three videos (two pads, frames of two sizes, uneven lengths) tracked on threads through one batcher."""
    import threading

    videos = [_tap_frames("tactip-331", 1), _tap_frames("tactip-127", 2)[:-3], _tap_frames("small-pad-100", 3)]
    alone = [_track(frames) for frames in videos]
    batcher = WindowBatcher(device="cpu")
    together, errors = [None] * len(videos), []

    def run(k):
        try:
            with batcher.member():
                together[k] = _track(videos[k], wrap=batcher.wrap)
        except Exception as exc:  # noqa: BLE001 - re-raised below
            errors.append(exc)

    threads = [threading.Thread(target=run, args=(k,)) for k in range(len(videos))]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(timeout=120)
    assert not errors and not any(thread.is_alive() for thread in threads)
    for mine, theirs in zip(together, alone):
        assert mine.shape == theirs.shape
        assert np.array_equal(np.isnan(mine), np.isnan(theirs))
        assert np.nanmax(np.abs(mine - theirs)) <= 0.01
    # Windows of several videos were measured in one batch (three at first, fewer as videos end).
    assert max(batcher.batches) == 3 and sum(batcher.batches) > 3 * len(videos[1])
    with pytest.raises(ValueError, match="start it first"):
        PinTracker().windows = None
