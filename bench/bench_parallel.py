"""Sweep executor: objects/s with 1 and 2 local workers, and peak memory of a 2,000-object sweep.

Throughput uses a CPU-bound toy task calibrated to about 50 ms per object in this process; the
ratio of the 2-worker and 1-worker rates is printed (target >= 1.7 on 2 idle cores; other load on
the machine lowers it). Memory runs a fast task (3 rows and a 16 KiB payload per object, written
per part by a ``part_writer``) over 500 and 2,000 objects in a fresh interpreter and prints the
client's peak RSS and the largest worker peak RSS; flat memory means the 2,000-object peak is
close to the 500-object one. Target: client + workers < 1 GiB.

Run: ``python -m bench.bench_parallel`` (or ``make bench``).
"""

from __future__ import annotations

import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import pyarrow as pa

from deformctl.artifacts.dataset import PartPayloads
from deformctl.artifacts.io import atomic_write_bytes
from deformctl.parallel import TaskOutput, run_sweep

CPU_SCHEMA = pa.schema([pa.field("object_id", pa.int64()), pa.field("checksum", pa.int64())])
MEM_SCHEMA = pa.schema(
    [
        pa.field("object_id", pa.int64()),
        pa.field("trial", pa.int64()),
        pa.field("force_n", pa.float64()),
        pa.field("worker_peak_rss_kib", pa.int64()),
    ]
)
TARGET_TASK_S = 0.050
GIB = 1024**3


def spin(n_iter: int, seed: int) -> int:
    """A fixed amount of pure-Python integer work (an LCG), about ``n_iter`` * 50 ns."""
    x = seed
    for _ in range(n_iter):
        x = (x * 6364136223846793005 + 1442695040888963407) & 0xFFFFFFFFFFFFFFFF
    return x >> 33


def cpu_task(item: dict[str, Any]) -> list[dict[str, Any]]:
    """One object of CPU-bound work."""
    return [{"checksum": spin(item["n_iter"], item["object_id"])}]


def peak_rss_kib() -> int:
    """This process's own peak resident set, KiB (``VmHWM``). ``getrusage``'s ``ru_maxrss``
    survives ``execve`` on Linux, so a fresh interpreter started by a big process would report
    its parent's peak; the high-water mark of /proc belongs to the new address space."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1])
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def fast_task(item: dict[str, Any]) -> TaskOutput:
    """Three rows and a 16 KiB payload; records the worker's own peak RSS."""
    i = item["object_id"]
    peak_kib = peak_rss_kib()
    rows = [{"trial": t, "force_n": 0.1 * i + t, "worker_peak_rss_kib": peak_kib} for t in range(3)]
    return TaskOutput(rows, bytes([i % 251]) * 16384)


def write_payloads(part: PartPayloads) -> None:
    """The per-part artifact hook: all payloads of the part in one file."""
    atomic_write_bytes(part.path(".bin"), b"".join(p for _, p in part.payloads))


def _calibrate() -> int:
    n = 20_000
    while True:
        t0 = time.perf_counter()
        spin(n, 1)
        dt = time.perf_counter() - t0
        if dt > 0.02:
            return max(1, int(n * TARGET_TASK_S / dt))
        n *= 2


def _throughput(n_iter: int, n_objects: int, workers: int, tmp: Path) -> float:
    items = [{"object_id": i, "n_iter": n_iter} for i in range(n_objects)]
    s = run_sweep(
        cpu_task,
        items,
        out_dir=tmp / f"cpu-{workers}",
        schema=CPU_SCHEMA,
        fingerprint={"command": "bench-cpu"},
        workers=workers,
        partition_size=10,
        progress=False,
    )
    return s.rate


def memory_sweep(n_objects: int, out_dir: str) -> dict[str, Any]:
    """Run the fast sweep in this (fresh) interpreter; peak RSS of client and workers, KiB."""
    from deformctl.artifacts.dataset import read_dataset

    items = [{"object_id": i} for i in range(n_objects)]
    t0 = time.perf_counter()
    s = run_sweep(
        fast_task,
        items,
        out_dir=out_dir,
        schema=MEM_SCHEMA,
        fingerprint={"command": "bench-memory"},
        workers=2,
        partition_size=100,
        progress=False,
        part_writer=write_payloads,
    )
    client_kib = peak_rss_kib()
    wall_s = time.perf_counter() - t0
    worker_kib = int(read_dataset(out_dir)["worker_peak_rss_kib"].max())
    return {
        "n": n_objects,
        "done": s.done,
        "rate": s.rate,
        "wall_s": wall_s,
        "client_peak_kib": client_kib,
        "worker_peak_kib": worker_kib,
    }


def _memory_in_subprocess(n_objects: int, tmp: Path) -> dict[str, Any]:
    code = (
        "import json, sys; from bench.bench_parallel import memory_sweep; "
        f"print(json.dumps(memory_sweep({n_objects}, {str(tmp / f'mem-{n_objects}')!r})))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], check=True, capture_output=True, text=True, timeout=600
    )
    return dict(json.loads(out.stdout.strip().splitlines()[-1]))


def main() -> None:
    with tempfile.TemporaryDirectory(prefix="bench_parallel_") as tmp_name:
        tmp = Path(tmp_name)
        n_iter = _calibrate()
        n_objects = 60
        _throughput(n_iter, 4, 2, tmp / "warm")  # start the fork server outside the timing
        rate_1 = _throughput(n_iter, n_objects, 1, tmp)
        rate_2 = _throughput(n_iter, n_objects, 2, tmp)
        print(
            f"cpu task ~{TARGET_TASK_S * 1e3:.0f} ms/object, {n_objects} objects: "
            f"1 worker {rate_1:.2f} objects/s, 2 workers {rate_2:.2f} objects/s, "
            f"ratio {rate_2 / rate_1:.2f}x (target >= 1.7x on 2 idle cores)"
        )
        for n in (500, 2000):
            m = _memory_in_subprocess(n, tmp)
            total_gib = (m["client_peak_kib"] + 2 * m["worker_peak_kib"]) * 1024 / GIB
            print(
                f"memory sweep {m['n']} objects (2 workers, 16 KiB payload each): "
                f"{m['rate']:.0f} objects/s, "
                f"client peak RSS {m['client_peak_kib'] / 1024:.0f} MiB, "
                f"worker peak RSS {m['worker_peak_kib'] / 1024:.0f} MiB, "
                f"client + 2 workers <= {total_gib:.2f} GiB (target < 1 GiB)"
            )


if __name__ == "__main__":
    main()
