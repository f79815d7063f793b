"""``--workers auto``: how many local processes pay for themselves, from measured costs.

A local worker is not free: the fork server starts a fresh interpreter and imports the task's
modules, and each worker's first object loads the compiled simulator kernels (measured on this
project's 2-core machine: 2-7 s before a worker's first result, against 0.4-1 s per paper-preset
object). On a short catalog that start costs more than the processes save, so ``auto`` compares
the estimated wall time of one process with that of ``n``:

    wall(1) = objects × per_object_s
    wall(n) = start_s + ceil(objects / n) × per_object_s × slowdown(n)

where ``per_object_s`` is measured on the objects the client runs first itself
(:data:`PROBE_OBJECTS`), ``start_s`` is the start cost measured the last time this kind of task
ran on local workers on this machine (kept in :func:`costs_path`, averaged with the value kept
before; :data:`DEFAULT_START_S` until then) and ``slowdown(n)`` is how much slower each of
``n`` processes runs than the one process did when the other load on the machine (the
1-minute load average) leaves fewer than ``n`` cores free (a fair share of the cores: ``n``
runnable processes beside ``busy`` others get ``min(n, n × cores / (busy + n))`` cores).
It picks the ``n`` of least ``wall(n)``, and more than one process only when that promises at
least :data:`GAIN_MARGIN` less wall time than one, so an estimate that is somewhat off still
does not make a run slower than ``--workers 1``.

:func:`choose_workers` is the pure rule (tested against known costs); the measuring is done by
:func:`deformctl.parallel.sweep.map_in_order`, which logs each :class:`WorkerChoice` on the
``deformctl.parallel`` logger (the commands put it in their summary line). The outputs never
depend on the count chosen.
"""

from __future__ import annotations

import json
import math
import os
import statistics
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Literal

#: Objects the client runs itself, timing each, before it chooses (the first one also loads the
#: kernels, so the last one is the per-object cost).
PROBE_OBJECTS = 2
#: Least estimated saving of wall time for which more than one process is started.
GAIN_MARGIN = 0.15
#: The start cost assumed before one was measured on this machine, s (measured here: 2.3 s to
#: start the fork server and 2-5 s more before a simulating worker's first result, on 2 cores
#: at a load average of 2-5).
DEFAULT_START_S = 4.0

Auto = Literal["auto"]
AUTO: Auto = "auto"


@dataclass(frozen=True)
class WorkerChoice:
    """What ``--workers auto`` chose, and why.

    Attributes:
        workers: the local processes chosen (1: the client runs every object itself).
        objects: objects left to run when the choice was made.
        cores: cores available to this process.
        busy: the other load on the machine (1-minute load average) the estimate assumed.
        start_s: the start cost of the worker processes assumed, s.
        start_measured: whether ``start_s`` was measured on this machine (else the default).
        per_object_s: the measured wall time of one object in the client, s.
        wall_1_s: estimated wall time of the objects left on one process, s.
        best_n: the number of processes (> 1) of least estimated wall time; None when there
            is no choice (one object left, or one core).
        wall_n_s: estimated wall time on ``best_n`` processes, s (None with ``best_n``).
        reason: one sentence.
    """

    workers: int
    objects: int
    cores: int
    busy: float
    start_s: float
    start_measured: bool
    per_object_s: float
    wall_1_s: float
    best_n: int | None
    wall_n_s: float | None
    reason: str

    def as_dict(self) -> dict[str, Any]:
        """A JSON-serialisable record of the choice."""
        return {"requested": AUTO, **asdict(self)}

    def line(self) -> str:
        """``workers: auto chose 1 process: ...``."""
        noun = "process" if self.workers == 1 else "processes"
        return f"workers: auto chose {self.workers} {noun}: {self.reason}"

    def note(self) -> str:
        """The short form for a summary line: ``workers auto: 1 (est. 1.1 s vs 5.1 s on 2)``."""
        if self.best_n is None or self.wall_n_s is None:
            return f"workers auto: {self.workers} ({self.reason})"
        source = "measured" if self.start_measured else "assumed"
        return (
            f"workers auto: {self.workers} (est. {self.wall_1_s:.1f} s on 1 vs "
            f"{self.wall_n_s:.1f} s on {self.best_n}, start {self.start_s:.1f} s {source})"
        )


def _share(n: int, cores: int, busy: float) -> float:
    """Cores that ``n`` runnable processes get beside ``busy`` others (a fair share)."""
    return min(float(n), n * cores / (busy + n))


def slowdown(n: int, cores: int, busy: float) -> float:
    """How much longer an object takes on each of ``n`` processes than on one, >= 1."""
    one = _share(1, cores, busy)
    each = _share(n, cores, busy) / n
    return one / each


