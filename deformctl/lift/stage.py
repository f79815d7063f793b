"""The ``lift`` stage: the minimum lifting force of every object of a catalog.

:func:`lift_catalog` runs one :func:`~deformctl.lift.search.find_min_lift_force` search per
catalog object, each with a runner from a :class:`RunnerFactory`
(:func:`deformctl.lift.runners.rig.rig_runner_factory` for an external rig,
:func:`deformctl.lift.runners.sim.sim_runner_factory` for the simulator), and returns a
:class:`CatalogLiftResult`: the lift_results table, every attempt (for the lift log) and the
failures, which it records instead of raising, so the caller can write everything before it
decides the exit code. :func:`lift_catalog_files` is the same from a catalog file to the table
and the log files (what ``deformctl lift`` runs; a dataset directory output is
:func:`deformctl.lift.runners.sim.lift_sweep`).

Example:
    >>> from deformctl.catalog import CatalogObject
    >>> from deformctl.series import TrialOutcome
    >>> box = CatalogObject.from_row({"object_id": "A", "size_x_cm": 10, "size_y_cm": 10,
    ...     "size_z_cm": 8, "weight_n": 5.0, "friction_mu": 0.5})
    >>> def make(obj: CatalogObject, max_force_n: float) -> TrialRunner:
    ...     return lambda grip_force_n, attempt_index: TrialOutcome(grip_force_n,
    ...                                                             grip_force_n >= 7.0, 0.0)
    >>> run = lift_catalog([box], RunnerFactory("test", make))
    >>> run.ok, list(run.table["f_w_n"])
    (True, [5.0])
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import pandas as pd

from deformctl.artifacts import (
    Provenance,
    check_output_path,
    validate_frame,
    write_lift_log,
    write_table,
)
from deformctl.artifacts.io import committed_together, is_stdio
from deformctl.catalog import CatalogObject, catalog_objects, select_objects
from deformctl.errors import DeformctlError, UsageError
from deformctl.lift.ceiling import CEILING_COLUMN, ForceCeiling, force_ceiling
from deformctl.lift.journal import LiftJournal
from deformctl.lift.objects import read_lift_objects
from deformctl.lift.options import DEFAULT_SEARCH, SearchOptions
from deformctl.lift.search import (
    LiftAttempt,
    LiftSearchResult,
    SearchAbortedError,
    SearchStart,
    TrialRunner,
    find_min_lift_force,
    search_lift_force,
    search_lift_force_seeded,
)
from deformctl.parallel import map_in_order, single_file_workers
from deformctl.parallel.auto import AUTO, Auto
from deformctl.reprs import short_repr
from deformctl.series import TrialOutcome

if TYPE_CHECKING:  # pragma: no cover - typing only; the seed sources import sklearn when used
    from deformctl.lift.seeded import StartEstimate, StartSeed

__all__ = [
    "CatalogLiftResult",
    "LiftProgress",
    "ObjectFailure",
    "RunnerFactory",
    "lift_catalog",
    "lift_catalog_files",
]

LiftProgress = Callable[[str, int, int], None]
"""``progress(object_id, objects_done, objects_total)``, called after each object of a catalog."""
Warn = Callable[[str], None]
"""``warn(line)``: one warning line (no ``warning:`` prefix), e.g. a start that fell back to F_w."""


def _no_row_fields(obj: CatalogObject) -> Mapping[str, object]:
    return {}


@dataclass(frozen=True)
class RunnerFactory:
    """Builds one trial runner per catalog object: what :func:`lift_catalog` searches with.

    Every runner kind (the external rig, the built-in simulator) is one factory, so the stage
    code does not care which one runs the attempts.

    Attributes:
        name: the runner's name, stored in the table's ``runner`` column (``"rig"``, ``"sim"``).
        make: ``make(obj, max_force_n) -> TrialRunner`` for one object; ``obj`` is its
            :class:`~deformctl.catalog.CatalogObject` (typed attributes, and a read-only mapping
            of the row), ``max_force_n`` its force ceiling, N (:mod:`deformctl.lift.ceiling`;
            the rig request carries it).
        row_fields: ``row_fields(obj) -> {column: value}``: the table columns this runner fills
            for the object (lift profile ``lift_accel_m_s2``, ``lift_speed_m_s``,
            ``lift_height_m``, ``slip_tolerance_m``, ``slip_criterion``).
        stop_on_failure: when a runner fails for one object (raises a
            :class:`~deformctl.errors.DeformctlError`), the remaining objects are not run.
        settings: JSON-serialisable settings of the runner, for the outputs' provenance.
        prepare: ``prepare(objects, path) -> objects``: refuse objects this runner cannot run
            (e.g. the simulator needs material values) by raising a
            :class:`~deformctl.errors.DeformctlError`, and return them as the runner runs them
            (the simulator: each with its run plan, built once); :func:`lift_catalog` calls it
            before any attempt. None: no runner-specific check.
        material_features: the catalog's material values are this runner's ground truth for
            D and λ (the simulator), so a seeded search may predict its start from them when
            no measured D and λ are given (:func:`deformctl.lift.seeded.object_features`).
        journal: every attempt is costly (a real rig): :func:`lift_catalog_files` keeps the
            table and the log on disk as the run goes (:mod:`deformctl.lift.journal`).
        absolute_limit: ``absolute_limit() -> ForceCeiling``: the runner's absolute force limit
            (the rig's handshake, :func:`deformctl.lift.ceiling.absolute_limit`), asked once
            before the first attempt; no object's ceiling is above it. None: no absolute
            limit (the simulator).
    """

    name: str
    make: Callable[[CatalogObject, float], TrialRunner]
    row_fields: Callable[[CatalogObject], Mapping[str, object]] = _no_row_fields
    stop_on_failure: bool = True
    settings: Mapping[str, Any] = field(default_factory=dict)
    prepare: Callable[[Sequence[CatalogObject], str | None], Sequence[CatalogObject]] | None = None
    material_features: bool = False
    journal: bool = False
    absolute_limit: Callable[[], ForceCeiling] | None = None


@dataclass(frozen=True)
class ObjectFailure:
    """An object whose search did not produce a converged L_f.

    Attributes:
        object_id: the object.
        message: one line: why (names the object; for a budget that ran out, the last force
            tried; for a runner failure, the attempt and the force).
        aborted: True when the runner failed (a rig crash, time-out or bad answer), False when
            the search ran out of attempts.
    """

    object_id: str
    message: str
    aborted: bool


@dataclass(frozen=True)
class CatalogLiftResult:
    """What :func:`lift_catalog` found for a set of catalog objects.

    Attributes:
        table: the lift_results table, one row per object in the order run (validated against
            ``schemas/lift_results.columns.json``); objects not run after a runner failure have
            ``attempts = 0`` and an ``error`` starting with ``not run``.
        attempts: every attempt that completed, in the order run (for the lift log); an aborted
            search contributes the attempts before the failure.
        results: the search result of every object that was run (the partial result for an
            aborted search).
        objects: the catalog rows of the objects (:meth:`CatalogObject.record`), for the log.
        failures: the objects that did not converge, in the order run.
        not_run: ids of the objects skipped after a runner failure.
    """

    __repr__ = short_repr

    table: pd.DataFrame
    attempts: tuple[LiftAttempt, ...]
    results: tuple[LiftSearchResult, ...]
    objects: tuple[dict[str, Any], ...]
    failures: tuple[ObjectFailure, ...]
    not_run: tuple[str, ...]

    @property
    def ok(self) -> bool:
        """True when every object's search converged."""
        return not self.failures and not self.not_run

    def error_message(self) -> str | None:
        """One line for the exit: the runner failure if any, else the first non-converged object.

        None when :attr:`ok`.
        """
        if self.ok:
            return None
        aborted = [f for f in self.failures if f.aborted]
        first = aborted[0] if aborted else self.failures[0]
        notes = []
        others = len(self.failures) - 1
        if others:
            notes.append(f"{others} more object{'s' if others > 1 else ''} did not converge")
        if self.not_run:
            n = len(self.not_run)
            notes.append(f"{n} later object{'s' if n > 1 else ''} not run")
        return first.message + (f" ({'; '.join(notes)})" if notes else "")


def lift_catalog(
    catalog: pd.DataFrame | Sequence[CatalogObject],
    factory: RunnerFactory,
    *,
    search: SearchOptions = DEFAULT_SEARCH,
    progress: LiftProgress | None = None,
    path: str | None = None,
    seed: StartSeed | None = None,
    warn: Warn | None = None,
    workers: int | Auto = 1,
    journal: LiftJournal | None = None,
) -> CatalogLiftResult:
    """Search the minimum lifting force of every object of a catalog, one after another.

    Each object gets its own runner from ``factory`` and one :func:`find_min_lift_force`
    search. Failures do not raise; they are recorded so the caller can still write every
    attempt and a row per object, then decide the exit:

    * a search that runs out of attempts gives a row with ``converged = False`` and the search's
      message in ``error``; the next object is run.
    * a runner failure (:class:`SearchAbortedError`) gives a row from the partial result with
      the failure in ``error``; the attempts before it are kept. When
      ``factory.stop_on_failure`` (the rig), the remaining objects are not run and get a
      ``not run`` row.

    Args:
        catalog: a validated catalog (see :func:`deformctl.artifacts.read_catalog`), already cut
            to the objects to lift (:func:`~deformctl.catalog.select_objects`), or its objects.
        factory: builds the runner of each object.
        search: the search's protocol, growth, tolerance, attempt budget and force ceiling
            (:class:`~deformctl.lift.options.SearchOptions`, checked when built). Each object's
            ceiling is ``search.max_force_n`` (``--max-force-n``) unless the catalog gives the
            object one, else the default of :mod:`deformctl.lift.ceiling`; no attempt requests
            more, the runner gets it (the rig request carries it) and a seeded start above it
            is clamped (``warn`` says so).
        progress: called after each object as ``progress(object_id, done, total)``.
        path: the catalog's file name, for error messages.
        seed: start each search from a predicted L_f (a model or an index table,
            :mod:`deformctl.lift.seeded`) with
            :func:`~deformctl.lift.search.find_min_lift_force_seeded`; an object outside the seed's
            range is searched by ``search.protocol`` from F_w instead, and ``warn`` gets one line
            for it before any attempt. The rows' ``predicted_lift_force_n``, ``start_force_n``,
            ``start_in_training_range`` and ``start_source`` are filled (null without a seed).
        warn: receives warning lines (None: they are dropped).
        workers: local processes to run the objects on, or ``"auto"``
            (:func:`deformctl.parallel.map_in_order`; results in catalog order, the same as one
            process); a runner that stops on failure
            (the rig) always runs in this process, one object after another.
        journal: record every attempt and every finished row in it as they happen
            (:mod:`deformctl.lift.journal`); the objects then run in this process.

    Returns:
        A :class:`CatalogLiftResult`.

    Raises:
        UsageError: a seed with the ``paper`` protocol (before anything runs; exit 2).
        InputDataError: an object the lift cannot use, e.g. ``friction_mu = 0``, one the
            runner refuses (``factory.prepare``), or (``seed``) one without D and λ (before
            anything runs; exit 65).
        SchemaError: an object's row holds a value its table refuses (raised as the object
            finishes; with a ``journal``, the attempts made and the rows of the objects before
            it are on disk).
    """
    if seed is not None and search.protocol == "paper":
        raise UsageError(
            "a seeded search bisects to the tolerance as refine does; protocol 'paper' "
            "cannot start from a prediction"
        )
    objects = (
        catalog_objects(catalog, path=path) if isinstance(catalog, pd.DataFrame) else list(catalog)
    )
    f_w = [obj.f_w_n() for obj in objects]
    if factory.prepare is not None:
        objects = list(factory.prepare(objects, path))
    starts: dict[str, StartEstimate] = {}
    if seed is not None:
        starts = seed.starts(objects, use_material=factory.material_features, path=path)
        for estimate in starts.values():
            if estimate.warning is not None and warn is not None:
                warn(estimate.warning)
    absolute = None if factory.absolute_limit is None else factory.absolute_limit()
    ceilings = _ceilings(objects, f_w, search.max_force_n, seed, path, absolute)
    for obj, f_w_n in zip(objects, f_w, strict=True):
        clamp = _clamp_warning(obj.object_id, f_w_n, starts.get(obj.object_id), seed, ceilings)
        if clamp is not None and warn is not None:
            warn(clamp)
    ceiling_n = [ceilings[obj.object_id].max_force_n for obj in objects]
    rows: list[dict[str, object]] = []
    attempts: list[LiftAttempt] = []
    results: list[LiftSearchResult] = []
    failures: list[ObjectFailure] = []
    not_run: list[str] = []
    stopped_at: str | None = None
    story: dict[str, dict[str, Any]] = {}  # a seeded run: each start and its outcome, for the log
    search_one = _ObjectSearch(factory, None if seed is None else seed.margin, search)
    jobs = [(obj, starts.get(obj.object_id), c) for obj, c in zip(objects, ceiling_n, strict=True)]
    records = [
        {**obj.record(), CEILING_COLUMN: c} for obj, c in zip(objects, ceiling_n, strict=True)
    ]
    if journal is not None:

        def placeholder(i: int, error: str, n: int) -> dict[str, object]:
            row = _not_run_row(objects[i], f_w[i], ceiling_n[i], factory, search, error, n)
            return {**row, **_start_columns(jobs[i][1], math.nan)}

        journal.begin(records, placeholder)

    def record(obj: CatalogObject, outcome: tuple[LiftSearchResult, str | None, bool]) -> None:
        result, error, aborted = outcome
        if error is not None:
            failures.append(ObjectFailure(obj.object_id, error, aborted=aborted))
        results.append(result)
        attempts.extend(LiftAttempt(obj.object_id, i, t) for i, t in enumerate(result.trials))
        row = result.table_row(runner=factory.name, error=error)
        row.update(factory.row_fields(obj))
        validate_frame(pd.DataFrame([row]), "lift_results", path=path)  # refused as it finishes
        rows.append(row)
        start = starts.get(obj.object_id)
        if start is not None:
            story[obj.object_id] = start_story(
                start, result, search.growth, search.tolerance_rel, search.max_attempts
            )

    def done(i: int) -> None:
        if progress is not None:
            progress(objects[i].object_id, i + 1, len(objects))

    if workers != 1 and not factory.stop_on_failure and journal is None:
        outcomes = map_in_order(search_one, jobs, workers=workers, on_result=lambda i, _: done(i))
        for obj, outcome in zip(objects, outcomes, strict=True):
            record(obj, outcome)
    else:
        for i, (job, f_w_n) in enumerate(zip(jobs, f_w, strict=True)):
            obj, start, ceiling = job
            if stopped_at is not None:
                why = f"not run: the run stopped at object {stopped_at!r} after a runner failure"
                row = _not_run_row(obj, f_w_n, ceiling, factory, search, why)
                rows.append({**row, **_start_columns(start, math.nan)})
                not_run.append(obj.object_id)
            else:
                if journal is not None:
                    journal.start_object(i)
                on_attempt = None if journal is None else journal.attempt
                outcome = search_one.run(job, on_attempt=on_attempt)
                record(obj, outcome)
                if outcome[2] and factory.stop_on_failure:
                    stopped_at = obj.object_id
            if journal is not None:
                journal.object_done(i, rows[-1])
            done(i)
    table = validate_frame(pd.DataFrame(rows), "lift_results")
    return CatalogLiftResult(
        table=table,
        attempts=tuple(attempts),
        results=tuple(results),
        objects=tuple(
            {**record, **({"start": story[obj.object_id]} if obj.object_id in story else {})}
            for obj, record in zip(objects, records, strict=True)
        ),
        failures=tuple(failures),
        not_run=tuple(not_run),
    )


def lift_catalog_files(
    catalog_path: str,
    factory: RunnerFactory,
    *,
    output: str,
    log: str | None = None,
    object_ids: Sequence[str] | None = None,
    search: SearchOptions = DEFAULT_SEARCH,
    progress: LiftProgress | None = None,
    force: bool = False,
    log_epoch_ns: int | None = None,
    seed: StartSeed | None = None,
    warn: Warn | None = None,
    workers: int | Auto | None = AUTO,
) -> CatalogLiftResult:
    """:func:`lift_catalog` from a catalog file: the lift_results table and the lift log written.

    Both are written (atomically, with provenance) before the caller decides the exit code, so
    a failed run keeps every attempt it made; they are renamed into place together
    (:func:`~deformctl.artifacts.io.committed_together`). A runner whose attempts are costly
    (``factory.journal``, the rig) also keeps both files on disk while the run goes
    (:mod:`deformctl.lift.journal`): a run killed or stopped by an error after its first attempt
    leaves every attempt in the log and the finished objects in the table, and an error's line
    ends with what was kept.

    Args:
        catalog_path: the catalog (CSV or Parquet; ``-`` for stdin), or a coefficients table
            whose objects carry their weight, size and μ (measured D and λ as the material,
            :func:`~deformctl.lift.objects.read_lift_objects`).
        factory: builds the runner of each object.
        output: the lift_results table (``-`` for stdout).
        log: the lift log with every attempt (``-`` for stdout), or None.
        object_ids: these objects, in this order (None: all).
        search, progress, seed, warn: as for :func:`lift_catalog`.
        force: overwrite existing outputs.
        log_epoch_ns: where the log's attempts without a wall clock (simulated ones) begin, ns
            since the Unix epoch (None: the log writer's fixed epoch, 2000-01-01).
        workers: local processes for the objects (see :func:`lift_catalog`); ``"auto"`` (or
            None): the count of least measured wall time (:mod:`deformctl.parallel.auto`). The
            outputs do not depend on it.

    Raises:
        UsageError: ``output`` and ``log`` are the same file, or both stdout (exit 2).
        OutputExistsError: an output exists and ``force`` is false (exit 1).
        MissingInputError, InputDataError: see :func:`~deformctl.artifacts.read_catalog` and
            :func:`lift_catalog`.
    """
    if log is not None:
        if is_stdio(output) and is_stdio(log):
            raise UsageError("-o and --log cannot both be - (stdout)")
        if not is_stdio(log) and os.path.abspath(log) == os.path.abspath(output):
            raise UsageError(f"-o and --log are the same file: {log!r}")
        check_output_path(log, force)
    check_output_path(output, force)
    selected = select_objects(read_lift_objects(catalog_path), object_ids)
    provenance = Provenance.from_invocation(
        [catalog_path, *(seed.inputs if seed is not None else ())],
        settings={
            "runner": factory.name,
            **factory.settings,
            **search.as_dict(),
            "objects": list(selected["object_id"]),
            **({"start": {"source": seed.source, **seed.settings}} if seed is not None else {}),
        },
    )
    epoch = {} if log_epoch_ns is None else {"epoch_ns": log_epoch_ns}
    journal = LiftJournal(output, log, provenance, epoch) if factory.journal else None
    try:
        run = lift_catalog(
            selected,
            factory,
            search=search,
            progress=progress,
            path=catalog_path,
            seed=seed,
            warn=warn,
            workers=single_file_workers(workers, len(selected)),  # the rig runs in-process anyway
            journal=journal if journal is not None and journal.active else None,
        )
    except DeformctlError as err:
        if journal is not None and journal.written:  # say what survived the failure
            err.message = f"{err.message} ({journal.kept()})"
        raise
    mine = force or (journal is not None and journal.written)  # the journal's files are ours
    with committed_together():  # the finished run replaces the journal's files (the table last)
        if log is not None:
            write_lift_log(
                log, run.objects, run.attempts, provenance=provenance, force=mine, **epoch
            )
        write_table(run.table, output, "lift_results", provenance=provenance, force=mine)
    return run


def attempts_from_f_w(
    lift_force_n: float,
    *,
    weight_n: float,
    friction_mu: float,
    growth: float,
    tolerance_rel: float,
    max_attempts: int,
) -> int | None:
    """How many attempts the ``refine`` search from F_w takes on an object that lifts exactly
    from ``lift_force_n`` on (the search replayed against that threshold; None when
    ``lift_force_n`` is not a finite number). What a seeded search is compared with."""
    from deformctl.series import TrialOutcome

    if not (math.isfinite(lift_force_n) and lift_force_n > 0):
        return None
    replay = find_min_lift_force(
        lambda force, _i: TrialOutcome(force, force >= lift_force_n, math.nan),
        weight_n=weight_n,
        friction_mu=friction_mu,
        protocol="refine",
        growth=growth,
        tolerance_rel=tolerance_rel,
        max_attempts=max_attempts,
    )
    return replay.attempts


def start_story(
    start: StartEstimate,
    result: LiftSearchResult,
    growth: float,
    tolerance_rel: float,
    max_attempts: int,
) -> dict[str, Any]:
    """One object of a seeded run as its lift log tells it: the prediction and its bound
    (:meth:`StartEstimate.record`), the first force tried, the attempts, the outcome (converged,
    the L_f found) and the attempts a search from F_w would have taken
    (:func:`attempts_from_f_w`, against the L_f found)."""
    from_f_w = attempts_from_f_w(
        result.lift_force_n,
        weight_n=result.weight_n,
        friction_mu=result.friction_mu,
        growth=growth,
        tolerance_rel=tolerance_rel,
        max_attempts=max_attempts,
    )
    return {
        **start.record(),
        "start_force_n": result.trials[0].grip_force_n if result.trials else None,
        "attempts": result.attempts,
        "converged": result.converged,
        "lift_force_n": result.lift_force_n if math.isfinite(result.lift_force_n) else None,
        "attempts_from_f_w": from_f_w,
        "attempts_saved": None if from_f_w is None else from_f_w - result.attempts,
    }


def _not_run_row(
    obj: CatalogObject,
    f_w_n: float,
    max_force_n: float,
    factory: RunnerFactory,
    search: SearchOptions,
    error: str,
    attempts: int = 0,
) -> dict[str, object]:
    """The row of an object without a result (not run, or interrupted after ``attempts``)."""
    row: dict[str, object] = {
        "object_id": obj.object_id,
        "weight_n": obj.weight_n,
        "friction_mu": obj.friction_mu,
        "f_w_n": f_w_n,
        "lift_force_n": math.nan,
        "f_d_n": math.nan,
        "attempts": int(attempts),
        "converged": False,
        "protocol": search.protocol,
        "bracket_low_n": math.nan,
        "bracket_high_n": math.nan,
        "tolerance_rel": math.nan if search.protocol == "paper" else float(search.tolerance_rel),
        "runner": factory.name,
        "error": error,
        "max_force_n": max_force_n,
    }
    row.update(factory.row_fields(obj))
    return row


def _recordable(predicted_n: float) -> float:
    """A prediction as the table records it: NaN when it is not a finite force > 0 (the
    warning line of the fallback names the value; the table holds forces only)."""
    return predicted_n if math.isfinite(predicted_n) and predicted_n > 0 else math.nan


def _fallback(result: LiftSearchResult, start: StartEstimate | None) -> LiftSearchResult:
    """A search from F_w that had a start it could not use: record the prediction with it."""
    if start is None or result.seeded:
        return result
    return dataclasses.replace(
        result,
        predicted_lift_force_n=_recordable(start.predicted_lift_force_n),
        start_force_n=result.f_w_n,
        start_in_training_range=start.in_range,
        start_source=start.source,
    )


def _start_columns(start: StartEstimate | None, start_force_n: float) -> dict[str, object]:
    """The start columns of a row that was not run (nothing when the run was not seeded)."""
    if start is None:
        return {}
    return {
        **({"protocol": "seeded"} if start.in_range else {}),
        "predicted_lift_force_n": _recordable(start.predicted_lift_force_n),
        "start_force_n": start_force_n,
        "start_in_training_range": start.in_range,
        "start_source": start.source,
    }


_Job = tuple[CatalogObject, "StartEstimate | None", float]
"""One object's search: the object, its start (None: from F_w) and its force ceiling, N."""


@dataclass(frozen=True)
class _ObjectSearch:
    """One object's search as a picklable task (:func:`lift_catalog` with ``workers > 1`` runs
    it in worker processes): ``(object, start, ceiling) -> (result, error, aborted)``.

    Attributes:
        factory: the runner factory (picklable for a parallel run).
        margin: the seed's start margin; None without a seed.
        search: the search options.
    """

    factory: RunnerFactory
    margin: float | None
    search: SearchOptions

    @property
    def worker_preload(self) -> tuple[str, ...]:
        """The modules the runner's local workers load first (the simulator's kernels)."""
        return tuple(getattr(self.factory.make, "worker_preload", ()))

    def __call__(self, job: _Job) -> tuple[LiftSearchResult, str | None, bool]:
        return self.run(job)

    def run(
        self, job: _Job, on_attempt: Callable[[LiftAttempt], None] | None = None
    ) -> tuple[LiftSearchResult, str | None, bool]:
        """The search; ``on_attempt`` gets every attempt as its answer arrives."""
        obj, start, max_force_n = job
        runner = self.factory.make(obj, max_force_n)
        if on_attempt is not None:
            runner = _Reporting(runner, obj.object_id, on_attempt)
        try:
            result = _search(runner, obj, start, self.margin, self.search, max_force_n)
        except _RecordingFailed as failed:  # not the runner's failure: the run stops
            raise failed.error from None
        except SearchAbortedError as err:
            return _fallback(err.partial, start), str(err), True
        return result, (None if result.converged else result.message), False


class _RecordingFailed(Exception):
    """Recording an attempt failed (not a runner failure, which the search would keep going
    from): carries the error past the search to the caller."""

    def __init__(self, error: DeformctlError) -> None:
        self.error = error
        super().__init__(str(error))


@dataclass(frozen=True)
class _Reporting:
    """A runner that hands every outcome to ``on_attempt`` before the search sees it."""

    runner: TrialRunner
    object_id: str
    on_attempt: Callable[[LiftAttempt], None]

    def __call__(self, grip_force_n: float, attempt_index: int, /) -> TrialOutcome:
        outcome = self.runner(grip_force_n, attempt_index)
        if isinstance(outcome, TrialOutcome):  # anything else: the search refuses it
            try:
                self.on_attempt(LiftAttempt(self.object_id, attempt_index, outcome))
            except DeformctlError as err:
                raise _RecordingFailed(err) from err
        return outcome


def _search(
    runner: TrialRunner,
    obj: CatalogObject,
    start: StartEstimate | None,
    margin: float | None,
    search: SearchOptions,
    max_force_n: float,
) -> LiftSearchResult:
    """One object's search under its ceiling: from its start when it has a usable one, else
    ``search.protocol``."""
    who = (runner, obj.object_id, obj.weight_n, obj.friction_mu, search, max_force_n)
    if start is not None and start.in_range and margin is not None:
        seed = SearchStart(start.predicted_lift_force_n, margin, start.source)
        return search_lift_force_seeded(*who, seed)
    return _fallback(search_lift_force(*who), start)


def _ceilings(
    objects: Sequence[CatalogObject],
    f_w: Sequence[float],
    max_force_n: float | None,
    seed: StartSeed | None,
    path: str | None,
    absolute: ForceCeiling | None = None,
) -> dict[str, ForceCeiling]:
    """Each object's force ceiling (:func:`~deformctl.lift.ceiling.force_ceiling`)."""
    coefficients: dict[str, Mapping[str, Any]] = {}
    if seed is not None and seed.coefficients is not None:
        coefficients = {str(r["object_id"]): r for r in seed.coefficients.to_dict("records")}
    return {
        obj.object_id: force_ceiling(
            obj.object_id,
            f_w_n,
            row=obj.row,
            max_force_n=max_force_n,
            coefficients=coefficients.get(obj.object_id),
            path=path,
            absolute=absolute,
        )
        for obj, f_w_n in zip(objects, f_w, strict=True)
    }


def _clamp_warning(
    object_id: str,
    f_w_n: float,
    start: StartEstimate | None,
    seed: StartSeed | None,
    ceilings: Mapping[str, ForceCeiling],
) -> str | None:
    """The warning of a seeded start (or an F_w) above the object's ceiling, else None."""
    ceiling = ceilings[object_id]
    if f_w_n > ceiling.max_force_n:
        return (
            f"object {object_id!r}: F_w = {f_w_n:.6g} N is above its {ceiling.describe()}: "
            "no safe grip, not lifted"
        )
    if start is None or seed is None or not start.in_range:
        return None
    wanted = max(f_w_n, start.predicted_lift_force_n * seed.margin)
    if wanted <= ceiling.max_force_n:
        return None
    return (
        f"object {object_id!r}: the {start.source}'s start {wanted:.6g} N is above its "
        f"{ceiling.describe()}: clamped to the ceiling"
    )
