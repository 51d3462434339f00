"""Per-frame cost of pin detection and tracking on one core, 640x480 synthetic TacTip frames.

Prints ms/frame at 331 and 532 pins (wall time of the best pass, and CPU time) for:

- disc:       `find_sensor_disc` (once per video or sensor, not per frame);
- detect:     `detect_pins(frame, disc=disc)` on the grey 640x480 frame, the disc found beforehand (what
              a tracked frame pays when a pin is lost or implausible): the disc crop, blur, adaptive
              threshold, labelling, touching-pin splitting and weighted centroids; not the disc search;
- LK+checks:  LK forward (full image from the constant-velocity guess, the pyramid only for pins
              that need it) and pyramidal LK backward on the disc crop, status / residual /
              forward-backward checks (`PinTracker(refine=False).update`);
- tracker:    the full `PinTracker.update`: LK + checks + refinement onto windowed centroids,
              with detection + recovery of lost pins only in frames that need it (what
              `tactip replay` runs); also its RMSE against the renderer's ground truth, px, and
              the frames that needed detection.

Frames are a 5 mm tap (peak displacement ~14 px), so LK sees real motion. Goals: tracking all
331 pins at >= 500 frames/s (2 ms/frame), detection <= 3 ms.

Run: .venv/bin/python bench/bench_pins.py
"""

from __future__ import annotations

import time

import cv2
import numpy as np

from scipy.spatial import cKDTree

from pins import PinTracker, detect_pins, find_sensor_disc
from tactip.synthetic import Contact, SyntheticTacTip

REPEATS = 5


def _per_frame_ms(step, frames, repeats=REPEATS, setup=None) -> tuple[float, float]:
    """(wall, cpu) ms per frame of `step(frame)` over `frames`: the best of `repeats` passes.

    The best pass estimates the cost without interference from other processes on a shared
    machine; the CPU time (`time.thread_time`, one thread) is what the stage itself costs.
    """
    wall, cpu = [], []
    for _ in range(repeats):
        if setup is not None:
            setup()
        start, start_cpu = time.perf_counter(), time.thread_time()
        for image in frames:
            step(image)
        wall.append((time.perf_counter() - start) / len(frames) * 1e3)
        cpu.append((time.thread_time() - start_cpu) / len(frames) * 1e3)
    return min(wall), min(cpu)


def bench(pins: int) -> dict[str, float]:
    """ms/frame of each stage at `pins` pins."""
    sensor = SyntheticTacTip(pins=pins, noise_sigma=4.0, seed=0)
    rest = sensor.render()
    tap = list(sensor.tap(Contact(indentation_mm=5.0, gap_width_mm=2.0), frame_rate=20.0))
    frames = [f.image for f in tap]
    disc = find_sensor_disc(rest.image)
    results = {"disc": _per_frame_ms(find_sensor_disc, frames[:5])}
    results["detect"] = _per_frame_ms(lambda image: detect_pins(image, disc=disc), frames)
    for name, refine in (("LK+checks", False), ("tracker", True)):
        tracker = PinTracker(refine=refine, disc=disc)
        results[name] = _per_frame_ms(tracker.update, frames, setup=lambda t=tracker: t.start(rest.image))
    # Accuracy of one more pass, against ground truth.
    identity = cKDTree(rest.centres).query(tracker.start(rest.image))[1]
    error = np.concatenate([tracker.update(f.image) - f.centres[identity] for f in tap])
    results["rmse"] = float(np.sqrt(np.mean(np.sum(error**2, axis=1))))
    results["detection frames"] = f"{tracker.detection_frames}/{len(tap)}"
    return results


def main() -> None:
    """Print the table."""
    cv2.setNumThreads(1)
    print(f"pins bench: ms/frame on one thread (cv2.setNumThreads(1)), 640x480, best of {REPEATS} passes, "
          "wall (cpu)")
    print(f"{'pins':>5} {'disc':>14} {'detect':>14} {'LK+checks':>14} {'tracker':>14} {'tracker fps':>12} "
          f"{'RMSE px':>8} {'detected':>9}")
    for pins in (331, 532):
        r = bench(pins)
        cells = " ".join(f"{r[k][0]:6.2f} ({r[k][1]:5.2f})" for k in ("disc", "detect", "LK+checks", "tracker"))
        print(f"{pins:>5} {cells} {1e3 / r['tracker'][0]:12.0f} {r['rmse']:8.3f} {r['detection frames']:>9}")


if __name__ == "__main__":
    main()
