"""tactip.replay.batch and `tactip replay ... --out-dir`: an archive on Dask, past a corrupt file, resumable.

Eight short synthetic recordings (127 pins, 320 x 240 px, one tap each) and one corrupt file. The
embedded cluster of these tests runs its workers as threads of the test process (no processes, no
network); one test starts a real ``dask scheduler`` and ``dask worker`` as subprocesses on 127.0.0.1.
"""

import json
import os
import pathlib
import subprocess
import sys
import time

import cv2
import numpy as np
import pytest

from tactip.cli import main
from tactip.cluster import open_client
from tactip.errors import SourceError, TactipError
from tactip.replay.batch import expand_videos, output_path, replay_batch
from tactip.replay.video import replay_video
from tactip.sim import Contact, SyntheticTacTip

ROOT = pathlib.Path(__file__).resolve().parents[3]
COUNT = 8


def _write_tap(path, seed: int, depth_mm: float) -> None:
    sensor = SyntheticTacTip(pins=127, seed=seed, image_size=(320, 240))
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), 20.0, (320, 240), True)
    for frame in sensor.tap(Contact(depth_mm, 1.0), frame_rate=20.0, rest_before_s=0.1, rest_after_s=0.1):
        writer.write(cv2.cvtColor(frame.image, cv2.COLOR_GRAY2BGR) if frame.image.ndim == 2 else frame.image)
    writer.release()


@pytest.fixture(scope="module")
def archive(tmp_path_factory):
    """A folder of 8 tap videos and a corrupt ``bad.mp4``; each good video's single replay (bytes)."""
    folder = tmp_path_factory.mktemp("archive")
    singles = tmp_path_factory.mktemp("singles")
    expected = {}
    for k in range(COUNT):
        video = folder / f"tap{k}.mp4"
        _write_tap(video, seed=k, depth_mm=2.0 + 0.3 * k)
        replay_video(str(video.resolve()), singles / f"tap{k}.h5")  # what `tactip replay V --out` writes
        expected[f"tap{k}.h5"] = (singles / f"tap{k}.h5").read_bytes()
    (folder / "bad.mp4").write_bytes(np.random.default_rng(0).integers(0, 256, 4000, dtype=np.uint8).tobytes())
    return folder, expected


@pytest.fixture(scope="module")
def client():
    with open_client(workers=2, processes=False) as c:
        yield c


def _h5_differences(a: bytes, b: bytes, limit: int = 8) -> list[str]:
    """What differs between two HDF5 files given as bytes: their datasets and attributes, by name (empty
    when they hold the same). Not their bytes: HDF5 writes some blocks with memory it never cleared
    (a clean-clone run's batch tap0.h5 held the same datasets and attributes as its single replay and
    differed in 224 bytes of such padding, pointer-like values), so equal contents may differ in layout."""
    import io

    import h5py

    found = []
    with h5py.File(io.BytesIO(a), "r") as fa, h5py.File(io.BytesIO(b), "r") as fb:
        def items(f):
            out = {"/": f}  # the file's own attributes too
            f.visititems(lambda name, obj: out.__setitem__(name, obj))
            return out

        ia, ib = items(fa), items(fb)
        for name in sorted(set(ia) | set(ib)):
            if name not in ia or name not in ib:
                found.append(f"{name}: only in {'first' if name in ia else 'second'}")
                continue
            for key in sorted(set(ia[name].attrs) | set(ib[name].attrs)):
                va, vb = ia[name].attrs.get(key), ib[name].attrs.get(key)
                if not np.array_equal(np.asarray(va), np.asarray(vb)):
                    found.append(f"{name}@{key}: {va!r} != {vb!r}"[:300])
            if isinstance(ia[name], h5py.Dataset):
                da, db = ia[name][()], ib[name][()]
                if np.shape(da) != np.shape(db) or not np.array_equal(da, db, equal_nan=da.dtype.kind == "f"):
                    where = "" if np.shape(da) != np.shape(db) else f", first at {np.argwhere(da != db)[:3].tolist()}"
                    found.append(f"{name}: {np.shape(da)} vs {np.shape(db)}{where}")
    return found[:limit]


def _same_as_singles(folder, expected) -> None:
    """Every ``*.h5`` in ``folder`` holds what its single replay holds (by contents, see `_h5_differences`)."""
    written = {p.name: p.read_bytes() for p in folder.glob("*.h5")}
    assert set(written) == set(expected)
    differing = {name: _h5_differences(written[name], expected[name]) for name in expected}
    assert not any(differing.values()), differing


def _mtimes(out):
    return {p.name: p.stat().st_mtime_ns for p in out.glob("*.h5")}


