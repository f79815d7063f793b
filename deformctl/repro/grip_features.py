"""What each law network's inputs are worth: a cross-validated comparison of input sets.

``python -m deformctl.repro.grip_features RUN_DIR [--law hc] [--folds 5] [--seed 0]``
    Reads a ``make model`` run's training objects (``RUN_DIR/train/index.parquet`` and
    ``coefficients.parquet``), keeps the rows of ``--law`` whose inputs are all known, and
    fits the law's network (the grip model's: 8-8 tanh, best of the seeded restarts on its
    training rows, the same settings ``train`` uses) on every input set of
    :data:`INPUT_SETS` in ``--folds``-fold cross-validation (one seeded split shared by every
    set). It prints, per set, the median, 90th percentile and max relative error of the
    held-out predictions of L_f. Only the training run's objects are used: the fresh
    population stays for ``grip_model report``.

The result for the bundled model's run is in docs/explanation/model.md.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from deformctl.grip.laws import (
    EARLIER_LAW_FEATURES,
    LAW_FEATURES,
    LAW_PARAMETER_COLUMNS,
    law_parameter_values,
)

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
    from deformctl.grip.lawtrain import join_laws

    index = read_table(run / "train" / "index.parquet", "index_table")
    coef = read_table(run / "train" / "coefficients.parquet", "coefficients")
    joined = join_laws(index, coef)
    rows = joined[joined["model"] == law].sort_values("object_id").reset_index(drop=True)
    nan = np.full(len(rows), np.nan)
    columns = {
        c: rows[c].to_numpy(dtype=np.float64) if c in rows.columns else nan
        for c in LAW_PARAMETER_COLUMNS[law]
    }
    params = law_parameter_values(
        law, columns, rows["weight_n"].to_numpy(), rows["deformability_n_per_cm"].to_numpy()
    )
    keep = np.all([np.isfinite(v) & (v > 0) for v in params.values()], axis=0)
    return rows[keep].reset_index(drop=True)


def cross_validated_errors(
    law: str, rows: pd.DataFrame, features: Sequence[str], folds: int, seed: int
) -> np.ndarray:
    """``[n]`` held-out relative errors of L_f (prediction / truth - 1) over ``folds`` folds."""
    from sklearn.exceptions import ConvergenceWarning
    from threadpoolctl import threadpool_limits

    from deformctl.grip.lawtrain import law_inputs
    from deformctl.grip.model import DEFAULT_GRIP_HIDDEN
    from deformctl.model import TrainOptions, scaled_mlp

    options = TrainOptions(seed=seed)
    Z, f_w, _ = law_inputs(law, rows, features)
    y = rows["lift_force_n"].to_numpy(dtype=np.float64)
    target = np.log(y / f_w)
    rng = np.random.default_rng(seed)
    fold = rng.permutation(len(rows)) % folds
    restarts = [int(s) for s in rng.integers(0, 2**31 - 1, size=options.restarts)]
    out = np.empty(len(rows))
    for k in range(folds):
        fit, held = fold != k, fold == k
        best, best_loss = None, np.inf
        for rs in restarts:
            net = scaled_mlp(options, DEFAULT_GRIP_HIDDEN, rs)
            with warnings.catch_warnings(), threadpool_limits(limits=1):
                warnings.simplefilter("ignore", ConvergenceWarning)
                net.fit(Z[fit], target[fit])
                loss = float(np.mean((net.predict(Z[fit]) - target[fit]) ** 2))
            if loss < best_loss:
                best, best_loss = net, loss
        assert best is not None
        with threadpool_limits(limits=1):
            out[held] = np.exp(best.predict(Z[held]) - target[held]) - 1.0
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
