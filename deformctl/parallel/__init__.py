"""Run one function per object over a population, locally or on a Dask cluster, resumably.

A *sweep* applies a picklable top-level ``task(item)`` to every catalog row (``item``, a dict
with an id column such as ``object_id``) and streams the rows it returns into a partitioned
Parquet dataset (:mod:`deformctl.artifacts.dataset` owns the directory: manifest, parts,
failures, part logs, atomic part writes, readers). This package is the executor only: it submits
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

Modules: :mod:`~deformctl.parallel.options` (:class:`SweepOptions`, the flags),
:mod:`~deformctl.parallel.auto` (``--workers auto``: :func:`choose_workers`, :class:`WorkerChoice`),
:mod:`~deformctl.parallel.backends` (the worker side, local processes, Dask) and
:mod:`~deformctl.parallel.sweep` (:func:`run_sweep`, :func:`map_in_order`); their public names are
re-exported here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from deformctl.lazy import lazy_face

# ruff: noqa: F401 - the imports below are the public names (deformctl.lazy.lazy_face)
if TYPE_CHECKING:  # for type checkers; at run time each loads on first use
    from deformctl.parallel.auto import WorkerChoice, choose_workers
    from deformctl.parallel.backends import TaskOutput, connect_dask
    from deformctl.parallel.options import (
        DEFAULT_CONNECT_TIMEOUT_S,
        DEFAULT_PARTITION_SIZE,
        SweepOptions,
    )
    from deformctl.parallel.sweep import (
        MIN_PARALLEL_OBJECTS,
        SweepSummary,
        map_in_order,
        run_sweep,
        single_file_workers,
    )

__getattr__, __dir__ = lazy_face(globals())
