"""One range check for every number a user gives: station keys, arm keys and command-line flags."""

from __future__ import annotations

__all__ = ["outside_range"]


def outside_range(value, low, high=None, *, low_open: bool = False, unit: str = "") -> str | None:
    """None when ``value`` lies in ``[low, high]`` (``(low, high]`` with ``low_open``), else what is accepted.

    The text completes "KEY ...": ``must be in 1..331 pins`` when the value and both bounds are whole
    numbers, ``must be in (0, 500] mm`` otherwise, ``must be >= 1`` without ``high``. NaN is outside
    every range; so are the infinities, unless a bound is infinite.

    Examples
    --------
    >>> outside_range(3, 1, 331, unit="pins") is None
    True
    >>> outside_range(0.0, 0, 500, low_open=True, unit="mm")
    'must be in (0, 500] mm'
    >>> outside_range(400, 1, 331, unit="pins")
    'must be in 1..331 pins'
    >>> outside_range(0, 1)
    'must be >= 1'
    """
    above = low < value if low_open else low <= value
    if above and (high is None or value <= high):
        return None
    suffix = f" {unit}" if unit else ""
    if high is None:
        return f"must be {'>' if low_open else '>='} {low if isinstance(low, int) else format(low, 'g')}{suffix}"
    if all(isinstance(v, int) and not isinstance(v, bool) for v in (value, low, high)):
        return f"must be in {low}..{high}{suffix}"
    return f"must be in {'(' if low_open else '['}{low:g}, {high:g}]{suffix}"
