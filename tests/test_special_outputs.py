"""Outputs that are not regular files (issue 22): streamed into, never renamed over, never a hang.

Every case runs in a temporary folder: a FIFO, a symlink to this process's standard output, and (as
root) a character device made with mknod that behaves as /dev/null, never the machine's own /dev.
"""

import os
import stat
import subprocess
import sys
import threading

import pytest

from perception import save_dataset
from tactip.cli import main
from tests.perception.synthetic import gap_dataset

GRID = dict(depths=3, widths=2, samples=5, dims=4, legible_from=0.0)
ROOT = os.geteuid() == 0


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    root = tmp_path_factory.mktemp("special")
    save_dataset(root / "train.h5", gap_dataset(seed=1, taps_per_class=2, **GRID))
    save_dataset(root / "test.h5", gap_dataset(seed=2, taps_per_class=2, **GRID))
    assert main(["train", str(root / "train.h5"), "--out", str(root / "model.h5"), "--locations", "3"]) == 0
    return root


def _tactip(*argv, cwd, stdout=subprocess.PIPE, timeout=120):
    return subprocess.run([sys.executable, "-m", "tactip.cli", *map(str, argv)], cwd=cwd, stdout=stdout,
                          stderr=subprocess.PIPE, text=True, timeout=timeout)


def _validate_json(files, out):
    return ["validate", files / "model.h5", files / "test.h5", "--runs", "50", "--thresholds", "0.5", "--policy",
            "stationary", "--quiet", "--json", out]


def test_a_fifo_with_a_reader_receives_the_output_and_stays_a_fifo(files, tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    received = []
    reader = threading.Thread(target=lambda: received.append(open(fifo, "rb").read()), daemon=True)
    reader.start()
    assert main([str(a) for a in _validate_json(files, fifo)]) == 0
    reader.join(60)
    assert b'"threshold": 0.5' in received[0]
    assert stat.S_ISFIFO(os.stat(fifo).st_mode) and sorted(p.name for p in tmp_path.iterdir()) == ["pipe"]


def test_a_fifo_nobody_reads_is_refused_at_once_and_the_result_kept(files, tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    done = _tactip(*_validate_json(files, fifo), cwd=tmp_path, timeout=120)    # a hang fails by the timeout
    assert done.returncode == 1
    assert "FIFO that no process is reading" in done.stderr and "Traceback" not in done.stderr
    kept = done.stderr.split("kept in ")[1].strip().strip("'")
    assert b'"threshold": 0.5' in open(kept, "rb").read()                          # nothing lost
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)


def test_a_link_to_standard_output_is_written_through_not_replaced(files, tmp_path):
    link = tmp_path / "stdout"
    link.symlink_to("/proc/self/fd/1")
    with open(tmp_path / "captured", "w") as captured:                          # as `--json LINK > captured`
        done = _tactip(*_validate_json(files, link), cwd=tmp_path, stdout=captured)
    assert done.returncode == 0, done.stderr
    assert '"threshold": 0.5' in (tmp_path / "captured").read_text()
    assert link.is_symlink() and os.readlink(link) == "/proc/self/fd/1"
    piped = _tactip(*_validate_json(files, link), cwd=tmp_path)                  # as `--json LINK | wc`
    assert piped.returncode == 0 and '"threshold": 0.5' in piped.stdout
    dash = _tactip(*_validate_json(files, "-"), cwd=tmp_path)                    # `-` is standard output
    assert dash.returncode == 0 and '"threshold": 0.5' in dash.stdout and not (tmp_path / "-").exists()


def test_a_link_to_a_file_replaces_the_file_and_keeps_the_link(files, tmp_path):
    (tmp_path / "real.json").write_text("old")
    (tmp_path / "link.json").symlink_to("real.json")
    assert main([str(a) for a in _validate_json(files, tmp_path / "link.json")]) == 0
    assert (tmp_path / "link.json").is_symlink()
    assert '"threshold": 0.5' in (tmp_path / "real.json").read_text()


@pytest.mark.skipif(not ROOT, reason="mknod of a device needs root")
def test_a_character_device_is_written_into_and_a_block_device_refused(files, tmp_path, capsys):
    null = tmp_path / "null"
    os.mknod(null, stat.S_IFCHR | 0o666, os.makedev(1, 3))                      # the /dev/null device
    assert main(["train", str(files / "train.h5"), "--out", str(null), "--locations", "3"]) == 0
    assert stat.S_ISCHR(os.stat(null).st_mode) and os.stat(null).st_rdev == os.makedev(1, 3)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["null"]                # nothing created beside it
    block = tmp_path / "disk"
    os.mknod(block, stat.S_IFBLK | 0o600, os.makedev(7, 200))
    with pytest.raises(SystemExit) as exit_:
        main(["train", str(files / "train.h5"), "--out", str(block), "--locations", "3"])
    assert exit_.value.code == 2 and "is a block device" in capsys.readouterr().err
    assert stat.S_ISBLK(os.stat(block).st_mode)
