"""``characterize`` at sweep speed: its time against the ``measure`` that made the log.

A seeded population (``deformctl population -n N --seed 0``, the paper's ranges) is squeezed with
the defaults a user runs (``measure pop.csv --sim --seed 0 -o squeeze/``: the ``paper`` preset,
5 particles along the longest side, 1 ms steps, three squeezes per object, every core), then
characterized from that dataset folder twice: as a sweep into a coefficients folder
(``characterize squeeze/ -o coefficients/``, every core) and into one file
(``characterize squeeze/ -o coefficients.parquet``, one process). Each command's wall time is
measured in this run, interpreter start-up included, and the ratio characterize / measure is
printed (target <= 0.25). The two tables must hold the same rows.

The breakdown times the phases of the one-file command in this process, per squeeze log part:
reading (the bulk reader of ``read_squeeze_log``; for the before/after, the reference reader,
``load_mcap`` then ``squeezes_from_contents``, beside it on the first two parts' bytes), the
fits and the table write.

Run: ``python -m bench.bench_characterize`` (200 objects, about 2 minutes on 2 cores; ``make
bench`` runs it) or ``python -m bench.bench_characterize --objects 2000`` (about 10 minutes).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

TARGET_RATIO = 0.25
DEFAULT_OBJECTS = 200
REFERENCE_PARTS = 2  # parts of 100 objects the reference reader also reads, for the comparison


def _run(*args: str) -> float:
    """Wall seconds of one ``deformctl`` command (it must succeed)."""
    cmd = [sys.executable, "-m", "deformctl", *args]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        what = " ".join(args[:1])
        raise RuntimeError(f"{what} failed (exit {proc.returncode}): {proc.stderr[-500:]}")
    return wall


def _breakdown(squeeze: Path, out: Path) -> dict[str, float]:
    """Seconds per phase of ``characterize squeeze/ -o out`` in this process."""
    from deformctl.artifacts import write_table
    from deformctl.artifacts.io import read_input_bytes
    from deformctl.artifacts.mcap import load_mcap, read_squeeze_log, squeezes_from_contents
    from deformctl.characterize import FitOptions, default_window_s, squeeze_log_parts
    from deformctl.characterize.coefficients import _coefficient_frame
    from deformctl.characterize.stage import _fit_object, _stored_rate
    from deformctl.signals import sg_smooth

    t = dict.fromkeys(("read", "fits", "write", "imports", "reference read", "read of those"), 0.0)
    t["reference objects"] = 0
    t0 = time.perf_counter()
    sg_smooth(np.zeros(9), 5, 3, 1.0)  # the fits' one-off scipy.signal import
    t["imports"] = time.perf_counter() - t0
    rows = []
    for k, part in enumerate(squeeze_log_parts(squeeze)):
        t0 = time.perf_counter()
        objects, squeezes = read_squeeze_log(part)
        t1 = time.perf_counter()
        if k < REFERENCE_PARTS:
            data = read_input_bytes(part)
            reference = squeezes_from_contents(load_mcap(data, part))
            if len(reference) != len(squeezes):
                raise RuntimeError(f"{part}: the two readers disagree")
            del reference, data
            t["reference objects"] += len(objects)
            t["reference read"] += time.perf_counter() - t1
            t["read of those"] += t1 - t0
        t2 = time.perf_counter()
        meta = {str(o["object_id"]): o for o in objects}
        by_object: dict[str, list] = {}
        for s in squeezes:
            by_object.setdefault(s.object_id, []).append(s)
        for oid, group in by_object.items():
            window = default_window_s(_stored_rate(meta.get(oid)))
            row, _ = _fit_object(oid, group, meta.get(oid), FitOptions(), window_s=window)
            rows.append(row)
        t3 = time.perf_counter()
        t["read"] += t1 - t0
        t["fits"] += t3 - t2
    t0 = time.perf_counter()
    write_table(_coefficient_frame(rows), out, "coefficients", provenance=None, force=True)
    t["write"] = time.perf_counter() - t0
    return t


def main(argv: list[str] | None = None) -> None:
    """Print measure and characterize wall times, their ratios and the phase breakdown."""
    parser = argparse.ArgumentParser(prog="python -m bench.bench_characterize")
    parser.add_argument("--objects", type=int, default=DEFAULT_OBJECTS)
    n = parser.parse_args(argv if argv is not None else []).objects
    cores = len(os.sched_getaffinity(0))
    print(f"{n} objects, default measure --sim settings; cores available: {cores}; "
          f"load average before: {os.getloadavg()[0]:.2f}")  # fmt: skip
    with tempfile.TemporaryDirectory(prefix="bench_characterize_") as tmp:
        d = Path(tmp)
        _run("population", "-n", str(n), "--seed", "0", "-o", str(d / "pop.csv"))
        measure_s = _run("measure", str(d / "pop.csv"), "--sim", "--seed", "0", "-o", f"{d}/sq/")
        sweep_s = _run("characterize", f"{d}/sq/", "-o", f"{d}/coefficients/")
        file_s = _run("characterize", f"{d}/sq/", "-o", str(d / "coefficients.parquet"))
        swept = pd.read_parquet(d / "coefficients").sort_values("object_id", ignore_index=True)
        single = pd.read_parquet(d / "coefficients.parquet")
        if not swept.equals(single.sort_values("object_id", ignore_index=True)):
            raise RuntimeError("the sweep and the one-file table differ")
        load = os.getloadavg()[0]
        for what, secs in (("-o coefficients/ (sweep, every core)", sweep_s),
                           ("-o coefficients.parquet (one process)", file_s)):  # fmt: skip
            ratio = secs / measure_s
            verdict = "ok" if ratio <= TARGET_RATIO else "MISSED"
            print(f"characterize {what}: {secs:.1f} s; measure -o squeeze/: {measure_s:.1f} s; "
                  f"ratio {ratio:.3f} (target <= {TARGET_RATIO}: {verdict})")  # fmt: skip
        print(f"  load average after: {load:.2f} (other load on the machine moves both times)")
        phases = _breakdown(d / "sq", d / "breakdown.parquet")
        total = phases["read"] + phases["fits"] + phases["write"] + phases["imports"]
        per = 1000.0 / n
        print(f"phases of the one-process characterize, {n} objects "
              f"({len(single)} rows), in ms per object:")  # fmt: skip
        print(f"  read (bulk reader): {phases['read'] * per:.1f}; "
              f"fits: {phases['fits'] * per:.1f}; table write: {phases['write'] * per:.2f}; "
              f"scipy.signal import (once per process): {phases['imports']:.1f} s; "
              f"sum {total:.1f} s")  # fmt: skip
        ref, m = phases["reference read"], phases["reference objects"]
        print(f"  the reference reader (load_mcap + per-message checks, before the bulk reader) "
              f"on the first {m:.0f} objects' logs: {ref * 1000 / m:.1f} ms per object, "
              f"{ref / phases['read of those']:.1f}x the bulk reader's time")  # fmt: skip


if __name__ == "__main__":
    main(sys.argv[1:])
