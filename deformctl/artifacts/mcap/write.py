"""Writing squeeze and lift logs, atomically: records, channels, and the log's time line.

See :mod:`deformctl.artifacts.mcap` for the layout and the time line (:data:`LOG_EPOCH_NS`,
:data:`GAP_S`).
"""

from __future__ import annotations

import io
import json
import math
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np
from mcap.writer import CompressionType, Writer

from deformctl.artifacts.io import PathArg, atomic_output, display_name
from deformctl.artifacts.mcap.contents import (
    _LIFT_FIELDS,
    FORMAT_VERSION,
    GAP_S,
    KIND_LIFT,
    KIND_SQUEEZE,
    LIFT_RESULT,
    LIFT_SAMPLE,
    LOG_EPOCH_NS,
    SCENE_TOPIC,
    _check_time,
    lift_topic,
    squeeze_topic,
    topic_schema,
)
from deformctl.artifacts.mcap.scene import SCENE_SCHEMA_NAME, foxglove_schema_bytes, scene_messages
from deformctl.artifacts.provenance import Provenance, _json_default
from deformctl.artifacts.schema import json_schema_bytes, load_json_schema
from deformctl.errors import InputDataError
from deformctl.scene import SceneFrames
from deformctl.series import LiftAttempt, SqueezeSeries
from deformctl.units import NS_PER_S, s_to_ns
from deformctl.version import version_string


class _LogWriter:
    """A thin layer over :class:`mcap.writer.Writer` with deformctl's records and time line."""

    def __init__(
        self, fh: io.BufferedWriter, kind: str, provenance: Provenance | None, epoch_ns: int
    ) -> None:
        self._w = Writer(
            fh,
            compression=CompressionType.ZSTD,
            enable_crcs=True,
            enable_data_crcs=True,
        )
        self._w.start(profile="", library=f"deformctl {version_string()}")
        self._w.add_metadata("deformctl", {"kind": kind, "format_version": FORMAT_VERSION})
        if provenance is not None:
            self._w.add_metadata("provenance", provenance.to_mcap_metadata())
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, int] = {}
        self._sequence: dict[str, int] = {}
        self._epoch_ns = epoch_ns
        self._next_ns: int | None = None  # where the next item laid end to end starts
        self._floor_ns: int | None = None  # no message may be logged before this

    def start_ns(self, source_ns: int | None) -> int:
        """Where the next squeeze / attempt begins: at its source clock when it has one (never
        before the previous message), else end to end after the previous one (the epoch)."""
        if source_ns is not None:
            return source_ns if self._floor_ns is None else max(source_ns, self._floor_ns)
        return self._epoch_ns if self._next_ns is None else self._next_ns

    def ended(self, last_ns: int) -> None:
        """The squeeze / attempt just written ended at ``last_ns``."""
        self._floor_ns = last_ns
        self._next_ns = last_ns + s_to_ns(GAP_S)

    def add_objects(self, objects: Iterable[Mapping[str, Any]], path: str) -> None:
        for obj in objects:
            oid = obj.get("object_id")
            if not isinstance(oid, str) or not oid:
                raise InputDataError("object without a string object_id", path=path)
            data = {str(k): json.dumps(v, default=_json_default) for k, v in obj.items()}
            self._w.add_metadata("object", data)

    def channel(self, topic: str) -> int:
        if topic == SCENE_TOPIC and topic not in self._channels:
            sid = self._w.register_schema(
                name=SCENE_SCHEMA_NAME, encoding="jsonschema", data=foxglove_schema_bytes()
            )
            self._channels[topic] = self._w.register_channel(
                topic=topic, message_encoding="json", schema_id=sid
            )
            self._sequence[topic] = 0
        if topic not in self._channels:
            found = topic_schema(topic)
            assert found is not None, topic
            name = found[0]
            if name not in self._schemas:
                self._schemas[name] = self._w.register_schema(
                    name=load_json_schema(name)["title"],
                    encoding="jsonschema",
                    data=json_schema_bytes(name),
                )
            sid = self._schemas[name]
            self._channels[topic] = self._w.register_channel(
                topic=topic, message_encoding="json", schema_id=sid
            )
            self._sequence[topic] = 0
        return self._channels[topic]

    def add(self, topic: str, log_time_ns: int, message: Mapping[str, Any]) -> None:
        self.add_encoded(
            topic, log_time_ns, json.dumps(message, separators=(",", ":"), allow_nan=False).encode()
        )

    def add_samples(
        self,
        topic: str,
        times_ns: Sequence[int],
        base: Mapping[str, Any],
        columns: Mapping[str, list[float]],
        scene: Sequence[tuple[int, str, bytes]] = (),
    ) -> None:
        """One message per sample: ``base`` plus sample i of every column (finite floats), and
        the ``scene`` messages ``(log time, topic, bytes)`` merged in log-time order (at equal
        times the sample first).

        The JSON text is built from a template instead of ``json.dumps`` per sample: the bytes are
        the same (a finite float's ``repr`` is its JSON form) and a long series encodes several
        times faster.
        """
        head = json.dumps(dict(base), separators=(",", ":"), allow_nan=False)[:-1]
        fields = ",".join(f"{json.dumps(k)}:%r" for k in columns)
        template = f"{head},{fields}}}" if base else f"{{{fields}}}"
        rows = zip(times_ns, zip(*columns.values(), strict=True), strict=True)
        # the merge by hand, one bound call per sample: a scene message goes before the first
        # sample of a later time (at equal times the sample first)
        add, cid = self._w.add_message, self.channel(topic)
        seq = self._sequence[topic]
        pending = iter(scene)
        nxt = next(pending, None)
        for t, row in rows:
            if nxt is not None and nxt[0] < t:
                self._sequence[topic] = seq
                while nxt is not None and nxt[0] < t:
                    self.add_encoded(nxt[1], nxt[0], nxt[2])
                    nxt = next(pending, None)
                seq = self._sequence[topic]
            data = (template % row).encode()
            add(channel_id=cid, log_time=t, data=data, publish_time=t, sequence=seq)
            seq += 1
        self._sequence[topic] = seq
        while nxt is not None:
            self.add_encoded(nxt[1], nxt[0], nxt[2])
            nxt = next(pending, None)

    def add_encoded(self, topic: str, log_time_ns: int, data: bytes) -> None:
        cid = self.channel(topic)
        self._w.add_message(
            channel_id=cid,
            log_time=log_time_ns,
            data=data,
            publish_time=log_time_ns,
            sequence=self._sequence[topic],
        )
        self._sequence[topic] += 1

    def finish(self) -> None:
        self._w.finish()


