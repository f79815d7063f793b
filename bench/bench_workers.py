"""``--workers auto`` against ``--workers 1`` (and 2), on 4 and on 40 objects, whole commands.

``measure --sim -o FILE`` and ``lift --sim -o FILE`` at the default preset (paper) on the
paper's four objects (datasets/paper/objects.csv) and on ``make_population(40, seed=0)``, each
with ``--workers 1``, ``auto`` and ``2``, one after another in the same run: wall time of the
whole command (interpreter start-up included, what a user waits for), the ratios auto / 1 and
2 / 1 (< 1: faster than one process), and what auto chose (from the summary line). Target:
auto <= 1.10 × one process on both sizes. The commands run with a fresh cost cache
(``XDG_CACHE_HOME`` in a temporary folder): the 4-object runs and the first 40-object run
assume the default start cost, later runs use the one measured by the first pool. The load
average is printed: other processes on the machine change every figure.

Run: ``python -m bench.bench_workers`` (or ``make bench``); about 4-6 minutes.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from deformctl.population import make_population

REPO = Path(__file__).resolve().parent.parent
PAPER = REPO / "datasets" / "paper" / "objects.csv"
TARGET = 1.10
COUNTS = ("1", "auto", "2")


def _run(
    command: str, catalog: Path, out: Path, workers: str, env: dict[str, str]
) -> tuple[float, str]:
    """Wall seconds of one command and what auto chose (from its summary line)."""
    extra = ["--seed", "0"] if command == "measure" else []
    cmd = [sys.executable, "-m", "deformctl", command, str(catalog), "--sim", *extra,
           "-o", str(out), "--workers", workers, "--force"]  # fmt: skip
    t0 = time.monotonic()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, check=False)
    wall = time.monotonic() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed (exit {proc.returncode}): {proc.stderr[-500:]}")
    match = re.search(r"workers auto: (\d+)[^;)]*(\([^)]*\))?", proc.stderr)
    return wall, (match.group(0) if match else "")


def main() -> None:
    """Print, per size and command, the wall times with 1, auto and 2 workers and the ratios."""
    print(f"cores available: {len(os.sched_getaffinity(0))}; target: auto <= {TARGET:.2f}x one "
          f"process (ratios < 1 are faster)")  # fmt: skip
    with tempfile.TemporaryDirectory(prefix="bench_workers_") as tmp:
        d = Path(tmp)
        env = {**os.environ, "XDG_CACHE_HOME": str(d / "cache")}
        forty = d / "pop40.csv"
        make_population(40, seed=0).to_csv(forty, index=False)
        for label, catalog in (("4 objects (paper)", PAPER), ("40 objects", forty)):
            for command in ("measure", "lift"):
                load = os.getloadavg()[0]
                walls: dict[str, float] = {}
                chose = ""
                suffix = ".mcap" if command == "measure" else ".parquet"
                for workers in COUNTS:
                    out = d / f"{command}-{catalog.stem}-{workers}{suffix}"
                    walls[workers], note = _run(command, catalog, out, workers, env)
                    chose = note or chose
                auto_ratio = walls["auto"] / walls["1"]
                verdict = "ok" if auto_ratio <= TARGET else "MISSED"
                print(
                    f"{label}, {command} --sim (wall s): 1 worker {walls['1']:.1f}, auto "
                    f"{walls['auto']:.1f}, 2 workers {walls['2']:.1f}; auto/1 {auto_ratio:.2f} "
                    f"({verdict}), 2/1 {walls['2'] / walls['1']:.2f}; load average {load:.2f}"
                )
                print(f"  auto: {chose or 'no choice reported'}")


if __name__ == "__main__":
    main()
