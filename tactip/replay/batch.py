"""Replay an archive of recordings on Dask distributed: one HDF5 file per video, resumable, past bad files.

``replay_batch`` runs `tactip.replay.video.replay_video` on every video of a list, each on a Dask
worker (`tactip.cluster`: an embedded local cluster, one worker process per core by default, or a
real cluster at a scheduler's address), and writes ``OUT/<stem>.h5`` for each: byte for byte the
file a single ``tactip replay VIDEO --out OUT/<stem>.h5`` writes (the video's absolute path is the
one recorded in it, so that a worker on any machine of the cluster finds it).

- A video that fails (corrupt, unreadable, no sensor in its rest frame, a worker that died on it)
  is named with its error in the result; the batch goes on with the others.
- It resumes: an output already in place was written whole (outputs are renamed into place only
  once complete) and its video is skipped, unless ``overwrite``. An output made from another video
  is not replaced: that video fails, named.
- ``OUT/summary.json`` has one row per video: its output, status (``written``, ``skipped`` or
  ``failed``), error, frames, pins, taps, warnings and the seconds its replay took.
- A progress bar counts the videos done and the frames read so far: each replay reports its frames
  every few frames as Dask events (``Worker.log_event``) that the bar's client subscribes to.
- On a GPU (``device="cuda"``, or ``auto`` where torch sees one) a task replays several videos
  together (`replay_together`): their trackers step in lockstep on threads and their windowed pin
  centroids are measured in one torch batch (`pins.accel.WindowBatcher`); the files are the same.

`expand_videos` turns the command line's videos, folders and glob patterns into the list of videos.

Example
-------
>>> from tactip.cluster import open_client                                    # doctest: +SKIP
>>> with open_client(workers=2) as client:                                     # doctest: +SKIP
...     result = replay_batch(expand_videos(["archive/"]), "out/", client=client)
>>> result.failed                                                              # doctest: +SKIP
[]
"""

from __future__ import annotations

import dataclasses
import glob
import json
import os
import pathlib
import time

from tactip.errors import SourceError, TactipError

__all__ = ["BatchResult", "VIDEO_SUFFIXES", "expand_videos", "replay_batch", "replay_together", "output_path"]

#: Files a folder given to a batch is searched for (a folder holding none is one recording: its frames).
#: Videos a task tracks together on a GPU (`replay_together`).
TOGETHER = 8
VIDEO_SUFFIXES = (".mp4", ".avi", ".mov", ".mkv", ".m4v", ".webm", ".mpg", ".mpeg", ".wmv")
SUMMARY = "summary.json"


def expand_videos(specs) -> list[pathlib.Path]:
    """The videos named by ``specs``: files, folders of videos and glob patterns, in order, each once.

    Parameters
    ----------
    specs : sequence of str or path
        A video file (or a folder of frames: one recording); a folder holding videos (its videos,
        sorted by name, not its subfolders); or a glob pattern (``'archive/*.mp4'``, quoted so the
        shell leaves it; ``**`` searches subfolders), its matches sorted.

    Returns
    -------
    list of pathlib.Path
        Absolute paths, duplicates dropped (first kept).

    Raises
    ------
    SourceError
        A spec names nothing: no such file or folder, and no file matches it as a pattern.
    """
    found: list[pathlib.Path] = []
    for spec in specs:
        path = pathlib.Path(spec)
        if path.is_dir():
            videos = sorted(p for p in path.iterdir() if p.is_file() and p.suffix.lower() in VIDEO_SUFFIXES)
            found += videos or [path]  # a folder without videos is a recording's frames
        elif path.exists():
            found.append(path)
        elif glob.has_magic(str(spec)):
            matches = sorted(pathlib.Path(p) for p in glob.glob(str(spec), recursive=True))
            if not matches:
                raise SourceError(f"no file matches {str(spec)!r}")
            found += matches
        else:
            raise SourceError(f"no such video or folder: {str(spec)!r}")
    unique = dict.fromkeys(p.resolve() for p in found)
    return list(unique)


def output_path(video, out_dir) -> pathlib.Path:
    """``out_dir/<stem>.h5``: where a batch writes ``video``'s replay (a folder of frames: its name)."""
    video = pathlib.Path(video)
    return pathlib.Path(out_dir) / f"{video.stem if video.suffix else video.name}.h5"