def _time_line_ns(t: np.ndarray, offset_ns: int) -> list[int]:
    """Log times: ``offset_ns`` plus the time since the first sample, ns."""
    if t.size == 0:
        return []
    return [offset_ns + int(v) for v in np.rint((t - t[0]) * NS_PER_S).astype(np.int64)]


def _scene(
    scene: SceneFrames | None, object_id: str, run: str, index: int, start_ns: int, t: np.ndarray
) -> list[tuple[int, str, bytes]]:
    """The ``/scene`` and ``/palms`` messages of a squeeze or attempt whose samples ``t`` start
    at ``start_ns`` (none without a scene or samples)."""
    if scene is None or t.size == 0 or len(scene) == 0:
        return []
    return scene_messages(
        scene, object_id=object_id, run=run, index=int(index), start_ns=start_ns, t0_s=float(t[0])
    )


def _finite(label: str, key: str, arr: np.ndarray, path: str) -> list[float]:
    if not np.all(np.isfinite(arr)):
        raise InputDataError(f"{label}: {key} has non-finite values", path=path)
    values: list[float] = arr.tolist()
    return values


def _check_ids(oid: object, idx: object, label: str, path: str) -> None:
    if not isinstance(oid, str) or not oid:
        raise InputDataError(f"{label}: object_id must be a non-empty string", path=path)
    if not isinstance(idx, int | np.integer) or int(idx) < 0:
        raise InputDataError(f"{label}: index must be a non-negative integer", path=path)


