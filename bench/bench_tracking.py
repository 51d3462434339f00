"""Tracking on real-like video: rim pins coming and going through a few taps; tracker cost against plain LK.

The video: taps of the rim-ring preset of the synthetic TacTip (`SyntheticTacTip.from_preset`, a
black rim ring with LED glare; the default 331-pin sensor with glare and gradient before that
preset exists), with the pins of the outer rings hidden and shown again over time
(``render(hidden=...)``): each rim pin is hidden for stretches of a few frames, about a third of
them at any time, as on a real pad whose rim pins drift in and out of view.

The tracker starts from the drawn pins' true rest centres, as from a calibration (detection is
benchmarked in `bench/bench_pins.py`). Printed, measured side by side in one run (best of several interleaved passes, one thread), so
that machine load cancels out in the ratio:

- tracker:  ms per `PinTracker.update` (LK forward + windowed refinement, windowed search for
            lost pins, retirement, blob detection at most one frame in `detect_every`);
- plain LK: ms per plain LK step over the same pins and frames: one forward
            ``cv2.calcOpticalFlowPyrLK``, 11x11 window, one pyramid level, no checks, chained
            from the rest positions;
- ratio:    tracker / plain LK (bar: <= 1.5);

and, from one more tracker pass: frames that needed blob detection, blank frames, pins lost and
retired per frame (median, max), RMSE against the renderer's ground truth over the visible pins
tracked (px), pins reported while not drawn (hidden), identity swaps, and the return to rest at the end of
each tap (median and 95th percentile over pins of |position - rest|, px; bar: median <= 0.3).

Run: .venv/bin/python bench/bench_tracking.py [--pins 331] [--taps 4] [--preset NAME]
"""

from __future__ import annotations

import argparse
import time

import cv2
import numpy as np
from scipy.spatial import cKDTree

from pins import DetectionParams, PinTracker, SensorDisc
from tactip.sim import Contact, SyntheticTacTip

PASSES = 7


def _sensor(preset: str | None, pins: int) -> tuple[SyntheticTacTip, str]:
    """The preset's sensor when the renderer has presets, else the default sensor with glare and gradient."""
    if preset and hasattr(SyntheticTacTip, "from_preset"):
        try:
            return SyntheticTacTip.from_preset(preset), preset
        except (KeyError, ValueError):
            pass
    return SyntheticTacTip(pins=pins, noise_sigma=4.0, glare=True, gradient=True, seed=0), f"default-{pins}"