@dataclasses.dataclass
class BatchResult:
    """What a batch did: one row per video (the rows of ``summary.json``).

    Attributes
    ----------
    out_dir : pathlib.Path
    rows : list of dict
        ``video``, ``output``, ``status`` (written, skipped, failed), ``error``, ``frames``, ``pins``,
        ``taps``, ``warnings``, ``seconds`` (the replay's, on its worker; 0 when skipped).
    seconds : float
        The whole batch, wall clock, s.
    """

    out_dir: pathlib.Path
    rows: list
    seconds: float

    def _with(self, status: str) -> list:
        return [r for r in self.rows if r["status"] == status]

    @property
    def failed(self) -> list:
        """The rows of the videos that failed."""
        return self._with("failed")

    def text(self) -> str:
        """A few lines: videos written, skipped and failed, frames replayed, and where the summary is."""
        written, skipped, failed = (self._with(s) for s in ("written", "skipped", "failed"))
        frames = sum(r["frames"] or 0 for r in written)
        rate = f", {frames / self.seconds:.0f} frames/s" if self.seconds > 0 and frames else ""
        lines = [f"{len(self.rows)} videos: {len(written)} written, {len(skipped)} skipped (already done), "
                 f"{len(failed)} failed; {frames} frames replayed in {self.seconds:.1f} s{rate}",
                 f"Outputs in {self.out_dir}; one row per video in {self.out_dir / SUMMARY}"]
        if skipped:
            lines.append("Skipped videos keep their outputs; --overwrite replays them again")
        return "\n".join(lines)