def write_squeeze_log(
    path: PathArg,
    objects: Sequence[Mapping[str, Any]],
    squeezes: Sequence[SqueezeSeries],
    *,
    provenance: Provenance | None,
    force: bool = False,
    epoch_ns: int = LOG_EPOCH_NS,
) -> None:
    """Write a squeeze log atomically (see the module docstring for the layout).

    Args:
        path: destination ``.mcap`` file, or ``-`` for stdout.
        objects: catalog rows (e.g. ``catalog.to_dict("records")``), one ``object`` metadata
            record each; values must be JSON-serialisable (numpy scalars are fine).
        squeezes: the squeezes, written in this order, one ``/squeeze`` message per sample.
        provenance: stored as the ``provenance`` metadata record.
        force: overwrite an existing file.
        epoch_ns: where squeezes without a source clock begin, ns since the Unix epoch.

    Raises:
        InputDataError: a non-finite sample value or time going backwards (nothing is written).
        OutputExistsError: ``path`` exists and ``force`` is false.
    """
    name = display_name(path)
    with atomic_output(path, force=force) as tmp, tmp.open("wb") as fh:
        log = _LogWriter(fh, KIND_SQUEEZE, provenance, epoch_ns)
        log.add_objects(objects, name)
        for sq in squeezes:
            label = f"object {sq.object_id!r} squeeze {sq.squeeze_index}"
            _check_ids(sq.object_id, sq.squeeze_index, label, name)
            _check_time(sq.time_s, label, name)
            columns: dict[str, list[float]] = {
                "time_s": _finite(label, "time_s", sq.time_s, name),
                "force_n": _finite(label, "force_n", sq.force_n, name),
                "compression_m": _finite(label, "compression_m", sq.compression_m, name),
            }
            for key in ("commanded_force_n", "palm_left_x_m", "palm_right_x_m"):
                arr = getattr(sq, key)
                if arr is not None:
                    columns[key] = _finite(label, key, arr, name)
            start = log.start_ns(sq.start_time_ns)
            times = _time_line_ns(sq.time_s, start)
            base = {"object_id": sq.object_id, "squeeze_index": int(sq.squeeze_index)}
            scene = _scene(sq.scene, sq.object_id, "squeeze", sq.squeeze_index, start, sq.time_s)
            log.add_samples(squeeze_topic(sq.object_id), times, base, columns, scene)
            if times:
                log.ended(times[-1])
        log.finish()


def write_lift_log(
    path: PathArg,
    objects: Sequence[Mapping[str, Any]],
    attempts: Sequence[LiftAttempt],
    *,
    provenance: Provenance | None,
    force: bool = False,
    epoch_ns: int = LOG_EPOCH_NS,
) -> None:
    """Write a lift log atomically: each attempt's samples, then its result message.

    Args:
        path: destination ``.mcap`` file, or ``-`` for stdout.
        objects: catalog rows, one ``object`` metadata record each.
        attempts: the attempts in search order; ``outcome.series`` may be None (a rig that
            records no time series), ``outcome.slip_m`` may be NaN (stored as null).
        provenance: stored as the ``provenance`` metadata record.
        force: overwrite an existing file.
        epoch_ns: where attempts without a wall clock begin, ns since the Unix epoch.

    Raises:
        InputDataError: non-finite samples, or details that are not JSON (nothing is written).
        OutputExistsError: ``path`` exists and ``force`` is false.
    """
    name = display_name(path)
    with atomic_output(path, force=force) as tmp, tmp.open("wb") as fh:
        log = _LogWriter(fh, KIND_LIFT, provenance, epoch_ns)
        log.add_objects(objects, name)
        for att in attempts:
            label = f"object {att.object_id!r} attempt {att.attempt_index}"
            _check_ids(att.object_id, att.attempt_index, label, name)
            out = att.outcome
            grip = float(out.grip_force_n)
            if not math.isfinite(grip) or grip < 0:
                raise InputDataError(f"{label}: grip_force_n must be finite and >= 0", path=name)
            base = {
                "object_id": att.object_id,
                "attempt_index": int(att.attempt_index),
                "grip_force_n": grip,
            }
            end_ns = log.start_ns(out.start_time_ns)
            if out.series is not None:
                s = out.series
                _check_time(s.time_s, label, name)
                columns = {"time_s": _finite(label, "time_s", s.time_s, name)}
                for key in _LIFT_FIELDS:
                    columns[key] = _finite(label, key, getattr(s, key), name)
                times = _time_line_ns(s.time_s, end_ns)
                scene = _scene(
                    out.scene, att.object_id, "lift", att.attempt_index, end_ns, s.time_s
                )
                log.add_samples(lift_topic(att.object_id, LIFT_SAMPLE), times, base, columns, scene)
                if times:
                    end_ns = times[-1]
            slip = float(out.slip_m)
            try:
                details = json.loads(
                    json.dumps(out.details, default=_json_default, allow_nan=False)
                )
            except (TypeError, ValueError) as err:
                raise InputDataError(f"{label}: details are not JSON ({err})", path=name) from None
            result = dict(base)
            result.update(
                {
                    "lifted": bool(out.lifted),
                    "slip_m": slip if math.isfinite(slip) else None,
                    "details": details,
                }
            )
            log.add(lift_topic(att.object_id, LIFT_RESULT), end_ns, result)
            log.ended(end_ns)
        log.finish()
