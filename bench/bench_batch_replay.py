"""Batch replay on Dask: files per second against workers (1, 2, all cores), as a ratio to one worker (issue 24).

Writes an archive of short real-like recordings to a temporary folder (the 331-pin synthetic TacTip
at 640 x 480 px, one tap each at its own depth, seed per file, mp4v as `tactip record` writes), then
replays the whole archive with `tactip.replay.batch.replay_batch` on the embedded local cluster
(`tactip.cluster.open_client`: worker processes, one thread each, as ``tactip replay DIR --out-dir``
runs it) for each worker count, into a fresh output folder each time. The cluster is started
before the clock starts (its start-up, about a second per worker process, is paid once per command);
the clock covers sending every video, replaying it and writing its HDF5 file and the summary.

For each worker count it prints files/s and frames/s of the best of the repeats (the run least
disturbed by other processes) and the ratio to one worker (bar on a 2-core machine: 2 workers
>= 1.15x one), with each repeat's ratio, and the rerun: the same batch again into the same folder,
which skips every finished file, as a fraction of the first run's time (bar: under 30 %).

With ``--device cuda`` (or ``torch-cpu``) it also replays the archive on one worker with that
device (``--together`` videos a task, tracked in lockstep, their pin windows measured in one torch
batch) and prints its frames/s against one worker on the NumPy path, on the same files.

Run: .venv/bin/python bench/bench_batch_replay.py [--files 16] [--repeats 3] [--workers 1 2 4]
     .venv/bin/python bench/bench_batch_replay.py --workers 1 --device cuda --together 16
"""

from __future__ import annotations

import argparse
import pathlib
import tempfile
import time

import cv2

from tactip.cluster import default_workers, open_client
from tactip.replay.batch import expand_videos, replay_batch
from tactip.sim import Contact, SyntheticTacTip


def write_archive(folder: pathlib.Path, files: int) -> int:
    """``files`` one-tap videos of the 331-pin sensor in ``folder``; returns the frames of each."""
    frames = 0
    for k in range(files):
        sensor = SyntheticTacTip(pins=331, seed=k)
        width, height = sensor.image_size
        writer = cv2.VideoWriter(str(folder / f"tap{k:03d}.mp4"), cv2.VideoWriter_fourcc(*"mp4v"), 20.0,
                                 (width, height), True)
        frames = 0
        for frame in sensor.tap(Contact(2.5 + 2.5 * k / max(files - 1, 1), 2.0), frame_rate=20.0,
                                rest_before_s=0.2, rest_after_s=0.2):
            writer.write(cv2.cvtColor(frame.image, cv2.COLOR_GRAY2BGR) if frame.image.ndim == 2 else frame.image)
            frames += 1
        writer.release()
    return frames


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--files", type=int, default=16, help="videos in the archive (default 16)")
    parser.add_argument("--repeats", type=int, default=3, help="runs per worker count (default 3)")
    parser.add_argument("--workers", type=int, nargs="+", help="worker counts (default 1, 2 and all cores)")
    parser.add_argument("--device", choices=("cuda", "torch-cpu"), help="also the batched torch path on one worker")
    parser.add_argument("--together", type=int, default=8, help="videos per task with --device (default 8)")
    args = parser.parse_args()
    counts = sorted({1, *(args.workers or {1, 2, default_workers()})})
    with tempfile.TemporaryDirectory() as tmp:
        root = pathlib.Path(tmp)
        (root / "archive").mkdir()
        per_file = write_archive(root / "archive", args.files)
        videos = expand_videos([root / "archive"])
        print(f"{len(videos)} videos of {per_file} frames (331 pins, 640x480 px, mp4v); {default_workers()} cores")
        best, runs, rerun = {}, {}, {}
        for repeat in range(args.repeats):
            for workers in counts:  # alternating, so that machine load falls on every count alike
                with open_client(workers=workers) as client:
                    client.wait_for_workers(workers)
                    out = root / f"out-{workers}-{repeat}"
                    started = time.perf_counter()
                    result = replay_batch(videos, out, client=client)
                    seconds = time.perf_counter() - started
                    assert not result.failed, result.failed
                    started = time.perf_counter()
                    again = replay_batch(videos, out, client=client)
                    rerun.setdefault(workers, []).append((time.perf_counter() - started) / seconds)
                    assert all(r["status"] == "skipped" for r in again.rows)
                runs.setdefault(workers, []).append(seconds)
                best[workers] = min(best.get(workers, seconds), seconds)
        if args.device:
            batched = []
            for repeat in range(args.repeats):
                with open_client(workers=1) as client:
                    client.wait_for_workers(1)
                    started = time.perf_counter()
                    result = replay_batch(videos, root / f"out-{args.device}-{repeat}", client=client,
                                          device=args.device, together=args.together)
                    batched.append(time.perf_counter() - started)
                    assert not result.failed, result.failed
        print(f"{'workers':>7} {'files/s':>8} {'frames/s':>9} {'x 1 worker':>10}  each repeat x 1 worker   rerun/first")
        for workers in counts:
            ratio = best[1] / best[workers] if 1 in best else float("nan")
            each = " ".join(f"{a / b:.2f}" for a, b in zip(runs.get(1, []), runs[workers]))
            print(f"{workers:>7} {len(videos) / best[workers]:>8.2f} {len(videos) * per_file / best[workers]:>9.0f} "
                  f"{ratio:>10.2f}  {each:<22} {max(rerun[workers]):.1%} (worst)")
        if args.device:
            frames = len(videos) * per_file
            print(f"1 worker, {args.device} batched ({args.together} videos a task): {frames / min(batched):.0f} "
                  f"frames/s, {best[1] / min(batched):.2f}x the NumPy path's {frames / best[1]:.0f} frames/s")


if __name__ == "__main__":
    main()