def replay_batch(videos, out_dir, *, client, overwrite: bool = False, progress: bool = False,
                 device: str = "cpu", together: int = TOGETHER, **options) -> BatchResult:
    """Replay every video into ``out_dir/<stem>.h5`` on a Dask client's workers; write ``out_dir/summary.json``.

    Parameters
    ----------
    videos : sequence of str or path
        The videos (see `expand_videos`); their output names must differ.
    out_dir : str or path
        Folder of the outputs (made if missing).
    client : distributed.Client
        Where the replays run (`tactip.cluster.open_client`).
    overwrite : bool
        Replay videos whose output is already in place (default: skip them).
    progress : bool
        A tqdm bar of videos done, with the frames read so far (reported by the workers as they go; on stderr).
    device : {"cpu", "auto", "cuda", "torch-cpu"}
        ``cpu`` (default): each video on its own, the NumPy path. ``cuda``: `together` videos per task
        tracked in lockstep, their windowed centroids measured in one torch batch on the worker's GPU
        (`replay_together`); ``auto``: ``cuda`` where torch sees a GPU here, else ``cpu`` (torch not
        needed). ``torch-cpu``: the batched path on the CPU's torch (slower than ``cpu``; for tests).
        The files are the same whichever runs.
    together : int
        Videos per task on a GPU.
    **options
        `replay_video`'s options (not ``annotate_path``); ``calibration`` and ``model`` as paths.
        Checked once, before any video is sent.

    Returns
    -------
    BatchResult
        Failed videos are rows of it, not errors: check ``result.failed``.

    Raises
    ------
    ValueError
        An option out of range.
    TactipError
        Two videos would write the same output, or an option the batch does not take.
    OSError
        ``out_dir`` or its summary cannot be written.
    """
    from tactip._output import write_text_atomic
    from tactip.replay.video import _load_station_files, check_replay_options

    if "annotate_path" in options:
        raise TactipError("a batch writes no annotated videos: replay one video with --annotate")
    if int(together) != together or together < 1:
        raise ValueError(f"together must be a positive integer, got {together}")
    torch_device = _torch_device(device)
    started = time.perf_counter()
    check_replay_options(**{k: options[k] for k in ("rest_frame", "pad_diameter_mm", "mm_per_px", "n_pins",
                                                    "pins_on_pad", "expected_pins", "min_separation_mm", "sensor")
                            if k in options})
    _load_station_files(options.get("calibration"), options.get("model"), options.get("decision_threshold"),
                        n_samples=int(options.get("n_samples", 40)),
                        given={k: options.get(k) for k in ("expected_pins", "params", "mm_per_px", "sensor",
                                                           "pins_on_pad", "pad_diameter_mm")})
    for key in ("calibration", "model"):  # workers read them from their paths, wherever they run
        if isinstance(options.get(key), (str, os.PathLike)):
            options[key] = str(pathlib.Path(options[key]).resolve())
    out_dir = pathlib.Path(out_dir).resolve()
    videos = [pathlib.Path(v).resolve() for v in videos]
    targets = _check_targets(videos, out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    rows, todo = [], []
    for video, target in zip(videos, targets):
        row = _finished_row(video, target) if target.exists() and not overwrite else None
        rows.append(row)
        if row is None:
            todo.append(len(rows) - 1)
    size = 1 if torch_device is None else int(together)
    _run(client, videos, targets, rows, [todo[k:k + size] for k in range(0, len(todo), size)], options,
         torch_device=torch_device, progress=progress)
    result = BatchResult(out_dir, rows, time.perf_counter() - started)
    write_text_atomic(out_dir / SUMMARY, json.dumps({"videos": len(rows), "failed": len(result.failed),
                                                    "seconds": round(result.seconds, 3), "rows": rows},
                                                   indent=1) + "\n", inputs=videos)
    return result


def _check_targets(videos, out_dir: pathlib.Path) -> list[pathlib.Path]:
    """Each video's output; two videos with the same output name are refused before any work."""
    targets, seen = [], {}
    for video in videos:
        target = output_path(video, out_dir)
        if target in seen:
            raise TactipError(f"{seen[target]} and {video} would both write {target}: give them separate "
                              f"--out-dir or rename one")
        seen[target] = video
        targets.append(target)
    return targets


def _row(video, target, status: str, *, error: str = "", frames=None, pins=None, taps=None, warnings=(),
         seconds: float = 0.0) -> dict:
    return {"video": str(video), "output": str(target), "status": status, "error": error, "frames": frames,
            "pins": pins, "taps": taps, "warnings": list(warnings), "seconds": round(float(seconds), 3)}


def _finished_row(video: pathlib.Path, target: pathlib.Path) -> dict:
    """The row of a video whose output is in place: skipped, or failed if it is not this video's replay."""
    import h5py

    from tactip.replay.video import FORMAT

    try:
        with h5py.File(target, "r") as h5:
            fmt, made_from = h5.attrs.get("format"), h5.attrs.get("video")
            frames, pins = h5["positions"].shape[:2]
            taps = len(h5["tap_bounds"])
            warnings = json.loads(h5.attrs.get("warnings", "[]"))
    except (OSError, KeyError, ValueError) as exc:
        return _row(video, target, "failed", error=f"{target} exists and is not a replay ({exc}); --overwrite "
                                                   f"replaces it")
    if fmt != FORMAT or made_from != str(video):
        return _row(video, target, "failed", error=f"{target} exists, made from {made_from!r} ({fmt}); "
                                                   f"--overwrite replaces it")
    return _row(video, target, "skipped", frames=int(frames), pins=int(pins), taps=int(taps), warnings=warnings)


def _replay_one(video: str, target: str, options: dict, topic: str | None = None) -> dict:
    """One video's replay on a worker: its summary row, an error as a row (the batch goes on).

    With a `topic`, the frames read are reported to it as they go (`_report_frames`).
    """
    from tactip.replay.video import replay_video

    started = time.perf_counter()
    try:  # one decoder thread: the cluster runs a replay per core already
        result = replay_video(video, target, progress=_report_frames(topic), decode_threads=1, **options)
    except Exception as exc:  # noqa: BLE001 - any error of one video is that video's, named in its row
        return _row(video, target, "failed", error=_one_line(exc), seconds=time.perf_counter() - started)
    return _row(video, target, "written", frames=result.frames, pins=result.pins, taps=len(result.tap_bounds),
                warnings=result.warnings, seconds=time.perf_counter() - started)


def _report_frames(topic: str | None):
    """A callable that logs frame counts as events of the Dask `topic` (the batch's bar subscribes), or False.

    False (no progress) without a topic or outside a Dask worker.
    """
    if topic is None:
        return False
    from distributed import get_worker

    try:
        worker = get_worker()
    except ValueError:  # not on a worker (a direct call)
        return False
    return lambda frames: worker.log_event(topic, int(frames))


def _one_line(exc: BaseException) -> str:
    """``Type: first line of the message`` (user errors of the packages read well without the type)."""
    text = (str(exc).strip().splitlines() or [""])[0]
    known = isinstance(exc, (TactipError, OSError, ValueError)) or type(exc).__name__.endswith("Error") and \
        type(exc).__module__.split(".")[0] in ("pins", "perception", "calibration", "arm")
    return text if known and text else f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _run(client, videos, targets, rows, chunks, options, *, torch_device, progress: bool) -> None:
    """Send the videos of each chunk to the workers (one task a chunk); fill their rows as they finish."""
    import threading
    import uuid

    from distributed import as_completed
    from _shared.progress import progress_bar as tqdm

    bar = tqdm(total=len(rows), initial=len(rows) - sum(map(len, chunks)), unit="video", desc="replay",
               disable=not progress, leave=False)
    frames, failed, lock = 0, 0, threading.Lock()
    # Frames as the workers read them (each video's replay logs its count every few frames): the bar's
    # frame count moves while the videos are long, not only when one finishes.
    topic = f"tactip-replay-frames-{uuid.uuid4().hex}" if progress else None
    live = {"frames": 0}

    def show() -> None:
        bar.set_postfix_str(f"{max(live['frames'], frames)} frames, {failed} failed")

    def on_frames(event) -> None:
        with lock:
            live["frames"] += int(event[1])
            show()

    if topic is not None:
        client.subscribe_topic(topic, on_frames)
    futures = {}
    for chunk in chunks:
        paths, outputs = [str(videos[i]) for i in chunk], [str(targets[i]) for i in chunk]
        key = f"replay-{chunk[0]}-{videos[chunk[0]].name}"
        future = (client.submit(_replay_one, paths[0], outputs[0], options, topic, pure=False, key=key)
                  if torch_device is None else
                  client.submit(replay_together, paths, outputs, device=torch_device, pure=False, key=key,
                                topic=topic, **options))
        futures[future] = chunk
    try:
        for future in as_completed(futures):
            chunk = futures[future]
            try:
                done = future.result()
                done = [done] if isinstance(done, dict) else done
            except Exception as exc:  # noqa: BLE001 - a worker that died on these videos (KilledWorker), say
                done = [_row(videos[i], targets[i], "failed", error=f"its worker failed: {_one_line(exc)}")
                        for i in chunk]
            for i, row in zip(chunk, done):
                rows[i] = row
                frames += row["frames"] or 0
            with lock:
                failed = sum(1 for r in rows if r is not None and r["status"] == "failed")
                show()
                bar.update(len(chunk))
    finally:
        if topic is not None:
            client.unsubscribe_topic(topic)
        bar.close()
        client.cancel([f for f in futures if not f.done()])


def _torch_device(device: str) -> str | None:
    """The torch device a batch tracks on, or None for the NumPy path (``auto`` without a GPU or torch)."""
    if device == "cpu":
        return None
    if device == "torch-cpu":
        return "cpu"
    if device == "auto":
        try:
            import torch
        except ImportError:  # the accel extra is not installed: nothing changes
            return None
        return "cuda" if torch.cuda.is_available() else None
    if device == "cuda":
        return "cuda"  # checked where the replays run: the workers' machines have the GPUs
    raise ValueError(f"unknown device {device!r}; choose from auto, cpu, cuda")


def replay_together(videos, targets, *, device: str = "auto", topic: str | None = None, **options) -> list[dict]:
    """Replay several videos at once, their trackers in lockstep (one thread each), windows measured in one batch.

    Each video's tracker gives its windowed centroids to one `pins.accel.WindowBatcher`, which
    measures every video's windows of a step together as torch tensors (on a GPU); each video's file is
    the one `replay_video` writes alone. Needs torch (the ``accel`` extra).

    Parameters
    ----------
    videos, targets : sequence of str
        The videos and their output files.
    device : str
        ``auto`` (a GPU if torch sees one, else the CPU), ``cuda`` or ``cpu``.
    topic : str, optional
        The Dask event topic each video's frames read are reported to (a batch's progress bar).
    **options
        `replay_video`'s options.

    Returns
    -------
    list of dict
        One summary row per video (as in ``summary.json``); a failed video's row names its error.
    """
    import threading

    from pins.accel import WindowBatcher

    batcher = WindowBatcher(device=device)
    rows: list = [None] * len(videos)

    def replay(k: int) -> None:
        with batcher.member():
            rows[k] = _replay_one(videos[k], targets[k], dict(options, wrap_windows=batcher.wrap), topic)

    threads = [threading.Thread(target=replay, args=(k,), name=f"replay-{k}") for k in range(len(videos))]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    return [row if row is not None else _row(video, target, "failed", error="its replay thread stopped")
            for video, target, row in zip(videos, targets, rows)]
