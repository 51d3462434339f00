"""Record frames from any source (a live camera, the synthetic TacTip) to a video file for replay.

``tactip replay`` reads a recording twice (to track, then to annotate), so a live camera is first
recorded: frames are read on a thread into a bounded queue (`tactip.sources.ThreadedReader`) and
written as they come, for a duration or a frame count. MPEG-4 (``.mp4``) is small; Motion-JPEG
(``.avi``) keeps more detail, as a USB webcam's own MJPG stream does. The file is written under a
temporary name and renamed at the end, so a failure or Ctrl-C leaves no half-written video.
"""

from __future__ import annotations

import math
import os
import pathlib
from dataclasses import dataclass

from tactip._output import (check_video_written, claim_output, discard_temporary, out_of_space, publish,
                            refuse_overwriting_inputs, write_error)
from tactip.errors import SourceError

__all__ = ["RecordResult", "record_video"]

_FOURCC = {".mp4": "mp4v", ".avi": "MJPG"}


@dataclass(frozen=True)
class RecordResult:
    """What a recording wrote.

    Attributes
    ----------
    path : pathlib.Path
    frames : int
    frame_rate : float
        Frames/s written in the file's header.
    duration_s : float
        Time from the first to the last frame, s.
    dropped_frames : int
        Frames the reader dropped because writing fell behind (live sources).
    """

    path: pathlib.Path
    frames: int
    frame_rate: float
    duration_s: float
    dropped_frames: int

    def summary(self) -> str:
        """One line for a person."""
        return (f"recorded {self.frames} frames ({self.duration_s:.2f} s at {self.frame_rate:g} frames/s, "
                f"{self.dropped_frames} dropped) to {self.path}")


def record_video(spec, out_path, *, seconds: float | None = None, frames: int | None = None,
                 frame_rate: float | None = None, progress: bool = False, **source_options) -> RecordResult:
    """Record a frame source to a video file.

    Parameters
    ----------
    spec : str, int or path
        Any `tactip.sources.open_source` spec: a camera index or ``/dev/videoN``, ``synthetic`` ...
    out_path : str or path
        ``.mp4`` (MPEG-4) or ``.avi`` (Motion-JPEG).
    seconds, frames : float, int, optional
        Stop after this long or this many frames (a live source needs one of them); a finite source
        also stops at its end.
    frame_rate : float, optional
        Frames/s for the file header; default the source's, else 30.
    progress : bool
        Show a progress bar (frames).
    **source_options
        Passed to the source (e.g. ``exposure=50``).

    Returns
    -------
    RecordResult

    Raises
    ------
    SourceError
        The source cannot be opened, stops delivering, or is live with no limit given.
    OSError
        The output cannot be written (checked before recording).
    """
    import cv2
    from _shared.progress import progress_bar as tqdm

    from tactip.sources import ThreadedReader, open_source

    out_path = pathlib.Path(out_path)
    fourcc = _FOURCC.get(out_path.suffix.lower())
    if fourcc is None:
        raise SourceError(f"cannot record to {str(out_path)!r}: use a .mp4 or .avi file")
    if seconds is not None and not (math.isfinite(seconds) and seconds > 0):
        raise ValueError(f"seconds must be a finite number > 0, got {seconds}")
    if frames is not None and frames < 1:
        raise ValueError(f"frames must be >= 1, got {frames}")
    if frame_rate is not None and not (math.isfinite(frame_rate) and 0.01 <= frame_rate <= 1000):
        # Below 0.01 frames/s the MPEG-4 encoder has no time base and fails to open.
        raise ValueError(f"frame_rate must be in [0.01, 1000] frames/s, got {frame_rate}")
    refuse_overwriting_inputs([out_path], [spec])  # a video file given as the source is an input
    part = claim_output(out_path)
    writer = None
    count, first_s, last_s, dropped = 0, None, None, 0
    try:
        source = open_source(spec, **source_options)
        if source.live:
            if seconds is None and frames is None:
                source.close()
                raise SourceError("a live source needs --seconds or --frames to know when to stop")
            source = ThreadedReader(source, maxsize=64, when_full="drop")
        rate = float(frame_rate or source.frame_rate or 30.0)
        width, height = source.frame_size
        writer = cv2.VideoWriter(str(part), cv2.VideoWriter_fourcc(*fourcc), rate, (width, height), True)
        if not writer.isOpened():
            raise OSError(f"cannot write {str(out_path)!r}: no {fourcc} encoder in this OpenCV build")
        total = frames if frames is not None else (round(seconds * rate) if seconds is not None else None)
        with source, tqdm(total=total, unit="frame", desc="record", disable=not progress) as bar:
            while frames is None or count < frames:
                frame = source.read()
                if frame is None:
                    break
                # Frame time stamps (monotonic on a camera, from the frame rate on a recording) end it.
                if seconds is not None and first_s is not None and frame.timestamp_s - first_s >= seconds:
                    break
                image = frame.image if frame.image.ndim == 3 else cv2.cvtColor(frame.image, cv2.COLOR_GRAY2BGR)
                writer.write(image)
                if count % 32 == 31 and out_of_space(part):  # the writer itself reports nothing
                    raise write_error(OSError(out_of_space(part), "no room"), out_path)
                first_s = frame.timestamp_s if first_s is None else first_s
                last_s = frame.timestamp_s
                count += 1
                bar.update(1)
            dropped = int(getattr(source, "dropped_frames", 0))
        if count == 0:
            raise SourceError(f"{spec!r} delivered no frames")
        writer.release()
        writer = None
        check_video_written(part, out_path, count)  # OpenCV's writer says nothing of a full disk
        with open(part, "rb+") as written:
            os.fsync(written.fileno())
        publish(part, out_path)        # renamed over a file, streamed into /dev/null or a FIFO
    finally:
        if writer is not None:
            writer.release()
        discard_temporary(part)
    return RecordResult(out_path, count, rate, float(last_s - first_s), dropped)
