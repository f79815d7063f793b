"""The reproduction of the seed paper and the CI dataset regression, on the bundled datasets.

* :mod:`deformctl.repro.paper`: a lift_results table beside the paper's Table II
  (``python -m deformctl.repro.paper LIFT.parquet``).
* :mod:`deformctl.repro.report`: the ``make reproduce`` report (``python -m
  deformctl.repro.report RUN_DIR``).
* :mod:`deformctl.repro.golden`: the golden population through the pipeline against its expected
  numbers (``python -m deformctl.repro.golden [--update]``).

The bundled data (``datasets/`` in a checkout) is found by :func:`deformctl.resources.dataset_path`
(re-exported here), so all three work from an installed wheel as well as from a checkout.
"""

from __future__ import annotations

from deformctl.resources import dataset_path

__all__ = ["dataset_path"]