def test_batch_writes_single_replays_names_the_corrupt_file_and_resumes(archive, client, tmp_path):
    folder, expected = archive
    out = tmp_path / "out"
    videos = expand_videos([folder])
    assert [v.name for v in videos] == ["bad.mp4"] + [f"tap{k}.mp4" for k in range(COUNT)]
    first = replay_batch(videos, out, client=client)
    # Every good video's output holds what its single replay holds; the corrupt one is named, nothing of it written.
    _same_as_singles(out, expected)
    assert [(r["video"], r["status"]) for r in first.failed] == [(str(folder / "bad.mp4"), "failed")]
    assert "not a video" in first.failed[0]["error"]
    assert not list(out.glob(".*part*"))
    summary = json.loads((out / "summary.json").read_text())
    assert summary["videos"] == COUNT + 1 and summary["failed"] == 1 and len(summary["rows"]) == COUNT + 1
    written = [r for r in summary["rows"] if r["status"] == "written"]
    assert len(written) == COUNT and all(r["frames"] == 20 and r["pins"] == 127 and r["taps"] == 1 for r in written)
    # A rerun skips the 8 finished files (untouched) and tries the corrupt one again.
    before = _mtimes(out)
    second = replay_batch(videos, out, client=client)
    assert [r["status"] for r in second.rows] == ["failed"] + ["skipped"] * COUNT
    assert _mtimes(out) == before
    assert all(r["frames"] == 20 and r["taps"] == 1 for r in second.rows[1:])
    assert "8 skipped" in second.text() and "1 failed" in second.text()
    # --overwrite replays them again, to the same contents.
    third = replay_batch(videos[1:3], out, client=client, overwrite=True)
    assert [r["status"] for r in third.rows] == ["written", "written"] and not third.failed
    assert not _h5_differences((out / "tap0.h5").read_bytes(), expected["tap0.h5"])
    assert (out / "tap0.h5").stat().st_mtime_ns != before["tap0.h5"]


def test_the_bar_hears_of_frames_as_the_workers_read_them(archive, client, tmp_path, monkeypatch):
    """With progress, each replay reports its frames as Dask events the batch's bar subscribes to."""
    events = []
    subscribe = client.subscribe_topic

    def spy(topic, handler):
        def record(event):
            events.append(event[1])
            handler(event)
        subscribe(topic, record)

    monkeypatch.setattr(client, "subscribe_topic", spy)
    folder, _ = archive
    result = replay_batch(expand_videos([folder / "tap0.mp4", folder / "tap1.mp4"]), tmp_path, client=client,
                          progress=True)
    frames = sum(r["frames"] for r in result.rows)
    # Reported a few frames at a time (events still in flight when the batch ends are not waited for).
    assert events and all(0 < n <= 10 for n in events) and sum(events) <= frames
    assert len(events) >= 2  # more than one report per batch: the count moves while the videos replay


def test_batch_options_reach_every_replay(archive, client, tmp_path):
    folder, _ = archive
    result = replay_batch([folder / "tap3.mp4"], tmp_path, client=client, n_samples=12, n_pins=10, rest_frame=1)
    single = replay_video(str((folder / "tap3.mp4").resolve()), tmp_path / "single.h5", n_samples=12, n_pins=10,
                          rest_frame=1)
    assert result.rows[0]["status"] == "written" and single.frames == 20
    assert not _h5_differences((tmp_path / "tap3.h5").read_bytes(), (tmp_path / "single.h5").read_bytes())
    with pytest.raises(ValueError, match="n_pins"):
        replay_batch([folder / "tap3.mp4"], tmp_path / "never", client=client, n_pins=0)
    assert not (tmp_path / "never").exists()


def test_an_output_made_from_another_video_is_not_replaced(archive, client, tmp_path):
    folder, expected = archive
    other = tmp_path / "other"
    other.mkdir()
    (other / "tap0.mp4").write_bytes((folder / "tap1.mp4").read_bytes())  # another video of the same name
    replay_batch([folder / "tap0.mp4"], tmp_path / "out", client=client)
    result = replay_batch([other / "tap0.mp4"], tmp_path / "out", client=client)
    assert result.failed and "made from" in result.failed[0]["error"] and "--overwrite" in result.failed[0]["error"]
    assert not _h5_differences((tmp_path / "out" / "tap0.h5").read_bytes(), expected["tap0.h5"])


def test_expand_videos_and_clashing_names(archive, client, tmp_path):
    folder, _ = archive
    assert [v.name for v in expand_videos([str(folder / "tap[12].mp4"), folder / "tap1.mp4"])] == ["tap1.mp4",
                                                                                                    "tap2.mp4"]
    frames = tmp_path / "frames"
    frames.mkdir()
    cv2.imwrite(str(frames / "000.png"), np.zeros((8, 8), np.uint8))
    assert expand_videos([frames]) == [frames.resolve()] and output_path(frames, "o").name == "frames.h5"
    with pytest.raises(SourceError, match="no file matches"):
        expand_videos([str(folder / "*.avi")])
    with pytest.raises(SourceError, match="no such video"):
        expand_videos([folder / "missing.mp4"])
    (tmp_path / "tap0.mp4").write_bytes((folder / "tap0.mp4").read_bytes())
    with pytest.raises(TactipError, match="would both write"):
        replay_batch([folder / "tap0.mp4", tmp_path / "tap0.mp4"], tmp_path / "out", client=client)


