"""Where a sweep's objects run: the worker side, local processes and a Dask cluster.

A task returns a :class:`TaskOutput` (or plain rows); :func:`_run_item` runs it in a worker and
turns any exception into a failed result. ``_LocalBackend`` runs the items on local processes
(:class:`concurrent.futures.ProcessPoolExecutor`, forkserver start method, one BLAS thread each,
workers that exit when their client dies); ``_DaskBackend`` on a running ``dask.distributed``
cluster (:func:`connect_dask`), which reschedules the objects of a worker that dies.
"""

from __future__ import annotations

import asyncio
import contextlib
import multiprocessing
import os
import socket
import sys
import threading
import time
import uuid
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import (
    FIRST_COMPLETED,
    Future,
    ProcessPoolExecutor,
    ThreadPoolExecutor,
    wait,
)
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import Any, Protocol
from urllib.parse import urlsplit

import pyarrow as pa

from deformctl.artifacts.dataset import ObjectResult, PartPayloads, rows_to_table
from deformctl.errors import DeformctlError, UsageError
from deformctl.reprs import short_repr


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

    __repr__ = short_repr

    rows: Any
    payload: Any = None
    error: str | None = None
    error_type: str = "ObjectFailed"


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
        """Wait for an object or a part-writer job; the objects finished (maybe none).

        Every :data:`_WATCHDOG_S` without one, the workers are checked: a worker killed while it
        was sending a result leaves the pool's result-reading thread waiting for the rest of
        that message for ever, so the pool never learns it is broken and no future ends.
        """
        pending: list[Future[Any]] = [*self._futures, *self._part_futures]
        done: set[Future[Any]] = set()
        while pending and not done:
            done, _ = wait(pending, timeout=_WATCHDOG_S, return_when=FIRST_COMPLETED)
            if not done and _a_worker_died(self._pool):
                raise DeformctlError(_WORKER_DIED)
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
        # a dead worker the pool itself may never notice (see wait_some): abandon it too
        if self._pool._broken or _a_worker_died(self._pool):
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
    # a result-reading thread stuck inside a dead worker's half-sent result reads on until
    # every write end of the result pipe is closed: the workers' (killed) and this process's
    results = getattr(pool, "_result_queue", None)
    with contextlib.suppress(Exception):
        results._writer.close()  # type: ignore[union-attr]
    pool.shutdown(wait=False, cancel_futures=True)


def _a_worker_died(pool: ProcessPoolExecutor) -> bool:
    """Whether a process of ``pool`` has exited (workers run until the pool shuts down)."""
    processes = getattr(pool, "_processes", None) or {}
    return any(proc.exitcode is not None for proc in list(processes.values()))


def _worker_context(task: Callable[..., Any], preload: Sequence[str] = ()) -> Any:
    """The start context of local workers: forkserver (spawn where unavailable).

    Workers fork from a server that has imported this module, ``preload``, the task's module
    and the modules the task names in a ``worker_preload`` attribute (e.g. one that loads the
    simulator's compiled kernels) once, so each worker starts in a few milliseconds (a no-op
    when this process started its fork server already). Python 3.11's fork server ignores the
    parent's sys.path: a task module must be importable from PYTHONPATH or the cwd.
    """
    methods = multiprocessing.get_all_start_methods()
    ctx = multiprocessing.get_context("forkserver" if "forkserver" in methods else "spawn")
    if ctx.get_start_method() == "forkserver":
        modules = ["deformctl.parallel.backends", *preload]
        module = getattr(task, "__module__", None)  # a function's, or an instance's class's
        if module and module != "__main__" and module in sys.modules:
            modules.append(module)
        modules.extend(getattr(task, "worker_preload", ()))
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
