"""The tracker's veil-tip fits (`Refiner.fit_tips`) on issue 20's radial slide video: their CPU cost per frame.

Writes the slide video of `bench_replay.py --slides N` (``radial-led-120``, 120 frames/s, slides of
3 pitches round the compass with 3-frame rests; MJPG), decodes it, finds the pin field and runs
`PinTracker.update` over every frame, with the fits (as shipped) and without them (no pin counted
as sloped, so `fit_tips` is never called), in interleaved rounds so that machine load falls on both
alike. Printed: the updates' CPU time per frame (``time.thread_time``, best round), the fits' own
share (calls per frame, ms per call), and the pin-frames reported lost with and without them.

Figures (2-core VM shared with other sessions, load ~2.5; 795 frames MJPG, best of 3 rounds, two runs each,
the fits' code before (4966203) and after the cut in alternate processes): fits off 1.32-1.38 ms/frame;
fits on 2.17-2.19 ms/frame before (0.70 calls a frame at 1.11 ms each), 1.87 after (0.63 ms each); lost
pin-frames 2576 with the fits, 6427 without, both codes.

Run: .venv/bin/python bench/bench_fit_tips.py [--slides 8] [--rounds 5] [--codec MJPG]
"""

from __future__ import annotations

import argparse
import pathlib
import tempfile
import time

import numpy as np

from pins import PinTracker, find_pin_field
from bench_replay import decode, write_slides


def run(images: list, field, fits: bool) -> dict[str, float]:
    """One pass of the tracker over `images` (after the first): CPU s of the updates, of the fits, their calls, lost pin-frames."""
    tracker = PinTracker(detection=field.params, disc=field.disc)
    tracker.start(images[0], field.centres)
    refiner = tracker._refiner
    if not fits:
        refiner.sloped[:] = False
    fit = refiner.fit_tips
    spent = {"fit": 0.0, "calls": 0}

    def timed_fit(*args, **kwargs):
        start = time.thread_time()
        try:
            return fit(*args, **kwargs)
        finally:
            spent["fit"] += time.thread_time() - start
            spent["calls"] += 1

    refiner.fit_tips = timed_fit  # this tracker's refiner only
    lost = 0
    start = time.thread_time()
    for image in images[1:]:
        lost += int(np.isnan(tracker.update(image)[:, 0]).sum())
    return dict(cpu=time.thread_time() - start, fit=spent["fit"], calls=spent["calls"], lost=lost)


def main() -> None:
    """Write and decode the video, time the tracker with and without the fits in interleaved rounds, print."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--slides", type=int, default=8)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--codec", choices=("mp4v", "MJPG"), default="MJPG")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        video = pathlib.Path(folder) / ("slides.avi" if args.codec == "MJPG" else "slides.mp4")
        frames = write_slides(video, "radial-led-120", args.slides, codec=args.codec)
        images = decode(video)
    field = find_pin_field(images[0])
    best: dict[bool, dict] = {}
    for _ in range(args.rounds):
        for fits in (True, False):
            result = run(images, field, fits)
            if fits not in best or result["cpu"] < best[fits]["cpu"]:
                best[fits] = result
    updates = frames - 1
    print(f"radial-led-120, {args.slides} slides: {frames} frames {args.codec}, {len(field.centres)} pins; "
          f"tracker CPU per frame, best of {args.rounds} interleaved rounds")
    for fits in (False, True):
        r = best[fits]
        per_call = r["fit"] / r["calls"] * 1e3 if r["calls"] else float("nan")
        print(f"fits {'on ' if fits else 'off'}: {r['cpu'] / updates * 1e3:6.3f} ms/frame; fits {r['calls'] / updates:.2f} "
              f"calls/frame, {per_call:.3f} ms/call, {r['fit'] / updates * 1e3:.3f} ms/frame; lost pin-frames {r['lost']}")
    print(f"fits on / off: {best[True]['cpu'] / best[False]['cpu']:.3f}")


if __name__ == "__main__":
    main()
