"""The runnable examples in the pins package's docstrings stay true.

Frames come from the synthetic TacTip, imported inside the examples (`tactip.sim` sits above `pins`).
"""

import doctest
import importlib

import pytest

MODULES = ["pins.detect", "pins.disc", "pins.lattice", "pins.track", "pins.lk", "pins.displacement", "pins.select",
           "pins.scale", "pins.features", "pins.segment", "pins.skin", "pins.accel_detect", "pins._tipfit", "pins._rescue",
           "pins._tipprobe", "pins._noise"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    if name.startswith("pins.accel"):  # the accel extra (make test installs it)
        pytest.importorskip("kornia")
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0 and result.failed == 0