def test_cli_refuses_mixed_modes(tmp_path, capsys, archive):
    folder, _ = archive
    cases = [(["replay", str(folder / "tap0.mp4"), str(folder / "tap1.mp4"), "--out", str(tmp_path / "a.h5")],
              "need --out-dir"),
             (["replay", str(folder / "tap0.mp4")], "give --out"),
             (["replay", str(folder / "tap0.mp4"), "--out", str(tmp_path / "a.h5"), "--workers", "2"], "--out-dir"),
             (["replay", str(folder), "--out-dir", str(tmp_path), "--annotate", str(tmp_path / "a.mp4")], "--annotate"),
             (["replay", str(folder), "--out-dir", str(tmp_path), "--workers", "2", "--scheduler", "tcp://x:1"],
              "--workers")]
    for argv, message in cases:
        assert main(argv + ["--quiet"]) == 1
        error = capsys.readouterr().err
        assert error.startswith("tactip replay: error:") and message in error and error.count("\n") == 1
    assert not list(tmp_path.iterdir())


def _dask(*words, env):
    return subprocess.Popen([str(pathlib.Path(sys.executable).parent / "dask"), *words], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


@pytest.fixture
def scheduler(tmp_path):
    """``tcp://127.0.0.1:PORT`` of a `dask scheduler` with one `dask worker`, both started here (and stopped)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])))
    info = tmp_path / "scheduler.json"
    started = [_dask("scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard", "--scheduler-file",
                     str(info), env=env)]
    try:
        deadline = time.monotonic() + 60
        while not info.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        address = json.loads(info.read_text())["address"]
        started.append(_dask("worker", address, "--host", "127.0.0.1", "--nthreads", "1", "--nworkers", "1",
                             "--no-dashboard", "--local-directory", str(tmp_path / "worker"), env=env))
        from distributed import Client

        with Client(address, timeout=60) as client:  # a worker that cannot start fails here, not by hanging
            client.wait_for_workers(1, timeout=60)
        yield address
    finally:
        for process in reversed(started):
            process.terminate()
            try:
                process.wait(timeout=20)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()


def test_cli_batch_on_a_dask_scheduler_and_worker(archive, scheduler, tmp_path, capsys):
    folder, expected = archive
    out = tmp_path / "out"
    assert main(["replay", str(folder), "--out-dir", str(out), "--scheduler", scheduler, "--quiet"]) == 1
    error = capsys.readouterr().err
    assert f"failed: {folder / 'bad.mp4'}: " in error and "1 of 9 videos failed" in error
    _same_as_singles(out, expected)
    rows = json.loads((out / "summary.json").read_text())["rows"]
    assert sorted(r["status"] for r in rows) == ["failed"] + ["written"] * COUNT
    # Resumed on the cluster: only the corrupt file is tried again.
    before = _mtimes(out)
    assert main(["replay", str(folder / "tap*.mp4"), "--out-dir", str(out), "--scheduler", scheduler]) == 0
    assert "8 skipped" in capsys.readouterr().out and _mtimes(out) == before


def test_videos_tracked_together_on_torch_write_the_same_files(archive, client, tmp_path):
    """The batched torch path (CPU torch here): several videos a task, windows measured together, the same files (by contents)."""
    pytest.importorskip("torch")
    folder, expected = archive
    videos = expand_videos([folder])
    result = replay_batch(videos, tmp_path, client=client, device="torch-cpu", together=3)
    _same_as_singles(tmp_path, expected)
    assert [r["status"] for r in result.rows] == ["failed"] + ["written"] * COUNT
    assert "not a video" in result.rows[0]["error"]
    with pytest.raises(ValueError, match="unknown device"):
        replay_batch(videos, tmp_path, client=client, device="tpu")


def test_cli_device_cuda_without_a_gpu_is_one_clear_error(archive, tmp_path, capsys):
    torch = pytest.importorskip("torch")
    if torch.cuda.is_available():
        pytest.skip("this machine has a GPU")
    folder, _ = archive
    assert main(["replay", str(folder), "--out-dir", str(tmp_path / "out"), "--device", "cuda", "--quiet"]) == 1
    error = capsys.readouterr().err
    assert error.startswith("tactip replay: error: --device cuda:") and "no GPU" in error and error.count("\n") == 1
    assert not (tmp_path / "out").exists()
