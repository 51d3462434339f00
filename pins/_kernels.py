"""Which implementation the tracker's hot paths run: compiled kernels (`pins._jit`, Numba) or NumPy.

The tracker measures windows and fits tips a few times a frame on arrays of a few to 120 rows,
where each NumPy call's fixed cost (a few us), not the arithmetic, sets the time: ~500 calls a
frame (issue 20, outcome 9). The compiled kernels do each pass in one call, a loop over the windows;
the bookkeeping round them too (`pins._jit_track`: the follow passes' judgements, neighbours' medians,
predictions, carried steps, identities, snap to rest), bit for bit their references.
The NumPy code stays the reference: it runs when the environment variable ``TACTIP_KERNELS`` is
``numpy`` (read once, when `pins._kernels` is imported: `compiled` runs ~17 times a frame, and reading the
environment each time cost ~4 % of an update) or after ``choose("numpy")``, or when Numba cannot be imported;
the tests hold the kernels to it (switching with `choose`).

Numba is imported, and the kernels loaded (compiled once per machine, then read from their cache
next to `pins._jit`), on the first call that needs them, not on ``import pins``. Since session 23 the field
search's lattice judgement is one of them (`pins._jit_judge`), so `tactip detect` and `calibrate` load Numba too:
a process's first `pins.find_pin_field` costs ~0.45-0.5 s of CPU, not ~0.2 (Numba's import and the kernels' cache,
once per process); replay loaded them anyway.

Numba's cache is checked against each kernel's own file only: a kernel that calls one in another module
(`pins._jit_rest` and `pins._jit_pairs` call `pins._jit_track`'s and `pins._jit`'s) keeps its cached code
when only that other module changes (Numba's documented limit). So the first load in a process compares a
digest of every kernel module's source (``pins/_jit*.py``) with the one stored beside the cache and, when they
differ (an edit, an upgrade), drops the kernels' cached code first (`_fresh_cache`).
"""

from __future__ import annotations

import hashlib
import importlib
import os
import pathlib

__all__ = ["choose", "compiled"]

_LOADED: dict = {}  # kernel module name -> the module, or None when Numba cannot be imported; once tried
# Whether `compiled` gives the NumPy reference: ``TACTIP_KERNELS=numpy`` at import, then `choose`.
_NUMPY = os.environ.get("TACTIP_KERNELS") == "numpy"


def choose(kernels: str | None = None) -> str:
    """Which code the tracker runs from now on: ``"numpy"`` (the NumPy reference) or ``"compiled"`` (the
    kernels, where Numba imports); None reads ``TACTIP_KERNELS`` again, as at import. Returns the choice it
    replaced, so that a test can put it back (``choose(choose("numpy"))``)."""
    global _NUMPY
    before = "numpy" if _NUMPY else "compiled"
    if kernels is None:
        kernels = os.environ.get("TACTIP_KERNELS", "compiled")
    _NUMPY = kernels == "numpy"
    return before


def compiled(module: str = "_jit"):
    """The compiled kernels (the module `pins._jit`, or ``pins.<module>``: ``"_jit_pairs"`` for the pair fit),
    or None: the NumPy reference chosen (``TACTIP_KERNELS=numpy`` when `pins` was imported, or `choose`), or
    Numba missing. Loaded on the first call that needs them."""
    if _NUMPY:
        return None
    if module not in _LOADED:
        try:
            _LOADED[module] = importlib.import_module(f"{__package__}.{module}")
        except ImportError:  # (Numba or its LLVM missing: the NumPy reference)
            _LOADED[module] = None
        else:
            _fresh_cache(_LOADED[module])
    return _LOADED[module]


_STAMP = "_jit_kernels.sha256"  # the kernel sources' digest, in the cache's folder


def _fresh_cache(kernels) -> None:
    """Drop every kernel module's cached machine code (``_jit*.nbi``, ``_jit*.nbc``) when the kernel sources
    changed since the digest stored beside it was written, then store theirs. Called once a module is imported,
    before any kernel runs (Numba reads its cache at a kernel's first call). Unwritable caches are left as they
    are (Numba then compiles in memory)."""
    sources = sorted(pathlib.Path(__file__).parent.glob("_jit*.py"))
    digest = hashlib.sha256(b"".join(path.read_bytes() for path in sources)).hexdigest()
    dispatchers = [value for value in vars(kernels).values() if hasattr(value, "_cache")]
    folder = getattr(getattr(dispatchers[0], "_cache", None), "_cache_path", None) if dispatchers else None
    if folder is None:
        return
    stamp = pathlib.Path(folder) / _STAMP
    try:
        if stamp.read_text() == digest:
            return
    except OSError:
        pass
    try:
        for cached in [*stamp.parent.glob("_jit*.nbi"), *stamp.parent.glob("_jit*.nbc")]:
            cached.unlink(missing_ok=True)
        stamp.parent.mkdir(parents=True, exist_ok=True)
        stamp.write_text(digest)
    except OSError:
        pass
