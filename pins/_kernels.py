"""Which implementation the tracker's hot paths run: compiled kernels (`pins._jit`, Numba) or NumPy.

The tracker measures windows and fits tips a few times a frame on arrays of a few to 120 rows,
where each NumPy call's fixed cost (a few us), not the arithmetic, sets the time: ~500 calls a
frame (issue 20, outcome 9). The compiled kernels do each pass in one call, a loop over the windows;
the bookkeeping round them too (`pins._jit_track`: the follow passes' judgements, neighbours' medians,
predictions, carried steps, identities, snap to rest), bit for bit their references.
The NumPy code stays the reference: it runs when the environment variable ``TACTIP_KERNELS`` is
``numpy`` or when Numba cannot be imported, and the tests hold the kernels to it.

Numba is imported, and the kernels loaded (compiled once per machine, then read from their cache
next to `pins._jit`), on the first call that needs them, not on ``import pins``: a command that
does not track pays nothing.
"""

from __future__ import annotations

import os

__all__ = ["compiled"]

_LOADED: list = []  # [the kernels module, or None when Numba cannot be imported], once tried


def compiled():
    """The compiled kernels (the module `pins._jit`), or None: ``TACTIP_KERNELS=numpy`` in the
    environment (read at every call, so a test may switch it), or Numba missing."""
    if os.environ.get("TACTIP_KERNELS") == "numpy":
        return None
    if not _LOADED:
        try:
            from . import _jit
        except ImportError:  # (Numba or its LLVM missing: the NumPy reference)
            _jit = None
        _LOADED.append(_jit)
    return _LOADED[0]
