"""Run the benchmarks in ``bench/`` (``make bench``) and record what they print.

``python -m bench`` runs every ``bench_*`` module (or the ones named: ``python -m bench sim
predict``), prints each one's output as it comes, and writes that output into
``docs/performance.md`` between the markers ``<!-- bench:NAME -->`` and ``<!-- /bench:NAME -->``,
with the date, the commit and the machine. So every figure of the performance page is what the
last ``make bench`` printed, next to the command that prints it; a benchmark without a marker
section is reported and its output is only printed. ``--no-write`` leaves the page alone.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import importlib
import io
import os
import pkgutil
import platform
import re
import subprocess
import sys
from pathlib import Path

BENCH = Path(__file__).resolve().parent
PAGE = BENCH.parent / "docs" / "performance.md"


class _Tee(io.TextIOBase):
    """Write to the real stdout and keep a copy."""

    def __init__(self, out: io.TextIOBase) -> None:
        self.out = out
        self.copy = io.StringIO()

    def write(self, text: str) -> int:
        self.out.write(text)
        self.out.flush()
        return self.copy.write(text)


def _machine() -> str:
    cpu = platform.processor() or platform.machine()
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], cwd=BENCH, capture_output=True, text=True
    ).stdout.strip()
    cores = len(os.sched_getaffinity(0))
    date = dt.datetime.now(dt.UTC).strftime("%Y-%m-%d")
    return f"{date}, commit {commit or 'unknown'}, {cores} cores, {cpu}"


def record(page: str, name: str, output: str, machine: str) -> tuple[str, bool]:
    """``page`` with ``name``'s marker section replaced by ``output``; False if it has none."""
    pattern = re.compile(rf"(<!-- bench:{name} -->\n).*?(<!-- /bench:{name} -->)", re.S)
    if not pattern.search(page):
        return page, False
    body = f"```text\n$ python -m bench {name.removeprefix('bench_')}   # {machine}\n"
    body += output.rstrip() + "\n```\n"
    return pattern.sub(lambda m: m.group(1) + body + m.group(2), page), True


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    write = "--no-write" not in args
    wanted = [a for a in args if a != "--no-write"]
    names = sorted(
        m.name for m in pkgutil.iter_modules([str(BENCH)]) if m.name.startswith("bench_")
    )
    if wanted:
        names = [n for n in names if n.removeprefix("bench_") in wanted or n in wanted]
    machine = _machine()
    for name in names:
        print(f"== {name}", flush=True)
        tee = _Tee(sys.stdout)  # type: ignore[arg-type]
        saved, sys.argv = sys.argv, [f"bench.{name}"]  # each benchmark sees no arguments
        try:
            with contextlib.redirect_stdout(tee):  # type: ignore[type-var]
                importlib.import_module(f"bench.{name}").main()
        finally:
            sys.argv = saved
        if write:
            page, found = record(
                PAGE.read_text(encoding="utf-8"), name, tee.copy.getvalue(), machine
            )
            if found:
                PAGE.write_text(page, encoding="utf-8")
            else:
                print(f"(no <!-- bench:{name} --> section in {PAGE.name}: not recorded)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
