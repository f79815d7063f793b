"""``adapt`` closes a sim-to-real gap we control (deformctl.repro.adapt_gap).

Lifts the 38 objects of ``population --grip -n 38 --seed 11`` with ``lift --sim --sim-preset
table`` (the "reality"), checks the lifts against the cached ones the test uses
(tests/data/adapt_gap.csv), then adapts the bundled grip model (the "simulator", trained on the
paper preset) with the first 8 and prints, on the other 30, the median error of the unadapted
and the adapted model and the coverage of the adapted model's P = 0.9 bound. About 40 lifts:
1-2 minutes on 2 idle cores. ``python -m bench.bench_adapt --write`` rewrites the cache.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from deformctl.artifacts import read_catalog, read_table
from deformctl.repro.adapt_gap import CACHE, POPULATION, gap_figures, lifts_frame, report_lines


def _lifts(tmp: Path) -> pd.DataFrame:
    dc = [sys.executable, "-m", "deformctl"]
    subprocess.run([*dc, "population", *POPULATION, "-o", str(tmp / "pop.csv")], check=True,
                   capture_output=True)  # fmt: skip
    subprocess.run([*dc, "lift", str(tmp / "pop.csv"), "--sim", "--sim-preset", "table",
                    "-o", str(tmp / "lift.parquet"), "--workers", "2"], check=True,
                   capture_output=True)  # fmt: skip
    return lifts_frame(read_catalog(tmp / "pop.csv"), read_table(tmp / "lift.parquet"))


def main() -> None:
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as d:
        fresh = _lifts(Path(d))
    print(f"38 lifts under the table preset: {time.perf_counter() - t0:.0f} s")
    if "--write" in sys.argv:
        fresh.to_csv(CACHE, index=False, float_format="%.17g")
    cached = pd.read_csv(CACHE, dtype={"object_id": str})
    rel = np.max(np.abs(fresh["lift_force_n"].to_numpy() / cached["lift_force_n"].to_numpy() - 1))
    print(f"largest difference to the cached lifts (tests/data/adapt_gap.csv): {100 * rel:.3f} %")
    for line in report_lines(gap_figures(fresh)):
        print(line)


if __name__ == "__main__":
    main()
