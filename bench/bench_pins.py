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

A second table, per synthetic preset (`tactip.sim.synthetic.PRESETS`, rest and a 5 mm tap), times the
one-off `find_pin_field` (the pin field without a count: candidate detections at a few parameter
sets, lattice consistency) beside the per-frame fast path it sets up (`detect_pins` with the
field's params and disc) and prints their ratio, and scores the field against the renderer's
ground truth without and with the count: recall over visible pins, precision (detections on
visible or partial pins are correct), centroid RMSE, px. Bars (issue 8): recall and precision
>= 99 %, RMSE <= 0.1 px.

Run: .venv/bin/python bench/bench_pins.py [--presets-only]
"""

from __future__ import annotations

import time

import cv2
import numpy as np

from scipy.spatial import cKDTree

from scipy.optimize import linear_sum_assignment

from pins import PinTracker, detect_pins, find_pin_field, find_sensor_disc
from tactip.sim import Contact, SyntheticTacTip, preset_names

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


def score(detected: np.ndarray, frame, gate_px: float = 3.0) -> tuple[float, float, float]:
    """(recall over visible pins, precision counting visible or partial pins, RMSE px over visible ones)."""
    drawn = frame.visible | frame.partial
    truth, is_visible = frame.centres[drawn], frame.visible[drawn]
    if len(detected) == 0:
        return 0.0, 1.0, float("nan")
    distance = np.hypot(*(truth[:, None, :] - detected[None, :, :]).transpose(2, 0, 1))
    rows, cols = linear_sum_assignment(np.where(distance <= gate_px, distance, 1e6))
    ok = distance[rows, cols] <= gate_px
    rows, cols = rows[ok], cols[ok]
    on_visible = is_visible[rows]
    errors = detected[cols[on_visible]] - truth[rows[on_visible]]
    return (on_visible.sum() / is_visible.sum(), ok.sum() / len(detected),
            float(np.sqrt(np.mean(np.sum(errors**2, axis=1)))))


def bench_field(name: str) -> list[str]:
    """Rows of the preset table for one preset: rest and tap."""
    sensor = SyntheticTacTip.from_preset(name, seed=0)
    rows = []
    for label, contact in (("rest", None), ("tap", Contact(indentation_mm=5.0, gap_width_mm=2.0))):
        f = sensor.render(contact)
        drawn = int((f.visible | f.partial).sum())
        centres = f.centres[f.visible]
        nearest = cKDTree(centres).query(centres, 2)[0][:, 1]
        gate = min(3.0, 0.4 * float(np.median(nearest)))
        cost = _per_frame_ms(lambda image: find_pin_field(image, dark_pins=sensor.dark_pins), [f.image], repeats=3)
        field = find_pin_field(f.image, dark_pins=sensor.dark_pins)
        given = find_pin_field(f.image, expected_pins=drawn, dark_pins=sensor.dark_pins)
        fast = _per_frame_ms(lambda image: detect_pins(image, params=field.params, disc=field.disc), [f.image] * 10)
        r0, p0, e0 = score(field.centres, f, gate)
        r1, p1, e1 = score(given.centres, f, gate)
        rows.append(f"{name:>14} {label:>4} {int(f.visible.sum()):>4} {f.image.shape[1]}x{f.image.shape[0]:<4} "
                    f"{field.count:>5} {r0:7.1%} {p0:7.1%} {e0:6.3f}  {given.count_error:+4d} {r1:7.1%} {p1:7.1%} "
                    f"{e1:6.3f} {cost[0]:8.0f} ({cost[1]:4.0f}) {fast[0]:6.2f} ({fast[1]:5.2f}) {cost[0] / fast[0]:7.0f}")
    return rows


def main() -> None:
    """Print the tables."""
    import sys

    cv2.setNumThreads(1)
    if "--presets-only" not in sys.argv[1:]:
        _tracking_table()
    print(f"\npin field per preset (one thread): find_pin_field once (ms wall (cpu), best of 3), then "
          f"detect_pins per frame with its params and disc (ms, best of {REPEATS}); scores without / with the count")
    print(f"{'preset':>14} {'':>4} {'vis':>4} {'size':<9} {'found':>5} {'recall':>7} {'precis':>7} {'RMSE':>6}  "
          f"{'err':>4} {'recall':>7} {'precis':>7} {'RMSE':>6} {'field ms':>15} {'detect ms':>14} {'ratio':>7}")
    for name in preset_names():
        for row in bench_field(name):
            print(row, flush=True)


def _tracking_table() -> None:
    """The tracking table at 331 and 532 pins."""
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
