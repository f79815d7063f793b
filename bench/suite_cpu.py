"""The CPU time of ``make test``: ``make test-cpu`` (``python -m bench.suite_cpu``).

Runs the suite as ``make test`` does (``deformctl warmup``, then ``pytest -n 2 -q``, every
marker, the 25 slowest tests printed) with :mod:`bench.pytest_cpu`, which adds the test files
and tests that took the most CPU time, and times both process trees as ``/usr/bin/time`` does
(user + sys of each process and of every process it waited for: the xdist workers, the CLI
runs, the docs blocks, the built wheel). Prints, last::

    make test: N s CPU (target ≤ 360 s): PASS, W s wall; load average 1.2 before, 3.4 after, 2 cores

The machine is shared: the wall time waits for the other jobs (hence the load average, before
and after); the CPU time is what the suite costs, though a loaded machine inflates it a little
too (caches and memory bandwidth are shared). Arguments are passed to pytest (e.g. ``-m "not
docs"`` or a test path). Not a ``bench_*`` module: ``make bench`` does not run it (the suite takes
minutes). Exits with pytest's exit code.
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import time
from pathlib import Path

#: the issue's target for ``make test``, CPU seconds
TARGET_CPU_S = 360.0
ROOT = Path(__file__).resolve().parents[1]


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    cmd = [sys.executable, "-m", "pytest", "-n", "2", "-q", "-p", "bench.pytest_cpu", *args]
    load_before = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    warmup = [sys.executable, "-m", "deformctl", "warmup"]
    code = subprocess.run(warmup, cwd=ROOT, check=False).returncode
    if code == 0:
        code = subprocess.run(cmd, cwd=ROOT, check=False).returncode
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    load_after = os.getloadavg()[0]
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    verdict = "PASS" if cpu <= TARGET_CPU_S else "MISSED"
    load = f"load average {load_before:.1f} before, {load_after:.1f} after, {os.cpu_count()} cores"
    target = f"target ≤ {TARGET_CPU_S:.0f} s"
    print(f"make test: {cpu:.0f} s CPU ({target}): {verdict}, {wall:.0f} s wall; {load}")
    return code


if __name__ == "__main__":
    sys.exit(main())
