"""The sweep: one task per object, a bounded window in flight, parts written as they complete.

:func:`run_sweep` streams the rows into a partitioned dataset directory (resumable);
:func:`map_in_order` runs the objects of a single-file output on local processes, in order.
"""

from __future__ import annotations

import logging
import math
import os
import statistics
import sys
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pyarrow as pa

from deformctl.artifacts.dataset import DatasetWriter, ObjectResult, PartPayloads
from deformctl.errors import EXIT_FAILURE, EXIT_OK, DeformctlError, InputDataError, UsageError
from deformctl.parallel.auto import (
    AUTO,
    DEFAULT_START_S,
    PROBE_OBJECTS,
    Auto,
    choose_workers,
    machine_load,
    measured_start_s,
    record_start_s,
    task_kind,
)
from deformctl.parallel.backends import (
    _abandon_pool,
    _Backend,
    _check_scheduler_address,
    _DaskBackend,
    _init_worker,
    _LocalBackend,
    _worker_context,
)
from deformctl.parallel.options import (
    DEFAULT_CONNECT_TIMEOUT_S,
    DEFAULT_PARTITION_SIZE,
    parse_workers,
)

_log = logging.getLogger("deformctl.parallel")

if TYPE_CHECKING:
    import pandas as pd


@dataclass(frozen=True)
class SweepSummary:
    """How a sweep went.

    Attributes:
        done: objects computed successfully in this run.
        failed: objects whose task raised in this run.
        skipped_resumed: objects in parts kept from an earlier run (``resume=True``).
        failed_total: failed objects in the whole dataset (this run and kept parts).
        parts: number of parts in the dataset.
        elapsed_s: wall time of this run, s.
        rate: objects finished per second in this run (done + failed) / elapsed_s.
        out_dir: the dataset directory.
    """

    done: int
    failed: int
    skipped_resumed: int
    failed_total: int
    parts: int
    elapsed_s: float
    rate: float
    out_dir: Path

    @property
    def exit_code(self) -> int:
        """0 when no object of the dataset failed, else 1."""
        return EXIT_FAILURE if self.failed_total else EXIT_OK

    def line(self) -> str:
        """A one-line summary for stderr."""
        return (
            f"{self.done} done, {self.failed} failed, {self.skipped_resumed} kept from an "
            f"earlier run ({self.failed_total} failed in total), {self.parts} parts in "
            f"{self.elapsed_s:.1f} s ({self.rate:.2f} objects/s)"
        )


class _Progress:
    """One rich bar on stderr (objects done, failed, rate, elapsed, ETA); silent unless stderr is
    a TTY."""

    def __init__(self, enabled: bool, total: int, completed: int) -> None:
        self._bar: Any = None
        self._start = time.monotonic()
        self._failed = 0
        self._finished = 0
        if not (enabled and sys.stderr.isatty()):
            return
        from rich import progress as rp
        from rich.console import Console

        self._bar = rp.Progress(
            rp.TextColumn("sweep"),
            rp.BarColumn(),
            rp.MofNCompleteColumn(),
            rp.TextColumn("{task.fields[failed]} failed  {task.fields[rate]:.2f} obj/s"),
            rp.TimeElapsedColumn(),
            rp.TextColumn("ETA"),
            rp.TimeRemainingColumn(),
            console=Console(stderr=True),
            transient=False,
        )
        self._task = self._bar.add_task("sweep", total=total, completed=completed, failed=0, rate=0)
        self._bar.start()

    def advance(self, ok: bool) -> None:
        self._finished += 1
        self._failed += 0 if ok else 1
        if self._bar is not None:
            rate = self._finished / max(time.monotonic() - self._start, 1e-9)
            self._bar.update(self._task, advance=1, failed=self._failed, rate=rate)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.stop()


def _items_as_dicts(items: Any) -> list[dict[str, Any]]:
    if hasattr(items, "to_dict") and hasattr(items, "columns"):
        return list(items.to_dict("records"))
    return [dict(it) for it in items]


