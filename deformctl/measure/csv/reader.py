"""The CSV source of ``measure``: one object's squeezes from a testing machine's or a gripper's
export (``measure csv``; the library's door is :func:`deformctl.measure.stage.read_recording`
with a :class:`CsvOptions`).

The file is read as it comes (:mod:`deformctl.measure.csv.table`: encoding, delimiter, decimal
mark, preamble, header, units row), the time, force and position columns are found by name with
their units (:mod:`deformctl.measure.csv.columns`), and the numbers are converted to SI. Then:

1. time must not go back (the row is named); repeated timestamps are merged;
2. a sample rate, peak force or peak compression that a unit mistake explains is refused with
   the unit that would make it plausible (:mod:`deformctl.plausibility`);
3. the force's sign: compressive force is the sign that grows with the compression
   (``force_sign="auto"``; a flip is reported and recorded);
4. the recording's defects are found and reported (:mod:`deformctl.measure.defects`), and the
   force's lag behind the position is estimated and, with ``lag_s``, shifted out (the lag
   taken out and whether it was given or estimated are recorded, :attr:`Recording.force_lag_s`);
5. the recording is cut into squeezes (:mod:`deformctl.measure.segment`).

What was found (layout, preamble, columns and units, force sign, lag) is returned in
:attr:`Recording.details`, which the squeeze log stores with the object.
"""

from __future__ import annotations

from collections.abc import Mapping
from os import PathLike
from typing import Any

import numpy as np

from deformctl.errors import DeformctlError, InputDataError, UsageError
from deformctl.measure.csv.columns import ColumnRole, column_roles, describe_roles
from deformctl.measure.csv.options import CsvOptions
from deformctl.measure.csv.table import CsvLayout, CsvSource, read_columns, read_layout
from deformctl.measure.defects import (
    Defect,
    coarse_force,
    estimate_lag,
    first_backwards,
    lag_defect,
    logging_gaps,
    merge_duplicate_times,
    shift_force,
)
from deformctl.measure.options import Segmentation
from deformctl.measure.recording import (
    Recording,
    _check_stream,
    _compression,
    _rate_hz,
)
from deformctl.measure.segment import _detection_window_s, _to_squeezes
from deformctl.plausibility import (
    MAX_PEAK_FORCE_N,
    SUGGESTED_UNITS,
    Reading,
    check_peak_compression,
    check_peak_force,
    check_sample_rate,
    compression_limit_m,
    compression_target_m,
    rate_ok,
    suggest_unit,
    unit_doubts,
)
from deformctl.series import FloatArray
from deformctl.squeeze.flags import LAG_ESTIMATED, LAG_GIVEN
from deformctl.units import GIB, UNITS, s_to_ns

#: Multiply a value in the unit by the factor to get SI; keys are lower-case unit names.
TIME_UNITS_S: dict[str, float] = {k.lower(): u.si for k, u in UNITS["time"].items()}
FORCE_UNITS_N: dict[str, float] = {k.lower(): u.si for k, u in UNITS["force"].items()}
LENGTH_UNITS_M: dict[str, float] = {k.lower(): u.si for k, u in UNITS["length"].items()}
#: A CSV time column whose first value (in s, after ``--units``) is at least this is Unix time
#: (2000-01-01T00:00:00Z): the squeeze log keeps those times as its ``log_time``.
ABSOLUTE_TIME_MIN_S = 946_684_800.0
#: Memory one data row of a CSV export costs until its squeeze log is written, bytes: measured
#: 204 and 210 B per row (peak RSS above a 10,000-row run's; 1 and 3 million rows of three
#: columns into one squeeze log), rounded up. The budget refuses a file before it is read.
CSV_ROW_BYTES = 250
#: ``force_sign="auto"``: a force this share of whose summed sizes has one sign is compressive
#: in that sign (a relaxation recording's force falls as the compression grows, yet stays
#: positive); below it, the sign that grows with the compression.
ONE_SIGN_SHARE = 0.9
#: Fewest data rows a recording must have.
MIN_ROWS = 2


def _unit_hint(role: ColumnRole, unit: str | None, what: str) -> str:
    """The fix a hint names: ``--units compression=mm``, or the file's own unit questioned."""
    if unit is None:
        return f"check the unit of {what}"
    if role.unit_from in ("header", "units row"):
        return (
            f"the file's {role.unit_from} says {role.unit.name}; the values are plausible in "
            f"{unit}: is the {role.unit_from} wrong?"
        )
    return f"did you mean --units {role.role}={unit}?"


