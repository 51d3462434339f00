"""Recorded video: record a camera to a file, replay a file through the pin pipeline, decide on its taps.

- `tactip.replay.record`: `record_video`, a camera (or any source) to MP4 or AVI;
- `tactip.replay.video`: `replay_video`, a recording to pin positions, contacts and features in HDF5,
  and an annotated video (`tactip.replay.result.ReplayResult`: what it found, and its summary);
  `track_video`, the same tracking, contacts and features without a file (``tactip dataset build``);
- `tactip.replay.decisions`: a passive perceiver deciding the gap width from a replay's taps.
"""

__all__: list[str] = []
