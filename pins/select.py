"""Selection of the pins used as tactile elements (paper 002, III-A.3).

The paper uses 40 of the 532 pins, at least 4 mm apart, which keeps the information of the
whole pad while removing the redundancy of neighbouring pins. The rule is greedy from the centre
of the pad outwards: each pin, in order of distance from the centre, is taken if it is at least
the separation from every pin already taken. Contact happens at the centre, so the selection
covers the contact region densely and reaches out as far as needed. The result depends only on
the rest positions: the same sensor always gives the same pins.

Two entry points share that rule:

- `select_pins` asks for exactly ``n_pins`` at the separation and raises `PinsError` when the pad
  has no room for them (the station's calibration, which must match a trained model);
- `select_feature_pins` never fails for lack of room: it returns the ``n_pins`` pins at the
  preferred separation when they fit; otherwise ``n_pins`` pins spread as far apart as the pad
  allows (the largest separation at which the same greedy rule still finds ``n_pins``: a
  bisection over the distances between pins), reporting the separation reached; and when the
  sensor has fewer pins than asked, all of them, with a warning. A small pad (40 pins cannot be
  4 mm apart on a 20 mm pad) or a partly seen one (rim pins hidden) still gives feature pins.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from .errors import PinsError, ShapeError

__all__ = ["select_pins", "select_feature_pins", "PinSelection", "median_spacing_px"]


@dataclass(frozen=True)
class PinSelection:
    """The feature pins chosen by `select_feature_pins`, and how far the request was met.

    Attributes
    ----------
    indices : (P,) ndarray of int
        Indices into the rest positions, in selection order (nearest the centre first).
    requested : int
        How many pins were asked for (P < requested only when the sensor has fewer usable pins).
    min_separation_mm : float
        The preferred smallest distance between two selected pins, mm.
    separation_mm : float
        The smallest distance between two selected pins reached, mm (inf for fewer than 2 pins):
        >= `min_separation_mm` when the request was met.
    warning : str
        Empty when `requested` pins at least `min_separation_mm` apart were found; otherwise one
        sentence saying what was done instead.
    """

    indices: np.ndarray
    requested: int
    min_separation_mm: float
    separation_mm: float
    warning: str = ""

    @property
    def n_pins(self) -> int:
        """Number of pins selected, P."""
        return int(len(self.indices))

    @property
    def as_requested(self) -> bool:
        """True when `requested` pins at least `min_separation_mm` apart were selected."""
        return not self.warning

    def describe(self) -> str:
        """One line for a person: how many pins, how far apart, against what was asked."""
        reached = "n/a" if not np.isfinite(self.separation_mm) else f"{self.separation_mm:.2f} mm"
        asked = f" ({self.requested} asked)" if self.n_pins != self.requested else ""
        text = f"{self.n_pins} pins{asked} at least {reached} apart"
        if self.separation_mm < self.min_separation_mm * (1 - 1e-9) and self.n_pins > 1:
            text += f" ({self.min_separation_mm:g} mm asked)"
        return text


def _check(rest_positions, n_pins, min_separation_mm, mm_per_px, centre):
    """Validated (rest, order): rest (N, 2) float64 and the centre-out order of the pins."""
    rest = np.asarray(rest_positions, dtype=np.float64)
    if rest.ndim != 2 or rest.shape[1] != 2:
        raise ShapeError(f"rest_positions must have shape (N, 2), got {rest.shape}")
    if not np.isfinite(rest).all():
        raise PinsError("rest_positions must be finite: select pins from a rest frame where every pin was found")
    if int(n_pins) != n_pins or n_pins < 1:
        raise ValueError(f"n_pins must be a positive integer, got {n_pins}")
    if not (min_separation_mm >= 0 and np.isfinite(min_separation_mm)):
        raise ValueError(f"min_separation_mm must be a finite number >= 0, got {min_separation_mm}")
    if not (mm_per_px > 0 and np.isfinite(mm_per_px)):
        raise ValueError(f"mm_per_px must be a finite number > 0, got {mm_per_px}")
    middle = rest.mean(axis=0) if centre is None else np.asarray(centre, dtype=np.float64)
    if middle.shape != (2,) or not np.isfinite(middle).all():
        raise ValueError(f"centre must be a finite (x, y), got {centre!r}")
    offset = rest - middle
    # Nearest the centre first; ties (symmetric layouts) broken by angle, then index: deterministic.
    order = np.lexsort((np.arctan2(offset[:, 1], offset[:, 0]), np.round(np.hypot(*offset.T), 6)))
    return rest, order


class _Greedy:
    """The centre-out greedy rule at any separation up to `limit_px`, over pairs found once.

    Each pin's neighbours closer than `limit_px` are kept sorted by distance (CSR), so blocking
    the neighbours of a chosen pin at a separation ``s`` is one `searchsorted` on its row.
    """

    def __init__(self, rest: np.ndarray, order: np.ndarray, limit_px: float) -> None:
        self.order = order
        n = len(rest)
        pairs = cKDTree(rest).query_pairs(r=limit_px, output_type="ndarray") if n > 1 else np.empty((0, 2), int)
        i = np.concatenate([pairs[:, 0], pairs[:, 1]])
        j = np.concatenate([pairs[:, 1], pairs[:, 0]])
        distance = np.hypot(*(rest[i] - rest[j]).T)
        by_row = np.lexsort((distance, i))
        self.neighbour, self.distance = j[by_row], distance[by_row]
        self.row_start = np.searchsorted(i[by_row], np.arange(n + 1))
        self.pair_distances = np.unique(np.round(distance, 9))

    def __call__(self, separation_px: float, n_pins: int) -> list[int]:
        """Up to `n_pins` pins, centre out, each at least `separation_px` from those before it."""
        # A hair less than the separation, so that exactly-min spacing is allowed.
        limit = separation_px * (1 - 1e-9)
        blocked = np.zeros(len(self.order), dtype=bool)
        chosen: list[int] = []
        for index in self.order:
            if blocked[index]:
                continue
            chosen.append(int(index))
            if len(chosen) == n_pins:
                break
            start, stop = self.row_start[index], self.row_start[index + 1]
            near = start + np.searchsorted(self.distance[start:stop], limit)
            blocked[self.neighbour[start:near]] = True
        return chosen


def select_pins(rest_positions: np.ndarray, *, n_pins: int = 40, min_separation_mm: float = 4.0,
                mm_per_px: float, centre: tuple[float, float] | None = None) -> np.ndarray:
    """Indices of `n_pins` pins at least `min_separation_mm` apart, from the centre outwards.

    Parameters
    ----------
    rest_positions : (N, 2) ndarray
        Pin positions (x, y) in the rest frame, px.
    n_pins : int
        How many pins to select (paper: 40).
    min_separation_mm : float
        Smallest distance between two selected pins, mm (paper: 4).
    mm_per_px : float
        Scale of the image at the pad, mm per px (e.g. pad diameter / disc diameter).
    centre : (x, y), optional
        Where the selection starts, px; the mean of the rest positions by default.

    Returns
    -------
    indices : (n_pins,) ndarray of int
        Indices into `rest_positions`, in selection order (nearest the centre first).

    Raises
    ------
    PinsError
        Fewer than `n_pins` pins can be that far apart (`select_feature_pins` adapts instead).

    Examples
    --------
    >>> from pins import detect_pins
    >>> from tactip.sim import SyntheticTacTip
    >>> rest = detect_pins(SyntheticTacTip(pins=331, seed=0).render().image)
    >>> chosen = select_pins(rest, n_pins=40, min_separation_mm=4.0, mm_per_px=0.15)
    >>> rest[chosen].shape
    (40, 2)
    """
    rest, order = _check(rest_positions, n_pins, min_separation_mm, mm_per_px, centre)
    separation_px = min_separation_mm / mm_per_px
    chosen = _Greedy(rest, order, separation_px)(separation_px, int(n_pins))
    if len(chosen) < n_pins:
        raise PinsError(f"only {len(chosen)} of {len(rest)} pins are at least {min_separation_mm:g} mm apart; "
                        f"lower n_pins ({n_pins}) or min_separation_mm")
    return np.array(chosen, dtype=np.intp)


def select_feature_pins(rest_positions: np.ndarray, *, n_pins: int = 40, min_separation_mm: float = 4.0,
                        mm_per_px: float, centre: tuple[float, float] | None = None) -> PinSelection:
    """`n_pins` pins at least `min_separation_mm` apart when the pad has room, else as far apart as it allows.

    The rule of `select_pins` (greedy from the centre out) at the preferred separation; when it
    finds fewer than `n_pins`, the same rule at the largest separation that still gives `n_pins`
    (bisection over the distances between pins, all found in one k-d tree query); when the
    sensor has fewer than `n_pins` pins, all of them. Never raises for lack of room.

    Parameters
    ----------
    rest_positions : (N, 2) ndarray
        Pin positions (x, y) in the rest frame, px (finite).
    n_pins : int
        How many pins to select (paper: 40).
    min_separation_mm : float
        Preferred smallest distance between two selected pins, mm (paper: 4).
    mm_per_px : float
        Scale of the image at the pad, mm per px.
    centre : (x, y), optional
        Where the selection starts, px; the mean of the rest positions by default.

    Returns
    -------
    PinSelection
        ``indices`` (P,) in selection order, ``separation_mm`` reached and a ``warning`` when the
        request was not met (empty otherwise).

    Examples
    --------
    >>> from pins import detect_pins
    >>> from tactip.sim import SyntheticTacTip
    >>> rest = detect_pins(SyntheticTacTip(pins=331, seed=0).render().image)
    >>> select_feature_pins(rest, n_pins=40, min_separation_mm=10.0, mm_per_px=0.15).describe()
    '40 pins at least ... mm apart (10 mm asked)'
    """
    rest, order = _check(rest_positions, n_pins, min_separation_mm, mm_per_px, centre)
    n_pins = int(n_pins)
    preferred_px = min_separation_mm / mm_per_px
    greedy = _Greedy(rest, order, preferred_px)
    chosen = greedy(preferred_px, n_pins)
    warning = ""
    if len(rest) < n_pins:
        chosen = [int(i) for i in order]
        warning = (f"only {len(rest)} pins to select from, {n_pins} asked: all {len(rest)} are feature pins")
    elif len(chosen) < n_pins:
        # Largest separation (one of the pair distances below the preferred one) at which the
        # rule still finds n_pins; the smallest candidate blocks nothing, so it always does.
        candidates = greedy.pair_distances
        low, high, best = 0, len(candidates) - 1, [int(i) for i in order[:n_pins]]
        while low <= high:
            middle = (low + high) // 2
            trial = greedy(candidates[middle], n_pins)
            if len(trial) == n_pins:
                best, low = trial, middle + 1
            else:
                high = middle - 1
        chosen = best
    indices = np.array(chosen, dtype=np.intp)
    separation = _smallest_distance(rest[indices]) * mm_per_px
    if not warning and separation < min_separation_mm * (1 - 1e-9):
        warning = (f"{n_pins} pins cannot be {min_separation_mm:g} mm apart on this pad "
                   f"(only {len(greedy(preferred_px, n_pins))} can): selected {n_pins} at least "
                   f"{separation:.2f} mm apart")
    return PinSelection(indices=indices, requested=n_pins, min_separation_mm=float(min_separation_mm),
                        separation_mm=float(separation), warning=warning)


def _smallest_distance(points: np.ndarray) -> float:
    """Smallest distance between two of `points`, px (inf for fewer than 2)."""
    if len(points) < 2:
        return float("inf")
    return float(cKDTree(points).query(points, k=2)[0][:, 1].min())


def median_spacing_px(points: np.ndarray) -> float:
    """Median distance from each pin to its nearest neighbour, px (NaN with fewer than 2 pins).

    Parameters
    ----------
    points : (N, 2) ndarray
        Pin positions (x, y), px.
    """
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 2:
        raise ShapeError(f"points must have shape (N, 2), got {points.shape}")
    if len(points) < 2:
        return float("nan")
    distance, _ = cKDTree(points).query(points, k=2)
    return float(np.median(distance[:, 1]))
