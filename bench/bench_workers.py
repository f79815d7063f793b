"""``--workers auto`` against ``--workers 1`` (and 2), on 4 and on 40 objects, whole commands.

``measure --sim -o FILE`` and ``lift --sim -o FILE`` at the default preset (paper) on the
paper's four objects (datasets/paper/objects.csv) and on ``make_population(40, seed=0)``, each
with ``--workers 1``, ``auto`` and ``2``, interleaved (each round in another order: 5 rounds on
4 objects, 2 on 40) in the same run: the median and the best wall time of the whole command
(interpreter start-up included, what a user waits for), the ratios of the medians auto / 1 and
2 / 1 (< 1: faster than one process) and of the best times (other load only adds time, so the
best is the least disturbed), every run's time, the median CPU time of the command's own process
(which the other load on the machine changes much less than the wall time; the worker processes
are not counted), and what auto
chose (from the summary line). Target:
auto <= 1.10 × one process on both sizes. The commands run with a fresh cost cache
(``XDG_CACHE_HOME`` in a temporary folder): the 4-object runs and the first 40-object run
assume the default start cost, later runs use the one measured by the first pool. The load
average is printed: other processes on the machine change every figure.

Run: ``python -m bench.bench_workers`` (or ``make bench``); about 8-12 minutes.
"""

from __future__ import annotations

import os
import re
import resource
import statistics
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
) -> tuple[float, float, str]:
    """Wall seconds and CPU seconds (user + system of the command's process; its worker
    processes, children of a fork server it does not reap, are not counted) of one command,
    and what auto chose (from its summary line)."""
    extra = ["--seed", "0"] if command == "measure" else []
    cmd = [sys.executable, "-m", "deformctl", command, str(catalog), "--sim", *extra,
           "-o", str(out), "--workers", workers, "--force"]  # fmt: skip
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.monotonic()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, check=False)
    wall = time.monotonic() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed (exit {proc.returncode}): {proc.stderr[-500:]}")
    match = re.search(r"(workers auto: .*)\)$", proc.stderr.strip().splitlines()[-1])
    return wall, cpu, (match.group(1) if match else "")


def main() -> None:
    """Print, per size and command, the wall times with 1, auto and 2 workers and the ratios."""
    print(f"cores available: {len(os.sched_getaffinity(0))}; target: auto <= {TARGET:.2f}x one "
          f"process (ratios < 1 are faster)")  # fmt: skip
    with tempfile.TemporaryDirectory(prefix="bench_workers_") as tmp:
        d = Path(tmp)
        env = {**os.environ, "XDG_CACHE_HOME": str(d / "cache")}
        forty = d / "pop40.csv"
        make_population(40, seed=0).to_csv(forty, index=False)
        for label, catalog, rounds in (("4 objects (paper)", PAPER, 5), ("40 objects", forty, 2)):
            for command in ("measure", "lift"):
                loads = [os.getloadavg()[0]]
                walls: dict[str, list[float]] = {w: [] for w in COUNTS}
                cpus: dict[str, list[float]] = {w: [] for w in COUNTS}
                chose: list[str] = []
                suffix = ".mcap" if command == "measure" else ".parquet"
                for r in range(rounds):
                    for workers in COUNTS[r % 3 :] + COUNTS[: r % 3]:  # no fixed order
                        out = d / f"{command}-{catalog.stem}-{workers}{suffix}"
                        wall, cpu, note = _run(command, catalog, out, workers, env)
                        walls[workers].append(wall)
                        cpus[workers].append(cpu)
                        chose += [note] if note else []
                    loads.append(os.getloadavg()[0])
                med = {w: statistics.median(t) for w, t in walls.items()}
                auto_ratio = med["auto"] / med["1"]
                verdict = "ok" if auto_ratio <= TARGET else "MISSED"
                print(
                    f"{label}, {command} --sim, median wall s of {rounds}: 1 worker "
                    f"{med['1']:.1f}, auto {med['auto']:.1f}, 2 workers {med['2']:.1f}; "
                    f"auto/1 {auto_ratio:.2f} ({verdict}), 2/1 {med['2'] / med['1']:.2f}; "
                    f"load average {min(loads):.1f}-{max(loads):.1f}"
                )
                best = {w: min(t) for w, t in walls.items()}
                print(
                    f"  best of {rounds}: 1 worker {best['1']:.1f}, auto {best['auto']:.1f}, 2 "
                    f"workers {best['2']:.1f}; auto/1 {best['auto'] / best['1']:.2f}, 2/1 "
                    f"{best['2'] / best['1']:.2f}"
                )
                runs = "; ".join(f"{w}: " + ", ".join(f"{t:.1f}" for t in walls[w]) for w in COUNTS)
                print(f"  every run (wall s): {runs}")
                cpu_med = {w: statistics.median(t) for w, t in cpus.items()}
                print(
                    f"  median CPU s of the command's own process (user + system; worker "
                    f"processes not counted): 1 worker {cpu_med['1']:.1f}, auto "
                    f"{cpu_med['auto']:.1f}, 2 workers {cpu_med['2']:.1f}"
                )
                for note in chose:
                    print(f"  {note}")


if __name__ == "__main__":
    main()