def run_sweep(
    task: Callable[[dict[str, Any]], Any],
    items: Iterable[Mapping[str, Any]] | pd.DataFrame,
    *,
    out_dir: str | os.PathLike[str],
    schema: pa.Schema,
    fingerprint: Mapping[str, Any],
    id_column: str = "object_id",
    workers: int | Auto | None = AUTO,
    scheduler: str | None = None,
    connect_timeout_s: float = DEFAULT_CONNECT_TIMEOUT_S,
    partition_size: int = DEFAULT_PARTITION_SIZE,
    resume: bool = False,
    force: bool = False,
    progress: bool = True,
    part_writer: Callable[[PartPayloads], None] | None = None,
    max_in_flight: int | None = None,
) -> SweepSummary:
    """Apply ``task`` to every item and write a partitioned, resumable Parquet dataset.

    Args:
        task: a picklable top-level function ``task(item) -> rows | TaskOutput``; rows are a list
            of dicts, a DataFrame or a pyarrow Table with ``schema``'s columns. Raising marks the
            object as failed.
        items: the catalog, ``[n]`` rows (dicts or a DataFrame), each with a unique
            ``id_column`` value (int or str).
        out_dir: the dataset directory.
        schema: the row schema of every part; must contain ``id_column``.
        fingerprint: JSON-serialisable description of what produced the data (command, settings,
            seed, tool version); a resume must present the same one.
        id_column: the item/row column identifying an object.
        workers: local worker processes; ``"auto"`` (or ``None``) uses every available core, at
            most one per object left.
        scheduler: ``tcp://HOST:PORT`` of a running Dask scheduler instead of local processes.
        connect_timeout_s: time allowed to reach the scheduler, s.
        partition_size: objects per part.
        resume: keep complete, valid parts of an earlier run of the same sweep.
        force: overwrite the sweep files of an existing directory when not resuming.
        progress: show a progress bar on stderr (only when stderr is a terminal).
        part_writer: hook called with each finished part's payloads before the part is committed;
            it runs in a worker process when it has a true ``in_workers`` attribute and the
            sweep runs on local processes (see :class:`PartPayloads`).
        max_in_flight: objects submitted but not yet finished (default: 2 per worker thread).

    Returns:
        The :class:`SweepSummary`; ``summary.exit_code`` is 1 when any object failed.

    Raises:
        UsageError: ``workers <= 0``, both ``workers`` and ``scheduler``, bad partition size.
        InputDataError: duplicate or missing ids; a resume directory of another sweep.
        OutputExistsError: a non-empty ``out_dir`` without ``resume`` or ``force``.
        DeformctlError: the scheduler cannot be reached, or the executor lost its workers.
    """
    start = time.monotonic()
    given = None if workers is None or workers == AUTO else parse_workers(workers)
    if given is not None and scheduler is not None:
        raise UsageError("give either --workers (local processes) or --scheduler, not both")
    if partition_size <= 0:
        raise UsageError(f"partition size must be >= 1, got {partition_size}")
    if max_in_flight is not None and max_in_flight <= 0:
        raise UsageError(f"max in flight must be >= 1, got {max_in_flight}")
    if scheduler is not None:
        _check_scheduler_address(scheduler)
    if id_column not in schema.names:
        raise ValueError(f"schema has no id column {id_column!r}")

    rows = _items_as_dicts(items)
    ids: list[Any] = []
    for n, row in enumerate(rows):
        if id_column not in row:
            raise InputDataError(f"object at position {n} has no {id_column!r}")
        value = row[id_column]
        if hasattr(value, "item"):  # numpy scalar from a DataFrame
            value = value.item()
            row[id_column] = value
        if not isinstance(value, str | int) or isinstance(value, bool):
            raise InputDataError(f"{id_column} {value!r} at position {n} is not a string or int")
        ids.append(value)
    if len(set(ids)) != len(ids):
        dup = next(i for i in ids if ids.count(i) > 1)
        raise InputDataError(f"duplicate {id_column} {dup!r} in the object list")
    writer = DatasetWriter(
        out_dir,
        ids,
        schema=schema,
        fingerprint=fingerprint,
        id_column=id_column,
        partition_size=partition_size,
    )
    parts = writer.parts

    # ---- read-only checks first: refuse, or find the parts to keep
    kept = writer.plan(resume=resume, force=force)  # part index -> failed objects in it
    todo = [
        k * partition_size + j
        for k in range(len(parts))
        if k not in kept
        for j in range(len(parts[k]))
    ]
    skipped = sum(len(parts[k]) for k in kept)

    # ---- then the executor (an unreachable scheduler leaves the directory untouched)
    backend: _Backend | None = None
    if todo:
        if scheduler is not None:
            backend = _DaskBackend(scheduler, connect_timeout_s, task, schema, id_column)
        else:
            n_workers = given if isinstance(given, int) else _available_cores()
            backend = _LocalBackend(min(n_workers, len(todo)), task, schema, id_column)

    buffers: dict[int, dict[int, ObjectResult]] = {}
    n_done = n_failed = 0
    bar: _Progress | None = None
    try:
        writer.open()  # now write: clean, manifest first
        bar = _Progress(progress, total=len(ids), completed=skipped)

        # ---- run the missing parts with a bounded window, committing each finished part
        if backend is not None:
            offload = (
                part_writer is not None
                and bool(getattr(part_writer, "in_workers", False))
                and isinstance(backend, _LocalBackend)
            )
            limit = max_in_flight or backend.capacity
            # bounds the buffered results when one object lags (and, when parts are written by
            # the workers, while a finished part waits for its writer job)
            lookahead = limit + (2 if offload else 1) * partition_size
            unfinished: set[int] = set()  # indices into todo, computing
            writing: dict[int, tuple[list[ObjectResult], bytes]] = {}  # part -> results, meta
            index_of = {position: i for i, position in enumerate(todo)}
            next_i = low = 0
            while next_i < len(todo) or unfinished or writing:
                while low < next_i and low not in unfinished:
                    k_low = todo[low] // partition_size
                    if k_low in writing:  # its results are held until its writer job ends
                        break
                    low += 1
                while next_i < len(todo) and len(unfinished) < limit and next_i - low < lookahead:
                    unfinished.add(next_i)
                    backend.submit(todo[next_i], rows[todo[next_i]])
                    next_i += 1
                for position, result in backend.wait_some():
                    k = position // partition_size
                    unfinished.discard(index_of[position])
                    buffers.setdefault(k, {})[position] = result
                    ok = result.error_type is None
                    n_done += ok
                    n_failed += not ok
                    bar.advance(ok)
                    if len(buffers[k]) == len(parts[k]):
                        got = buffers.pop(k)
                        results = [got[p] for p in sorted(got)]
                        meta = writer.commit_failures(k, results)
                        part = writer.payloads(k, results)
                        if offload and part_writer is not None:
                            backend.submit_part(part_writer, part)
                            writing[k] = ([r.without_payload() for r in results], meta)
                            continue
                        if part_writer is not None:
                            part_writer(part)
                        writer.commit_rows(k, results, meta)
                for k in backend.parts_written():
                    results, meta = writing.pop(k)
                    writer.commit_rows(k, results, meta)
    finally:
        if bar is not None:
            bar.close()
        if backend is not None:
            backend.close()
    elapsed_s = time.monotonic() - start
    return SweepSummary(
        done=n_done,
        failed=n_failed,
        skipped_resumed=skipped,
        failed_total=n_failed + sum(kept.values()),
        parts=len(parts),
        elapsed_s=elapsed_s,
        rate=(n_done + n_failed) / elapsed_s if elapsed_s > 0 else 0.0,
        out_dir=Path(out_dir),
    )


