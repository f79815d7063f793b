"""Where a robot waits: one ``deformctl predict grip`` command, and one library call.

Prints, measured side by side in this run (the machine is shared; quote the ratios):

* the wall time and the CPU time (user + sys) of ``python -c pass`` and of one-object
  ``deformctl predict grip --weight-n ... --friction-mu ... --coverage 0.9`` (median of 7 runs
  each, the command's own console script), and their ratio; target: the command <= 1.0 s wall.
  On a shared machine the wall time waits for the other jobs (the load average is printed); the
  CPU time is what the command costs;
* the cost of :meth:`deformctl.grip.fast.Predictor.load` (``grip``) and of one
  :meth:`~deformctl.grip.fast.Predictor.predict` call after loading, with and without a bound
  (median over 7 batches of 2,000 calls), beside a bare numpy ``(1, 2) @ (2, 8)`` product as
  the yardstick; target: <= 100 µs per call.
"""

from __future__ import annotations

import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

CLI_TARGET_S = 1.0
CALL_TARGET_US = 100.0
OBJECT = ("2.9", "30", "0.47", "0.5")  # Table I's sand: W, D, λ, μ


def _wall(cmd: list[str], runs: int = 7) -> tuple[float, float]:
    """(median wall s, median CPU s: user + sys of the child) over ``runs`` runs."""
    walls, cpus = [], []
    for _ in range(runs):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True)
        walls.append(time.perf_counter() - t0)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpus.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    return statistics.median(walls), statistics.median(cpus)


def _per_call_us(fn: object, calls: int = 2000, batches: int = 7) -> float:
    times = []
    for _ in range(batches):
        t0 = time.perf_counter()
        for _ in range(calls):
            fn()  # type: ignore[operator]
        times.append((time.perf_counter() - t0) / calls * 1e6)
    return statistics.median(times)


def main() -> None:
    import numpy as np

    from deformctl.grip.fast import Predictor, resolve_model_path

    if not resolve_model_path("grip").is_file():
        print("no bundled model (datasets/models/grip.skops): run make model")
        return
    script = str(Path(sys.executable).with_name("deformctl"))
    w, d, lam, mu = OBJECT
    command = [
        script, "predict", "grip", "--weight-n", w, "--deformability-n-per-cm", d,
        "--damping-ns-per-cm", lam, "--friction-mu", mu, "--coverage", "0.9",
    ]  # fmt: skip
    base, base_cpu = _wall([sys.executable, "-c", "pass"])
    cli, cli_cpu = _wall(command)
    print(f"load average (1 min): {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print(
        f"python -c pass:                    {base:.3f} s wall, {base_cpu:.3f} s CPU (median of 7)"
    )
    ratio = cli / base
    print(
        f"deformctl predict grip (1 object): {cli:.3f} s wall, {cli_cpu:.3f} s CPU (median of 7),"
        f" {ratio:.1f} x python -c pass; target <= {CLI_TARGET_S:.1f} s wall"
    )

    t0 = time.perf_counter()
    grip = Predictor.load("grip")
    load_ms = (time.perf_counter() - t0) * 1e3
    args = (float(w), float(d), float(lam), float(mu))
    a, b = np.ones((1, 2)), np.ones((2, 8))
    matmul = _per_call_us(lambda: a @ b)
    plain = _per_call_us(lambda: grip.predict(*args))
    bound = _per_call_us(lambda: grip.predict(*args, coverage=0.9))
    print(f"Predictor.load('grip'):            {load_ms:.1f} ms")
    print(f"numpy (1,2) @ (2,8), yardstick:    {matmul:.2f} µs per call")
    print(f"Predictor.predict:                 {plain:.1f} µs per call ({plain / matmul:.0f} x "
          f"the product); target <= {CALL_TARGET_US:.0f} µs")  # fmt: skip
    print(f"Predictor.predict, coverage 0.9:   {bound:.1f} µs per call ({bound / matmul:.0f} x)")


if __name__ == "__main__":
    main()
