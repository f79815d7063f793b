"""The reproduction of the seed paper and the CI dataset regression, on the bundled datasets.

* :mod:`deformctl.repro.paper`: a lift_results table beside the paper's Table II
  (``python -m deformctl.repro.paper LIFT.parquet``).
* :mod:`deformctl.repro.report`: the ``make reproduce`` report (``python -m
  deformctl.repro.report RUN_DIR``).
* :mod:`deformctl.repro.golden`: the golden population through the pipeline against its expected
  numbers (``python -m deformctl.repro.golden [--update]``).

The bundled data (``datasets/`` in a checkout) is the package data ``deformctl.datasets``;
:func:`dataset_path` finds it through :mod:`importlib.resources`, so all three work from an
installed wheel as well as from a checkout.
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

__all__ = ["dataset_path"]


def dataset_path(*parts: str) -> Path:
    """The path of a bundled dataset file, e.g. ``dataset_path("paper", "table2.csv")``.

    The datasets are installed as files (not zipped), so this is a real path on disk.
    """
    return Path(str(files("deformctl.datasets").joinpath(*parts)))
