"""deformctl.version: the installed distribution's version, read on first use."""

from __future__ import annotations

import importlib.metadata
import re

import pytest

import deformctl
from deformctl import version


def test_the_version_is_the_installed_distributions() -> None:
    installed = importlib.metadata.version("deformctl")
    assert version.version_string() == installed
    assert version.__version__ == installed
    assert deformctl.__version__ == installed
    assert re.fullmatch(r"\d+\.\d+\.\d+\S*", installed), installed  # PEP 440-ish, not unknown


def test_other_names_are_attribute_errors() -> None:
    with pytest.raises(
        AttributeError, match=r"^module 'deformctl\.version' has no attribute 'nope'$"
    ):
        _ = version.nope  # type: ignore[attr-defined]
