"""``lift --sim`` sweeps through the CLI: objects/s with 1 and 2 local workers, and peak memory.

Fast setting (stated, used for every run here): ``--alpha-cm 10 --dt-s 0.002 --lift-hold-s 0.05
--lift-height-m 0.01 --protocol paper --max-attempts 20`` (a coarse lattice, a 1 cm rise, the
paper's +20 % ramp: about two simulated attempts per object). The catalog is
``make_population(n, seed=0)`` (the paper's ranges).

Throughput: the same objects with ``--workers 1`` and ``--workers 2``; the rate is the sweep's
own (objects / wall time of the sweep, printed in its summary line; interpreter start-up
excluded, pool start-up included). Target: 2 workers >= 1.7x 1 worker on 2 idle cores (other load
on the machine lowers it). It is measured twice: at the simulator's default settings (the work a
real sweep does, about half a second of CPU per object), which is the figure the target is
about, and at the fast setting, where an object costs ~20 ms of CPU and the client's per-object
work (collecting results, committing parts) weighs more. The MCAP part logs are encoded by the
workers (the sweep's part-writer jobs), not by the client.
Memory: a 2,000-object sweep with 2 workers (parts of 100 objects,
each with its MCAP attempt log); the peak of the summed PSS (and, for reference, RSS) of the
client and every process under it (/proc polled every 0.1 s) and the largest single-process
peak RSS (``getrusage`` of the children). Target: PSS sum < 1 GiB. About 400 MiB of the client
is the ``deformctl`` CLI's imports (OpenCV, scikit-learn, numba, ...), whatever the sweep size.

Single files: ``measure --sim -o FILE`` and ``lift --sim -o FILE`` of the same 40 objects at the
default preset with ``--workers 1`` and ``--workers 2`` (wall time of the whole command,
interpreter start-up included: what ``make reproduce`` pays), and whether the two outputs hold
the same rows.

Run: ``python -m bench.bench_sweep`` (or ``make bench``); about 3-5 minutes.
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

FAST = [
    "--alpha-cm", "10", "--dt-s", "0.002", "--lift-hold-s", "0.05", "--lift-height-m", "0.01",
    "--protocol", "paper", "--max-attempts", "20",
]  # fmt: skip
SPEED_OBJECTS = 160
SPEED_OBJECTS_DEFAULT = 40
MEMORY_OBJECTS = 2000
GIB = 1024**3


def _tree_memory_bytes(root: int) -> tuple[int, int, int]:
    """(summed PSS, summed RSS, largest single RSS) of ``root`` and all its descendants, bytes
    (from /proc; ``getrusage``'s peak would carry this benchmark's own peak into every child,
    because Linux keeps ``ru_maxrss`` across ``execve``).

    PSS counts a page shared by n processes as 1/n in each (the workers fork from one server
    and share the interpreter and libraries), so its sum is the tree's real footprint; the RSS
    sum counts shared pages once per process and overstates it.
    """
    parents: dict[int, int] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                stat = Path(f"/proc/{entry}/stat").read_text()
            except OSError:
                continue
            parents[int(entry)] = int(stat.rsplit(")", 1)[1].split()[1])
    members = {root}
    grew = True
    while grew:
        new = {p for p, parent in parents.items() if parent in members} - members
        grew = bool(new)
        members |= new
    pss = rss = single = 0
    for pid in members:
        try:
            lines = Path(f"/proc/{pid}/smaps_rollup").read_text().splitlines()
        except OSError:
            continue
        for line in lines:
            if line.startswith("Pss:"):
                pss += int(line.split()[1]) * 1024
            elif line.startswith("Rss:"):
                rss += int(line.split()[1]) * 1024
                single = max(single, int(line.split()[1]) * 1024)
    return pss, rss, single


def _sweep(
    catalog: Path, out: Path, workers: int, setting: list[str] = FAST
) -> tuple[float, tuple[int, int, int], str]:
    """Run one CLI sweep; (objects/s of the sweep, peak tree (PSS sum, RSS sum, largest single
    RSS) bytes, summary line)."""
    cmd = [sys.executable, "-m", "deformctl", "lift", str(catalog), "--sim", "-o", f"{out}/",
           *setting, "--workers", str(workers)]  # fmt: skip
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    peak_pss = peak_rss = peak_single = 0
    while proc.poll() is None:
        pss, rss, single = _tree_memory_bytes(proc.pid)
        peak_pss, peak_rss = max(peak_pss, pss), max(peak_rss, rss)
        peak_single = max(peak_single, single)
        time.sleep(0.1)
    err = proc.stderr.read().decode() if proc.stderr else ""
    line = err.strip().splitlines()[-1] if err.strip() else ""
    match = re.search(r"\(([\d.]+) objects/s\)", line)
    if proc.returncode not in (0, 1) or match is None:
        raise RuntimeError(f"sweep failed (exit {proc.returncode}): {err[-500:]}")
    return float(match.group(1)), (peak_pss, peak_rss, peak_single), line


def _single_file(catalog: Path, d: Path, workers: int) -> tuple[float, float]:
    """Wall seconds of ``measure --sim`` and ``lift --sim`` into single files with ``workers``."""
    times = []
    for cmd in (
        ["measure", str(catalog), "--sim", "--seed", "0", "-o", str(d / f"sq{workers}.mcap")],
        ["lift", str(catalog), "--sim", "-o", str(d / f"lift{workers}.parquet")],
    ):
        t0 = time.monotonic()
        subprocess.run(
            [sys.executable, "-m", "deformctl", *cmd, "--workers", str(workers)],
            check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        )  # fmt: skip
        times.append(time.monotonic() - t0)
    return times[0], times[1]


def single_files() -> None:
    """Single-file outputs on 1 and 2 local processes: wall times, ratios, same rows."""
    from deformctl.artifacts import read_table

    with tempfile.TemporaryDirectory(prefix="bench_single_") as tmp:
        d = Path(tmp)
        cat = d / "pop.csv"
        make_population(SPEED_OBJECTS_DEFAULT, seed=0).to_csv(cat, index=False)
        m1, l1 = _single_file(cat, d, 1)
        m2, l2 = _single_file(cat, d, 2)
        same = read_table(d / "lift1.parquet").equals(read_table(d / "lift2.parquet"))
        load = os.getloadavg()[0]
        print(f"single files, paper preset, {SPEED_OBJECTS_DEFAULT} objects (wall s, 1 vs 2 "
              f"workers): measure --sim {m1:.1f} vs {m2:.1f} ({m1 / m2:.2f}x), lift --sim "
              f"{l1:.1f} vs {l2:.1f} ({l1 / l2:.2f}x); same lift rows: {same}; "
              f"load average {load:.2f}")  # fmt: skip


def main() -> None:
    """Print objects/s with 1 and 2 workers, their ratio, and the 2,000-object peak memory."""
    single_files()
    print(f"fast setting: {' '.join(FAST)}; cores available: {len(os.sched_getaffinity(0))}")
    print(f"load average before: {os.getloadavg()[0]:.2f} (a loaded machine lowers the ratio)")
    with tempfile.TemporaryDirectory(prefix="bench_sweep_") as tmp:
        d = Path(tmp)
        real = d / "real.csv"
        make_population(SPEED_OBJECTS_DEFAULT, seed=0).to_csv(real, index=False)
        # Parts of 10 objects: each part's log is written while the workers compute the next.
        rate1, _, _ = _sweep(real, d / "r1", 1, ["--partition-size", "10"])
        rate2, _, _ = _sweep(real, d / "r2", 2, ["--partition-size", "10"])
        load = os.getloadavg()[0]
        print(f"lift --sim, default settings, parts of 10, {SPEED_OBJECTS_DEFAULT} objects: "
              f"1 worker {rate1:.2f} objects/s, 2 workers {rate2:.2f} objects/s, "
              f"ratio {rate2 / rate1:.2f}x (target >= 1.7x on 2 idle cores; "
              f"load average {load:.2f})")  # fmt: skip
        small = d / "small.csv"
        make_population(SPEED_OBJECTS, seed=0).to_csv(small, index=False)
        rate1, _, _ = _sweep(small, d / "w1", 1)
        rate2, _, _ = _sweep(small, d / "w2", 2)
        load = os.getloadavg()[0]
        print(f"lift --sim, fast setting, {SPEED_OBJECTS} objects: 1 worker {rate1:.2f} "
              f"objects/s, 2 workers {rate2:.2f} objects/s, ratio {rate2 / rate1:.2f}x "
              f"(small objects: the client's per-object overhead weighs)")  # fmt: skip
        big = d / "big.csv"
        make_population(MEMORY_OBJECTS, seed=0).to_csv(big, index=False)
        t0 = time.monotonic()
        rate, peak, line = _sweep(big, d / "big", 2)
        wall_s = time.monotonic() - t0
        pss, rss, single = peak
        print(f"lift --sim, {MEMORY_OBJECTS} objects, 2 workers: {rate:.2f} objects/s, "
              f"{wall_s:.0f} s wall; peak memory client + workers (PSS sum) {pss / 2**20:.0f} MiB "
              f"(target < {GIB / 2**20:.0f} MiB: {'ok' if pss < GIB else 'MISSED'}); "
              f"RSS sum {rss / 2**20:.0f} MiB (shared pages counted per process); "
              f"largest single process RSS {single / 2**20:.0f} MiB")  # fmt: skip
        print(f"  summary: {line}")


if __name__ == "__main__":
    main()