def choose_workers(
    objects: int,
    *,
    cores: int,
    start_s: float,
    per_object_s: float,
    busy: float = 0.0,
    start_measured: bool = True,
    margin: float = GAIN_MARGIN,
) -> WorkerChoice:
    """The number of local processes of least estimated wall time (a pure rule).

    Args:
        objects: objects still to run.
        cores: cores available to this process.
        start_s: the start cost of a set of worker processes (fork server, imports, the first
            object's kernel load), s.
        per_object_s: one object's wall time on one process, s.
        busy: other runnable processes on the machine (the load average).
        start_measured: recorded in the choice (``start_s`` was measured, not the default).
        margin: least relative saving for which more than one process is chosen.

    Returns:
        The :class:`WorkerChoice`; ``workers`` is 1 unless ``wall(n) <= (1 - margin) wall(1)``.
    """
    start_s, per_object_s, busy = max(start_s, 0.0), max(per_object_s, 0.0), max(busy, 0.0)
    wall_1 = objects * per_object_s

    def choice(workers: int, best_n: int | None, reason: str) -> WorkerChoice:
        return WorkerChoice(
            workers=workers, objects=objects, cores=cores, busy=busy, start_s=start_s,
            start_measured=start_measured, per_object_s=per_object_s, wall_1_s=wall_1,
            best_n=best_n, wall_n_s=None if best_n is None else walls[best_n], reason=reason,
        )  # fmt: skip

    walls: dict[int, float] = {}
    if objects <= 1 or cores <= 1:
        return choice(1, None, "one object left" if objects <= 1 else "one core available")
    walls = {
        n: start_s + math.ceil(objects / n) * per_object_s * slowdown(n, cores, busy)
        for n in range(2, min(cores, objects) + 1)
    }
    best = min(walls, key=lambda n: (walls[n], n))
    source = "measured" if start_measured else "assumed"
    estimate = (
        f"{objects} objects at {per_object_s:.2f} s each: est. {wall_1:.1f} s on 1 process, "
        f"{walls[best]:.1f} s on {best} (start {start_s:.1f} s {source}, load {busy:.1f} "
        f"on {cores} cores)"
    )
    if walls[best] <= (1.0 - margin) * wall_1:
        return choice(best, best, estimate)
    return choice(1, best, f"{estimate}; saves less than {margin:.0%}")


#: reads of the kernel's count of runnable processes behind one :func:`machine_load`, and the
#: pause between two reads, s
LOAD_READS = 5
LOAD_READ_PAUSE_S = 0.002


def machine_load(loadavg: str = "/proc/loadavg") -> float:
    """Other processes running or ready to run now, besides this one.

    On Linux the median of :data:`LOAD_READS` reads of the kernel's count of runnable
    processes (``/proc/loadavg``'s fourth field, ``running/total``, which counts the reader),
    less one. Not the 1-minute load average: it lags, so the work of a command that has just
    ended, or the client's own probe objects, read as a load that is not there (measured: a
    60-object ``measure`` after another one saw a load of 1.2 on an idle 2-core machine, took
    two processes for 1.5 times slower than one, and ran 16.1 s on one process against 12.6 s
    on two). Elsewhere the 1-minute load average (0 where the platform has none).
    """
    counts = []
    for i in range(LOAD_READS):
        try:
            with open(loadavg, encoding="ascii") as fh:
                counts.append(int(fh.read().split()[3].split("/")[0]) - 1)
        except (OSError, ValueError, IndexError):
            break
        if i + 1 < LOAD_READS:
            time.sleep(LOAD_READ_PAUSE_S)
    if counts:
        return float(max(0, statistics.median_low(counts)))
    try:
        return float(os.getloadavg()[0])
    except (AttributeError, OSError):
        return 0.0


def costs_path() -> Path:
    """Where the measured start costs are kept: ``$XDG_CACHE_HOME/deformctl/worker-costs.json``
    (``~/.cache`` by default)."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "deformctl" / "worker-costs.json"


def _read_costs() -> dict[str, Any]:
    try:
        data = json.loads(costs_path().read_text())
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def task_kind(task: Any) -> str:
    """The key a task's costs are kept under: its class's (or function's) qualified name."""
    owner = task if callable(task) and hasattr(task, "__qualname__") else type(task)
    inner = getattr(task, "task", None)  # a wrapper (e.g. the CSV reader's error catcher)
    suffix = f"[{task_kind(inner)}]" if inner is not None and inner is not task else ""
    return f"{owner.__module__}.{owner.__qualname__}{suffix}"


def measured_start_s(kind: str) -> float | None:
    """The start cost last measured for ``kind`` on this machine, s (None: never)."""
    entry = _read_costs().get(kind)
    value = entry.get("start_s") if isinstance(entry, dict) else None
    if isinstance(value, int | float) and math.isfinite(value) and value >= 0:
        return float(value)
    return None


def record_start_s(kind: str, start_s: float, workers: int) -> None:
    """Keep the start cost measured for ``kind``: the mean of the one kept and this one, so one
    run on a briefly loaded machine does not decide the next alone (best effort: a read-only
    cache is skipped)."""
    if not (math.isfinite(start_s) and start_s >= 0):
        return
    before = measured_start_s(kind)
    kept = start_s if before is None else 0.5 * (before + start_s)
    data = _read_costs()
    data[kind] = {"start_s": round(kept, 3), "workers": workers}
    path = costs_path()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        tmp.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n")
        os.replace(tmp, path)
    except OSError:
        pass