def read_csv(
    path: str | PathLike[str],
    options: CsvOptions,
    object_id: str,
    segmentation: Segmentation,
    size_x_cm: float | None,
) -> Recording:
    """The CSV source of :func:`deformctl.measure.stage.read_recording` (its door; the steps
    are the module docstring's).

    Args:
        path: the CSV file, or ``-`` for stdin.
        options: how to read the file and what its columns are (:class:`CsvOptions`).
        object_id: catalog id written into the squeezes.
        segmentation: how the file is cut (one squeeze per file unless
            ``segmentation.segment``; :class:`~deformctl.measure.options.Segmentation`).
        size_x_cm: the object's size along the squeeze axis, when known.

    Raises:
        MissingInputError: the file does not exist (exit 66).
        InputDataError: an empty file, text that does not decode, no header, a column that is
            not found, a unit the file states that is unknown, non-numeric or empty cells,
            time going back, fewer than two rows, or an implausible recording (a sample rate,
            peak force or peak compression a unit mistake explains, the force or compression
            of the wrong sign); the message names the file (exit 65).
        UsageError: ambiguous columns, a ``units`` value that contradicts the file, a file
            above the memory budget (exit 2).
    """
    source = CsvSource.open(path)
    try:
        return _read(
            source, options, object_id=object_id, segmentation=segmentation, size_x_cm=size_x_cm
        )
    except DeformctlError as err:
        if err.path is None:
            err.path = source.name
        raise


def _check_budget(layout: CsvLayout, options: CsvOptions, name: str) -> None:
    need = layout.rows_estimate * CSV_ROW_BYTES
    if need > options.memory_budget_gib * GIB:
        raise UsageError(
            f"about {layout.rows_estimate:,} data rows, an estimated {need / GIB:.3g} GiB "
            f"in memory, above the memory budget of {options.memory_budget_gib:g} GiB "
            f"({CSV_ROW_BYTES} B per row); split the file or raise --memory-budget-gib"
        )


def _read(
    source: CsvSource,
    options: CsvOptions,
    *,
    object_id: str,
    segmentation: Segmentation,
    size_x_cm: float | None,
) -> Recording:
    name = source.name
    layout = read_layout(source, options.dialect)
    _check_budget(layout, options, name)
    roles = column_roles(layout, options)
    raw = read_columns(source, layout, [r.index for r in roles.values()])
    n = raw[roles["time"].index].shape[0]
    if n < MIN_ROWS:
        raise InputDataError(
            f"only {n} data row (line {layout.data_line}): a squeeze needs at least {MIN_ROWS}"
        )
    arrays = {role: raw[r.index] * r.unit.si for role, r in roles.items()}
    pos_role = next(r for r in ("position", "gap", "compression") if r in roles)
    time_s = arrays["time"]
    back = first_backwards(time_s)
    if back is not None:
        t = roles["time"]
        raise InputDataError(
            f"time goes back at data row {back + 1} (line {_line_of_row(source, layout, back)}): "
            f"{t.name!r} is {raw[t.index][back]:.9g} after {raw[t.index][back - 1]:.9g}"
        )
    notes = [f"columns: {describe_roles(roles)}"]
    warnings: list[str] = []
    for r in roles.values():
        if r.unit_from == "default":
            warnings.append(
                f"column {r.name!r} ({r.role}) states no unit: read in {r.unit.name} (pass --units "
                f"{r.role}=UNIT to say which)"
            )
    time_s, (force_n, position), merged = merge_duplicate_times(
        time_s, arrays["force"], arrays[pos_role]
    )
    if merged:
        warnings.append(
            f"{merged} sample(s) repeat the timestamp of the one before: merged (averaged)"
        )
    if time_s.shape[0] < MIN_ROWS:
        raise InputDataError(f"every row has the same time: a squeeze needs at least {MIN_ROWS}")
    for role, values in (("time", time_s), ("force", force_n), (pos_role, position)):
        _check_stream(f"column {roles[role].name!r}", time_s, values, name)
    _check_time_and_force(time_s, force_n, roles, name)
    force_n, sign = _force_sign(force_n, position, options, roles["force"])
    if sign["flipped"]:
        notes.append(
            f"the force is negative under compression in column {roles['force'].name!r}: sign "
            f"flipped (--force-sign {options.force_sign})"
        )
    defects: list[Defect] = [d for d in (logging_gaps(time_s), coarse_force(force_n)) if d]
    kind = options.position_is if pos_role == "position" else pos_role
    reading = position_reading(roles[pos_role], kind)
    if pos_role != "compression":  # a compression column has one reading
        notes.append(f"position: {reading['text']}")
    threshold_frac = segmentation.force_threshold_frac
    what = f"column {roles[pos_role].name!r}"

    def compression_of(t: FloatArray, f: FloatArray, p: FloatArray) -> FloatArray:
        return _compression(
            p, f, kind, name, threshold_frac, options.compression_zero,
            options.position_increases_when, what,
        )  # fmt: skip

    compression_m = compression_of(time_s, force_n, position)
    _check_compression(compression_m, roles[pos_role], size_x_cm, name)
    lag = estimate_lag(time_s, force_n, compression_m)
    shift_s = 0.0
    removed: tuple[float, str] | None = None  # the lag taken out and where it came from
    if options.lag_s == "auto":
        if lag.lag_s is not None and lag.lag_s > 0:
            shift_s = lag.lag_s
            removed = (shift_s, LAG_ESTIMATED)
        else:
            warnings.append(f"--lag-s auto: the force's lag is {lag.describe()}: not shifted")
    elif isinstance(options.lag_s, float):
        shift_s = options.lag_s
        removed = (shift_s, LAG_GIVEN)
    if shift_s:
        time_s, force_n, position = shift_force(time_s, force_n, position, shift_s)
        compression_m = compression_of(time_s, force_n, position)
        notes.append(f"force shifted {shift_s:.3g} s earlier (--lag-s {options.lag_s})")
    else:
        found = lag_defect(lag, float(np.median(np.diff(time_s))))
        if found is not None:
            defects.append(found)
    rate_hz = _rate_hz(time_s)
    defects += _unit_doubts(rate_hz, force_n, compression_m, roles, pos_role, name)
    warnings.extend(d.text for d in defects)
    absolute = float(time_s[0]) >= ABSOLUTE_TIME_MIN_S
    squeezes, ruptures = _to_squeezes(
        time_s - time_s[0],
        force_n,
        compression_m,
        object_id=object_id,
        segmentation=segmentation,
        segment=segmentation.segments(False),
        path=name,
        window_s=_detection_window_s(rate_hz),
        clock_origin_ns=s_to_ns(float(time_s[0])) if absolute else None,
    )
    details: dict[str, Any] = {
        "layout": layout.as_dict(),
        "columns": {role: r.as_dict() for role, r in roles.items()},
        "preamble": dict(layout.preamble),
        "preamble_lines": list(layout.preamble_lines),
        "force_sign": sign,
        "position_reading": {k: v for k, v in reading.items() if k != "text"},
        "merged_timestamps": merged,
        "lag": {**lag.as_dict(), "shifted_s": shift_s},
    }
    return Recording(
        squeezes,
        rate_hz,
        rate_hz,
        source=CsvOptions.kind,
        phase=segmentation.phase,
        ruptures=tuple(ruptures),
        flags=tuple(d.flag for d in defects),
        force_lag_s=None if removed is None else removed[0],
        force_lag_source="" if removed is None else removed[1],
        defects=tuple(d.as_dict() for d in defects),
        details=details,
        notes=tuple(notes),
        warnings=tuple(warnings),
    )


