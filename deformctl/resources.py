"""The files bundled with the package: the datasets (``datasets/`` in a checkout).

The bundled data is the package data ``deformctl.datasets``; :func:`dataset_path` finds it through
:mod:`importlib.resources`, so the paper reproduction, the golden regression, the paper's objects
(:func:`deformctl.population.paper_objects`) and the presets' calibration work from an installed
wheel as well as from a checkout.
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
