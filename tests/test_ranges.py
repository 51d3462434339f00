"""_shared.ranges: one range check, and the three places that refuse numbers all say it the same way."""

import argparse
import doctest
import math

import pytest

import _shared.ranges
from _shared import outside_range


def test_docstring_examples():
    result = doctest.testmod(_shared.ranges)
    assert result.attempted > 0 and result.failed == 0


@pytest.mark.parametrize("value, inside", [(0.0, False), (1e-9, True), (5.0, True), (5.0 + 1e-9, False),
                                           (math.nan, False), (math.inf, False), (-math.inf, False)])
def test_a_half_open_range(value, inside):
    assert (outside_range(value, 0.0, 5.0, low_open=True, unit="mm") is None) == inside


def test_station_arm_and_command_line_refuse_with_the_same_words():
    from arm.config import arm_config_from_table
    from arm.errors import ArmConfigError
    from tactip.cli._types import float_in_range, int_in_range

    phrase = outside_range(7.5, 0, 5, unit="s")
    assert phrase == "must be in [0, 5] s"
    with pytest.raises(argparse.ArgumentTypeError, match=r"must be in \[0, 5\] s, got 7.5"):
        float_in_range(0, 5, unit="s")("7.5")
    with pytest.raises(argparse.ArgumentTypeError, match=r"must be in 1\.\.3, got 4"):
        int_in_range(1, 3)("4")
    table = {"backend": "sim", "workspace": [[-20.0, -20.0, -8.0], [200.0, 40.0, 40.0]],
             "max_tap_depth": 5.0, "tap": {"dwell": 100000}}
    with pytest.raises(ArmConfigError) as refused:
        arm_config_from_table(table)
    assert "[arm.tap] dwell: must be in [" in str(refused.value) and "got 100000" in str(refused.value)
