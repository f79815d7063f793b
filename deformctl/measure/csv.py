"""The CSV source of ``measure``: one object's squeezes from a testing machine's or a gripper's
export (``--csv``).

A file is plain (names in row one) or carries its units in row two; the mapped columns give time,
force and one position signal (:mod:`deformctl.measure.recording`). Units come from the file, or
``units`` for the columns whose unit the file does not state, else SI. A recording whose sample
rate, peak force or peak compression a unit mistake explains is refused with the unit that would
make it plausible (:mod:`deformctl.plausibility`).
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping, Sequence
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np

from deformctl.artifacts.io import note_input
from deformctl.characterize.rupture import Phase
from deformctl.errors import InputDataError, MissingInputError
from deformctl.measure.options import (
    DEFAULT_FORCE_THRESHOLD_FRAC,
    DEFAULT_MIN_GAP_S,
    DEFAULT_MIN_SQUEEZE_S,
    DEFAULT_SEGMENTATION,
    FORCE_UNITS_N,
    LENGTH_UNITS_M,
    TIME_UNITS_S,
    UNITS_BY_KEY,
    CompressionZero,
    CsvSource,
    IncreasesWhen,
    PositionIs,
    Segmentation,
    norm_unit,
)
from deformctl.measure.recording import (
    Recording,
    _check_stream,
    _compression,
    _rate_hz,
)
from deformctl.measure.segment import (
    _detection_window_s,
    _to_squeezes,
)
from deformctl.plausibility import (
    MAX_PEAK_FORCE_N,
    check_peak_compression,
    check_peak_force,
    check_sample_rate,
    compression_limit_m,
    compression_target_m,
    rate_ok,
    suggest_unit,
)
from deformctl.series import FloatArray, SqueezeSeries
from deformctl.units import NS_PER_S

#: A CSV time column whose first value (in s, after ``--units``) is at least this is Unix time
#: (2000-01-01T00:00:00Z): the squeeze log keeps those times as its ``log_time``.
ABSOLUTE_TIME_MIN_S = 946_684_800.0


#: How the units are spelled in messages (the tables above key them in lower case).
_UNIT_SPELLING = {"n": "N", "kn": "kN", "mn": "mN"}


def _unit_hint(key: str, unit: str | None, what: str, stated: str | None = None) -> str:
    """``did you mean --units key=unit?``; ``stated``: the unit the file's units row gives."""
    if unit is None:
        return f"check the unit of {what}"
    spelled = _UNIT_SPELLING.get(unit, unit)
    if stated is not None:
        return f"the file's units row says {stated!r}; is {what} in {spelled}?"
    return f"did you mean --units {key}={spelled}?"


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def read_csv_export(
    path: str | PathLike[str],
    *,
    columns: Mapping[str, str],
    object_id: str,
    units: Mapping[str, str] | None = None,
    position_is: PositionIs = "palm",
    compression_zero: CompressionZero = "first",
    segment: bool = False,
    force_threshold_frac: float = DEFAULT_FORCE_THRESHOLD_FRAC,
    min_gap_s: float = DEFAULT_MIN_GAP_S,
    min_squeeze_s: float = DEFAULT_MIN_SQUEEZE_S,
    phase: Phase = "all",
    position_increases_when: IncreasesWhen | None = None,
    size_x_cm: float | None = None,
) -> Recording:
    """Read squeezes from a CSV export: plain, or names in row one and units in row two.

    The file is a two-header-row export when every mapped column's second row is not a number;
    that row is then read as the columns' units (``N``, ``[mm]``, ``(s)`` are all accepted).
    Units given in ``units`` apply to columns whose unit the file does not state; a unit stated
    in both places must agree. Columns with no unit anywhere are taken as SI (s, N, m).

    Args:
        path: the CSV file (comma-separated; UTF-8, a BOM is accepted).
        columns: mapping of ``time``, ``force`` and exactly one of ``position`` (one palm's
            travel, see ``position_is``), ``gap`` (between the palms) or ``compression`` (the
            compression itself, e.g. a testing machine's crosshead travel) to CSV column names.
        object_id: catalog id written into the squeezes.
        units: mapping of the same keys to units: time s/ms/us/ns, force N/kN/mN/lbf,
            lengths m/cm/mm/um/in.
        position_is: meaning of a ``position`` column: ``"palm"`` or ``"gap"``.
        compression_zero: ``"first"`` (the first row) or ``"lead_in"`` (module docstring).
        segment: split the file into squeezes (default: one squeeze per file).
        force_threshold_frac, min_gap_s, min_squeeze_s: segmentation (module docstring).
        phase, position_increases_when, size_x_cm: as :func:`read_ros2_bag` (a compression
            column grows when closing unless ``position_increases_when="opening"``).

    Returns:
        The squeezes in SI, the file's median sample rate (for force and position alike) and
        the ruptures.

    Raises:
        MissingInputError: the file does not exist.
        InputDataError: a mapped column missing from the file, an unknown unit in the file,
            file and option units that disagree, non-numeric or NaN cells, non-monotonic time,
            no compression, or an implausible recording: a sample rate, peak force or peak
            compression that a unit mistake explains (the message suggests the ``--units``), a
            compression of the wrong sign (it names ``--position-increases-when``).
        UsageError: a bad ``columns`` mapping, a ``units`` key that names no mapped column or an
            unknown unit in ``units``.
    """
    source = CsvSource(
        columns=columns,
        units=units or {},
        position_is=position_is,
        compression_zero=compression_zero,
        position_increases_when=position_increases_when,
    )
    segmentation = Segmentation(
        segment=segment,
        force_threshold_frac=force_threshold_frac,
        min_gap_s=min_gap_s,
        min_squeeze_s=min_squeeze_s,
        phase=phase,
    )
    return read_csv(
        path, source, object_id=object_id, segmentation=segmentation, size_x_cm=size_x_cm
    )


