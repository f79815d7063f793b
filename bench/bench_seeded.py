"""Attempts per object: the paper ramp, refine, and searches seeded by the model or the table.

The measurement. On the ``make reproduce`` objects (``population -n 73 --seed 0``, squeezed
and lifted in the simulator, ``train --train-size 40 --seed 0``) it lifts the 33 *test* objects
four ways with the ``deformctl`` command, in this run:

* ``paper``: ``lift --protocol paper`` (F_w, +20 % until it lifts; resolves L_f to 20 %);
* ``refine``: the pipeline's own ``lift`` (the same ramp, then bisection to 0.5 %);
* ``model``: ``lift --start-model model.skops --coefficients coefficients.parquet``;
* ``table``: ``lift --start-table`` with an index table of the 40 *training* objects only (the
  whole table holds the test objects' own answers), the same coefficients.

It prints every object's attempts and L_f side by side, the distributions (quartiles, mean,
max, total), the agreement of each L_f with refine's, and, replayed on the measured refine
brackets without simulating, the attempts the seeded search would take at other start margins
(the measurement behind ``DEFAULT_START_MARGIN``).

``python -m bench.bench_seeded [RUN_DIR]``: with a ``make reproduce`` folder (``reports/``) it
reuses that folder's pipeline outputs instead of building its own in a temp dir. The simulator
is the cost: the pipeline is ``make reproduce``'s (about 2.5 minutes on 2 idle cores) and the
three lifts of the test objects run side by side (about 320 attempts in all); on a shared
machine at load 9 the whole run took 17 minutes.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from deformctl.artifacts import Provenance, read_catalog, read_table, write_table
from deformctl.catalog import catalog_objects
from deformctl.lift import (
    DEFAULT_START_MARGIN,
    DEFAULT_TOLERANCE_REL,
    find_min_lift_force,
    find_min_lift_force_seeded,
)
from deformctl.lift.search import TrialRunner
from deformctl.lift.seeded import StartEstimate, load_start_model, load_start_table
from deformctl.series import TrialOutcome

MARGINS = (1.0, 1.0025, 1.005, 1.01, 1.02, 1.05)


def _dc(*args: object, cwd: Path) -> float:
    """Run ``deformctl ARGS`` in ``cwd``; wall seconds."""
    t0 = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-m", "deformctl", *map(str, args)],
        cwd=cwd, capture_output=True, text=True,
    )  # fmt: skip
    if done.returncode != 0:
        raise SystemExit(f"deformctl {args[0]} failed: {done.stderr.strip()}")
    return time.perf_counter() - t0


def pipeline(run: Path) -> None:
    """The ``make reproduce`` lines up to ``train`` (what the seeds are built from)."""
    steps = [
        ("population", "-n", 73, "--seed", 0, "-o", "population.csv"),
        ("measure", "population.csv", "--sim", "--seed", 0, "-o", "squeeze.mcap"),
        ("characterize", "squeeze.mcap", "-o", "coefficients.parquet"),
        ("lift", "population.csv", "--sim", "-o", "lift.parquet"),
        ("table", "coefficients.parquet", "lift.parquet", "-o", "index.parquet"),
        ("train", "index.parquet", "-o", "model.skops", "--hidden", 2, "--train-size", 40,
         "--seed", 0, "--metrics", "metrics.json"),
    ]  # fmt: skip
    for step in steps:
        print(f"  {step[0]:<13} {_dc(*step, cwd=run):6.1f} s", flush=True)


def _quartiles(values: np.ndarray) -> str:
    q1, q2, q3 = np.percentile(values, [25, 50, 75])
    return (
        f"{q1:4.1f} {q2:6.1f} {q3:4.1f} {values.mean():6.2f} {values.max():4.0f} "
        f"{values.sum():6.0f}"
    )


def _threshold(t_n: float) -> TrialRunner:
    return lambda f, _i: TrialOutcome(f, f >= t_n, 0.0)


def margin_sweep(
    refine: pd.DataFrame, catalog: pd.DataFrame, starts: dict[str, dict[str, StartEstimate]]
) -> None:
    """Seeded attempts at other margins, replayed on a threshold inside each refine bracket."""
    objects = {o.object_id: o for o in catalog_objects(catalog)}
    print("\nstart margin, replayed on the refine brackets (threshold at their midpoints):")
    print(f"{'seed':>6} {'margin':>7}  attempts q25 median q75  mean  max")
    for name, est in starts.items():
        for margin in MARGINS:
            n = []
            for oid, row in refine.iterrows():
                obj, start = objects[str(oid)], est[str(oid)]
                runner = _threshold(0.5 * (row.bracket_low_n + row.bracket_high_n))
                if start.in_range:
                    r = find_min_lift_force_seeded(
                        runner, weight_n=obj.weight_n, friction_mu=obj.friction_mu,
                        predicted_lift_force_n=start.predicted_lift_force_n, margin=margin,
                    )  # fmt: skip
                else:
                    r = find_min_lift_force(
                        runner, weight_n=obj.weight_n, friction_mu=obj.friction_mu
                    )
                n.append(r.attempts)
            a = np.array(n, dtype=float)
            q1, q2, q3 = np.percentile(a, [25, 50, 75])
            mark = "  <- default" if margin == DEFAULT_START_MARGIN else ""
            print(
                f"{name:>6} {margin:7.4f}  {q1:12.1f} {q2:6.1f} {q3:4.1f} {a.mean():5.2f} "
                f"{a.max():4.0f}{mark}"
            )


def main(argv: list[str] | None = None) -> None:
    args = sys.argv[1:] if argv is None else argv
    with tempfile.TemporaryDirectory(prefix="bench_seeded_") as tmp:
        work = Path(tmp)
        if args:
            run = Path(args[0]).resolve()
            print(f"pipeline outputs from {run}")
        else:
            run = work
            print("the make-reproduce pipeline (73 objects, 40 train / 33 test), wall s:")
            pipeline(run)
        metrics = json.loads((run / "metrics.json").read_text())
        train_ids, test_ids = metrics["split"]["train"], metrics["split"]["test"]
        index = read_table(run / "index.parquet", "index_table")
        train_index = work / "train_index.parquet"
        provenance = Provenance.from_invocation([run / "index.parquet"])
        train_rows = index[index["object_id"].isin(train_ids)]
        write_table(train_rows, train_index, "index_table", provenance=provenance, force=True)
        catalog = run / "population.csv"
        coefficients = run / "coefficients.parquet"
        common = ["lift", catalog, "--sim", "--objects", ",".join(test_ids)]
        runs = {
            "paper": [*common, "--protocol", "paper", "-o", work / "paper.parquet"],
            "model": [*common, "--start-model", run / "model.skops", "--coefficients",
                      coefficients, "-o", work / "model.parquet"],
            "table": [*common, "--start-table", train_index, "--coefficients", coefficients,
                      "-o", work / "table.parquet"],
        }  # fmt: skip
        t0 = time.perf_counter()
        procs = {
            name: subprocess.Popen(
                [sys.executable, "-m", "deformctl", *map(str, cmd)],
                stdout=subprocess.DEVNULL,
                stderr=subprocess.PIPE,
                text=True,
            )
            for name, cmd in runs.items()
        }
        for name, proc in procs.items():
            _, err = proc.communicate()
            if proc.returncode != 0:
                raise SystemExit(f"lift {name} failed: {err.strip()}")
            fallbacks = [line for line in err.splitlines() if line.startswith("warning:")]
            print(f"lift {name}: {len(fallbacks)} fallback warning(s)")
        print(f"the 3 lifts of the {len(test_ids)} test objects (in parallel): "
              f"{time.perf_counter() - t0:.1f} s wall")  # fmt: skip

        tables = {"refine": read_table(run / "lift.parquet", "lift_results")}
        for name in runs:
            tables[name] = read_table(work / f"{name}.parquet", "lift_results")
        frames = {name: t.set_index("object_id").loc[test_ids] for name, t in tables.items()}
        refine = frames["refine"]
        names = ["paper", "refine", "model", "table"]

        print("\nper test object: attempts and L_f (N); * = start outside the range (from F_w)")
        print(f"{'object':>6} " + " ".join(f"{n:>6} {'L_f':>8}" for n in names))
        for oid in test_ids:
            cells = []
            for n in names:
                row = frames[n].loc[oid]
                star = "*" if n in ("model", "table") and not row.start_in_training_range else " "
                cells.append(f"{row.attempts:5d}{star} {row.lift_force_n:8.3f}")
            print(f"{oid:>6} " + " ".join(cells))

        print(f"\nattempts per object ({len(test_ids)} test objects):")
        print(f"{'search':>7}  q25 median  q75   mean  max  total   max |L_f/refine - 1|")
        for n in names:
            a = frames[n]["attempts"].to_numpy(dtype=float)
            dev = np.abs(frames[n]["lift_force_n"] / refine["lift_force_n"] - 1).max()
            print(f"{n:>7} {_quartiles(a)}   {dev:8.2%}")
        med = {n: float(frames[n]["attempts"].median()) for n in names}
        tol = DEFAULT_TOLERANCE_REL
        for n in ("model", "table"):
            dev = np.abs(frames[n]["lift_force_n"] / refine["lift_force_n"] - 1)
            inside = frames[n]["start_in_training_range"].to_numpy(dtype=bool)
            pred = frames[n]["predicted_lift_force_n"] / refine["lift_force_n"] - 1
            goal = (  # the target of the model seed
                f", must be <= 0.5x: {'ok' if med[n] <= med['refine'] / 2 else 'NOT MET'}"
                if n == "model"
                else ""
            )
            print(
                f"{n}-seeded: median {med[n]:g} vs refine {med['refine']:g} attempts "
                f"({med[n] / med['refine']:.2f}x{goal}); "
                f"L_f within {tol:.1%} of refine's on {int((dev <= tol + 1e-12).sum())}/"
                f"{len(dev)}; prediction error median {np.median(np.abs(pred[inside])):.2%}, "
                f"max {np.abs(pred[inside]).max():.2%}; {int((~inside).sum())} from F_w"
            )
        total = {n: int(frames[n]["attempts"].sum()) for n in names}
        print(
            f"lifts saved on the test objects: model {1 - total['model'] / total['refine']:.0%}"
            f", table {1 - total['table'] / total['refine']:.0%} of refine's {total['refine']}"
        )

        cat = read_catalog(catalog)
        objects = catalog_objects(cat[cat["object_id"].isin(test_ids)])
        order = {oid: i for i, oid in enumerate(test_ids)}
        objects.sort(key=lambda o: order[o.object_id])
        estimates = {
            "model": load_start_model(
                str(run / "model.skops"), margin=1.0, coefficients=str(coefficients)
            ).starts(objects),
            "table": load_start_table(
                str(train_index), margin=1.0, coefficients=str(coefficients)
            ).starts(objects),
        }
        margin_sweep(refine, cat, estimates)
        if not math.isfinite(med["model"]):
            raise SystemExit("no model-seeded result")


if __name__ == "__main__":
    main()
