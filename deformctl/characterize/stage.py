"""The ``characterize`` stage: squeeze logs in, the coefficients table out.

:func:`read_and_characterize` fits every object of a squeeze log (the window and preload chosen
per object from what the log stores: :func:`~deformctl.squeeze.window.default_window_s`,
:func:`default_preload`), :func:`characterize_dir` those of a ``measure`` dataset directory, and
:func:`characterize_file` writes their table; at scale, :class:`CharacterizeTask` is the sweep task
of one object and :func:`characterize_sweep` writes a coefficients dataset directory.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd

from deformctl.artifacts import check_output_path, write_table
from deformctl.artifacts.dataset import (
    MANIFEST_NAME,
    dataset_fingerprint,
    dataset_log_paths,
    iter_dataset_parts,
    part_log_path,
    spec_rows,
    table_schema,
)
from deformctl.artifacts.provenance import Provenance, sha256_file
from deformctl.characterize.coefficients import _coefficient_frame, object_fields
from deformctl.characterize.fit import _fit_rows
from deformctl.characterize.material_options import RIG_SOURCES, default_lag
from deformctl.characterize.options import (
    DEFAULT_FIT,
    DEFAULT_POLICY,
    FitOptions,
    Preload,
    QualityPolicy,
)
from deformctl.characterize.plot import check_plot_dir, plot_fits
from deformctl.characterize.quality import (
    enforce,
    finite_row,
    with_damping_ratio_flag,
    with_recording_flags,
)
from deformctl.errors import InputDataError, MissingInputError, UsageError
from deformctl.parallel import SweepOptions, SweepSummary, run_sweep
from deformctl.reprs import short_repr
from deformctl.series import SqueezeSeries, ruptures_from_object
from deformctl.squeeze.window import default_window_s

if TYPE_CHECKING:  # pragma: no cover - typing only
    from deformctl.characterize.objectfit import ObjectFit


@dataclass(frozen=True)
class LogCoefficients:
    """What :func:`read_and_characterize` found in one squeeze log.

    Attributes:
        table: one row per object, columns :data:`COEFFICIENT_COLUMNS`, in log order.
        window_s: object id → the Savitzky–Golay window used, s.
        position_rate_hz: object id → the position sample rate stored in the log, Hz (None
            when the log does not say).
        preload: object id → the preload mode used (``fit`` or ``zero``; lsq only).
        warnings: one line per flagged object (``<file>: object 'X': <flags>``), for stderr.
        fits: object id → its material fit (lsq; for plots), when asked to keep them.
        plots: the plot files written, in object order.
    """

    __repr__ = short_repr

    table: pd.DataFrame
    window_s: dict[str, float]
    position_rate_hz: dict[str, float | None]
    preload: dict[str, str] = dataclasses.field(default_factory=dict)
    warnings: list[str] = dataclasses.field(default_factory=list)
    fits: dict[str, ObjectFit] = dataclasses.field(default_factory=dict)
    plots: list[str] = dataclasses.field(default_factory=list)


def _stored_rate(obj: Mapping[str, object] | None) -> float | None:
    value = None if obj is None else obj.get("position_rate_hz")
    if isinstance(value, int | float) and not isinstance(value, bool):
        return float(value)
    return None


def default_preload(obj: Mapping[str, object] | None) -> Preload:
    """The preload mode of an object whose log does not choose one: ``fit`` for rig recordings.

    A rig's palms may already press on the object when its compression zero is taken (a testing
    machine starts at a seating preload); ignored, a preload of 1 % of the peak force raises D by
    1–3 % and one of 5 % by 6–15 % (synthetic Kelvin–Voigt squeezes), while fitting it costs
    at most 0.3 % on squeezes without one. Simulated squeezes start from rest at exactly zero force,
    so their preload is known to be 0 (``zero``): there an intercept would only absorb the
    lattice's departure from Kelvin–Voigt (it moves the simulator's D by −0.3 to −2.2 %). Logs that
    do not say where they came from (written before ``source`` was stored) keep ``zero``.
    """
    source = None if obj is None else obj.get("source")
    return "fit" if source in RIG_SOURCES else "zero"


def _fit_object(
    oid: str,
    group: Sequence[SqueezeSeries],
    obj: Mapping[str, object] | None,
    options: FitOptions,
    *,
    window_s: float,
    fits: dict[str, ObjectFit] | None = None,
) -> tuple[dict[str, object], str]:
    """One object's coefficients row (see :func:`characterize`) and the preload mode used;
    its material fit goes into ``fits`` when given."""
    mode: Preload = options.preload if options.preload is not None else default_preload(obj)
    if options.method == "paper":
        mode = "zero"
    rows = _fit_rows(
        {oid: group},
        options.method,
        preload=mode,
        recorded_ruptures={oid: ruptures_from_object(dict(obj or {}))},
        model=options.materials.model,
        at_force_n=options.materials.at_force_n,
        lag_s=default_lag(obj),
        objects={oid: dict(obj or {})},
        fits_out=fits,
        window_s=window_s,
    )
    row = rows[0]
    row["quality"] = with_recording_flags(str(row["quality"]), (obj or {}).get("recording_flags"))
    row["quality"] = with_damping_ratio_flag(str(row["quality"]), row, dict(obj or {}))
    row.update(object_fields(obj))
    return finite_row(row), mode


def _read_logs(
    paths: Sequence[str | PathLike[str]],
) -> tuple[str, list[dict[str, Any]], list[SqueezeSeries]]:
    """The logs' objects (the first row of each id) and squeezes, and the name of the first.

    The squeezes of one object in several logs (recordings of one object at several speeds)
    are numbered on from one log to the next.
    """
    from deformctl.artifacts.io import display_name
    from deformctl.artifacts.mcap import read_squeeze_log

    objects: list[dict[str, Any]] = []
    seen: set[str] = set()
    squeezes: list[SqueezeSeries] = []
    count: dict[str, int] = {}
    for path in paths:
        objs, sq = read_squeeze_log(path)
        if not sq:
            raise InputDataError("the squeeze log holds no squeezes", path=display_name(path))
        for o in objs:
            if str(o["object_id"]) not in seen:
                seen.add(str(o["object_id"]))
                objects.append(dict(o))
        for s in sq:
            k = count.get(s.object_id, 0)
            count[s.object_id] = k + 1
            squeezes.append(s if k == s.squeeze_index else dataclasses.replace(s, squeeze_index=k))
    return display_name(paths[0]), objects, squeezes


def read_and_characterize(
    path: str | PathLike[str] | Sequence[str | PathLike[str]],
    options: FitOptions = DEFAULT_FIT,
    policy: QualityPolicy = DEFAULT_POLICY,
    *,
    keep_fits: bool = False,
) -> LogCoefficients:
    """Read a squeeze log (validated), group its squeezes by object and fit each object.

    Args:
        path: the squeeze-log ``.mcap``, or ``-`` for stdin (read into memory); or several logs,
            whose squeezes of one object id are fitted together (one joint fit over speeds).
        options: the method (:func:`fit_lsq` or :func:`fit_paper`), the Savitzky–Golay window
            (None: per object from the ``position_rate_hz`` the log stores for it,
            :func:`default_window_s`), the preload (None: per object, :func:`default_preload`;
            the paper method never fits one) and, lsq, the material law and the operating force
            (:class:`~deformctl.characterize.options.FitOptions`; the command's defaults).
        policy: what happens to flagged objects: ``strict`` (any flag is an error,
            :func:`deformctl.characterize.quality.enforce`) or ``allow_flagged`` (keep objects
            with negative D instead of refusing them).
        keep_fits: keep each object's material fit in the result (for plots).

    Returns:
        The coefficient table, the window and preload used for each object and the warning
        lines of the flagged objects.

    Raises:
        MissingInputError: the log does not exist (exit 66).
        InputDataError: a damaged log or one that does not match its schema, no squeezes, an
            object whose squeezes cannot be fitted (no compression, too short, ...), an object
            with negative D (unless ``allow_flagged``) or any flagged object with ``strict``;
            the message names the file and the object (exit 65).
        UsageError: an operating force above an object's peak force (exit 2; the options are
            checked when built).
    """
    paths = [path] if isinstance(path, str | PathLike) else list(path)
    name, objects, squeezes = _read_logs(paths)
    by_object: dict[str, list[SqueezeSeries]] = {}
    for s in squeezes:
        by_object.setdefault(s.object_id, []).append(s)
    meta = {str(o["object_id"]): o for o in objects}
    rates = {oid: _stored_rate(meta.get(oid)) for oid in by_object}
    windows = {
        oid: options.window_s if options.window_s is not None else default_window_s(rates[oid])
        for oid in by_object
    }
    rows = []
    modes: dict[str, str] = {}
    fits: dict[str, ObjectFit] = {}
    for oid, group in by_object.items():
        try:
            row, modes[oid] = _fit_object(
                oid,
                group,
                meta.get(oid),
                options,
                window_s=windows[oid],
                fits=fits if keep_fits else None,
            )
        except InputDataError as err:
            if err.path is None:  # the estimators name the object; add the file
                raise InputDataError(err.message, path=name) from err
            raise
        rows.append(row)
    table = _coefficient_frame(rows)
    warnings = enforce(table, strict=policy.strict, allow_flagged=policy.allow_flagged, path=name)
    return LogCoefficients(
        table=table,
        window_s=windows,
        position_rate_hz=rates,
        preload=modes,
        warnings=warnings,
        fits=fits,
    )


# --------------------------------------------------------------------------------------------
# Squeeze-log directories and sweeps (measure --sim -o DIR/, characterize -o DIR/)
# --------------------------------------------------------------------------------------------


def squeeze_log_parts(path: str | PathLike[str]) -> list[Path]:
    """The squeeze logs ``_logs/part-*.mcap`` of a ``measure`` dataset directory, in part order.

    Raises:
        InputDataError: no logs, or a part of the sweep missing (rerun measure with --resume).
    """
    return dataset_log_paths(path, ".mcap", what="squeeze logs", rerun="measure")


def characterize_dir(
    path: str | PathLike[str],
    options: FitOptions = DEFAULT_FIT,
    policy: QualityPolicy = DEFAULT_POLICY,
    *,
    keep_fits: bool = False,
) -> LogCoefficients:
    """:func:`read_and_characterize` of every squeeze log of a ``measure`` directory, in order."""
    parts = [
        read_and_characterize(p, options, policy, keep_fits=keep_fits)
        for p in squeeze_log_parts(path)
    ]
    return LogCoefficients(
        table=pd.concat([p.table for p in parts], ignore_index=True),
        window_s={k: v for p in parts for k, v in p.window_s.items()},
        position_rate_hz={k: v for p in parts for k, v in p.position_rate_hz.items()},
        preload={k: v for p in parts for k, v in p.preload.items()},
        warnings=[line for p in parts for line in p.warnings],
        fits={k: v for p in parts for k, v in p.fits.items()},
    )


def characterize_file(
    log: str | Sequence[str],
    options: FitOptions = DEFAULT_FIT,
    policy: QualityPolicy = DEFAULT_POLICY,
    *,
    output: str,
    force: bool = False,
    plot_dir: str | None = None,
) -> LogCoefficients:
    """``characterize LOG -o TABLE``: fit a squeeze log (or a ``measure`` directory's logs).

    The quality policy is applied before anything is written (see :func:`read_and_characterize`);
    the coefficients table is then written atomically with its provenance (the options as given,
    the window and preload used for each object and the position sample rates behind them).
    With ``plot_dir`` (lsq) each object's fit is drawn into ``plot_dir/<object_id>.png`` after
    the table is written
    (:func:`deformctl.characterize.plot.plot_object`). The caller prints ``result.warnings``
    and ``result.plots``.

    Raises:
        OutputExistsError: ``output`` exists and ``force`` is false (exit 1).
        MissingInputError, InputDataError, UsageError: see :func:`read_and_characterize`;
            ``plot_dir`` with the paper method (exit 2).
    """
    check_output_path(output, force)
    if plot_dir is not None:
        if options.method != "lsq":
            raise UsageError("--plot draws the material laws' fits: use it with --method lsq")
        check_plot_dir(plot_dir)
    logs = [log] if isinstance(log, str) else list(log)
    keep_fits = plot_dir is not None
    if len(logs) == 1 and os.path.isdir(logs[0]):
        result = characterize_dir(logs[0], options, policy, keep_fits=keep_fits)
    else:
        result = read_and_characterize(logs, options, policy, keep_fits=keep_fits)
    provenance = Provenance.from_invocation(
        logs,
        settings={
            **options.as_dict(),
            "window_s": result.window_s,
            "position_rate_hz": result.position_rate_hz,
            "preload": result.preload,
        },
    )
    write_table(result.table, output, "coefficients", provenance=provenance, force=force)
    if plot_dir is not None:
        quality = dict(zip(result.table["object_id"], result.table["quality"], strict=True))
        result = dataclasses.replace(result, plots=plot_fits(result.fits, quality, plot_dir))
    return result


def sweep_warnings(out_dir: str | PathLike[str]) -> list[str]:
    """One warning line per flagged object of a coefficients dataset directory (parts in order).

    Returns an empty list when the directory's parts cannot be read (an interrupted sweep).
    """
    from deformctl.errors import DeformctlError

    lines: list[str] = []
    try:
        for table in iter_dataset_parts(out_dir):
            lines.extend(enforce(table.to_pandas(), path=str(out_dir)))
    except DeformctlError:
        return []
    return lines


def characterize_items(path: str | PathLike[str]) -> list[dict[str, Any]]:
    """One sweep item per object of a ``measure`` dataset: ``object_id`` and its log's path.

    The objects are those with rows in the dataset (failed objects have no squeezes).
    """
    from deformctl.artifacts.mcap import read_squeeze_log

    d = Path(path).resolve()
    logs = squeeze_log_parts(d)
    items: list[dict[str, Any]] = []
    if (d / MANIFEST_NAME).is_file() and any(d.glob("part-*.parquet")):
        for k, table in enumerate(iter_dataset_parts(d)):
            part_log = str(part_log_path(d, k))
            items.extend(
                {"object_id": oid, "log_path": part_log} for oid in table["object_id"].to_pylist()
            )
        return items
    for log in logs:  # no manifest: ask each log for its objects
        objects, _ = read_squeeze_log(log)
        items.extend({"object_id": str(o["object_id"]), "log_path": str(log)} for o in objects)
    return items


_LOG_CACHE: dict[tuple[str, int], tuple[dict[str, Any], dict[str, list[SqueezeSeries]]]] = {}


def _read_log_cached(path: str) -> tuple[dict[str, Any], dict[str, list[SqueezeSeries]]]:
    """A squeeze log's objects and squeezes by object id; the last log read is kept per process.

    Items arrive in catalog order, so a worker reads each part's log about once.
    """
    from deformctl.artifacts.mcap import read_squeeze_log

    key = (path, os.stat(path).st_mtime_ns)
    if key not in _LOG_CACHE:
        objects, squeezes = read_squeeze_log(path)
        by_object: dict[str, list[SqueezeSeries]] = {}
        for s in squeezes:
            by_object.setdefault(s.object_id, []).append(s)
        _LOG_CACHE.clear()
        _LOG_CACHE[key] = ({str(o["object_id"]): o for o in objects}, by_object)
    return _LOG_CACHE[key]


@dataclass(frozen=True)
class CharacterizeTask:
    """``characterize`` for one object of a squeeze-log directory (a picklable sweep task).

    Attributes:
        fit: the fit options (the material law and operating force among them), as
            :func:`read_and_characterize`'s.
        policy: ``strict``: a flagged object fails (recorded in ``_failures/``) instead of being
            written; ``allow_flagged``: write an object with negative D (flagged) instead of
            failing it.
    """

    fit: FitOptions = DEFAULT_FIT
    policy: QualityPolicy = DEFAULT_POLICY

    def __call__(self, item: dict[str, Any]) -> Any:
        """Fit one object; its coefficients row (an Arrow table).

        Raises:
            InputDataError: the object has no squeezes, cannot be fitted, or is refused by the
                quality policy (recorded as failed).
        """
        oid, log = str(item["object_id"]), str(item["log_path"])
        meta, by_object = _read_log_cached(log)
        group = by_object.get(oid)
        if not group:
            raise InputDataError(f"object {oid!r} has no squeezes", path=log)
        rate_hz = _stored_rate(meta.get(oid))
        window = self.fit.window_s if self.fit.window_s is not None else default_window_s(rate_hz)
        try:
            row, _ = _fit_object(oid, group, meta.get(oid), self.fit, window_s=window)
        except InputDataError as err:
            if err.path is None:
                raise InputDataError(err.message, path=log) from err
            raise
        df = _coefficient_frame([row])
        enforce(df, strict=self.policy.strict, allow_flagged=self.policy.allow_flagged, path=log)
        return spec_rows(df, "coefficients")


def characterize_sweep(
    log_dir: str,
    task: CharacterizeTask,
    *,
    output: str,
    sweep: SweepOptions,
    force: bool = False,
) -> SweepSummary:
    """``characterize DIR -o OUT/``: one fit per object of a squeeze-log directory, in parallel.

    Raises:
        MissingInputError: ``log_dir`` does not exist (exit 66).
        UsageError: ``log_dir`` is a file (exit 2).
    """
    if not os.path.isdir(log_dir):
        if not os.path.exists(log_dir):
            raise MissingInputError("no such file or directory", path=log_dir)
        raise UsageError(
            "a dataset directory output (-o DIR/) needs a squeeze-log directory input "
            "(measure --sim -o DIR/)"
        )
    settings = {**task.fit.as_dict(), **task.policy.as_dict()}
    fingerprint = dataset_fingerprint(
        "characterize", "coefficients", settings, {"log": sha256_file(log_dir)}
    )
    return run_sweep(
        task,
        characterize_items(log_dir),
        out_dir=output,
        schema=table_schema("coefficients"),
        fingerprint=fingerprint,
        force=force,
        **sweep.run_kwargs(),
    )
