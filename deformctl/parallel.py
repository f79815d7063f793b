"""Run one function per object over a population, locally or on a Dask cluster, resumably.

A *sweep* applies a picklable top-level ``task(item)`` to every catalog row (``item``, a dict
with an id column such as ``object_id``) and streams the rows it returns into a partitioned
Parquet dataset (:mod:`deformctl.artifacts.dataset` owns the directory: manifest, parts,
failures, part logs, atomic part writes, readers). This module is the executor only: it submits
objects, keeps a bounded window of them in flight, and hands each finished part to the
dataset's writer, so at most that window is held in memory whatever the population size.

Items are split into partitions by position, so the dataset does not depend on the number of
workers or on the order in which objects finish; ``resume=True`` keeps the parts that are
complete and valid and recomputes the others, which gives the same dataset, row for row, as an
uninterrupted run.

Executors: ``workers`` local processes (:class:`concurrent.futures.ProcessPoolExecutor`,
forkserver start method), or an existing ``dask.distributed`` cluster given by its scheduler
address (``tcp://HOST:PORT``). Dask reschedules the objects of a worker that dies.

A task signals a per-object failure by raising; any :class:`Exception` is recorded in the
failures part with its type and one-line message and the sweep goes on. Each stage module
exposes its own task (:class:`deformctl.measure.SimulateCatalogTask`,
:class:`deformctl.characterize.CharacterizeTask`, :class:`deformctl.lift.runners.sim.LiftTask`).
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import multiprocessing
import os
import socket
import sys
import threading
import time
import uuid
from collections.abc import Callable, Iterable, Mapping, Sequence
from concurrent.futures import (
    FIRST_COMPLETED,
    Future,
    ProcessPoolExecutor,
    ThreadPoolExecutor,
    wait,
)
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol
from urllib.parse import urlsplit

import pyarrow as pa

from deformctl.artifacts.dataset import (
    DatasetWriter,
    ObjectResult,
    PartPayloads,
    is_dataset_output,
    rows_to_table,
)
from deformctl.errors import EXIT_FAILURE, EXIT_OK, DeformctlError, InputDataError, UsageError

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "DEFAULT_CONNECT_TIMEOUT_S",
    "DEFAULT_PARTITION_SIZE",
    "SweepOptions",
    "SweepSummary",
    "TaskOutput",
    "connect_dask",
    "map_in_order",
    "run_sweep",
    "single_file_workers",
]


DEFAULT_CONNECT_TIMEOUT_S = 10.0  #: time allowed to reach a Dask scheduler, s
DEFAULT_PARTITION_SIZE = 100  #: objects per part of a dataset directory


@dataclass(frozen=True)
class TaskOutput:
    """What a task may return instead of bare rows: rows plus one payload for the part writer.

    Attributes:
        rows: the object's result rows (list of dicts, a pandas DataFrame or a pyarrow Table),
            each with the sweep schema's columns; the id column may be left out.
        payload: any picklable object (e.g. the MCAP bytes of the object's time series) handed to
            the sweep's ``part_writer`` together with the other payloads of the same part.
        error: a one-line reason when the object failed but still has rows worth keeping (e.g.
            a lift search that did not converge: its row records the attempts made). The rows
            are written and the object is also counted and recorded as failed.
        error_type: the failure's type name in the failures part (with ``error``).
    """

    rows: Any
    payload: Any = None
    error: str | None = None
    error_type: str = "ObjectFailed"


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


@dataclass(frozen=True)
class SweepOptions:
    """The scale-out flags of a stage command, as given (None: not given).

    Attributes:
        workers: ``--workers N`` local processes.
        scheduler: ``--scheduler tcp://HOST:PORT`` of a running Dask scheduler.
        connect_timeout_s: ``--connect-timeout S``.
        partition_size: ``--partition-size N`` objects per part.
        resume: ``--resume``.
    """

    workers: int | None = None
    scheduler: str | None = None
    connect_timeout_s: float | None = None
    partition_size: int | None = None
    resume: bool = False

    def given(self) -> list[str]:
        """The flags given on the command line."""
        flags = [
            ("--workers", self.workers),
            ("--scheduler", self.scheduler),
            ("--connect-timeout", self.connect_timeout_s),
            ("--partition-size", self.partition_size),
        ]
        out = [flag for flag, value in flags if value is not None]
        return out + (["--resume"] if self.resume else [])

    def check(self, output: str, *, file_workers: bool = False) -> bool:
        """Check the flags against the output; True when the output is a dataset directory.

        Args:
            output: the ``-o`` value.
            file_workers: the command also runs a single-file output on ``--workers`` local
                processes (:func:`map_in_order`), so that flag is allowed without a directory.

        Raises:
            UsageError: a sweep flag with a single-file output (``--workers`` too unless
                ``file_workers``), ``--workers`` < 1, both ``--workers`` and ``--scheduler``,
                ``--connect-timeout`` without ``--scheduler`` or <= 0, ``--partition-size`` < 1.
        """
        dataset = is_dataset_output(output)
        needs_dir = [f for f in self.given() if not (file_workers and f == "--workers")]
        if not dataset and needs_dir:
            raise UsageError(
                f"{needs_dir[0]} needs a dataset directory output "
                f"(end -o with /, e.g. -o {output.rstrip('/') or 'out'}/)"
            )
        if self.workers is not None and self.workers < 1:
            raise UsageError(f"--workers must be >= 1, got {self.workers}")
        if self.workers is not None and self.scheduler is not None:
            raise UsageError("give either --workers (local processes) or --scheduler, not both")
        if self.connect_timeout_s is not None:
            if self.scheduler is None:
                raise UsageError("--connect-timeout needs --scheduler")
            if not (math.isfinite(self.connect_timeout_s) and self.connect_timeout_s > 0):
                raise UsageError(f"--connect-timeout must be > 0 s, got {self.connect_timeout_s}")
        if self.partition_size is not None and self.partition_size < 1:
            raise UsageError(f"--partition-size must be >= 1, got {self.partition_size}")
        return dataset

    def run_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of :func:`run_sweep` for these flags."""
        kwargs: dict[str, Any] = {
            "workers": self.workers,
            "scheduler": self.scheduler,
            "resume": self.resume,
        }
        if self.connect_timeout_s is not None:
            kwargs["connect_timeout_s"] = self.connect_timeout_s
        if self.partition_size is not None:
            kwargs["partition_size"] = self.partition_size
        return kwargs


# --------------------------------------------------------------------------- worker side


def _one_line(text: str) -> str:
    return " ".join(text.split())


def _run_item(
    task: Callable[[dict[str, Any]], Any], item: dict[str, Any], schema: pa.Schema, id_column: str
) -> ObjectResult:
    """Run ``task`` on one item in a worker; any exception becomes a failed result."""
    item_id = item[id_column]
    try:
        out = task(item)
        error: str | None = None
        error_type = ""
        if isinstance(out, TaskOutput):
            rows, payload = out.rows, out.payload
            if out.error is not None:
                error, error_type = _one_line(out.error) or out.error_type, out.error_type
        else:
            rows, payload = out, None
        table = rows_to_table(rows, schema, id_column, item_id)
    except Exception as err:
        message = _one_line(str(err)) or type(err).__name__
        return ObjectResult(item_id, None, None, type(err).__name__, message)
    if error is not None:
        return ObjectResult(item_id, table, payload, error_type, error)
    return ObjectResult(item_id, table, payload)


# --------------------------------------------------------------------------- executors


class _Backend(Protocol):
    capacity: int

    def submit(self, position: int, item: dict[str, Any]) -> None: ...

    def wait_some(self) -> list[tuple[int, ObjectResult]]: ...

    def submit_part(self, part_writer: Callable[[PartPayloads], None], part: PartPayloads) -> None:
        """Run ``part_writer(part)`` as a job; :meth:`parts_written` reports its completion."""
        ...

    def parts_written(self) -> list[int]:
        """Indices of the part-writer jobs finished since the last call (errors re-raised)."""
        ...

    def close(self) -> None: ...


_WORKER_DIED = "a local worker process died; the parts written so far are kept, rerun with --resume"


class _LocalBackend:
    """A process pool; forkserver (spawn where unavailable) so workers start from a clean state."""

    def __init__(
        self, workers: int, task: Callable[..., Any], schema: pa.Schema, id_column: str
    ) -> None:
        # pyarrow imports pandas lazily when it converts rows, so pandas is preloaded too
        ctx = _worker_context(task, ["pandas"])
        self._pool = ProcessPoolExecutor(
            max_workers=workers,
            mp_context=ctx,
            initializer=_init_worker,
            initargs=(os.getpid(),),
        )
        self._task, self._schema, self._id_column = task, schema, id_column
        self._futures: dict[Future[ObjectResult], int] = {}
        self._part_futures: dict[Future[None], int] = {}
        self._written: list[int] = []
        self.capacity = 2 * workers

    def submit(self, position: int, item: dict[str, Any]) -> None:
        try:
            fut = self._pool.submit(_run_item, self._task, item, self._schema, self._id_column)
        except BrokenProcessPool as err:  # a worker died while results were being collected
            raise DeformctlError(_WORKER_DIED) from err
        self._futures[fut] = position

    def submit_part(self, part_writer: Callable[[PartPayloads], None], part: PartPayloads) -> None:
        try:
            fut = self._pool.submit(_write_part, part_writer, part)
        except BrokenProcessPool as err:
            raise DeformctlError(_WORKER_DIED) from err
        self._part_futures[fut] = part.index

    def wait_some(self) -> list[tuple[int, ObjectResult]]:
        """Wait for an object or a part-writer job; the objects finished (maybe none)."""
        pending: list[Future[Any]] = [*self._futures, *self._part_futures]
        done, _ = wait(pending, return_when=FIRST_COMPLETED)
        out = []
        for fut in done:
            try:
                if fut in self._part_futures:
                    index = self._part_futures.pop(fut)
                    fut.result()  # a hook's own error propagates, as it does in the client
                    self._written.append(index)
                else:
                    position = self._futures.pop(fut)
                    out.append((position, fut.result()))
            except BrokenProcessPool as err:
                raise DeformctlError(_WORKER_DIED) from err
        return out

    def parts_written(self) -> list[int]:
        written, self._written = self._written, []
        return written

    def close(self) -> None:
        if self._pool._broken:
            _abandon_pool(self._pool)
        else:
            self._pool.shutdown(wait=True, cancel_futures=True)


def _abandon_pool(pool: ProcessPoolExecutor) -> None:
    """Shut a broken pool down without waiting for its workers: terminate them first.

    After a worker died, the pool's result-reading thread is gone, so a surviving worker that is
    sending a large result (an object's attempt series) blocks on the full pipe for ever and
    ``shutdown(wait=True)`` joins it for ever (seen under heavy load as a hung client). The
    sweep is aborting anyway and its parts are committed, so the survivors are killed.
    """
    processes = getattr(pool, "_processes", None) or {}
    for proc in list(processes.values()):
        with contextlib.suppress(Exception):
            proc.kill()
    pool.shutdown(wait=False, cancel_futures=True)


def _worker_context(task: Callable[..., Any], preload: Sequence[str] = ()) -> Any:
    """The start context of local workers: forkserver (spawn where unavailable).

    Workers fork from a server that has imported this module, ``preload`` and the task's module
    once (a no-op when this process started its fork server already). Python 3.11's fork server
    ignores the parent's sys.path: a task module must be importable from PYTHONPATH or the cwd.
    """
    methods = multiprocessing.get_all_start_methods()
    ctx = multiprocessing.get_context("forkserver" if "forkserver" in methods else "spawn")
    if ctx.get_start_method() == "forkserver":
        modules = ["deformctl.parallel", *preload]
        module = getattr(task, "__module__", None)  # a function's, or an instance's class's
        if module and module != "__main__" and module in sys.modules:
            modules.append(module)
        ctx.set_forkserver_preload(modules)
    return ctx


def _write_part(part_writer: Callable[[PartPayloads], None], part: PartPayloads) -> None:
    """A part-writer job in a worker process."""
    part_writer(part)


_THREAD_ENV = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


#: How often a local worker checks that its client is still alive, s.
_WATCHDOG_S = 0.5


def _init_worker(client_pid: int) -> None:
    """Worker initializer: one BLAS thread (:func:`_one_blas_thread`) and a client watchdog.

    The watchdog is a daemon thread that ends the worker when the client process is gone (killed
    with ``kill -9``, so it could not shut its pool down): no worker outlives its client by
    more than about :data:`_WATCHDOG_S`. The fork server exits by itself when the client's end of
    its pipe closes, and the resource tracker when the last worker holding it is gone.
    """
    _one_blas_thread()
    threading.Thread(target=_watch_client, args=(client_pid,), daemon=True).start()


def _watch_client(client_pid: int) -> None:
    while True:
        time.sleep(_WATCHDOG_S)
        try:
            os.kill(client_pid, 0)
        except ProcessLookupError:
            os._exit(1)
        except OSError:  # pragma: no cover - alive but not ours to signal
            pass


def _one_blas_thread() -> None:
    """Worker initializer: one BLAS/OpenMP thread per worker process.

    Parallelism comes from the processes; a BLAS that also spreads each worker's dense solves
    over every core oversubscribes the machine (measured: one worker already used 1.35 cores,
    and two workers gained little over one). The libraries loaded now are limited through
    threadpoolctl; the environment variables limit those a task loads later (scipy brings its
    own OpenBLAS, whose idle threads spin: measured +30 % CPU per worker when left at 2).
    """
    from threadpoolctl import threadpool_limits

    for name in _THREAD_ENV:
        os.environ[name] = "1"
    threadpool_limits(limits=1)


def _check_scheduler_address(scheduler: str) -> tuple[str, int]:
    parts = urlsplit(scheduler)
    try:
        port = parts.port
    except ValueError:
        port = None
    if parts.scheme not in ("tcp", "tls") or not parts.hostname or port is None:
        raise UsageError(f"scheduler address {scheduler!r} is not of the form tcp://HOST:PORT")
    return parts.hostname, port


def connect_dask(scheduler: str, connect_timeout_s: float) -> Any:
    """Connect a ``distributed.Client`` to a running scheduler, or raise one clear error.

    Args:
        scheduler: ``tcp://HOST:PORT`` of a running ``dask scheduler``.
        connect_timeout_s: total time allowed for the connection, s.

    Raises:
        UsageError: a malformed address or a non-positive timeout.
        DeformctlError: nothing answers at the address within the timeout.
    """
    host, port = _check_scheduler_address(scheduler)
    if not connect_timeout_s > 0:
        raise UsageError(f"connect timeout must be > 0 s, got {connect_timeout_s}")
    start = time.monotonic()
    prefix = f"cannot connect to the Dask scheduler at {scheduler}"
    try:  # a plain TCP probe gives a fast, precise reason (refused, unknown host, timeout)
        with socket.create_connection((host, port), timeout=connect_timeout_s):
            pass
    except TimeoutError:
        raise DeformctlError(f"{prefix}: no answer within {connect_timeout_s:g} s") from None
    except OSError as err:
        reason = err.strerror or str(err) or type(err).__name__
        raise DeformctlError(f"{prefix}: {reason}") from None
    import distributed

    # distributed.Client can wait forever for the handshake of a peer that accepts connections
    # but never answers, so ask for the scheduler's identity under a hard deadline first.
    def remaining_s() -> float:
        return max(connect_timeout_s - (time.monotonic() - start), 0.5)

    probe_pool = ThreadPoolExecutor(max_workers=1)
    probe = probe_pool.submit(asyncio.run, _dask_identity(scheduler, remaining_s()))
    try:
        identity = probe.result(timeout=remaining_s() + 1.0)
    except Exception as err:
        detail = "" if isinstance(err, TimeoutError) else f" ({_describe(err)})"
        raise DeformctlError(
            f"{prefix}: no Dask scheduler answered within {connect_timeout_s:g} s{detail}"
        ) from None
    finally:
        probe_pool.shutdown(wait=False)
    if not isinstance(identity, Mapping) or identity.get("type") != "Scheduler":
        raise DeformctlError(f"{prefix}: the peer is not a Dask scheduler")
    try:
        return distributed.Client(scheduler, timeout=remaining_s(), set_as_default=False)
    except Exception as err:
        raise DeformctlError(f"{prefix}: {_describe(err)}") from None


def _describe(err: BaseException) -> str:
    return f"{type(err).__name__}: {_one_line(str(err))[:200]}"


async def _dask_identity(scheduler: str, timeout_s: float) -> Any:
    """The ``identity`` answer of a Dask server, or TimeoutError after ``timeout_s``."""
    from distributed.comm import connect

    async def ask() -> Any:
        comm = await connect(scheduler, timeout=timeout_s)
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    return await asyncio.wait_for(ask(), timeout_s)


class _DaskBackend:
    """Futures on an existing cluster; the scheduler reschedules the work of a lost worker."""

    def __init__(
        self,
        scheduler: str,
        connect_timeout_s: float,
        task: Callable[..., Any],
        schema: pa.Schema,
        id_column: str,
    ) -> None:
        import distributed

        self._client = connect_dask(scheduler, connect_timeout_s)
        self._ac = distributed.as_completed(loop=self._client.loop)
        self._task, self._schema, self._id_column = task, schema, id_column
        self._positions: dict[str, int] = {}
        self._run = uuid.uuid4().hex[:12]
        n_threads = sum(self._client.nthreads().values())
        self.capacity = max(8, 2 * n_threads)

    def submit(self, position: int, item: dict[str, Any]) -> None:
        key = f"deformctl-sweep-{self._run}-{position}"
        fut = self._client.submit(
            _run_item, self._task, item, self._schema, self._id_column, key=key, pure=False
        )
        self._positions[key] = position
        self._ac.add(fut)

    def wait_some(self) -> list[tuple[int, ObjectResult]]:
        out = []
        for fut in self._ac.next_batch(block=True):
            position = self._positions.pop(fut.key)
            try:
                result = fut.result()
            except Exception as err:
                raise DeformctlError(
                    f"the Dask cluster lost object at position {position} "
                    f"({type(err).__name__}: {_one_line(str(err))[:200]}); the parts written so "
                    "far are kept, rerun with --resume"
                ) from None
            fut.release()
            out.append((position, result))
        return out

    def submit_part(self, part_writer: Callable[[PartPayloads], None], part: PartPayloads) -> None:
        raise NotImplementedError("a Dask sweep runs its part writer in the client")

    def parts_written(self) -> list[int]:
        return []

    def close(self) -> None:
        with contextlib.suppress(Exception):
            self._ac.clear()
        with contextlib.suppress(Exception):
            self._client.close(timeout=5)


# --------------------------------------------------------------------------- progress


class _Progress:
    """One rich bar on stderr (objects done, failed, rate); silent unless stderr is a TTY."""

    def __init__(self, enabled: bool, total: int, completed: int) -> None:
        self._bar: Any = None
        self._start = time.monotonic()
        self._failed = 0
        self._finished = 0
        if not (enabled and sys.stderr.isatty()):
            return
        from rich.console import Console
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn

        self._bar = Progress(
            TextColumn("sweep"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("{task.fields[failed]} failed  {task.fields[rate]:.2f} obj/s"),
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


# --------------------------------------------------------------------------- the sweep


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
    workers: int | None = None,
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
        workers: local worker processes; ``None`` uses every available core.
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
    if workers is not None and scheduler is not None:
        raise UsageError("give either --workers (local processes) or --scheduler, not both")
    if workers is not None and workers <= 0:
        raise UsageError(f"--workers must be >= 1, got {workers}")
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
            n_workers = workers if workers is not None else _available_cores()
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


#: A single-file output runs its objects on local processes only from this many objects on: a
#: worker costs about a second to start (imports and the compiled kernels), more than a short
#: catalog's whole run.
MIN_PARALLEL_OBJECTS = 8


def single_file_workers(workers: int | None, n_items: int) -> int:
    """How many local processes a single-file output uses for ``n_items`` objects.

    ``workers`` as given (``--workers N``), else every available core once the catalog has
    :data:`MIN_PARALLEL_OBJECTS` objects (in this process below that); never more than the
    objects.
    """
    if workers is None:
        workers = _available_cores() if n_items >= MIN_PARALLEL_OBJECTS else 1
    return max(1, min(workers, n_items))


def map_in_order(
    task: Callable[[Any], Any],
    items: Sequence[Any],
    *,
    workers: int,
    on_result: Callable[[int, Any], None] | None = None,
) -> list[Any]:
    """``[task(item) for item in items]``, on ``workers`` local processes, results in item order.

    The processes are set up as a sweep's (:class:`_LocalBackend`: fork server, one BLAS thread,
    a watchdog that ends them with their client). For a single-file output that holds every
    result anyway, so a result does not depend on the number of workers. ``workers <= 1`` (or
    one item) runs in this process.

    Args:
        task: a picklable callable; its module must be importable by the workers.
        items: picklable items.
        workers: local processes.
        on_result: called as ``on_result(index, result)`` in item order, as results arrive
            (e.g. progress).

    Raises:
        whatever ``task`` raised for the first item (in order) that failed; the items after it
        are cancelled. DeformctlError: a worker process died.
    """
    if workers <= 1 or len(items) <= 1:
        out = []
        for i, item in enumerate(items):
            out.append(task(item))
            if on_result is not None:
                on_result(i, out[-1])
        return out
    ctx = _worker_context(task)
    results: list[Any] = [None] * len(items)
    with ProcessPoolExecutor(
        max_workers=workers, mp_context=ctx, initializer=_init_worker, initargs=(os.getpid(),)
    ) as pool:
        futures = [pool.submit(task, item) for item in items]
        try:
            for i, fut in enumerate(futures):
                results[i] = fut.result()
                if on_result is not None:
                    on_result(i, results[i])
        except BrokenProcessPool as err:
            _abandon_pool(pool)
            raise DeformctlError("a local worker process died") from err
        finally:
            for fut in futures:
                fut.cancel()
    return results


def _available_cores() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)
