"""The numeric limits a user's numbers are held to, and one range check for all of them.

The limits that more than one place enforces (a station key and a command-line flag, the station and
the arm) are defined here once; each bounds what would hang or exhaust a station, not what is useful.
"""

from __future__ import annotations

__all__ = ["MAX_BINS", "MAX_LOCATIONS", "MAX_SAMPLES", "MAX_SEED", "MAX_TAPS", "MAX_TAXEL_TAPS", "outside_range"]

MAX_SEED = 2**32 - 1        # random seeds: NumPy's legacy range, which every seeded generator here accepts
MAX_TAPS = 1000             # taps of one inspection or Monte Carlo run ([perception] max_taps, --max-taps)
MAX_LOCATIONS = 1000        # depth (location) classes of a model
MAX_BINS = 10_000           # value bins per feature of a histogram model
MAX_SAMPLES = 1000          # samples per tap feature array
MAX_TAXEL_TAPS = 100_000    # taps per simulated taxel collection


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
