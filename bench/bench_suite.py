"""``make test``'s CPU time, as ``make bench`` prints it: :mod:`bench.suite_cpu` run whole.

The suite runs as ``make test`` runs it (its warm-up, then ``pytest -n 2 -q``, every marker),
under :mod:`bench.suite_cpu`'s timer; its own output (the tests, their durations) is kept out of
this page, and the lines printed here are the test files and tests of most CPU time and the
verdict line::

    make test: N s CPU (target ≤ 360 s): PASS|MISSED, W s wall; load average ...

Takes as long as ``make test`` (about 5 minutes on 2 idle cores). ``BENCH_SUITE=0`` skips it.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    if os.environ.get("BENCH_SUITE", "1") == "0":
        print("BENCH_SUITE=0: make test's CPU time not measured")
        return
    done = subprocess.run(
        [sys.executable, "-m", "bench.suite_cpu", "--cpu-top", "10"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=False,
    )
    lines = done.stdout.splitlines()
    start = next((i for i, line in enumerate(lines) if line.startswith("top ")), len(lines))
    end = next((i for i in range(start, len(lines)) if lines[i].startswith("=")), len(lines))
    tail = [x for x in lines if x.startswith("make test:") or re.match(r"^\d+ (passed|failed)", x)]
    print("\n".join([*lines[start:end], *tail]))
    if done.returncode != 0:
        print(f"the suite failed (pytest exit {done.returncode}): the time is not make test's")


if __name__ == "__main__":
    main()
