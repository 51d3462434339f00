"""Replay's luma-to-grey lookup compiled (Numba): two pixels a lookup (`tactip.replay.luma.look_up`)."""

from __future__ import annotations

from numba import njit


@njit(cache=True, nogil=True, boundscheck=False)
def look_up_pairs(pixels, pairs):
    """Each uint16 of `pixels` (two uint8 pixels, in place) replaced by its entry in the (65536,) uint16 `pairs`
    (`tactip.replay.luma.pair_table`)."""
    for i in range(pixels.size):
        pixels[i] = pairs[pixels[i]]
