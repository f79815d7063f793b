"""Before and after: the same commands, this tree against an earlier commit, in one run.

The house issue split ``sim/kernels.py``, ``measure``, ``characterize`` and the MCAP module into
packages and bundled the numba kernels' arguments; speed may not drop by more than 5 %. This
benchmark checks that as a user sees it: it unpacks the commit ``BENCH_BASE`` (default
``aa8bb22``, the last commit before the split) into ``.bench/base-<commit>/`` with its own venv
(made once, about 3 minutes: pip install and the numba warm-up), then runs each command below
with the base's ``deformctl`` and this tree's, in turn (base, head, base, head, ...), and prints
the median of the per-pair ratios head / base of wall time and of CPU time (user + system of
the finished child). Pairing keeps a ratio meaningful while the shared machine's speed drifts;
CPU time is the judge (target <= 1.05), wall time is printed beside it.

The commands do the same work in both trees: this tree's simulator logs are written without
the Foxglove scene (``--scene-hz 0``, which the base does not have) and ``characterize`` fits
the base's one law (``--model kv``). ``BENCH_BASE=`` (empty) skips the benchmark;
``BENCH_ROUNDS`` sets the pairs per command (default 5).

Run: ``python -m bench revision`` (or ``make bench``).
"""

from __future__ import annotations

import os
import resource
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
DEFAULT_BASE = "aa8bb22"
TARGET_RATIO = 1.05
CATALOG = REPO / "datasets" / "paper" / "objects.csv"


def _run(cmd: list[str], cwd: Path) -> tuple[float, float]:
    """Wall and CPU seconds of one run of ``cmd`` (which must succeed)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} exited {done.returncode}:\n{done.stderr[-2000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def base_tree(commit: str) -> Path:
    """``commit``'s files with an installed venv, made once under ``.bench/``."""
    sha = subprocess.run(
        ["git", "rev-parse", "--short", f"{commit}^{{commit}}"],
        cwd=REPO,
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    root = REPO / ".bench" / f"base-{sha}"
    ready = root / ".venv" / ".installed"
    if ready.exists():
        return root
    root.mkdir(parents=True, exist_ok=True)
    print(f"(making {root.relative_to(REPO)}: the files of {sha} and a venv; once)", flush=True)
    archive = subprocess.run(
        ["git", "archive", "--format=tar", sha], cwd=REPO, capture_output=True, check=True
    ).stdout
    with tempfile.TemporaryFile() as tmp:
        tmp.write(archive)
        tmp.seek(0)
        with tarfile.open(fileobj=tmp) as tar:
            tar.extractall(root, filter="data")
    python = root / ".venv" / "bin" / "python"
    subprocess.run([sys.executable, "-m", "venv", str(root / ".venv")], check=True)
    subprocess.run([python, "-m", "pip", "install", "--quiet", "-e", str(root)], check=True)
    subprocess.run([python, "-m", "deformctl.sim.warmup"], cwd=root, check=True)
    ready.touch()
    return root


def commands(work: Path, side: str) -> list[tuple[str, list[str]]]:
    """(name, arguments) of each command for one tree (``side``: "base" or "head"); each
    writes a fresh file under ``work`` (removed before each run), and ``characterize`` reads
    the squeeze log that the same tree's ``measure`` wrote."""
    head = side == "head"
    return [
        ("deformctl --help", ["--help"]),
        ("measure --sim (4 paper objects)", _measure(work / f"{side}-m.mcap", side)),
        (
            "characterize (4 squeezes, kv)",
            ["characterize", str(work / f"{side}.mcap"), "-o", str(work / f"{side}-c.parquet")]
            + (["--model", "kv"] if head else []),
        ),
        (
            "lift --sim (4 paper objects)",
            ["lift", str(CATALOG), "--sim", "-o", str(work / f"{side}-l.parquet")],
        ),
    ]


def _measure(log: Path, side: str) -> list[str]:
    """``measure --sim`` of the paper's objects into ``log``, without the scene in this tree."""
    args = ["measure", str(CATALOG), "--sim", "--seed", "0", "-o", str(log)]
    return args + (["--scene-hz", "0"] if side == "head" else [])


def _fresh(cli: str, args: list[str], work: Path) -> tuple[float, float]:
    """One run of ``cli args`` after removing the file it writes."""
    for name in ("-m.mcap", "-c.parquet", "-l.parquet"):
        for old in work.glob(f"*{name}"):
            old.unlink()
    return _run([cli, *args], work)


def main() -> None:
    commit = os.environ.get("BENCH_BASE", DEFAULT_BASE)
    if not commit:
        print("BENCH_BASE is empty: skipped")
        return
    rounds = int(os.environ.get("BENCH_ROUNDS", "5"))
    base = base_tree(commit)
    base_cli = str(base / ".venv" / "bin" / "deformctl")
    head_cli = str(Path(sys.executable).parent / "deformctl")
    print(f"base {commit} ({base_cli}) against this tree; {rounds} pairs per command")
    print(f"{'command':34s} {'base s':>8s} {'head s':>8s} {'wall ratio':>10s} {'cpu ratio':>10s}")
    worst = 0.0
    with tempfile.TemporaryDirectory(prefix="bench-revision-") as tmp:
        work = Path(tmp)
        for side, cli in (("base", base_cli), ("head", head_cli)):  # the logs characterize reads
            _run([cli, *_measure(work / f"{side}.mcap", side)], work)
        for k, (name, _) in enumerate(commands(work, "head")):
            base_args, head_args = commands(work, "base")[k][1], commands(work, "head")[k][1]
            _fresh(base_cli, base_args, work)  # warm-up: page cache, numba caches
            _fresh(head_cli, head_args, work)
            walls: list[tuple[float, float]] = []
            cpus: list[tuple[float, float]] = []
            for _ in range(rounds):
                b = _fresh(base_cli, base_args, work)
                h = _fresh(head_cli, head_args, work)
                walls.append((b[0], h[0]))
                cpus.append((b[1], h[1]))
            wall_ratio = statistics.median(h / b for b, h in walls)
            cpu_ratio = statistics.median(h / b for b, h in cpus)
            worst = max(worst, cpu_ratio)
            print(
                f"{name:34s} {statistics.median(b for b, _ in walls):8.3f} "
                f"{statistics.median(h for _, h in walls):8.3f} {wall_ratio:10.3f} "
                f"{cpu_ratio:10.3f}",
                flush=True,
            )
    verdict = "PASS" if worst <= TARGET_RATIO else "MISSED"
    print(f"worst cpu ratio head/base {worst:.3f} (target <= {TARGET_RATIO}): {verdict}")


if __name__ == "__main__":
    main()
