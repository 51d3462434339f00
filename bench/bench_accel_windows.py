"""Windowed pin centroids: the batched torch path (`pins.accel`) against the NumPy path, on the same frames.

Renders a batch of frames of one synthetic preset (default ``dense-1000``, the most pins), each with
its pins pressed to its own depth, and measures every pin's window in every frame: the NumPy path
(`pins._window.WindowCentroids.measure`) one frame at a time, as the tracker calls it, and the
torch path with all the batch's windows at once, on ``--device`` (``auto``: a GPU if torch sees
one, else the CPU). Prints windows/s and frames/s of each (best of the repeats), their ratio, and
the largest difference of the centroids, px. Frames are sent to the device inside the timing.

Run: .venv/bin/python bench/bench_accel_windows.py [--preset dense-1000] [--frames 64] [--device auto]
"""

from __future__ import annotations

import argparse
import time

import cv2
import numpy as np

from pins import PinTracker, find_pin_field
from pins.accel import BatchedWindowCentroids
from tactip.sim import Contact, SyntheticTacTip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default="dense-1000")
    parser.add_argument("--frames", type=int, default=64)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--device", default="auto")
    args = parser.parse_args()
    sensor = SyntheticTacTip.from_preset(args.preset, seed=1)

    def grey(frame):
        return frame.image if frame.image.ndim == 2 else cv2.cvtColor(frame.image, cv2.COLOR_BGR2GRAY)

    rest = sensor.render()
    field = find_pin_field(grey(rest))
    tracker = PinTracker(detection=field.params, disc=field.disc)
    tracker.start(grey(rest), field.centres)
    refiner, origin = tracker._refiner, tracker._origin
    frames, points, radius = [], [], []
    for k in range(args.frames):
        frame = sensor.render(Contact(5.0 * k / max(args.frames - 1, 1), 2.0))
        frames.append(tracker._bright(np.ascontiguousarray(grey(frame)[tracker._crop])))
        guess = tracker.rest_positions + np.random.default_rng(k).normal(0, 0.4, tracker.rest_positions.shape)
        points.append(guess - origin)
        radius.append(refiner.window_radius(guess))
    frames = np.stack(frames)
    index = np.repeat(np.arange(args.frames), len(tracker.rest_positions))
    flat_points, flat_radius = np.concatenate(points), np.concatenate(radius)
    batched = BatchedWindowCentroids(refiner.windows, device=args.device)
    windows = len(flat_points)
    numpy_s, torch_s = [], []
    for _ in range(args.repeats):
        started = time.perf_counter()
        expected = [refiner.windows.measure(f, p, r)[0] for f, p, r in zip(frames, points, radius)]
        numpy_s.append(time.perf_counter() - started)
        started = time.perf_counter()
        centres, _ = batched.measure(frames, index, flat_points, flat_radius)
        torch_s.append(time.perf_counter() - started)
    expected = np.concatenate(expected)
    finite = np.isfinite(expected)
    difference = np.abs(centres[finite] - expected[finite]).max()
    print(f"{args.preset}: {args.frames} frames x {len(tracker.rest_positions)} pins = {windows} windows "
          f"of {2 * refiner.windows.half_px + 1} px; torch on {batched.device}")
    for name, seconds in (("numpy (frame by frame)", min(numpy_s)), (f"torch batched ({batched.device})", min(torch_s))):
        print(f"{name:>28}: {windows / seconds:>10.0f} windows/s {args.frames / seconds:>8.1f} frames/s")
    print(f"torch / numpy speed: {min(numpy_s) / min(torch_s):.2f}x; largest centroid difference {difference:.2e} px")


if __name__ == "__main__":
    main()