def read_csv(
    path: str | PathLike[str],
    source: CsvSource,
    *,
    object_id: str,
    segmentation: Segmentation = DEFAULT_SEGMENTATION,
    size_x_cm: float | None = None,
) -> Recording:
    """:func:`read_csv_export` with its options as the checked objects the command builds.

    Args:
        path: the CSV file.
        source: the columns, their units and the position signal
            (:class:`~deformctl.measure.options.CsvSource`).
        object_id: catalog id written into the squeezes.
        segmentation: how the file is cut (one squeeze unless ``segmentation.segment``).
        size_x_cm: the object's size along the squeeze axis, when known.

    Raises:
        see :func:`read_csv_export`.
    """
    p = Path(path)
    if not p.is_file():
        raise MissingInputError("no such CSV file", path=p)
    note_input(p)
    columns = source.columns
    pos_key = source.position_key
    keys = ("time", "force", pos_key)
    opt_units = {k: norm_unit(v) for k, v in source.units.items()}

    try:
        with p.open(newline="", encoding="utf-8-sig") as fh:
            rows = [r for r in csv.reader(fh) if any(cell.strip() for cell in r)]
    except UnicodeDecodeError as err:
        raise InputDataError(f"not UTF-8 text (byte {err.start})", path=p) from None
    except csv.Error as err:
        raise InputDataError(f"not a readable CSV file: {err}", path=p) from None
    if not rows:
        raise InputDataError("empty CSV file", path=p)
    header = [h.strip() for h in rows[0]]
    idx: dict[str, int] = {}
    for k in keys:
        name = columns[k]
        if name not in header:
            raise InputDataError(
                f"mapped column {k}={name!r} not in the file; columns: {', '.join(header)}",
                path=p,
            )
        idx[k] = header.index(name)
    body = rows[1:]
    file_units: dict[str, str] = {}
    if body and all(not _is_number(_cell(body[0], idx[k])) for k in keys):
        for k in keys:
            u = norm_unit(_cell(body[0], idx[k]))
            if not u:
                continue
            if u not in UNITS_BY_KEY[k]:
                raise InputDataError(
                    f"column {columns[k]!r}: unknown {k} unit {u!r} in the units row; "
                    f"supported: {', '.join(UNITS_BY_KEY[k])}",
                    path=p,
                )
            file_units[k] = u
        body = body[1:]
    for k, u in file_units.items():
        if k in opt_units and UNITS_BY_KEY[k][opt_units[k]] != UNITS_BY_KEY[k][u]:
            raise InputDataError(
                f"column {columns[k]!r}: the file says unit {u!r}, the option says "
                f"{opt_units[k]!r}",
                path=p,
            )
    arrays: dict[str, FloatArray] = {}
    used: dict[str, str] = {}
    for k in keys:
        u = (
            file_units.get(k)
            or opt_units.get(k)
            or ("s" if k == "time" else "n" if k == "force" else "m")
        )
        used[k] = u
        vals = np.empty(len(body))
        for i, row in enumerate(body):
            cell = _cell(row, idx[k]).strip()
            try:
                vals[i] = float(cell) if cell else math.nan
            except ValueError as err:
                raise InputDataError(
                    f"column {columns[k]!r}: non-numeric value {cell!r} in data row {i + 1}",
                    path=p,
                ) from err
        arrays[k] = vals * UNITS_BY_KEY[k][u]
    where = str(p)
    time_s = arrays["time"]
    for k in keys:
        _check_stream(f"column {columns[k]!r}", time_s, arrays[k], where)
    rate_hz = _rate_hz(time_s)
    _check_time_and_force(arrays, used, columns, where, file_units)
    kind = source.position_is if pos_key == "position" else pos_key
    compression_m = _compression(
        arrays[pos_key],
        arrays["force"],
        kind,
        where,
        segmentation.force_threshold_frac,
        source.compression_zero,
        source.position_increases_when,
        f"column {columns[pos_key]!r}",
    )
    peak_m = float(np.max(compression_m))
    factor = UNITS_BY_KEY[pos_key][used[pos_key]]
    unit = suggest_unit(
        peak_m / factor,
        LENGTH_UNITS_M,
        to_value=lambda m: m,
        ok=lambda m: m <= compression_limit_m(size_x_cm),
        target=compression_target_m(size_x_cm),
    )
    check_peak_compression(
        peak_m,
        size_x_cm=size_x_cm,
        what=f"column {columns[pos_key]!r}",
        path=where,
        hint=_unit_hint(pos_key, unit, f"column {columns[pos_key]!r}", file_units.get(pos_key)),
    )
    absolute = float(time_s[0]) >= ABSOLUTE_TIME_MIN_S
    squeezes, ruptures = _to_squeezes(
        time_s - time_s[0],
        arrays["force"],
        compression_m,
        object_id=object_id,
        segmentation=segmentation,
        segment=segmentation.segments(False),
        path=where,
        window_s=_detection_window_s(rate_hz),
        clock_origin_ns=round(float(time_s[0]) * NS_PER_S) if absolute else None,
    )
    return Recording(
        squeezes,
        rate_hz,
        rate_hz,
        source=source.kind,
        phase=segmentation.phase,
        ruptures=tuple(ruptures),
    )


