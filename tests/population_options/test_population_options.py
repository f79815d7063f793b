"""deformctl.population_options: the population's defaults pass the one rule of each quantity,
and the module imports neither numpy nor pandas (so ``--help`` can state them cheaply)."""

from __future__ import annotations

import inspect
import subprocess
import sys

import pytest

from deformctl.errors import UsageError
from deformctl.population_options import (
    DEFAULT_FRICTION_MU,
    PAPER_POPULATION_SIZE,
    PAPER_TRAIN_SIZE,
)
from deformctl.quantities import FRICTION_MU


def test_the_defaults_pass_the_quantity_rules() -> None:
    assert FRICTION_MU.check(DEFAULT_FRICTION_MU) == 0.5
    with pytest.raises(UsageError, match="--friction-mu"):
        FRICTION_MU.check(0.0)  # the rule bites: F_w = W / 2μ needs μ > 0
    assert isinstance(PAPER_POPULATION_SIZE, int)
    assert isinstance(PAPER_TRAIN_SIZE, int)
    assert 0 < PAPER_TRAIN_SIZE < PAPER_POPULATION_SIZE  # objects remain to test on


def test_the_library_defaults_are_these() -> None:
    from deformctl.model import TrainOptions
    from deformctl.population import make_population

    defaults = inspect.signature(make_population).parameters
    assert defaults["n"].default == PAPER_POPULATION_SIZE
    assert defaults["friction_mu"].default == DEFAULT_FRICTION_MU
    assert TrainOptions().train_size == PAPER_TRAIN_SIZE


def test_importing_it_imports_neither_numpy_nor_pandas() -> None:
    code = (
        "import sys, deformctl.population_options; "
        "print(sorted({'numpy', 'pandas'} & set(sys.modules)))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"
