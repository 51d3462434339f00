"""The runnable examples in the perception package's docstrings stay true."""

import doctest
import importlib

import pytest

MODULES = ["perception.dataset", "perception.bayes", "perception.policies", "perception.adaptive", "perception.baselines"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