#: How each reading makes the compression of a position column (``d`` from the column ``p``).
POSITION_RULES: dict[str, str] = {
    "compression": "d = p - p(first row)",
    "travel": "d = |p - p(first row)|, signed positive at the peak force",
    "palm": "d = 2 x |p - p(first row)|, one palm's travel, its partner mirroring it",
    "gap": "d = p(first row) - p, the distance between the palms",
}
#: Why a reading was taken, and the option for another.
_READING_WHY: dict[str, str] = {
    "travel": "a crosshead's or a gripper jaw's travel is the compression; --position-is palm "
    "reads it as one palm's travel (x2), --position-is gap as the distance between the palms",
    "palm": "--position-is palm",
    "gap": "--position-is gap",
    "compression": "the column is the compression",
}


def position_reading(role: ColumnRole, kind: str) -> dict[str, Any]:
    """How the position column was read: its role, the reading, the factor on its travel, the
    rule, and the line ``measure`` prints (``text``) and the squeeze log records (without it)."""
    factor = 2.0 if kind == "palm" else 1.0
    rule = POSITION_RULES[kind]
    return {
        "column": role.name,
        "role": role.role,
        "reading": kind,
        "factor": factor,
        "rule": rule,
        "text": f"column {role.name!r} ({role.role}) read as {kind}: {rule} ({_READING_WHY[kind]})",
    }


def _line_of_row(source: CsvSource, layout: CsvLayout, row: int) -> int:
    """The file line of data row ``row`` (0-based; blank lines are not rows)."""
    import io

    with source.stream(layout.data_offset) as fh:
        text = io.TextIOWrapper(fh, encoding=layout.encoding, newline="")
        seen = -1
        for k, line in enumerate(text):
            if line.strip():
                seen += 1
                if seen == row:
                    return layout.data_line + k
    return layout.data_line + row


