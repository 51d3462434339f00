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
measures: each call costs a fixed ~0.05 ms of NumPy calls (~0.09 ms for all 120 windows), so their
number, not their size, sets the tracker's cost. Best of the repeats (the least disturbed run).

Figures (2-core VM shared with four other sessions, load average 20-25; 795 frames, MJPG):
main thread ~2.2 s, of which tracker updates 87-90 % (follow passes 64-67 %, window measurements
42-44 % in 4.21 calls per frame, snap to rest 9 %), the field search 3-4 %, contacts, features and
the HDF5 file 3-5 %, the frame loop 3 %.

Session "replay4" (load average 4-7, the code of that session: the tracker's outputs as before, a few %
less CPU): main thread 4.57 ms/frame, of which tracker updates 91 % (follow passes 51 %, window
measurements 31 % in 4.3 calls per frame, tip fits on slopes 20 % on 69 % of the frames, snap to rest 7 %,
recovery by blobs 2 %), the field search 4 %, contacts, features and the HDF5 file 2 %, the frame loop 2 %.

Session "speed6" (2026-11-29; load average 5-12; main 9a221aa against this session's code, outputs bit for
bit): main thread 2.11 -> 2.01 ms/frame (best of 2, wrapped parts; before the last commit), of which tracker
updates 91-92 % (follow passes 48-50 %, window measurements 27-29 % in 4.3 calls per frame, tip fits on
slopes 19 %, snap to rest 7 %, recovery by blobs 2 %), the field search 3 %, contacts, features and the HDF5
file 2 %, the frame loop 2 %. ``--against`` main, 5 rounds, the final code, tracker updates ms/frame CPU
(median of the paired ratios): MJPG 1.562 -> 1.394 (0.88; window measurements 0.493 -> 0.405, 0.81; tip fits
0.345 -> 0.304, 0.86; snap to rest 0.88), mp4v 1.504 -> 1.341 (0.95; 0.87; 0.92; 0.93); two earlier runs
(all but the last commit) 0.93 (MJPG) and 0.91 (mp4v). Follow passes 0.87 / 0.94 through their window
measurements alone (their own code is another session's). ``--calls``, MJPG, per frame: calls 543 -> 495
(tip fits 115 -> 86, window measurements 177 -> 159, snap to rest 53 -> 51), operations 1670 -> 1630; the
counts say less than the time: a reduction costs several elementwise calls, `np.linalg.solve` three calls of
its LAPACK gufunc, an in-place division whose divisor overlaps it twice a new one, and a window measurement
of one window ~50 us against ~90 us for 120.

Session "speed7" (2026-11-29; load average 3-5; main 187772a against this session's code, outputs bit for
bit on both videos and on bench_slides' renders): cheaper bookkeeping round the window measurements.
``--against`` main, tracker updates ms/frame CPU (median of the paired ratios), the final code, 5 rounds
MJPG 1.273 -> 1.218 (0.94; follow passes 0.653 -> 0.605, 0.92, their own code less their window
measurements 0.292 -> 0.247; tip fits 0.99; window measurements 0.98, not this session's: the load), mp4v
1.312 -> 1.229 (0.95, faster in 5 of 5 rounds; follow 0.92, own code 0.307 -> 0.250; tip fits 1.00); the
commit before, 7 rounds each, MJPG 1.397 -> 1.302 (0.95; follow 0.92), mp4v 1.297 -> 1.236 (0.96, faster in
7 of 7 rounds; follow 0.93; tip fits 1.00). ``--calls``, MJPG, per frame: calls 512 -> 543, operations 1680
-> 1706: more calls, cheaper ones. A gather of the 36 identity neighbours of 30 pins as rows costs ~20 us,
as complex numbers (a view, a take, a view) ~9 us; below ~160 points the rows win (`pins._identity.gathered`).
Counted calls include each Python function and each NumPy wrapper (`np.take`, `ndarray.any` are three).

Session "speed8" (2026-11-29; load average 5-7; main f24c3ab against this session's code): compiled kernels
(Numba, `pins._jit`) for the window measurements, the contrast alone and the tip fits' centre step, one call
a pass. ``--against`` main, 5 rounds, tracker updates ms/frame CPU (median of the paired ratios): MJPG 1.306
-> 0.875 (0.70; window measurements 0.383 -> 0.107, 0.29; tip fits 0.295 -> 0.169, 0.61; follow passes 0.648
-> 0.381, 0.61, through their windows; snap to rest 0.097 -> 0.073, 0.79; recovery by blobs 0.99), mp4v 1.369
-> 0.944 (0.66; 0.28; 0.56; 0.59; 0.75; 1.01). Lost and retired pins identical, positions within 1.3e-12 px
(MJPG) and 1.1e-11 px (mp4v), 0 of 95280 pin-frames apart by more than 1e-6 px (the window measurements are
the reference's bit for bit; the centre step's sums and 8 x 8 solve run in another order). ``--calls``,
MJPG, per frame: calls 543 -> 503 (window measurements 158 -> 103: each measurement now ~24 Python-level calls
round one kernel, the error state and the environment's choice of kernels among them; tip fits 89 -> 104,
the kernel's arguments), operations 1706 -> 1209. What is left of the tracker's 0.875 ms/frame (MJPG): the
follow passes' own code ~0.3 (`pins._follow`), the tip fits' own ~0.12 (`pins._recover`: predictions from
neighbours, one pin per tip, kept own tips), snap to rest ~0.05, recovery by blobs 0.05, and the update's
bookkeeping outside these parts ~0.2 (predictions, carried steps, learnt scatters, identities): a few hundred
NumPy calls a frame in files this session did not own.

Session "speed9" (2026-11-29; load average 14-15 from other sessions; main ee48907 against this session's
code): compiled kernels for the tracker's bookkeeping round its window measurements (`pins._jit_track`,
`pins._jit_rest`): the follow passes' judgements, their re-centring rounds with their window measurements
in one call (`pins._jit.follow_passes`), neighbours' medians, predictions, trusted searches, carried
steps, remembered displacements, one pin per tip, kept own tips, the still steps' scatter and snap to
rest. ``--against`` main, 5 rounds, tracker updates ms/frame CPU (median of the paired ratios): MJPG 1.028
-> 0.736 (0.64; follow passes 0.449 -> 0.258, 0.52; snap to rest 0.088 -> 0.048, 0.52; tip fits 0.192 ->
0.175, 0.82, through their kept own tips and predictions; recovery by blobs 1.08, noise), mp4v 1.034 ->
0.661 (0.64; 0.52; 0.49; 0.84; 1.16). "window measurements" now counts only those outside the follow
passes' re-centring rounds (1.35 calls a frame against 4.30; 0.50-0.51 of main's time). Lost and retired
pins identical, positions bit for bit (0 px apart) on both codecs, as on bench_slides' renders (12 videos:
radial-led-120, tactip-331, small-pad-100; seeds 0-1; model and realistic skins) and `bench_phenomena.py`
seeds 0-2 (the same lines). ``--calls``, MJPG, per frame, main -> this: calls 507 -> 504 (follow passes
202 -> 163, snap to rest 51 -> 56, tip fits 104 -> 119: a kernel's call through Numba's dispatcher counts
as several), operations 1218 -> 819 (561 -> 258, 121 -> 82, 211 -> 201). What is left of the tracker's ~0.47-0.5 ms/frame on a quieter machine: the window measurements'
own work (their kernels, ~0.1), the tip fits (~0.12-0.16, `pins._recover`, `pins._tipfit`), the update's
own code in `pins.track` (~0.07), recovery by blobs (0.05).

Session 19's "rest14" (2026-11-30; load average 3-15 from other sessions; main 09118d1 against this session's
code): the still pad's bookkeeping session 18 added (faint tips' levels, bounds and steadiness; the rest frame's
probe) cheaper, with the same results: per-pin arrays and compiled kernels (`pins._jit_rest` draw_bounds,
faint_steady, faint_here, probe_matches with an early exit), and ``TACTIP_KERNELS`` read once (`pins._kernels`).
``--against`` main, tracker updates ms/frame CPU (median of the paired ratios), the speed commit alone, 3 rounds
(positions, lost and retired pins identical on all six videos): radial-led-120 mp4v 0.653 -> 0.576 (0.86), MJPG
0.714 -> 0.656 (0.88; still steps 0.44-0.50 with the bounds they redraw, faint levels 0.69-0.72, RestMatch
0.62-0.66); ``--preset tactip-331`` and ``rim-ring-331`` (no faint tip: nothing to save) 0.96-1.03. The final code,
5 rounds at load 15: mp4v 0.781 -> 0.717 (0.92), MJPG 0.793 -> 0.672 (0.86); still steps 0.064 -> 0.031, faint
levels 0.026 -> 0.018, RestMatch 0.029 -> 0.017 (its probe alone 21 -> 2 us a frame); lost and retired pins
identical, positions but in frames 1-4 (the still pair's calm test, `pins._rest`: 43 / 7 pin-frames, <= 0.59 px).
Parts added here: ``--preset``, and the still steps, faint levels, RestMatch, overlapping pairs and own tips timed.

Session 20's "speed16" (load average 12-13): the contacts' medians, now computed per frame while tracking
(`pins.segment.NeighbourMedians.add`), and the luma lookup (`tactip.replay.luma.look_up`) are parts of their own:
mp4v, best of 2, main thread 0.79 ms/frame, of which tracker updates 0.534, the field search 0.076, the lookup 0.064,
the medians 0.030 (these wrappers' own cost included; ~9 us a frame unwrapped), contacts, scale and feature pins 0.026,
the HDF5 file 0.008, contact features 0.004.

Session 21's "speed21" (load average 10-11): the tip fits on slopes in one compiled call (`pins._jit_fit`). ``--against``
main (c368916), 5 rounds, tracker updates ms/frame CPU (median of the paired ratios): mp4v 0.648 -> 0.563 (0.87; tip fits
0.137 -> 0.063, 0.46), MJPG 0.646 -> 0.544 (0.85; 0.139 -> 0.066, 0.47); the other parts 0.90-1.05 (not changed:
the load); positions, lost and retired pins bit for bit. With the closing bookkeeping in one call too
(`pins._predict.settle`) and the surround stored through the crop's flat view: mp4v 0.623 -> 0.528 (0.85), MJPG 0.583 ->
0.496 (0.85, 3 rounds). Replay's luma lookup is now a part of its own once the tracker
has started (`tactip.replay.luma.look_up_part`, the tracker's region alone). What is left of the updates (mp4v, one
process, ms/frame): the follow passes 0.14 (`pins._follow`), recovery by blobs 0.04 (24 blob detections, 1.3 ms each),
the fits' own kernel 0.04 (the tip fit's arithmetic), snap to rest 0.03, carried steps 0.02, still steps 0.014, and
the update's own NumPy calls ~0.06 (`pins.track`: ~40 calls a frame on 120 rows).

Load-independent figures (``--calls``): the tracker alone (`pins.PinTracker` started on the decoded
video's first frame from `pins.find_pin_field`, as replay starts it, then `update` on every frame)
with every Python-level call counted by part (``sys.setprofile``: Python functions and the C
functions called from Python, NumPy's included; a ufunc or an operator on arrays is not such an
event) and every operation (``sys.settrace`` opcode events: calls, operators, comparisons and
subscripts, which a ufunc or an operator on arrays is): counts do not vary with load. And
``--against TREE`` (another source tree of the project, e.g. ``git archive main | tar -x -C TREE``):
the tracker's CPU by part (``time.thread_time``), this tree against TREE in interleaved rounds
(``--rounds``, each in a fresh process per tree, the order alternating), with the median of the
paired ratios per part, and whether the two trees' positions, lost and retired pins are identical.

Run: .venv/bin/python bench/bench_replay_parts.py [--slides N] [--codec mp4v|MJPG] [--preset NAME] [--repeats N]
     .venv/bin/python bench/bench_replay_parts.py --calls [--slides N] [--codec mp4v|MJPG]
     .venv/bin/python bench/bench_replay_parts.py --against TREE [--rounds N] [--slides N] [--codec mp4v|MJPG]
"""

from __future__ import annotations

import argparse
import collections
import dis
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

import pins._refine
import pins._rest
import pins._return
import pins._window
import pins.segment
import pins.track
import tactip.pipeline
import tactip.replay.luma
import tactip.replay.video
from bench_replay import decode, write_slides

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
    (pins._rest._AtRest, "observe_still", "  still steps (observe_still)"),
    (pins._rest._AtRest, "_learn_levels", "  faint levels (_learn_levels)"),
    (pins._return.RestMatch, "restore", "  rest frame again (RestMatch)"),
    (pins.track, "part_overlapping", "  overlapping pairs"),
    (pins.track, "kept_on_own_tips", "  own tips (kept_on_own_tips)"),
    (pins.segment.NeighbourMedians, "add", "contacts' medians, per frame (NeighbourMedians)"),
    (tactip.replay.luma, "look_up", "luma to grey (look_up)"),
    (tactip.replay.luma, "look_up_part", "luma to grey, the tracker's region (look_up_part)"),
    (tactip.replay.video, "analyse", "contacts, scale, feature pins"),
    (tactip.pipeline, "contact_features", "contact features"),
    (tactip.replay.video, "write_hdf5", "HDF5 file"),
]


def timed(seconds: collections.Counter, windows: list) -> None:
    """Wrap each part so that its main-thread CPU time adds up in `seconds` (s); window counts go to `windows`."""
    for owner, name, label in _PARTS:
        function = getattr(owner, name, None)
        if function is None:
            continue

        def wrapper(*args, _function=function, _label=label, **kwargs):
            start = time.thread_time()
            try:
                return _function(*args, **kwargs)
            finally:
                seconds[_label] += time.thread_time() - start
                if _label.endswith("window measurements"):
                    windows.append(len(args[2]))

        setattr(owner, name, wrapper)


# The opcodes counted as operations (`--calls`): calls, and the operators a NumPy call hides behind.
_OPERATIONS = frozenset(dis.opmap[name] for name in ("CALL", "CALL_FUNCTION_EX", "BINARY_OP", "COMPARE_OP",
                                                     "BINARY_SUBSCR", "STORE_SUBSCR", "UNARY_NEGATIVE",
                                                     "UNARY_INVERT") if name in dis.opmap)

# The tracker's own parts (`--calls`, `--against`): the labels of `_PARTS` inside the tracker's updates.
_TRACKER = [part for part in _PARTS if part[2] == "tracker updates" or part[2].startswith(" ")]


class _Counted:
    """Wraps the tracker's parts: main-thread CPU (s) and, with `calls`, Python-level calls and operations
    by part, each counted for every part it runs inside: calls from ``sys.setprofile`` ('call' and 'c_call'
    events: Python functions, and C functions called from Python, NumPy's functions included), operations
    from ``sys.settrace`` opcode events (calls, arithmetic, comparisons, subscripts: `_OPERATIONS`; a NumPy
    ufunc or operator on arrays is one of these, not a call)."""

    def __init__(self, calls: bool) -> None:
        self.seconds: collections.Counter = collections.Counter()
        self.calls: collections.Counter = collections.Counter()
        self.operations: collections.Counter = collections.Counter()
        self.windows: list[int] = []
        self._active: list[str] = []
        self._count = calls
        self._restore = []
        for owner, name, label in _TRACKER:
            function = getattr(owner, name, None)
            if function is None:  # (a part another tree does not have)
                continue
            self._restore.append((owner, name, function))
            setattr(owner, name, self._wrap(function, label))

    def _wrap(self, function, label):
        def wrapper(*args, **kwargs):
            self._active.append(label)
            start = time.thread_time()
            try:
                return function(*args, **kwargs)
            finally:
                self.seconds[label] += time.thread_time() - start
                self._active.pop()
                if label.endswith("window measurements"):
                    self.windows.append(len(args[2]))
        return wrapper

    def _profile(self, frame, event, arg) -> None:
        if event == "call" or event == "c_call":
            for label in set(self._active):
                self.calls[label] += 1

    def _trace(self, frame, event, arg):
        if event == "call":
            frame.f_trace_opcodes = True
            frame.f_trace_lines = False
        elif event == "opcode" and frame.f_code.co_code[frame.f_lasti] in _OPERATIONS:
            for label in set(self._active):
                self.operations[label] += 1
        return self._trace

    def run(self, images: list) -> dict:
        """Start a tracker on the first image (`find_pin_field`), update it on the others: its per-frame
        positions, lost and retired pins (arrays) and CPU seconds of the updates alone."""
        field = pins.find_pin_field(images[0])
        tracker = pins.track.PinTracker(detection=field.params, disc=field.disc)
        tracker.start(images[0], field.centres)
        self.seconds.clear()
        self.calls.clear()
        self.windows.clear()
        positions, lost, retired = [], [], []
        if self._count:
            sys.setprofile(self._profile)
            sys.settrace(self._trace)
        start = time.thread_time()
        try:
            for image in images[1:]:
                positions.append(tracker.update(image))
                lost.append(tracker.lost.copy())
                retired.append(tracker.retired.copy())
        finally:
            total = time.thread_time() - start
            sys.setprofile(None)
            sys.settrace(None)
        return dict(total=total, positions=np.array(positions), lost=np.array(lost), retired=np.array(retired))


def _frames(args, folder: str) -> tuple[list, pathlib.Path]:
    """The slide video's decoded frames (cached as .npy in `folder` for the workers) and that file."""
    video = pathlib.Path(folder) / ("slides.avi" if args.codec == "MJPG" else "slides.mp4")
    write_slides(video, args.preset, args.slides, codec=args.codec)
    images = decode(video)
    stored = pathlib.Path(folder) / "frames.npy"
    np.save(stored, np.array(images))
    return images, stored


def count_calls(args) -> None:
    """`--calls`: the tracker's Python-level calls per frame by part (load-independent), and its windows."""
    with tempfile.TemporaryDirectory() as folder:
        images, _ = _frames(args, folder)
    counted = _Counted(calls=True)
    counted.run(images)
    frames = len(images) - 1
    sizes = np.array(counted.windows)
    print(f"{args.preset}, {args.slides} slides, {args.codec}: tracker updates over {frames} frames; per frame, "
          f"by part: Python-level calls (functions, NumPy's C functions included) and operations (calls, "
          f"operators, comparisons, subscripts: a NumPy ufunc or array operator is one)")
    print(f"{'':40s}{'calls/frame':>12s}{'%':>7s}{'ops/frame':>11s}{'%':>7s}")
    whole, ops = counted.calls["tracker updates"], counted.operations["tracker updates"]
    for _, _, label in _TRACKER:
        print(f"{label:40s}{counted.calls[label] / frames:12.1f}{100 * counted.calls[label] / max(whole, 1):7.1f}"
              f"{counted.operations[label] / frames:11.1f}{100 * counted.operations[label] / max(ops, 1):7.1f}")
    print(f"window measurements: {len(sizes) / frames:.2f} per frame, windows per call: median {np.median(sizes):g}")


def _worker(frames_path: str, out_path: str) -> None:
    """One tree's tracker over the stored frames: CPU by part (JSON on stdout), outputs to `out_path` (.npz)."""
    images = list(np.load(frames_path))
    counted = _Counted(calls=False)
    result = counted.run(images)
    np.savez(out_path, positions=result["positions"], lost=result["lost"], retired=result["retired"])
    print(json.dumps(dict(total=result["total"], parts=dict(counted.seconds))))


def against(args) -> None:
    """`--against TREE`: the tracker's CPU by part, this tree against TREE, in interleaved rounds (fresh
    processes, order alternating): per-round figures, the median of the paired ratios, identical outputs."""
    here = pathlib.Path(__file__).resolve().parents[1]
    trees = {"this": here, "other": pathlib.Path(args.against).resolve()}
    runs: dict[str, list[dict]] = {"this": [], "other": []}
    with tempfile.TemporaryDirectory() as folder:
        images, stored = _frames(args, folder)
        frames = len(images) - 1
        del images
        outputs = {}
        for round_ in range(args.rounds):
            for name in (("this", "other") if round_ % 2 == 0 else ("other", "this")):
                out = pathlib.Path(folder) / f"{name}.npz"
                environment = dict(os.environ, PYTHONPATH=f"{trees[name]}{os.pathsep}{trees[name] / 'bench'}",
                                   PYTHONDONTWRITEBYTECODE="1")
                done = subprocess.run([sys.executable, str(trees["this"] / "bench" / "bench_replay_parts.py"),
                                       "--worker", str(stored), str(out)], env=environment, check=True,
                                      capture_output=True, text=True, cwd=folder)
                runs[name].append(json.loads(done.stdout.strip().splitlines()[-1]))
                with np.load(out) as data:
                    outputs[name] = {key: data[key] for key in data.files}
            figures = " ".join(f"{name} {runs[name][-1]['total'] / frames * 1e3:.3f}" for name in runs)
            print(f"round {round_ + 1}: tracker updates, ms/frame CPU: {figures}", flush=True)
    same = {key: np.array_equal(outputs["this"][key], outputs["other"][key], equal_nan=True)
            for key in ("positions", "lost", "retired")}
    mine, theirs = outputs["this"]["positions"], outputs["other"]["positions"]
    gap = np.nanmax(np.abs(mine - theirs))
    # Pin-frames whose position differs by more than 1e-6 px, or found in one tree and not the other.
    apart = (np.abs(mine - theirs) > 1e-6).any(axis=2) | (np.isnan(mine) != np.isnan(theirs)).any(axis=2)
    print(f"outputs identical: {same}; largest position difference {gap:.3g} px; pin-frames differing by more "
          f"than 1e-6 px (or found in one tree only): {int(apart.sum())} of {apart.size}")
    print(f"{'':40s}{'this ms/f':>10s}{'other ms/f':>11s}{'ratio':>7s}  (medians; ratio: median of paired)")
    labels = ["tracker updates"] + [label for _, _, label in _TRACKER if label.startswith(" ")]
    for label in labels:
        mine = np.array([run["parts"].get(label, 0.0) for run in runs["this"]])
        theirs = np.array([run["parts"].get(label, 0.0) for run in runs["other"]])
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.median(mine / theirs)
        print(f"{label:40s}{np.median(mine) / frames * 1e3:10.3f}{np.median(theirs) / frames * 1e3:11.3f}{ratio:7.2f}")
    print(f"load average {' '.join(f'{x:.1f}' for x in os.getloadavg())}")


def main() -> None:
    """Write the video, replay it `--repeats` times, print the main thread's CPU by part (best run)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--slides", type=int, default=8)
    parser.add_argument("--preset", default="radial-led-120", help="the synthetic TacTip that slides (tactip-331 ...)")
    parser.add_argument("--codec", choices=("mp4v", "MJPG"), default="MJPG")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--calls", action="store_true", help="the tracker's Python-level calls per frame by part")
    parser.add_argument("--against", metavar="TREE", help="the tracker's CPU by part against another source tree")
    parser.add_argument("--rounds", type=int, default=5, help="interleaved rounds of --against")
    parser.add_argument("--worker", nargs=2, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        return _worker(*args.worker)
    if args.calls:
        return count_calls(args)
    if args.against:
        return against(args)
    seconds: collections.Counter = collections.Counter()
    windows: list[int] = []
    timed(seconds, windows)
    best: dict | None = None
    with tempfile.TemporaryDirectory() as folder:
        video = pathlib.Path(folder) / ("slides.avi" if args.codec == "MJPG" else "slides.mp4")
        frames = write_slides(video, args.preset, args.slides, codec=args.codec)
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
    print(f"{args.preset}, {args.slides} slides: {frames} frames {args.codec}; main thread {total:.3f} s CPU, "
          f"{total / frames * 1e3:.2f} ms/frame; best of {args.repeats}")
    print(f"{'':40s}{'s':>8s}{'ms/frame':>10s}{'%':>7s}")
    for label, value in sorted(parts.items(), key=lambda item: -item[1]):
        print(f"{label:40s}{value:8.3f}{value / frames * 1e3:10.3f}{100 * value / total:7.1f}")
    print(f"window measurements: {len(sizes) / (frames - 1):.2f} per frame (the tracker's start included), windows "
          f"per call: median {np.median(sizes):g}, mean {sizes.mean():.1f} (a frame's first pass measures every pin, "
          f"the others a few)")


if __name__ == "__main__":
    main()
