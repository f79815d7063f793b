"""A command line that answers at once: how long ``deformctl --help`` and each
``deformctl <command> --help`` take, beside ``python -c pass`` measured in the same run.

Prints, for ``python -c pass``, ``deformctl --help`` and ``deformctl <command> --help`` of every
command (the console script, a fresh process each time): the median wall time and the median CPU
time (user + sys of the child) over 7 rounds, the wall time as a multiple of ``python -c pass``,
and PASS or MISSED against the targets: ``deformctl --help`` <= 0.3 s wall, each
``<command> --help`` <= 0.5 s wall. The rounds interleave the commands (round 1 runs each once,
then round 2, ...), so a change of the machine's load falls on all of them alike. The machine is
shared: the wall time waits for the other jobs (the load average is printed before and after);
the CPU time and the ratio are what the start-up costs.
"""

from __future__ import annotations

import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROUNDS = 7
TOP_TARGET_S = 0.3
COMMAND_TARGET_S = 0.5


def _run(cmd: list[str]) -> tuple[float, float]:
    """(wall s, CPU s: user + sys of the child) of one run of ``cmd``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime


def main() -> None:
    from deformctl.cli import COMMAND_NAMES

    script = str(Path(sys.executable).with_name("deformctl"))
    cases: dict[str, tuple[list[str], float | None]] = {
        "python -c pass": ([sys.executable, "-c", "pass"], None),
        "deformctl --help": ([script, "--help"], TOP_TARGET_S),
    }
    # each command's row is labelled by its name alone: the docs' checks of the invocations
    # they show (tests/test_cli_measure.py) read this output in docs/performance.md
    for name in COMMAND_NAMES:
        cases[f"  {name}"] = ([script, name, "--help"], COMMAND_TARGET_S)
    for cmd, _ in cases.values():  # warm the file cache and the bytecode once
        subprocess.run(cmd, check=True, capture_output=True)
    walls: dict[str, list[float]] = {label: [] for label in cases}
    cpus: dict[str, list[float]] = {label: [] for label in cases}
    load_before = os.getloadavg()[0]
    for _ in range(ROUNDS):
        for label, (cmd, _) in cases.items():
            wall, cpu = _run(cmd)
            walls[label].append(wall)
            cpus[label].append(cpu)
    load_after = os.getloadavg()[0]
    print(f"load average (1 min): {load_before:.1f} before, {load_after:.1f} after, on "
          f"{os.cpu_count()} cores; medians of {ROUNDS} interleaved rounds")  # fmt: skip
    base = statistics.median(walls["python -c pass"])
    width = max(len(label) for label in cases)
    for label, (_, target) in cases.items():
        if label == f"  {COMMAND_NAMES[0]}":
            print("each command's --help:")
        wall, cpu = statistics.median(walls[label]), statistics.median(cpus[label])
        line = f"{label:<{width}}  {wall:.3f} s wall, {cpu:.3f} s CPU"
        if target is not None:
            verdict = "PASS" if wall <= target else "MISSED"
            line += f", {wall / base:4.1f} x python -c pass; target <= {target:.1f} s: {verdict}"
        print(line)


if __name__ == "__main__":
    main()
