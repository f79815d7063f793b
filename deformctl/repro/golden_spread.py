"""``make golden-spread``: the golden numbers under every OpenBLAS kernel, and their spread.

OpenBLAS picks its kernels per CPU (SkylakeX on a recent Intel or AMD server, Haswell on an older
one or where ``OPENBLAS_CORETYPE`` says so, ...), and the kernels round differently in the last
bits. This script measures what that does to the numbers the tests compare:

1. It asks each OpenBLAS core name (:data:`CORETYPES`) which kernel it really selects: a
   subprocess with ``OPENBLAS_CORETYPE=name`` reports threadpoolctl's ``architecture`` for every
   BLAS library loaded (numpy's and scipy's). Names that select the same kernel are grouped.
2. It recomputes :func:`deformctl.repro.golden.compute_golden` in a subprocess under each
   requested kernel (default: :data:`REQUIRED_KERNELS`, plus one name for each other kernel the
   installed libraries accept) x each BLAS thread count (``OPENBLAS_NUM_THREADS``; the child
   checks that threadpoolctl reports that kernel and that thread count), and prints each
   number's spread (max - min over the runs) beside its tolerance
   (:data:`deformctl.repro.golden.TOLERANCES`) and the worst move from
   ``datasets/golden/expected.json`` as a fraction of what the tolerance allows.
3. It runs test files (default ``tests/repro/test_golden.py``) under each kernel with pytest, in a
   subprocess that first prints the kernel threadpoolctl reports.

Only this script sets OpenBLAS variables, in its own subprocesses; the tests and CI never do.
``default`` runs with ``OPENBLAS_CORETYPE`` and ``OPENBLAS_L2_SIZE`` unset (the library's own
choice); a named kernel sets the first and unsets the second (a cache size detected for one
CPU would otherwise size another kernel's blocks). The exit status is 1 when a run failed, a
kernel did not take effect, a number moved beyond its tolerance or a test failed.

Usage::

    python -m deformctl.repro.golden_spread [--kernels default,Haswell,...] [--threads 1,2]
        [--jobs N] [--tests FILE ...] [--no-spread] [--json OUT.json] [--verbose]

``--no-spread --tests tests/train/test_train.py ...`` is the audit mode: the given test files under
each kernel (x each ``--threads`` value with ``--test-threads``), no golden run.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any

#: The kernels the issue asks for; ``default`` is the library's own choice for this CPU.
REQUIRED_KERNELS = ("default", "Haswell", "Zen", "SkylakeX", "Sandybridge", "Prescott")
#: OpenBLAS's x86_64 core names (``OPENBLAS_CORETYPE`` values); a build accepts a subset and maps
#: the others to a kernel it has (threadpoolctl then reports that kernel).
CORETYPES = (
    "Katmai", "Coppermine", "Northwood", "Prescott", "Banias", "Atom", "Core2", "Penryn",
    "Dunnington", "Nehalem", "Athlon", "Opteron", "Opteron_SSE3", "Barcelona", "Nano",
    "Sandybridge", "Bobcat", "Bulldozer", "Piledriver", "Haswell", "Steamroller", "Excavator",
    "Zen", "SkylakeX", "Cooperlake", "SapphireRapids",
)  # fmt: skip
DEFAULT_TESTS = ("tests/repro/test_golden.py",)
_BLAS_VARS = ("OPENBLAS_CORETYPE", "OPENBLAS_L2_SIZE", "OPENBLAS_NUM_THREADS")


def kernel_env(kernel: str, threads: int | None) -> dict[str, str]:
    """The environment of a subprocess that runs under ``kernel`` with ``threads`` BLAS threads.

    ``threads`` None leaves the thread count to the library (the machine's core count).
    """
    env = {k: v for k, v in os.environ.items() if k not in _BLAS_VARS}
    if kernel != "default":
        env["OPENBLAS_CORETYPE"] = kernel
    if threads is not None:
        env["OPENBLAS_NUM_THREADS"] = str(threads)
    return env


def _architectures(blas: list[dict[str, Any]]) -> str:
    """``SkylakeX`` (or ``SkylakeX/Haswell`` when the libraries disagree)."""
    return "/".join(sorted({str(lib.get("architecture")) for lib in blas})) or "no BLAS"


# --- the children ---------------------------------------------------------------------------


def _loaded_blas() -> list[dict[str, Any]]:
    import numpy  # noqa: F401  (numpy's OpenBLAS)
    import scipy.linalg  # noqa: F401  (scipy's OpenBLAS)

    from deformctl.blas import blas_info

    return blas_info()


def _child_golden() -> int:
    from deformctl.repro.golden import compute_golden

    start = time.perf_counter()
    golden = compute_golden()
    seconds = time.perf_counter() - start
    print(json.dumps({"blas": _loaded_blas(), "seconds": seconds, "golden": golden}))
    return 0


def _child_pytest(args: list[str]) -> int:
    import pytest

    from deformctl.blas import blas_summary

    print(f"BLAS: {blas_summary(_loaded_blas())}", flush=True)
    return int(pytest.main(args))


# --- the parent -----------------------------------------------------------------------------


def _child(mode: str, kernel: str, threads: int | None, extra: Sequence[str] = ()) -> Any:
    cmd = [sys.executable, "-m", "deformctl.repro.golden_spread", mode, *extra]
    return subprocess.run(
        cmd, env=kernel_env(kernel, threads), capture_output=True, text=True, check=False
    )


def probe(kernel: str) -> list[dict[str, Any]]:
    """The BLAS libraries a subprocess under ``kernel`` loads, as :func:`blas_info` reports."""
    proc = _child("--child-probe", kernel, None)
    if proc.returncode != 0:
        raise RuntimeError(f"probe of {kernel} failed: {proc.stderr.strip()[-500:]}")
    return list(json.loads(proc.stdout.strip().splitlines()[-1]))


def choose_kernels(requested: Sequence[str] | None, jobs: int) -> dict[str, str]:
    """Requested kernel name -> the architecture it selects.

    With ``requested`` None: :data:`REQUIRED_KERNELS` plus the first name of every other
    architecture among :data:`CORETYPES`. Prints which names select which kernel.
    """
    names = list(dict.fromkeys(["default", *CORETYPES, *(requested or ())]))
    with ThreadPoolExecutor(max(1, jobs)) as pool:
        archs = dict(zip(names, pool.map(lambda k: _architectures(probe(k)), names), strict=True))
    groups: dict[str, list[str]] = {}
    for name, arch in archs.items():
        groups.setdefault(arch, []).append(name)
    print("OpenBLAS core names -> the kernel threadpoolctl reports:")
    for arch, members in groups.items():
        print(f"  {arch}: {', '.join(members)}")
    if requested is not None:
        return {k: archs[k] for k in requested}
    chosen = {k: archs[k] for k in REQUIRED_KERNELS}
    for arch, members in groups.items():
        if arch not in chosen.values():
            chosen[members[0]] = arch
    return chosen


@dataclass(frozen=True)
class Run:
    """One golden run: the kernel asked for, the threads, what the child reported."""

    kernel: str
    threads: int | None
    architecture: str
    num_threads: str
    seconds: float
    golden: dict[str, Any] | None
    error: str = ""


def run_golden(kernel: str, threads: int | None, expected_arch: str) -> Run:
    """compute_golden in a subprocess under ``kernel`` x ``threads``; checks the kernel took."""
    proc = _child("--child-golden", kernel, threads)
    if proc.returncode != 0:
        return Run(kernel, threads, "?", "?", math.nan, None, proc.stderr.strip()[-800:])
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    arch = _architectures(out["blas"])
    nthreads = "/".join(sorted({str(lib["num_threads"]) for lib in out["blas"]}))
    error = ""
    if arch != expected_arch:
        error = f"kernel did not take effect: asked {kernel} ({expected_arch}), got {arch}"
    elif threads is not None and nthreads != str(threads):
        error = f"thread count did not take effect: asked {threads}, got {nthreads}"
    return Run(kernel, threads, arch, nthreads, float(out["seconds"]), out["golden"], error)


def spread_rows(runs: Sequence[Run], expected: dict[str, Any]) -> list[dict[str, Any]]:
    """Per tolerance family: instances, spread, tolerance and the worst move from expected."""
    from deformctl.repro.golden import REPORTED_ONLY, TOLERANCES, family, flatten

    flat_expected = flatten(expected)
    values: dict[str, list[float]] = {}
    for run in runs:
        if run.golden is not None:
            for key, value in flatten(run.golden).items():
                values.setdefault(key, []).append(value)
    rows: dict[str, dict[str, Any]] = {}
    for key, vals in sorted(values.items()):
        fam = family(key)
        row = rows.setdefault(
            fam,
            {"family": fam, "n": 0, "abs": 0.0, "rel": 0.0, "ratio": math.inf, "worst": 0.0,
             "where": ""},
        )  # fmt: skip
        lo, hi = min(vals), max(vals)
        spread = hi - lo
        mid = sorted(vals)[len(vals) // 2]
        rel = spread / abs(mid) if mid else (0.0 if spread == 0 else math.inf)
        row["n"] += 1
        if spread > row["abs"]:
            row["abs"], row["where"] = spread, key
        row["rel"] = max(row["rel"], rel)
        tol = TOLERANCES.get(fam)
        row["tolerance"] = (
            "not compared" if fam in REPORTED_ONLY else (tol.basis if tol else "MISSING")
        )
        if tol is not None and fam not in REPORTED_ONLY and key in flat_expected:
            e = flat_expected[key]
            allowed = tol.allowed(e)
            if spread > 0:
                row["ratio"] = min(row["ratio"], allowed / spread)
            worst = max(abs(v - e) for v in vals)
            moved = worst / allowed if allowed > 0 else (math.inf if worst > 0 else 0.0)
            row["worst"] = max(row["worst"], moved)
    return list(rows.values())


def _fmt(x: float) -> str:
    if math.isinf(x):
        return "inf"
    return "0" if x == 0 else f"{x:.2g}"


def print_spread(rows: Sequence[dict[str, Any]]) -> None:
    """The spread table, in Markdown."""
    print(
        "\n| number | n | spread (abs) | spread (rel) | tolerance | tolerance / spread "
        "| worst move / allowed |"
    )
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        compared = r["tolerance"] not in ("not compared", "MISSING")
        ratio = ("exact" if r["abs"] == 0 else _fmt(r["ratio"])) if compared else "-"
        worst = _fmt(r["worst"]) if compared else "-"
        print(
            f"| {r['family']} | {r['n']} | {_fmt(r['abs'])} | {_fmt(r['rel'])} "
            f"| {r['tolerance']} | {ratio} | {worst} |"
        )


def run_tests(
    kernels: dict[str, str],
    threads: Sequence[int | None],
    files: Sequence[str],
    jobs: int,
    pytest_args: Sequence[str],
) -> bool:
    """Each test file set under each kernel x thread count; prints one line per run."""
    combos = [(k, t) for k in kernels for t in threads]

    def one(combo: tuple[str, int | None]) -> tuple[str, int | None, int, str, str, float]:
        start = time.perf_counter()
        proc = _child(
            "--child-pytest", *combo, ["-q", "-p", "no:cacheprovider", *pytest_args, *files]
        )
        lines = proc.stdout.strip().splitlines()
        blas = next((ln[6:] for ln in lines if ln.startswith("BLAS: ")), "?")
        failed = [ln for ln in lines if ln.startswith(("FAILED ", "ERROR "))]
        summary = "\n    ".join([lines[-1] if lines else proc.stderr.strip()[-300:], *failed])
        return (*combo, proc.returncode, blas, summary, time.perf_counter() - start)

    print(f"\ntests under each kernel: {' '.join(files)}")
    ok = True
    with ThreadPoolExecutor(max(1, jobs)) as pool:
        for kernel, t, code, blas, summary, seconds in pool.map(one, combos):
            took = (
                all(kernels[kernel] in part for part in blas.split(", ")) if blas != "?" else False
            )
            status = "PASS" if code == 0 and took else "FAIL"
            ok &= status == "PASS"
            note = "" if took else f" (kernel {kernels[kernel]} did not take effect)"
            print(
                f"  {status} {kernel} threads={t or 'default'} [{blas}] {seconds:.0f} s: "
                f"{summary}{note}"
            )
    return ok


def _threads(text: str) -> list[int | None]:
    return [None if t == "default" else int(t) for t in text.split(",")]


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (see the module docstring)."""
    args = list(sys.argv[1:] if argv is None else argv)
    if args[:1] == ["--child-probe"]:
        print(json.dumps(_loaded_blas()))
        return 0
    if args[:1] == ["--child-golden"]:
        return _child_golden()
    if args[:1] == ["--child-pytest"]:
        return _child_pytest(args[1:])
    parser = argparse.ArgumentParser(prog="python -m deformctl.repro.golden_spread")
    parser.add_argument("--kernels", help="comma list (default: the required ones + the rest)")
    parser.add_argument("--threads", default="1,2", help="BLAS thread counts of the golden runs")
    parser.add_argument("--test-threads", default="default", help="thread counts of the tests")
    parser.add_argument("--jobs", type=int, default=1, help="subprocesses side by side")
    parser.add_argument("--tests", nargs="*", default=list(DEFAULT_TESTS), help="test files")
    parser.add_argument("--pytest-args", default="", help="extra pytest arguments, one string")
    parser.add_argument("--no-spread", action="store_true", help="only run the tests")
    parser.add_argument("--json", help="write every run's numbers to this file")
    parser.add_argument("--verbose", action="store_true", help="print every run's errors")
    opts = parser.parse_args(args)
    if hasattr(sys.stdout, "reconfigure"):  # each line as it comes, also into a pipe or a file
        sys.stdout.reconfigure(line_buffering=True)

    from deformctl.repro.golden import EXPECTED_PATH, compare

    start = time.perf_counter()
    kernels = choose_kernels(opts.kernels.split(",") if opts.kernels else None, opts.jobs)
    ok = True
    if not opts.no_spread:
        combos = [(k, t) for k in kernels for t in _threads(opts.threads)]
        with ThreadPoolExecutor(max(1, opts.jobs)) as pool:
            runs = list(pool.map(lambda c: run_golden(c[0], c[1], kernels[c[0]]), combos))
        expected = json.loads(EXPECTED_PATH.read_text())
        print("\n| kernel asked | kernel used | BLAS threads | seconds | vs expected.json |")
        print("|---|---|---|---|---|")
        for run in runs:
            moved = compare(expected, run.golden) if run.golden is not None else []
            verdict = (
                run.error.splitlines()[-1]
                if run.error
                else (f"{len(moved)} moved" if moved else "within tolerance")
            )
            ok &= not run.error and not moved
            print(
                f"| {run.kernel} | {run.architecture} | {run.num_threads} | {run.seconds:.1f} "
                f"| {verdict} |"
            )
            if opts.verbose or moved:
                for line in moved:
                    print(f"    {line}")
        print_spread(spread_rows(runs, expected))
        if opts.json:
            with open(opts.json, "w") as fh:
                json.dump([vars(r) for r in runs], fh, indent=1)
    if opts.tests:
        ok &= run_tests(
            kernels, _threads(opts.test_threads), opts.tests, opts.jobs, opts.pytest_args.split()
        )
    print(f"\n{'all passed' if ok else 'FAILED'} in {time.perf_counter() - start:.0f} s")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
