"""Replay's output reaches the disk once: synced by `publish` before the rename, not a second time before it."""

import errno
import os

import cv2
import numpy as np
import pytest

import _shared.files
from tactip.replay.video import replay_video
from tactip.sim import Contact, SyntheticTacTip


def _write(path, frames: int = 12) -> None:
    sensor = SyntheticTacTip(pins=127, seed=3, image_size=(320, 240))
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), 20.0, (320, 240), True)
    for k in range(frames):
        image = sensor.render(Contact(3.0 * np.sin(np.pi * k / frames), 2.0, 0.0)).image
        writer.write(cv2.cvtColor(image, cv2.COLOR_GRAY2BGR) if image.ndim == 2 else image)
    writer.release()


def _synced(monkeypatch, fail: bool = False) -> list:
    """Record the name of every file os.fsync flushes (and fail on the HDF5 output's, when asked)."""
    synced, real = [], os.fsync

    def fsync(fd):
        name = os.path.basename(os.readlink(f"/proc/self/fd/{fd}"))
        synced.append(name)
        if fail and name.endswith(".h5"):
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(fd)

    monkeypatch.setattr(os, "fsync", fsync)
    return synced


@pytest.mark.skipif(not os.path.isdir("/proc/self/fd"), reason="names the synced files through /proc")
def test_the_result_is_synced_once_then_renamed(tmp_path, monkeypatch):
    video = tmp_path / "tap.mp4"
    _write(video)
    synced = _synced(monkeypatch)
    replay_video(video, tmp_path / "r.h5")
    files = [name for name in synced if name.endswith(".h5")]
    assert len(files) == 1  # the temporary file, by publish (then its folder); not also just before
    assert (tmp_path / "r.h5").is_file() and synced.count(tmp_path.name) == 1


@pytest.mark.skipif(not os.path.isdir("/proc/self/fd"), reason="names the synced files through /proc")
def test_a_full_disk_at_the_sync_is_named_and_keeps_the_old_result(tmp_path, monkeypatch):
    video = tmp_path / "tap.mp4"
    _write(video)
    out = tmp_path / "r.h5"
    out.write_bytes(b"old result")
    _synced(monkeypatch, fail=True)
    assert _shared.files.os.fsync is os.fsync  # publish syncs through the patched function
    with pytest.raises(OSError, match="disk full while writing"):
        replay_video(video, out)
    assert out.read_bytes() == b"old result" and sorted(p.name for p in tmp_path.iterdir()) == ["r.h5", "tap.mp4"]
