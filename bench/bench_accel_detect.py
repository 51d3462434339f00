"""Adaptive-threshold detection: the batched tensor path (`pins.accel_detect`) against the CPU path, on the same frames.

Renders frames of synthetic presets (default ``tactip-331`` and ``dense-1000``), each pressed to its own
depth, and detects the pins of every frame: the CPU path (`pins.detect_blobs`, OpenCV and NumPy) one
frame at a time, and the batched path `--together` frames per batch on ``--device`` (``auto``: a GPU if
torch sees one, else the CPU), with the blob stage on the tensors (``labelling="tensor"``) and on the
CPU (``"cpu"``). Prints frames/s of each (best of the repeats), their ratio to OpenCV's, the frames/s of
the tensor filters alone, and the largest difference of the pins, px. Frames are sent to the device
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
from tactip.sim import Contact, SyntheticTacTip


def _bench(preset: str, args) -> None:
    sensor = SyntheticTacTip.from_preset(preset, seed=args.seed)
    frames = []
    for k in range(args.frames):
        image = sensor.render(Contact(5.0 * k / max(args.frames - 1, 1), 2.0)).image
        frames.append(image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY))
    frames = np.stack(frames)
    field = find_pin_field(frames[0])
    batches = [frames[i:i + args.together] for i in range(0, len(frames), args.together)]
    detectors = {labelling: BatchedDetector(field.disc, frames.shape[1:], field.params, device=args.device,
                                            labelling=labelling) for labelling in ("tensor", "cpu")}
    for detector in detectors.values():
        detector.detect_pins(batches[0])  # warm-up: first calls allocate
    seconds = {name: [] for name in ("opencv", "filters", "tensor", "cpu")}
    got = {}
    for _ in range(args.repeats):
        started = time.perf_counter()
        expected = [detect_blobs(frame, params=field.params, disc=field.disc).centres for frame in frames]
        seconds["opencv"].append(time.perf_counter() - started)
        started = time.perf_counter()
        for batch in batches:
            [t.cpu() for t in detectors["tensor"].filtered(batch)]
        seconds["filters"].append(time.perf_counter() - started)
        for labelling, detector in detectors.items():
            started = time.perf_counter()
            got[labelling] = [pins for batch in batches for pins in detector.detect_pins(batch)]
            seconds[labelling].append(time.perf_counter() - started)
    n = len(frames)
    device = detectors["tensor"].device
    print(f"{preset}: {n} frames of {frames.shape[2]}x{frames.shape[1]} px, {len(expected[0])} pins; "
          f"batches of {args.together} on {device}")
    print(f"{'opencv (frame by frame)':>40}: {n / min(seconds['opencv']):8.1f} frames/s")
    for labelling, what in (("tensor", "batched, all on tensors"), ("cpu", "batched, blobs on the CPU")):
        same = all(a.shape == b.shape for a, b in zip(got[labelling], expected))
        difference = (max(np.abs(a - b).max(initial=0.0) for a, b in zip(got[labelling], expected)) if same
                      else np.inf)
        print(f"{f'{what} ({device})':>40}: {n / min(seconds[labelling]):8.1f} frames/s  "
              f"{min(seconds['opencv']) / min(seconds[labelling]):.2f}x opencv; largest pin difference "
              f"{difference:.2e} px")
    print(f"{'(the filters alone)':>40}: {n / min(seconds['filters']):8.1f} frames/s")


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
