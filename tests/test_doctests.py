"""The examples in the docstrings of the numerical packages run and give what they show."""
from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest

import seamless_usd.imaging
import seamless_usd.metrics
import seamless_usd.synthesis

MODULES = sorted(
    info.name
    for package in (seamless_usd.metrics, seamless_usd.synthesis, seamless_usd.imaging)
    for info in pkgutil.walk_packages(package.__path__, package.__name__ + ".")
)


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples failed in {name}"