def _force_sign(
    force_n: FloatArray, position: FloatArray, options: CsvOptions, role: ColumnRole
) -> tuple[FloatArray, dict[str, Any]]:
    """The force with compression positive, and what was decided.

    The compressive sign is the force's own when nearly all of it has one sign (at least
    :data:`ONE_SIGN_SHARE` of the sum of its sizes: a relaxation recording, whose force falls
    while the compression holds or grows, keeps its positive force); otherwise the one that
    grows with the compression: the sign of the covariance of the force with the position's
    distance from its start (whichever way the position runs).

    Raises:
        InputDataError: an explicit ``force_sign`` under which the force falls as the
            compression grows (names ``--force-sign``).
    """
    travel = np.abs(position - position[0])
    cov = float(np.mean((force_n - force_n.mean()) * (travel - travel.mean())))
    grows = cov >= 0
    positive = float(np.sum(np.clip(force_n, 0.0, None)))
    negative = float(np.sum(np.clip(-force_n, 0.0, None)))
    total = positive + negative
    by = "covariance"
    if total > 0 and max(positive, negative) >= ONE_SIGN_SHARE * total:
        by = "one_sign"
    if options.force_sign == "auto":
        flipped = negative > positive if by == "one_sign" else not grows
    else:
        flipped = options.force_sign == "negative"
        if grows == flipped and cov != 0:
            other = "positive" if flipped else "negative"
            raise InputDataError(
                f"column {role.name!r}: with --force-sign {options.force_sign} the force falls "
                f"as the compression grows; the compressive force is {other} in this file: pass "
                f"--force-sign {other} (or auto)"
            )
    decided = {
        "option": options.force_sign,
        "compressive": "negative" if flipped else "positive",
        "flipped": bool(flipped),
        "by": by if options.force_sign == "auto" else "option",
    }
    return (-force_n if flipped else force_n), decided


def _check_time_and_force(
    time_s: FloatArray, force_n: FloatArray, roles: Mapping[str, ColumnRole], where: str
) -> None:
    """Refuse a CSV whose sample rate or peak force a unit mistake explains (names the unit)."""
    dt_s = float(np.median(np.diff(time_s)))
    rate_hz = 1.0 / dt_s
    t_role, f_role = roles["time"], roles["force"]
    if not rate_ok(rate_hz):
        unit = suggest_unit(
            dt_s / t_role.unit.si,
            SUGGESTED_UNITS["time"],
            to_value=lambda dt: 1.0 / dt,
            ok=rate_ok,
            target=1000.0,
        )
        what = f"column {t_role.name!r}"
        check_sample_rate(rate_hz, what=what, path=where, hint=_unit_hint(t_role, unit, what))
    peak_n = float(np.max(np.abs(force_n)))
    unit = suggest_unit(
        peak_n / f_role.unit.si,
        SUGGESTED_UNITS["force"],
        to_value=lambda f: f,
        ok=lambda f: f <= MAX_PEAK_FORCE_N,
        target=10.0,
    )
    what = f"column {f_role.name!r}"
    check_peak_force(peak_n, what=what, path=where, hint=_unit_hint(f_role, unit, what))


def _unit_doubts(
    rate_hz: float,
    force_n: FloatArray,
    compression_m: FloatArray,
    roles: Mapping[str, ColumnRole],
    pos_role: str,
    where: str,
) -> list[Defect]:
    """The two-sided plausibility flags (:func:`deformctl.plausibility.unit_doubts`), each
    line naming the column and the unit that would make its values plausible.

    Raises:
        InputDataError: a doubtful value no recognised unit makes plausible (exit 65).
    """

    def reading(role: ColumnRole) -> Reading:
        stated = role.unit_from != "default"
        return Reading(f"column {role.name!r}", role.unit.name, role.unit.si, stated)

    doubts = unit_doubts(
        rate_hz=rate_hz,
        peak_force_n=float(np.max(np.abs(force_n))),
        peak_compression_m=float(np.max(compression_m)),
        readings={
            "time": reading(roles["time"]),
            "force": reading(roles["force"]),
            "length": reading(roles[pos_role]),
        },
        path=where,
    )
    return [Defect(flag, line, numbers) for flag, line, numbers in doubts]


def _check_compression(
    compression_m: FloatArray, role: ColumnRole, size_x_cm: float | None, where: str
) -> None:
    """Refuse a peak compression larger than the object (or 0.5 m); the hint names the unit."""
    peak_m = float(np.max(compression_m))
    unit = suggest_unit(
        peak_m / role.unit.si,
        SUGGESTED_UNITS["length"],
        to_value=lambda m: m,
        ok=lambda m: m <= compression_limit_m(size_x_cm),
        target=compression_target_m(size_x_cm),
    )
    what = f"column {role.name!r}"
    check_peak_compression(
        peak_m, size_x_cm=size_x_cm, what=what, path=where, hint=_unit_hint(role, unit, what)
    )
