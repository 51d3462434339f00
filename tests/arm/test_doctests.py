"""The runnable examples in the arm package's docstrings stay true."""

import doctest
import importlib

import pytest

MODULES = ["arm.pose", "arm.world", "arm.tap", "arm.safety", "arm.profile", "arm.sim", "arm.factory", "arm.commissioning"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
