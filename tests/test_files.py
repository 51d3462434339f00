"""_shared: atomic writes, write errors named for what they are, outputs never over inputs."""

import errno
import os

import pytest

from _shared import atomic_path, refuse_overwriting_inputs, write_error


def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path):
    out = tmp_path / "out.txt"
    out.write_text("old")
    with pytest.raises(OSError, match="disk full while writing .*out.txt"):
        with atomic_path(out) as tmp:
            tmp.write_text("half")
            raise OSError(errno.ENOSPC, "No space left on device")
    assert out.read_text() == "old" and sorted(p.name for p in tmp_path.iterdir()) == ["out.txt"]


def test_a_finished_write_replaces_the_file(tmp_path):
    out = tmp_path / "out.txt"
    out.write_text("old")
    with atomic_path(out) as tmp:
        assert tmp.parent == tmp_path and tmp.name.startswith(".out.") and tmp.suffix == ".txt"
        tmp.write_text("new")
    assert out.read_text() == "new" and sorted(p.name for p in tmp_path.iterdir()) == ["out.txt"]


@pytest.mark.parametrize("exc, words", [
    (OSError(errno.ENOSPC, "No space left on device"), "disk full while writing"),
    (OSError(errno.EACCES, "Permission denied"), "permission denied writing"),
    (OSError(errno.EFBIG, "File too large"), "file size limit reached"),
    (OSError("Can't synchronously write data (file write failed: errno = 28, error message = 'No space')"),
     "disk full while writing"),
    (RuntimeError("database or disk is full"), "disk full while writing"),
])
def test_write_errors_are_named_for_what_they_are(exc, words):
    error = write_error(exc, "data/train.h5")
    assert words in error.strerror and "data/train.h5" in error.strerror


def test_an_output_may_not_be_an_input_under_any_name(tmp_path):
    data = tmp_path / "train.h5"
    data.write_bytes(b"taps")
    os.link(data, tmp_path / "hard.h5")
    os.symlink(data, tmp_path / "soft.h5")
    for alias in (data, tmp_path / "hard.h5", tmp_path / "soft.h5", tmp_path / "sub" / ".." / "train.h5"):
        with pytest.raises(FileExistsError, match="is the input"):
            refuse_overwriting_inputs([alias], [data])
    with pytest.raises(FileExistsError, match="same file"):
        refuse_overwriting_inputs([tmp_path / "a.h5", tmp_path / "a.h5"], [])
    refuse_overwriting_inputs([tmp_path / "model.h5", None], [data, None, 0])   # different files: fine
    assert data.read_bytes() == b"taps"