#: Objects from which the old rule (before ``auto``) ran a single-file output on every core; kept
#: for callers that import it. ``auto`` (:mod:`deformctl.parallel.auto`) measures instead.
MIN_PARALLEL_OBJECTS = 8


def single_file_workers(workers: int | Auto | None, n_items: int) -> int | Auto:
    """How many local processes a single-file output uses for ``n_items`` objects.

    ``workers`` as given (``--workers N``), never more than the objects; ``None`` or ``"auto"``:
    ``"auto"`` (:func:`map_in_order` measures and chooses), or 1 for a single object.
    """
    if workers is None or workers == AUTO:
        return AUTO if n_items > 1 else 1
    return max(1, min(int(workers), n_items))


def map_in_order(
    task: Callable[[Any], Any],
    items: Sequence[Any],
    *,
    workers: int | Auto,
    on_result: Callable[[int, Any], None] | None = None,
) -> list[Any]:
    """``[task(item) for item in items]``, on ``workers`` local processes, results in item order.

    The processes are set up as a sweep's (:class:`_LocalBackend`: fork server, one BLAS thread,
    a watchdog that ends them with their client). For a single-file output that holds every
    result anyway, so a result does not depend on the number of workers. ``workers <= 1`` (or
    one item) runs in this process. ``workers="auto"`` runs the first
    :data:`~deformctl.parallel.auto.PROBE_OBJECTS` items here, timing them, then the rest on
    the number of processes :func:`~deformctl.parallel.auto.choose_workers` picks (logged on
    the ``deformctl.parallel`` logger as a :class:`~deformctl.parallel.auto.WorkerChoice`).

    Args:
        task: a picklable callable; its module must be importable by the workers.
        items: picklable items.
        workers: local processes, or ``"auto"``.
        on_result: called as ``on_result(index, result)`` in item order, as results arrive
            (e.g. progress).

    Raises:
        whatever ``task`` raised for the first item (in order) that failed; the items after it
        are cancelled. DeformctlError: a worker process died.
    """
    if workers == AUTO:
        return _map_auto(task, items, on_result)
    assert isinstance(workers, int)
    if workers <= 1 or len(items) <= 1:
        return _map_here(task, items, on_result)
    return _map_pool(task, items, workers, on_result)[0]


