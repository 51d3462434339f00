"""Pin displacements from a rest frame (paper 002, III-A.3).

The sensor signal of a TacTip is how far each pin has moved from where it was at rest, off
contact. The tracker gives absolute positions, so the displacement is a difference from the rest
positions; a stream of frame-to-frame flows integrates to the same thing. Lost pins (NaN)
stay NaN: an unknown position is never replaced by a guess here (see `pins.features.fill_lost`).
"""

from __future__ import annotations

import numpy as np

from .errors import ShapeError

__all__ = ["displacement_from_rest", "integrate_flow", "displacement_magnitude"]


def displacement_from_rest(positions: np.ndarray, rest_positions: np.ndarray) -> np.ndarray:
    """Displacement of each pin from its rest position.

    Parameters
    ----------
    positions : (N, 2) or (T, N, 2) ndarray
        Pin positions (x, y), px, of one frame or of T frames; NaN where lost.
    rest_positions : (N, 2) ndarray
        Positions in the rest frame (no contact), px.

    Returns
    -------
    displacements : ndarray, same shape as `positions`
        (dx, dy), px; NaN where lost.

    Examples
    --------
    >>> displacement_from_rest(np.array([[11.0, 20.5]]), np.array([[10.0, 20.0]]))
    array([[1. , 0.5]])
    """
    positions = np.asarray(positions, dtype=np.float64)
    rest_positions = np.asarray(rest_positions, dtype=np.float64)
    if rest_positions.ndim != 2 or rest_positions.shape[1] != 2:
        raise ShapeError(f"rest_positions must have shape (N, 2), got {rest_positions.shape}")
    if positions.shape[-2:] != rest_positions.shape or positions.ndim not in (2, 3):
        raise ShapeError(f"positions must have shape {rest_positions.shape} or (T, *{rest_positions.shape}), "
                         f"got {positions.shape}")
    return positions - rest_positions


def integrate_flow(flows: np.ndarray) -> np.ndarray:
    """Displacements from the rest frame by integrating frame-to-frame flows.

    Parameters
    ----------
    flows : (T, N, 2) ndarray
        Motion of each pin from frame t-1 to frame t, px; ``flows[0]`` is the motion from the rest
        frame to the first frame. NaN where a pin was lost.

    Returns
    -------
    displacements : (T, N, 2) ndarray
        Cumulative displacement from the rest frame, px. Once a pin's flow is NaN its
        displacement stays NaN: the integral is unknown from then on.
    """
    flows = np.asarray(flows, dtype=np.float64)
    if flows.ndim != 3 or flows.shape[2] != 2:
        raise ShapeError(f"flows must have shape (T, N, 2), got {flows.shape}")
    return np.cumsum(flows, axis=0)


def displacement_magnitude(displacements: np.ndarray) -> np.ndarray:
    """Length of each displacement vector, px (NaN where lost).

    Parameters
    ----------
    displacements : (..., 2) ndarray
        (dx, dy), px.

    Returns
    -------
    magnitude : (...) ndarray
    """
    displacements = np.asarray(displacements, dtype=np.float64)
    if displacements.shape[-1:] != (2,):
        raise ShapeError(f"displacements must end in a (dx, dy) axis of 2, got shape {displacements.shape}")
    return np.hypot(displacements[..., 0], displacements[..., 1])
