"""Reading squeeze and lift logs: the reference path (every message decoded and validated).

:func:`read_squeeze_log` first tries the bulk reader (:mod:`deformctl.artifacts.mcap.bulk`), which
returns the same result or gives up, and otherwise rebuilds the squeezes here
(:func:`squeezes_from_contents`); :func:`read_lift_log` rebuilds the attempts.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import numpy as np

from deformctl.artifacts.io import PathArg, read_input_bytes
from deformctl.artifacts.mcap.bulk import _bulk_squeeze_log
from deformctl.artifacts.mcap.contents import (
    _LIFT_FIELDS,
    _SQUEEZE_OPTIONAL,
    KIND_LIFT,
    KIND_SQUEEZE,
    LIFT_RESULT,
    LIFT_RESULT_TOPIC,
    LIFT_SAMPLE,
    SQUEEZE_SAMPLE,
    McapContents,
    _check_kind,
    _check_time,
    _decoded_messages,
    decode_objects,
    load_mcap,
)
from deformctl.errors import SchemaError
from deformctl.series import LiftAttempt, LiftAttemptSeries, SqueezeSeries, TrialOutcome


def _group(
    messages: Iterable[dict[str, Any]], index_key: str
) -> dict[tuple[str, int], list[dict[str, Any]]]:
    groups: dict[tuple[str, int], list[dict[str, Any]]] = {}
    for m in messages:
        groups.setdefault((m["object_id"], m[index_key]), []).append(m)
    return groups


def _column(samples: list[dict[str, Any]], key: str) -> np.ndarray:
    return np.fromiter((s[key] for s in samples), dtype=np.float64, count=len(samples))


def squeezes_from_contents(contents: McapContents) -> list[SqueezeSeries]:
    """Rebuild the squeezes of a verified squeeze log (see :func:`read_squeeze_log`)."""
    _check_kind(contents, KIND_SQUEEZE)
    messages = _decoded_messages(contents, SQUEEZE_SAMPLE)
    out: list[SqueezeSeries] = []
    for (oid, idx), samples in _group(messages, "squeeze_index").items():
        label = f"object {oid!r} squeeze {idx}"
        optional: dict[str, np.ndarray | None] = {}
        for key in _SQUEEZE_OPTIONAL:
            present = sum(key in s for s in samples)
            if present not in (0, len(samples)):
                raise SchemaError(
                    f"{label}: present in {present} of {len(samples)} samples",
                    path=contents.path,
                    field=key,
                )
            optional[key] = _column(samples, key) if present else None
        t = _column(samples, "time_s")
        _check_time(t, label, contents.path)
        out.append(
            SqueezeSeries(
                object_id=oid,
                squeeze_index=idx,
                time_s=t,
                force_n=_column(samples, "force_n"),
                compression_m=_column(samples, "compression_m"),
                commanded_force_n=optional["commanded_force_n"],
                palm_left_x_m=optional["palm_left_x_m"],
                palm_right_x_m=optional["palm_right_x_m"],
            )
        )
    return out


def read_squeeze_log(path: PathArg) -> tuple[list[dict[str, Any]], list[SqueezeSeries]]:
    """Read a squeeze log.

    Args:
        path: the ``.mcap`` file, or ``-`` for stdin (read into memory).

    Returns:
        ``(objects, squeezes)``: the catalog rows stored in the log (values as written) and the
        squeezes in the order their first sample appears. ``force_left_n`` / ``force_right_n``
        are validated but not part of :class:`SqueezeSeries`, so they are not returned.

    Raises:
        MissingInputError: ``path`` does not exist (exit 66).
        InputDataError: not MCAP, truncated or damaged (exit 65).
        SchemaError: not a squeeze log, or a message that does not match its schema (exit 65).
    """
    data = read_input_bytes(path)
    bulk = _bulk_squeeze_log(data, path)
    if bulk is not None:
        return bulk
    contents = load_mcap(data, path)
    squeezes = squeezes_from_contents(contents)
    return decode_objects(contents), squeezes


def lift_attempts_from_contents(contents: McapContents) -> list[LiftAttempt]:
    """Rebuild the attempts of a verified lift log (see :func:`read_lift_log`)."""
    _check_kind(contents, KIND_LIFT)
    samples_by_key = _group(_decoded_messages(contents, LIFT_SAMPLE), "attempt_index")
    results = _decoded_messages(contents, LIFT_RESULT)
    out: list[LiftAttempt] = []
    seen: set[tuple[str, int]] = set()
    for res in results:
        key = (res["object_id"], res["attempt_index"])
        label = f"object {key[0]!r} attempt {key[1]}"
        if key in seen:
            raise SchemaError(f"{label}: two results", path=contents.path, field=LIFT_RESULT_TOPIC)
        seen.add(key)
        series = None
        samples = samples_by_key.get(key)
        if samples:
            if any(s["grip_force_n"] != res["grip_force_n"] for s in samples):
                raise SchemaError(
                    f"{label}: samples and result disagree on the grip force",
                    path=contents.path,
                    field="grip_force_n",
                )
            t = _column(samples, "time_s")
            _check_time(t, label, contents.path)
            series = LiftAttemptSeries(t, *(_column(samples, k) for k in _LIFT_FIELDS))
        slip = res["slip_m"]
        outcome = TrialOutcome(
            grip_force_n=float(res["grip_force_n"]),
            lifted=bool(res["lifted"]),
            slip_m=math.nan if slip is None else float(slip),
            series=series,
            details=dict(res["details"]),
        )
        out.append(LiftAttempt(object_id=key[0], attempt_index=key[1], outcome=outcome))
    orphans = set(samples_by_key) - seen
    if orphans:
        oid, idx = sorted(orphans)[0]
        raise SchemaError(
            f"object {oid!r} attempt {idx}: samples without a result",
            path=contents.path,
            field=LIFT_RESULT_TOPIC,
        )
    return out


def read_lift_log(path: PathArg) -> tuple[list[dict[str, Any]], list[LiftAttempt]]:
    """Read a lift log.

    Args:
        path: the ``.mcap`` file, or ``-`` for stdin (read into memory).

    Returns:
        ``(objects, attempts)``: the catalog rows stored in the log and the attempts in the order
        of their result messages; ``slip_m`` is NaN where the runner could not tell.

    Raises:
        MissingInputError: ``path`` does not exist (exit 66).
        InputDataError: not MCAP, truncated or damaged (exit 65).
        SchemaError: not a lift log, or a message that does not match its schema (exit 65).
    """
    contents = load_mcap(read_input_bytes(path), path)
    attempts = lift_attempts_from_contents(contents)
    return decode_objects(contents), attempts
