"""The frame's motion field from the pins placed first: guesses for the others (issue 20: slides).

Each frame the tracker's windows start at the pins' constant-velocity guesses. Where the pad
accelerates (a slide's lift: the skin springs back to rest, its pins speeding from nothing to most of a
spacing a frame within a few frames), the guesses of the fastest pins lie a third of a spacing or more
off, and LK from them, or a window, lands on a neighbour's tip. Session 19 (slide14) measured where the
swaps of `bench_conditions`' slides (120 frames/s, seeds 0-5) begin: tactip-127 465 of 486 onsets in
lifts, 376 of them placed by LK from guesses 0.25-0.6 spacings off; tactip-331 269 of 603 in lifts
(the others in the drag, in skin squeezed until tips merge, placed by the follow passes).

A skin's motion is smooth and, through a stroke, keeps its shape: the field of displacements from rest
grows as the plate drags and shrinks back as it lifts (a slide's skin moves as ``D(q, t) = S(t) f(q)``
and a press's as its own shape: two modes, each with its own time course). So a pin's step is, across
the pad, about a multiple of its displacement from rest at the last frame plus a multiple of its last step
and a shift (on the renders, fitted to every pin, within 0.3 spacings in the fastest lift frames, where the
constant-velocity guess is up to 0.8 off). `spring_steps` fits that function (two scalars and a shift in x
and y: 4 coefficients, least squares, once more without the pins far from the first fit) to the pins placed
from their guesses in this frame (the slow ones, far from the contact) and predicts the others: the fast
pins' steps scale with their large displacements. The pins fitted lie near rest and step little, so an
affine function of both (5 x 2 coefficients, sessions 19-22) was ill-conditioned: fitted to them it held,
with -8 times the last step in x, and stepped the pins needing LK by about 0.2 spacings (median, tactip-127 seed 4's
second lift of `tests/pins/test_track_lift_field.py`), too little to be used (`_LEAST_STEP`). Where no
plain fit holds (in a lift's first frame a fifth of the pins placed may sit where they were while their tips
sprang back half a spacing), a trimmed one (`_trimmed`) is tried. `pins.track.PinTracker` runs it only on
frames where many pins were not placed from their guesses (those LK looks for: a still pad costs nothing),
starts LK there from the field, and takes off the pins placed more than half a spacing from it (on another
pin's tip).

Not in a drag filmed slowly: at 30 frames/s the skin under the plate steps a spacing a frame, beyond what any guess
keeps from a neighbour's tip, and the field fitted to the slow skin around it steps those pins by a fifth of that;
its guesses there swapped more pins than constant velocity's (session 19, slide15: `bench_conditions` slides, apart
pin-frames, seeds 0-5, tactip-127 4893 -> 5689). So the field is used only where it steps the pins not placed by a
third of a spacing or more (median; a lift's spring-back: `_LEAST_STEP`).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ._window import _squared_norm

# The fit is used when at least this many pins were placed from their guesses (10 coefficients), ...
_LEAST_PINS = 12
# ... and, after one refit without the pins farther than `_OUTLIER_FRACTION` of the spacing from the first
# fit, at least `_HOLD_SHARE` of them lie within `_HOLD_FRACTION` of the spacing of it.
_OUTLIER_FRACTION = 0.15
_HOLD_FRACTION = 0.1
_HOLD_SHARE = 0.5
# Where the field holds, a pin placed farther than this fraction of the spacing from where it puts the pin is on
# another's tip (its nearest neighbours lie a spacing away): LK looks for it from there; ...
_DISAGREE_FRACTION = 0.5
# ... and guesses come from the field only for the pins it steps by at most this many spacings, ...
_FIELD_REACH = 1.0
# ... on frames where it steps the pins not placed by at least this many spacings (median). A field that moves them
# less adds nothing to their constant-velocity guesses: they were not placed from those, so they move in a way the
# pins placed do not share (the skin under a plate dragged at 30 frames/s steps a spacing a frame, the skin around
# it a fifth), and the field's small steps would pull their guesses back towards standing still. A lift's spring-back
# moves the whole skin the field's way (its median step 0.45-0.67 spacings in tactip-127's lifts at 120 frames/s).
_LEAST_STEP = 0.3
# Where no plain fit holds, one more of least trimmed squares: refitted to this share of the pins nearest the last fit,
# at most this many times (a fifth of the pins placed in a lift's first frame may lag their tips by half a spacing).
_TRIM_SHARE = 0.8
_TRIM_ROUNDS = 6


def spring_steps(rest: np.ndarray, reference: np.ndarray, last_step: np.ndarray, positions: np.ndarray,
                 settled: np.ndarray, which: np.ndarray, spacing_px: float) -> np.ndarray | None:
    """Steps of pins `which` from the frame's motion field, px (L, 2), or None where no field holds.

    Parameters
    ----------
    rest : (N, 2) ndarray
        Pins at rest, px.
    reference : (N, 2) ndarray
        Pins in the last good frame, px (NaN where lost there).
    last_step : (N, 2) ndarray
        Their steps into it, px (NaN where unknown).
    positions : (N, 2) ndarray
        Pins placed in this frame so far, px (NaN where not).
    settled : (N,) ndarray of bool
        Pins whose placements the fit may use (placed from their guesses).
    which : (L,) ndarray of int
        Pins to predict (finite `reference`).
    spacing_px : float
        Pin spacing at rest, px.

    Returns
    -------
    steps : (L, 2) ndarray of float64 or None
        ``reference[which] + steps`` is where the field puts them; None when fewer than `_LEAST_PINS`
        pins settled or the field does not hold on them.

    Examples
    --------
    >>> rest = np.array([[x, y] for x in range(0, 70, 10) for y in range(0, 70, 10)], float)
    >>> reference = rest + 0.3 * (rest - 30.0)        # the skin spread from (30, 30) ...
    >>> now = rest + 0.15 * (rest - 30.0)             # ... and half way back
    >>> settled = np.abs(rest - 30.0).max(axis=1) <= 20   # the slow pins near the centre were placed
    >>> still = np.zeros_like(rest)                  # (the pad had stopped: no last step)
    >>> steps = spring_steps(rest, reference, still, np.where(settled[:, None], now, np.nan), settled,
    ...                      np.array([0, 48]), 10.0)
    >>> np.round(reference[[0, 48]] + steps, 6) + 0.0  # the corners, farthest out: half way back too
    array([[-4.5, -4.5],
           [64.5, 64.5]])
    """
    fit = settled & np.isfinite(positions[:, 0]) & np.isfinite(reference[:, 0]) & np.isfinite(last_step[:, 0])
    if np.count_nonzero(fit) < _LEAST_PINS:
        return None
    x = _spring_design(rest, reference, last_step, fit.nonzero()[0])
    step = (positions[fit] - reference[fit]).T.ravel()  # (the x steps, then the y steps)
    for kept in (np.ones(len(step) // 2, dtype=bool), None):
        if kept is None:  # (no plain fit holds: one trimmed of the pins left behind)
            kept = _trimmed(x, step)
        coefficients = _lstsq(x, step, kept)
        kept = _pin_errors(x @ coefficients - step) <= (_OUTLIER_FRACTION * spacing_px) ** 2
        if np.count_nonzero(kept) < _LEAST_PINS:
            continue
        coefficients = _lstsq(x, step, kept)
        error = _pin_errors(x @ coefficients - step)
        if np.count_nonzero(error <= (_HOLD_FRACTION * spacing_px) ** 2) >= _HOLD_SHARE * len(error):
            return (_spring_design(rest, reference, last_step, which) @ coefficients).reshape(2, -1).T
    return None


def _spring_design(rest: np.ndarray, reference: np.ndarray, last_step: np.ndarray, which: np.ndarray) -> np.ndarray:
    """`spring_steps`' design matrix for pins `which`, (2 L, 4): rows of their x steps, then of their y steps, against
    (displacement from rest, last step, 1 in x, 1 in y), px (an unknown last step: 0)."""
    design = np.zeros((2, len(which), 4))
    design[:, :, 0] = (reference[which] - rest[which]).T
    last = last_step[which]
    design[:, :, 1] = np.where(np.isfinite(last), last, 0.0).T
    design[0, :, 2] = design[1, :, 3] = 1.0
    return design.reshape(-1, 4)


def _lstsq(x: np.ndarray, step: np.ndarray, kept: np.ndarray) -> np.ndarray:
    """Least-squares coefficients (4,) of `spring_steps`' design `x` (2 M, 4) for the steps `step` (2 M,) px of the
    pins `kept` (M,) bool."""
    both = np.concatenate([kept, kept])
    return np.linalg.lstsq(x[both], step[both], rcond=None)[0]


def _pin_errors(residual: np.ndarray) -> np.ndarray:
    """Squared distances (M,) px^2 of the pins' residuals (2 M,) px: x ones, then y ones."""
    return _squared_norm(residual.reshape(2, -1).T)


