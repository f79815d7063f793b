"""``measure --csv`` on 190 real-sized exports in one call (target: ≤ 60 s on 2 cores).

The 190 files are made from the real silicone phantom recordings (the 38 of the shared folder
when it is there, else the 3 shipped in ``datasets/examples/phantom/``, cycled), each written in
five dialects a user meets, all read with no option but ``--weight-n``:

1. the file as it is (a 7-line preamble, units in the names);
2. ``;`` and a decimal comma;
3. the load negative in compression (an Instron convention);
4. two header rows (names, then ``(s),(mm),(kN)``), quoted values, the load in kN;
5. tab-separated, with a UTF-8 byte-order mark.

Timed in this run, interpreter start-up included: ``measure --csv <190 files> -o DIR/`` (every
core; the target), the same into one log, ``characterize DIR/ --model kv``, and one single-file
``measure`` + ``characterize`` pair (a shell loop over the files costs 190 of them: the ratio is
printed). The five dialects of a recording must give the same D (the spread is printed).

``--memory`` also measures the peak memory per data row (1 million rows against 10,000; the
figure behind ``deformctl.measure.csv.reader.CSV_ROW_BYTES``).

Run: ``python -m bench.bench_csv`` (about a minute on 2 cores; ``make bench`` runs it).
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

TARGET_S = 60.0
FILES = 190
REPO = Path(__file__).resolve().parents[1]
SHARED = Path("/work/shared/data/phantom")
SHIPPED = REPO / "datasets" / "examples" / "phantom"


def _run(*args: str) -> float:
    """Wall seconds of one ``deformctl`` command (it must succeed)."""
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "deformctl", *args], capture_output=True, text=True, check=False
    )
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"{args[0]} failed (exit {proc.returncode}): {proc.stderr[-800:]}")
    return wall


def _variants(src: Path, out: Path, stem: str) -> list[Path]:
    """The five dialects of one real export (module docstring)."""
    lines = src.read_text(encoding="utf-8").splitlines()
    pre, header, rows = lines[:7], lines[7], [r.split(",") for r in lines[8:]]
    paths = [out / f"{stem}_v{k}.csv" for k in range(1, 6)]
    shutil.copyfile(src, paths[0])
    euro = [";".join(c.replace(".", ",") for c in r) for r in rows]
    paths[1].write_text("\n".join([*pre, header.replace(",", ";"), *euro]) + "\n")
    neg = [",".join([r[0], r[1], f"{-float(r[2]):.6f}", *r[3:]]) for r in rows]
    paths[2].write_text("\n".join([*pre, header, *neg]) + "\n")
    names = "Time,Compression,Load"
    blue = [f'"{r[0]}","{r[1]}","{float(r[2]) / 1e3:.9f}"' for r in rows]
    paths[3].write_text("\n".join([*pre, names, "(s),(mm),(kN)", *blue]) + "\n")
    tab = ["\t".join(r) for r in rows]
    data = "\n".join([*pre, header.replace(",", "\t"), *tab]) + "\n"
    paths[4].write_bytes(b"\xef\xbb\xbf" + data.encode())
    return paths


def _memory_per_row(work: Path) -> None:
    """Peak RSS of ``measure --csv`` on 1 million rows against 10,000, per row."""
    rss = {}
    for n in (10_000, 1_000_000):
        t = np.arange(n) / 1000.0
        f = 5.0 * (1.0 - np.cos(2.0 * np.pi * t / t[-1]))
        path = work / f"rows{n}.csv"
        with path.open("w") as fh:
            fh.write("Time (s),Load (N),Compression (mm)\n")
            np.savetxt(fh, np.column_stack([t, f, f / 2.0]), fmt="%.5f", delimiter=",")
        before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
        _run("measure", "--csv", str(path), "--object-id", "x", "--weight-n", "1",
             "-o", str(work / f"rows{n}.mcap"), "--memory-budget-gib", "8")  # fmt: skip
        rss[n] = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
        if rss[n] == before:
            print(f"  (peak RSS of the {n:,}-row run not above an earlier child's: not measured)")
    per_row = (rss[1_000_000] - rss[10_000]) * 1024 / 990_000
    print(f"memory: {per_row:.0f} B per data row (peak RSS, 1,000,000 rows vs 10,000)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--files", type=int, default=FILES)
    parser.add_argument("--memory", action="store_true", help="also measure bytes per row")
    args = parser.parse_args()
    real = sorted(SHARED.glob("*.csv")) if SHARED.is_dir() else sorted(SHIPPED.glob("*.csv"))
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        exports = work / "exports"
        exports.mkdir()
        files: list[Path] = []
        k = 0
        while len(files) < args.files:
            src = real[k % len(real)]
            files += _variants(src, exports, f"{src.stem}_{k // len(real)}")
            k += 1
        files = files[: args.files]
        size = sum(f.stat().st_size for f in files)
        print(
            f"{len(files)} files from {len(real)} real recordings x 5 dialects, "
            f"{size / 1e6:.1f} MB, {os.cpu_count()} cores"
        )
        common = ["--weight-n", "0.62"]
        names = [str(f) for f in files]
        t_dir = _run("measure", "--csv", *names, *common, "-o", f"{work / 'squeeze'}/")
        verdict = "meets" if t_dir <= TARGET_S else "MISSES"
        print(f"measure --csv <{len(files)} files> -o DIR/: {t_dir:.1f} s "
              f"({t_dir / TARGET_S:.2f} x the {TARGET_S:g} s target: {verdict})")  # fmt: skip
        t_log = _run("measure", "--csv", *names, *common, "-o", str(work / "all.mcap"))
        print(f"measure --csv <{len(files)} files> -o all.mcap: {t_log:.1f} s")
        coef = work / "coef.parquet"
        t_char = _run("characterize", f"{work / 'squeeze'}/", "-o", str(coef), "--model", "kv")
        print(f"characterize DIR/ --model kv: {t_char:.1f} s")
        one = work / "one.mcap"
        t_one = _run("measure", "--csv", names[0], *common, "-o", str(one))
        t_one += _run("characterize", str(one), "-o", str(work / "one.parquet"))
        loop = t_one * len(files)
        print(f"one file, measure + characterize: {t_one:.1f} s; a shell loop over "
              f"{len(files)} files about {loop:.0f} s, {loop / (t_dir + t_char):.0f} x this "
              "run's two commands")  # fmt: skip
        table = pd.read_parquet(coef)
        table["recording"] = table["object_id"].str.rsplit("_v", n=1).str[0]
        spread = table.groupby("recording")["deformability_n_per_cm"].agg(
            lambda d: d.max() / d.min() - 1
        )
        print(f"D of the 5 dialects of a recording: largest spread {100 * spread.max():.4f} % "
              f"(D {table['deformability_n_per_cm'].min():.1f}-"
              f"{table['deformability_n_per_cm'].max():.1f} N/cm)")  # fmt: skip
        if args.memory:
            _memory_per_row(work)


if __name__ == "__main__":
    main()
