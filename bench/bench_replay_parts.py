"""Where replay's main thread goes, by part, on issue 20's real-like slide video (outcome 9).

Writes the slide video of `bench_replay.py --slides N` (``radial-led-120``: about 120 small pins in
radial spokes, LED reflections inside the pad, 120 frames/s, slides of 3 pitches round the compass
with 3-frame rests), replays it with `tactip.replay.video.replay_video` and prints the main thread's
CPU time (``time.thread_time``: other processes disturb it far less than the clock) by part: the
pin field search, the tracker's start and updates (inside them the follow passes, the window
measurements, the snap back to rest, LK with refinement, recovery by blobs and the fits of tips on
slopes: nested, so they do
not add up), the contacts, their features, the HDF5 file and the rest (the frame loop, the queue
from the decode thread, stacking). Also the window measurements per frame and how many windows each
measures: each call costs a fixed ~0.1 ms of NumPy calls on a few dozen windows, so their number,
not their size, sets the tracker's cost. Best of the repeats (the least disturbed run).

Figures (2-core VM shared with four other sessions, load average 20-25; 795 frames, MJPG):
main thread ~2.2 s, of which tracker updates 87-90 % (follow passes 64-67 %, window measurements
42-44 % in 4.21 calls per frame, snap to rest 9 %), the field search 3-4 %, contacts, features and
the HDF5 file 3-5 %, the frame loop 3 %.

Session "replay4" (load average 4-7, the code of that session: the tracker's outputs as before, a few %
less CPU): main thread 4.57 ms/frame, of which tracker updates 91 % (follow passes 51 %, window
measurements 31 % in 4.3 calls per frame, tip fits on slopes 20 % on 69 % of the frames, snap to rest 7 %,
recovery by blobs 2 %), the field search 4 %, contacts, features and the HDF5 file 2 %, the frame loop 2 %.

Run: .venv/bin/python bench/bench_replay_parts.py [--slides N] [--codec mp4v|MJPG] [--repeats N]
"""

from __future__ import annotations

import argparse
import collections
import pathlib
import tempfile
import time

import numpy as np

import pins._refine
import pins._window
import pins.track
import tactip.pipeline
import tactip.replay.video
from bench_replay import write_slides

# (owner, attribute, label); labels indented by two spaces are parts of the tracker's updates.
_PARTS = [
    (tactip.replay.video, "find_pin_field", "field search (find_pin_field)"),
    (pins.track.PinTracker, "start", "tracker start"),
    (pins.track.PinTracker, "update", "tracker updates"),
    (pins._refine.Refiner, "follow", "  follow passes (with their windows)"),
    (pins._window.WindowCentroids, "measure", "  window measurements"),
    (pins._refine.Refiner, "snap_to_rest", "  snap to rest (with its windows)"),
    (pins._refine.Refiner, "refine", "  LK retry and refinement"),
    (pins._refine.Refiner, "recover", "  recovery by blobs"),
    (pins._refine.Refiner, "fit_tips", "  tip fits on slopes (fit_tips)"),
    (tactip.replay.video, "analyse", "contacts, scale, feature pins"),
    (tactip.pipeline, "contact_features", "contact features"),
    (tactip.replay.video, "write_hdf5", "HDF5 file"),
]


def timed(seconds: collections.Counter, windows: list) -> None:
    """Wrap each part so that its main-thread CPU time adds up in `seconds` (s); window counts go to `windows`."""
    for owner, name, label in _PARTS:
        function = getattr(owner, name)

        def wrapper(*args, _function=function, _label=label, **kwargs):
            start = time.thread_time()
            try:
                return _function(*args, **kwargs)
            finally:
                seconds[_label] += time.thread_time() - start
                if _label.endswith("window measurements"):
                    windows.append(len(args[2]))

        setattr(owner, name, wrapper)


def main() -> None:
    """Write the video, replay it `--repeats` times, print the main thread's CPU by part (best run)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--slides", type=int, default=8)
    parser.add_argument("--codec", choices=("mp4v", "MJPG"), default="MJPG")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    seconds: collections.Counter = collections.Counter()
    windows: list[int] = []
    timed(seconds, windows)
    best: dict | None = None
    with tempfile.TemporaryDirectory() as folder:
        video = pathlib.Path(folder) / ("slides.avi" if args.codec == "MJPG" else "slides.mp4")
        frames = write_slides(video, "radial-led-120", args.slides, codec=args.codec)
        for repeat in range(args.repeats):
            seconds.clear()
            windows.clear()
            start = time.thread_time()
            tactip.replay.video.replay_video(video, pathlib.Path(folder) / f"replay{repeat}.h5", sensor=None)
            total = time.thread_time() - start
            if best is None or total < best["total"]:
                best = dict(total=total, parts=dict(seconds), windows=np.array(windows))
    total, parts, sizes = best["total"], best["parts"], best["windows"]
    parts["rest (frame loop, queue, stacking)"] = total - sum(v for k, v in parts.items() if not k.startswith(" "))
    print(f"radial-led-120, {args.slides} slides: {frames} frames {args.codec}; main thread {total:.3f} s CPU, "
          f"{total / frames * 1e3:.2f} ms/frame; best of {args.repeats}")
    print(f"{'':40s}{'s':>8s}{'ms/frame':>10s}{'%':>7s}")
    for label, value in sorted(parts.items(), key=lambda item: -item[1]):
        print(f"{label:40s}{value:8.3f}{value / frames * 1e3:10.3f}{100 * value / total:7.1f}")
    print(f"window measurements: {len(sizes) / (frames - 1):.2f} per frame (the tracker's start included), windows "
          f"per call: median {np.median(sizes):g}, mean {sizes.mean():.1f} (a frame's first pass measures every pin, "
          f"the others a few)")


if __name__ == "__main__":
    main()