def _check_time_and_force(
    arrays: Mapping[str, FloatArray],
    used: Mapping[str, str],
    columns: Mapping[str, str],
    where: str,
    stated: Mapping[str, str],
) -> None:
    """Refuse a CSV whose sample rate or peak force a unit mistake explains (names the unit).

    ``stated``: the units the file's units row gives (the hint then questions the file).
    """
    time_s, force_n = arrays["time"], arrays["force"]
    dt_s = float(np.median(np.diff(time_s)))
    rate_hz = 1.0 / dt_s
    if not rate_ok(rate_hz):
        unit = suggest_unit(
            dt_s / TIME_UNITS_S[used["time"]],
            TIME_UNITS_S,
            to_value=lambda dt: 1.0 / dt,
            ok=rate_ok,
            target=1000.0,
        )
        what = f"column {columns['time']!r}"
        hint = _unit_hint("time", unit, what, stated.get("time"))
        check_sample_rate(rate_hz, what=what, path=where, hint=hint)
    peak_n = float(np.max(np.abs(force_n)))
    factor = FORCE_UNITS_N[used["force"]]
    unit = suggest_unit(
        peak_n / factor,
        FORCE_UNITS_N,
        to_value=lambda f: f,
        ok=lambda f: f <= MAX_PEAK_FORCE_N,
        target=10.0,
    )
    what = f"column {columns['force']!r}"
    hint = _unit_hint("force", unit, what, stated.get("force"))
    check_peak_force(peak_n, what=what, path=where, hint=hint)


def _cell(row: Sequence[str], i: int) -> str:
    return row[i] if i < len(row) else ""


def squeeze_from_csv(path: str | PathLike[str], **options: Any) -> list[SqueezeSeries]:
    """The squeezes of :func:`read_csv_export` (same keyword arguments and errors), no rates."""
    return read_csv_export(path, **options).squeezes
