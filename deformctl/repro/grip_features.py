"""What each law network's inputs are worth: a cross-validated comparison of input sets.

``python -m deformctl.repro.grip_features RUN_DIR [--law hc] [--folds 5] [--seed 0]``
    Reads a ``make model`` run's training objects (``RUN_DIR/train/index.parquet`` and
    ``coefficients.parquet``), keeps the rows of ``--law`` whose inputs are all known, and
    fits the law's network as ``train`` does (:func:`deformctl.grip.lawtrain.best_network`: 8-8
    tanh, the best of the seeded restarts on its training rows) on every input set of
    :data:`INPUT_SETS` in ``--folds``-fold cross-validation (one seeded split shared by every
    set). It prints, per set, the median, 90th percentile and max relative error of the
    held-out predictions of L_f. Only the training run's objects are used: the fresh
    population stays for ``grip_model report``.

The result for the bundled model's run is in docs/explanation/model.md.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from deformctl.grip.laws import EARLIER_LAW_FEATURES, LAW_FEATURES

#: The input sets compared per law: today's and every earlier one.
INPUT_SETS: dict[str, dict[str, tuple[str, ...]]] = {
    "hc": {
        "without the shape (before)": EARLIER_LAW_FEATURES["hc"][0],
        "with the shape (today)": LAW_FEATURES["hc"],
    },
    "sls": {"today": LAW_FEATURES["sls"]},
}


def law_rows(run: Path, law: str) -> pd.DataFrame:
    """The training run's rows of ``law`` with every parameter known, sorted by id."""
    from deformctl.artifacts import read_table
    from deformctl.grip.lawtrain import join_laws, known_rows

    index = read_table(run / "train" / "index.parquet", "index_table")
    coef = read_table(run / "train" / "coefficients.parquet", "coefficients")
    joined = join_laws(index, coef)
    return known_rows(law, joined[joined["model"] == law])[0]


def cross_validated_errors(
    law: str, rows: pd.DataFrame, features: Sequence[str], folds: int, seed: int
) -> np.ndarray:
    """``[n]`` held-out relative errors of L_f (prediction / truth - 1) over ``folds`` folds,
    each fold's network fitted as ``train`` fits a law's (best of the seeded restarts)."""
    from threadpoolctl import threadpool_limits

    from deformctl.grip.lawtrain import best_network, law_inputs
    from deformctl.model import TrainOptions

    options = TrainOptions(seed=seed)
    Z, f_w, _ = law_inputs(law, rows, features)
    y = rows["lift_force_n"].to_numpy(dtype=np.float64)
    rng = np.random.default_rng(seed)
    fold = rng.permutation(len(rows)) % folds
    restarts = [int(s) for s in rng.integers(0, 2**31 - 1, size=options.restarts)]
    out = np.empty(len(rows))
    for k in range(folds):
        fit, held = fold != k, fold == k
        net, _ = best_network(options, Z[fit], y[fit], f_w[fit], restarts)
        with threadpool_limits(limits=1):
            out[held] = np.exp(net.predict(Z[held])) * f_w[held] / y[held] - 1.0
    return out


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m deformctl.repro.grip_features")
    parser.add_argument("run", type=Path, help="a make model run directory (build/grip)")
    parser.add_argument("--law", default="hc", choices=sorted(INPUT_SETS))
    parser.add_argument("--folds", type=int, default=5)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    if args.folds < 2:
        print("error: --folds must be >= 2", file=sys.stderr)
        return 2
    if not (args.run / "train" / "index.parquet").exists():
        print(f"error: no training run in {args.run} (make model writes one)", file=sys.stderr)
        return 66
    rows = law_rows(args.run, args.law)
    print(f"{args.law}: {len(rows)} training objects, {args.folds}-fold cross-validation")
    for name, features in INPUT_SETS[args.law].items():
        err = np.abs(cross_validated_errors(args.law, rows, features, args.folds, args.seed))
        print(
            f"  {name}: {len(features)} inputs; held-out relative error median "
            f"{np.median(err):.2%}, p90 {np.quantile(err, 0.9):.2%}, max {np.max(err):.2%}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