def _trimmed(x: np.ndarray, step: np.ndarray) -> np.ndarray:
    """Pins (M,) bool of a trimmed least-squares fit of `spring_steps`' design `x` to `step` (as `_lstsq`): refitted
    to the `_TRIM_SHARE` of the pins nearest the last fit until that set stays (at most `_TRIM_ROUNDS` refits;
    concentration steps of least trimmed squares, Rousseeuw and Van Driessen 2006)."""
    kept = np.ones(len(step) // 2, dtype=bool)
    for _ in range(_TRIM_ROUNDS):
        error = _pin_errors(x @ _lstsq(x, step, kept) - step)
        nearest = error <= np.quantile(error, _TRIM_SHARE)
        if np.array_equal(nearest, kept):
            break
        kept = nearest
    return kept


def field_guesses(rest: np.ndarray, reference: np.ndarray, last_step: np.ndarray, guess: np.ndarray,
                  positions: np.ndarray, need: np.ndarray,
                  spacing_px: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A frame's guesses, positions and pins needing LK, (N, 2) px, (N, 2) px, (N,) bool, with the field's say.

    The field (`spring_steps`, fitted to the pins placed, ``~need``; `rest`, `reference`, `last_step` as there)
    guesses the pins that need LK, and takes off (NaN in `positions`, True in `need`) the placed pins farther than
    `_DISAGREE_FRACTION` of the spacing from it, for the pins it steps by at most `_FIELD_REACH` spacings (a pin
    stepped farther, by slides filmed at 15-30 frames/s, is beyond what a guess keeps from a neighbour's tip: its
    constant-velocity `guess` stands, and `pins._return` at rest). New arrays; the given ones where no field holds
    or where it steps the pins that need LK by less than `_LEAST_STEP` spacings (median): a drag's, not a lift's.
    """
    which = np.isfinite(reference[:, 0]).nonzero()[0]
    steps = spring_steps(rest, reference, last_step, positions, ~need, which, spacing_px)
    if steps is None:
        return guess, positions, need
    needed = need[which]
    if not np.count_nonzero(needed) or np.median(np.sqrt(_squared_norm(steps[needed]))) < _LEAST_STEP * spacing_px:
        return guess, positions, need
    near = _squared_norm(steps) <= (_FIELD_REACH * spacing_px) ** 2
    which, field = which[near], reference[which[near]] + steps[near]
    off = _squared_norm(positions[which] - field) > (_DISAGREE_FRACTION * spacing_px) ** 2  # (NaN: False)
    if np.count_nonzero(off):
        positions, need = positions.copy(), need.copy()
        positions[which[off]] = np.nan
        need[which[off]] = True
    guess = guess.copy()
    guess[which[need[which]]] = field[need[which]]
    return guess, positions, need





# Retired pins (issue 20, outcomes 1 and 2): guessed from this many placed pins nearest at rest, ...
_AROUND_PINS = 8
# ... among its this many nearest at rest (about 4 spacings around), ...
_NEAREST = 48
# ... where their displacements agree: their median distance from their median within this fraction of a spacing
# (a patch moved as one; not the squeezed skin ahead of a slide, whose displacement changes by most of a spacing per
# spacing: there, at 0.1-0.25, tactip-331's apart pin-frames rose, seeds 0-2, 228 -> 254-266).
_AGREE_FRACTION = 0.05


def retired_guesses(rest: np.ndarray, reference: np.ndarray, retired: np.ndarray, spacing_px: float,
                    still: np.ndarray | None = None) -> np.ndarray:
    """Guesses for the `retired` (N,) bool pins, px (L, 2), L of them: each one's rest position moved by the median
    displacement of the `_AROUND_PINS` pins placed in `reference` (N, 2), px, nearest it at `rest` (N, 2), px (among its
    `_NEAREST`); NaN where those displacements do not agree (their median distance from their median beyond
    `_AGREE_FRACTION` of `spacing_px`), or where any of those pins moved in the last frame (`still` (N,) bool given
    and False there: the pad is not at rest around it).

    A retired pin in a patch of lost pins has no neighbour placed (seen22: 53 % of radial-led-120's retired lost
    pin-frames on creeping-skin tours), so `pins._predict` leaves it where it was last seen, 1.5-2 spacings behind the
    skin, and its search is never trusted (`Refiner._trusted`): the patch came back only at rest. `PinTracker` follows
    these guesses as it follows the others' (`pins._identity` keeps each tip to the pin expected nearest).

    Only around still pins (session 23, retire23): guessed mid-motion (a lift's spring-back, 12-16 px a frame on
    tactip-127's creeping-skin tours), a burst of retired pins came back in the frame after the lift with what the slide
    left in the skin, and the contacts' tap signal (a percentile over the pins seen) rose by 2-3 px as the pad stopped:
    no rest taken there, slides merged (tactip-127 seed 6, frame 515: 95 -> 117 pins seen). Kept still, they come back
    in the rest that follows. Against the renderer's truth the tracking barely changes: tactip-127 seeds 0-6, lost
    visible pin-frames main 232836 -> 22862 without this, 29018 with it; apart pin-frames 131 -> 9 and 9.
    """
    which = np.flatnonzero(retired)
    guesses = np.full((len(which), 2), np.nan)
    nearest = _nearest_at_rest(rest)[which]
    placed = np.isfinite(reference[nearest, 0])
    enough = np.count_nonzero(placed, axis=1) >= _AROUND_PINS
    which, nearest, placed = which[enough], nearest[enough], placed[enough]
    if not len(which):
        return guesses
    # The first `_AROUND_PINS` placed ones, nearest first (a stable sort of not-placed: placed first, in order).
    index = np.take_along_axis(nearest, np.argsort(~placed, axis=1, kind="stable")[:, :_AROUND_PINS], axis=1)
    displacement = reference[index] - rest[index]
    shift = np.median(displacement, axis=1)
    spread = np.median(np.sqrt(_squared_norm(displacement - shift[:, None])), axis=1)
    agree = spread <= _AGREE_FRACTION * spacing_px
    if still is not None:
        agree &= still[index].all(axis=1)
    guesses[enough.nonzero()[0][agree]] = rest[which[agree]] + shift[agree]
    return guesses


def _nearest_at_rest(rest: np.ndarray) -> np.ndarray:
    """Each pin's `_NEAREST` nearest others at `rest` (N, 2), px, nearest first: (N, K) int; kept while `rest` is."""
    memo = _nearest_at_rest.__dict__.get("memo")
    if memo is None or memo[0] is not rest:
        k = min(_NEAREST, len(rest) - 1)
        memo = (rest, cKDTree(rest).query(rest, k=k + 1)[1][:, 1:] if k > 0 else np.zeros((len(rest), 0), int))
        _nearest_at_rest.memo = memo
    return memo[1]