def _map_here(
    task: Callable[[Any], Any],
    items: Sequence[Any],
    on_result: Callable[[int, Any], None] | None,
    offset: int = 0,
    times: list[float] | None = None,
) -> list[Any]:
    out = []
    for i, item in enumerate(items):
        t0 = time.perf_counter()
        out.append(task(item))
        if on_result is not None:
            on_result(offset + i, out[-1])
        if times is not None:  # the whole cost of an object here: its task and its result's
            times.append(time.perf_counter() - t0)  # handling (measure: writing the log)
    return out


def _map_pool(
    task: Callable[[Any], Any],
    items: Sequence[Any],
    workers: int,
    on_result: Callable[[int, Any], None] | None,
    offset: int = 0,
) -> tuple[list[Any], float]:
    """The items on ``workers`` processes; (results, seconds from the start to the first one)."""
    ctx = _worker_context(task)
    results: list[Any] = [None] * len(items)
    start = time.perf_counter()
    first_s = math.nan
    with ProcessPoolExecutor(
        max_workers=workers, mp_context=ctx, initializer=_init_worker, initargs=(os.getpid(),)
    ) as pool:
        futures = [pool.submit(task, item) for item in items]
        try:
            wait(futures, return_when=FIRST_COMPLETED)
            first_s = time.perf_counter() - start
            for i, fut in enumerate(futures):
                results[i] = fut.result()
                if on_result is not None:
                    on_result(offset + i, results[i])
        except BrokenProcessPool as err:
            _abandon_pool(pool)
            raise DeformctlError("a local worker process died") from err
        finally:
            for fut in futures:
                fut.cancel()
    return results, first_s


def _map_auto(
    task: Callable[[Any], Any],
    items: Sequence[Any],
    on_result: Callable[[int, Any], None] | None,
) -> list[Any]:
    """:func:`map_in_order` with ``workers="auto"``: probe here, choose, run the rest.

    While the choice is one process the client runs the next object itself and chooses again
    with the mean time of the objects it timed (the first one, which loads the kernels, left
    out): one cheap probe object does not decide for a catalog whose objects cost more (measured
    on a 60-object population: the second object took 0.12 s, the mean was 0.27 s, and one
    process took 16.1 s where two took 12.6 s). An object run here is never run twice, so the
    rule costs nothing when one process is right. The choice logged is the one that started the
    pool, or else the last one made with more than one object left.
    """
    probe = min(len(items), PROBE_OBJECTS)
    times: list[float] = []
    out = _map_here(task, items[:probe], on_result, times=times)
    kind = task_kind(task)
    measured = measured_start_s(kind)
    done, shown = probe, None
    if done < len(items):  # read once, and only when there is a choice (5 reads, ~9 ms)
        busy, cores = machine_load(), _available_cores()
    while done < len(items):
        choice = choose_workers(
            len(items) - done,
            cores=cores,
            start_s=DEFAULT_START_S if measured is None else measured,
            per_object_s=statistics.fmean(times[1:] or times),
            busy=busy,
            start_measured=measured is not None,
        )
        if shown is None or choice.objects > 1 or choice.workers > 1:
            shown = choice
        if choice.workers > 1:
            break
        out += _map_here(task, items[done : done + 1], on_result, offset=done, times=times)
        done += 1
    if shown is not None:
        _log.info(shown.line(), extra={"worker_choice": shown})
    if done == len(items) or shown is None:
        return out
    results, first_s = _map_pool(task, items[done:], shown.workers, on_result, offset=done)
    # the first result came after the start cost and one object's work
    record_start_s(kind, first_s - shown.per_object_s, shown.workers)
    return out + results


def _available_cores() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)
