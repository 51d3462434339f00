"""Adaptive-threshold detection: the batched tensor path (`pins.accel_detect`) against the CPU path, on the same frames.

Renders frames of synthetic presets (default ``tactip-331`` and ``dense-1000``), each pressed to its own
depth, and detects the pins of every frame: the CPU path (`pins.detect_blobs`, OpenCV and NumPy) one
frame at a time, and the batched path `--together` frames per batch on ``--device`` (``auto``: a GPU if
torch sees one, else the CPU). Prints frames/s of each (best of the repeats), their ratio, the batched
path's time split between its tensor stage (blur and threshold means, kornia) and its per-frame CPU stage
(labelling, split, centroids), and the largest difference of the pins, px. Frames are sent to the device
inside the timing.

Run: .venv/bin/python bench/bench_accel_detect.py [--preset tactip-331 --preset dense-1000] [--frames 32]
     [--together 16] [--device auto]
"""

from __future__ import annotations

import argparse
import time

import cv2
import numpy as np

from pins import detect_blobs, find_pin_field
from pins.accel_detect import BatchedDetector
from pins.detect import _blobs
from tactip.sim import Contact, SyntheticTacTip


def _bench(preset: str, args) -> None:
    sensor = SyntheticTacTip.from_preset(preset, seed=args.seed)
    frames = []
    for k in range(args.frames):
        image = sensor.render(Contact(5.0 * k / max(args.frames - 1, 1), 2.0)).image
        frames.append(image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY))
    frames = np.stack(frames)
    field = find_pin_field(frames[0])
    detector = BatchedDetector(field.disc, frames.shape[1:], field.params, device=args.device)
    batches = [frames[i:i + args.together] for i in range(0, len(frames), args.together)]
    detector.detect_pins(batches[0])  # warm-up: first calls allocate
    cpu_s, batched_s, tensor_s = [], [], []
    for _ in range(args.repeats):
        started = time.perf_counter()
        expected = [detect_blobs(frame, params=field.params, disc=field.disc).centres for frame in frames]
        cpu_s.append(time.perf_counter() - started)
        started = time.perf_counter()
        got, tensors = [], 0.0
        for batch in batches:
            begun = time.perf_counter()
            image, smooth, mean = (t.cpu().numpy() for t in detector.filtered(batch))
            tensors += time.perf_counter() - begun
            got += [_blobs(image[k], smooth[k], mean[k], field.disc, field.params, detector.x0, detector.y0).centres
                    for k in range(len(batch))]
        batched_s.append(time.perf_counter() - started)
        tensor_s.append(tensors)
    same = all(a.shape == b.shape for a, b in zip(got, expected))
    difference = max(np.abs(a - b).max(initial=0.0) for a, b in zip(got, expected)) if same else np.inf
    n = len(frames)
    best = int(np.argmin(batched_s))
    print(f"{preset}: {n} frames of {frames.shape[2]}x{frames.shape[1]} px, {len(expected[0])} pins; "
          f"batches of {args.together} on {detector.device}")
    print(f"{'cpu (OpenCV, frame by frame)':>34}: {n / min(cpu_s):8.1f} frames/s")
    print(f"{f'batched ({detector.device})':>34}: {n / min(batched_s):8.1f} frames/s  (tensor stage "
          f"{tensor_s[best] / batched_s[best]:.0%}, {n / tensor_s[best]:.1f} frames/s alone)")
    print(f"batched / cpu speed: {min(cpu_s) / min(batched_s):.2f}x; largest pin difference {difference:.2e} px")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", action="append", help="preset (repeatable; default tactip-331 and dense-1000)")
    parser.add_argument("--frames", type=int, default=32)
    parser.add_argument("--together", type=int, default=16)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--device", default="auto")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    for preset in args.preset or ["tactip-331", "dense-1000"]:
        _bench(preset, args)


if __name__ == "__main__":
    main()
