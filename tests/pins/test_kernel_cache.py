"""The kernels' cache is dropped when any kernel source changed (`pins._kernels._fresh_cache`).

Numba checks a cached kernel against its own file only; a kernel calling one in another kernel module would
keep stale machine code after that module changed (an edit, an upgrade).
"""

import hashlib
import pathlib
from types import SimpleNamespace

import pins
from pins import _kernels


def _kernels_cached_in(folder):
    """A stand-in kernel module whose one dispatcher caches in `folder`."""
    return SimpleNamespace(kernel=SimpleNamespace(_cache=SimpleNamespace(_cache_path=str(folder))))


def _digest():
    sources = sorted(pathlib.Path(pins.__file__).parent.glob("_jit*.py"))
    return hashlib.sha256(b"".join(path.read_bytes() for path in sources)).hexdigest()


def test_a_changed_source_drops_every_kernel_modules_cache_and_keeps_others(tmp_path):
    stale = [tmp_path / "_jit_rest.rest_judge-40.py311.nbi", tmp_path / "_jit_track._like-10.py311.1.nbc"]
    other = tmp_path / "other.kernel-3.py311.nbi"
    for path in (*stale, other):
        path.write_bytes(b"old")
    (tmp_path / _kernels._STAMP).write_text("a digest of other sources")
    _kernels._fresh_cache(_kernels_cached_in(tmp_path))
    assert not any(path.exists() for path in stale)
    assert other.exists()
    assert (tmp_path / _kernels._STAMP).read_text() == _digest()


def test_the_same_sources_keep_the_cache(tmp_path):
    cached = tmp_path / "_jit._corner-28.py311.nbi"
    cached.write_bytes(b"current")
    (tmp_path / _kernels._STAMP).write_text(_digest())
    _kernels._fresh_cache(_kernels_cached_in(tmp_path))
    assert cached.read_bytes() == b"current"


def test_a_cache_without_a_digest_is_dropped_and_a_missing_folder_made(tmp_path):
    cached = tmp_path / "_jit._corner-28.py311.nbi"
    cached.write_bytes(b"of unknown sources")
    _kernels._fresh_cache(_kernels_cached_in(tmp_path))
    assert not cached.exists()
    _kernels._fresh_cache(_kernels_cached_in(tmp_path / "new"))
    assert (tmp_path / "new" / _kernels._STAMP).read_text() == _digest()