def video(sensor: SyntheticTacTip, taps: int, *, frame_rate: float = 20.0, seed: int = 1):
    """Frames of `taps` taps with rim pins hidden and shown over time (the rest frame first), and each tap's last index."""
    rng = np.random.default_rng(seed)
    rest = sensor.render()
    radius = np.linalg.norm(rest.centres - np.asarray(sensor.disc[:2]), axis=1)
    rim = radius > 0.8 * radius[rest.visible].max()
    period = rng.integers(8, 20, sensor.n_pins)
    phase = rng.integers(0, 20, sensor.n_pins)
    frames = [rest]
    depths = np.linspace(5.0, 3.0, taps)
    offsets = rng.uniform(-3.0, 3.0, taps)
    k, ends = 0, []
    for depth, offset in zip(depths, offsets):
        contact = Contact(indentation_mm=float(depth), gap_width_mm=2.0, gap_offset_mm=float(offset))
        for state in sensor.tap(contact, frame_rate=frame_rate):
            k += 1
            # Each rim pin hidden for a third of its period.
            hidden = rim & ((k + phase) % period < period // 3)
            frames.append(sensor.render(state.contact, hidden=hidden, timestamp_s=k / frame_rate))
        ends.append(k)
    return frames, ends


def _plain_lk(images: list[np.ndarray], start: np.ndarray) -> None:
    points = start.astype(np.float32).reshape(-1, 1, 2)
    for previous, current in zip(images[:-1], images[1:]):
        points, _, _ = cv2.calcOpticalFlowPyrLK(previous, current, points, None, winSize=(11, 11), maxLevel=1)


def _tracker_pass(tracker: PinTracker, images: list[np.ndarray]) -> None:
    for image in images[1:]:
        tracker.update(image)


def _tracker(sensor: SyntheticTacTip, rest) -> tuple[PinTracker, np.ndarray]:
    """A tracker started from the drawn pins' true rest centres (as from a calibration), and their indices."""
    drawn = np.flatnonzero(rest.visible | getattr(rest, "partial", np.zeros_like(rest.visible)))
    tracker = PinTracker(detection=DetectionParams(dark_pins=sensor.dark_pins), disc=SensorDisc(*sensor.disc))
    tracker.start(rest.image, pins=rest.centres[drawn])
    return tracker, drawn


def timed(sensor: SyntheticTacTip, frames, passes: int = PASSES) -> dict[str, tuple[float, float]]:
    """(wall, cpu) ms per frame of the tracker and of plain LK: best of interleaved passes."""
    tracker, drawn = _tracker(sensor, frames[0])
    images = [f.image for f in frames]
    start = tracker.rest_positions.copy()
    steps = len(images) - 1
    best = {"tracker": [np.inf, np.inf], "plain LK": [np.inf, np.inf]}
    for _ in range(passes):
        for name, run in (("tracker", lambda: _tracker_pass(tracker, images)),
                          ("plain LK", lambda: _plain_lk(images, start))):
            tracker.start(images[0], pins=start)  # not timed: once per video
            wall, cpu = time.perf_counter(), time.thread_time()
            run()
            wall, cpu = time.perf_counter() - wall, time.thread_time() - cpu
            best[name] = [min(best[name][0], wall / steps * 1e3), min(best[name][1], cpu / steps * 1e3)]
    return {name: tuple(values) for name, values in best.items()}


def accuracy(sensor: SyntheticTacTip, frames, ends) -> dict[str, float | str]:
    """One tracker pass against ground truth."""
    tracker, identity = _tracker(sensor, frames[0])
    errors, lost, retired, hidden_reported, swaps, rest_errors = [], [], [], 0, 0, []
    for k, f in enumerate(frames[1:], start=1):
        positions = tracker.update(f.image)
        lost.append(int(tracker.lost.sum()))
        retired.append(int(tracker.retired.sum()))
        visible = f.visible[identity]
        drawn = f.visible | getattr(f, "partial", np.zeros_like(f.visible))
        found = np.isfinite(positions[:, 0])
        errors.append(positions[found & visible] - f.centres[identity][found & visible])
        hidden_reported += int(np.count_nonzero(found & ~drawn[identity]))
        if found.any():
            index = np.flatnonzero(drawn)
            nearest = index[cKDTree(f.centres[index]).query(positions[found])[1]]
            swaps += int(np.count_nonzero(nearest != identity[found]))
        if k in ends:
            rest_errors.append(np.linalg.norm(positions[found] - tracker.rest_positions[found], axis=1))
    errors = np.concatenate(errors)
    back = [(np.median(e), np.percentile(e, 95)) for e in rest_errors]
    return {"rmse": float(np.sqrt(np.mean(np.sum(errors**2, axis=1)))),
            "detection": f"{tracker.detection_frames}/{len(frames) - 1}", "blank": tracker.blank_frames,
            "lost": f"{np.median(lost):.0f} / {max(lost)}", "retired": f"{np.median(retired):.0f} / {max(retired)}",
            "hidden reported": hidden_reported, "swaps": swaps,
            "rest": " ".join(f"{m:.3f}/{p:.3f}" for m, p in back), "worst rest median": max(m for m, _ in back),
            "pins": len(identity)}


def main() -> None:
    """Print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default="rim-ring-331")
    parser.add_argument("--pins", type=int, default=331, help="pins of the default sensor when the preset is missing")
    parser.add_argument("--taps", type=int, default=4)
    args = parser.parse_args()
    cv2.setNumThreads(1)
    sensor, name = _sensor(args.preset, args.pins)
    frames, ends = video(sensor, args.taps)
    hidden = np.mean([np.count_nonzero(~f.visible) for f in frames[1:]])
    print(f"tracking bench: {name}, {len(frames) - 1} frames ({args.taps} taps), {sensor.n_pins} pins, "
          f"{hidden:.0f} not wholly visible per frame on average; one thread, best of {PASSES} interleaved passes")
    t = timed(sensor, frames)
    ratio = t["tracker"][0] / t["plain LK"][0]
    print(f"  tracker update  {t['tracker'][0]:6.3f} ms wall ({t['tracker'][1]:6.3f} cpu)")
    print(f"  plain LK step   {t['plain LK'][0]:6.3f} ms wall ({t['plain LK'][1]:6.3f} cpu)  "
          f"(11x11, one pyramid level, same pins and frames)")
    print(f"  ratio           {ratio:6.2f} wall ({t['tracker'][1] / t['plain LK'][1]:.2f} cpu)   bar <= 1.5")
    a = accuracy(sensor, frames, ends)
    print(f"  detection frames {a['detection']}, blank frames {a['blank']}, lost per frame median/max {a['lost']}, "
          f"retired {a['retired']}")
    print(f"  RMSE vs truth {a['rmse']:.3f} px (visible pins tracked), pins reported while hidden "
          f"{a['hidden reported']}, identity swaps {a['swaps']}")
    print(f"  back at rest after each tap, median/p95 px: {a['rest']}   (bar: median <= 0.3)")


if __name__ == "__main__":
    main()
