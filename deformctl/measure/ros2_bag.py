"""The ROS 2 bag source of ``measure``: one object's squeezes from an MCAP bag (``measure bag``;
the library's door is :func:`deformctl.measure.stage.read_recording` with a :class:`BagSource`).

**Force.** ``geometry_msgs/msg/WrenchStamped`` ``wrench.force.<axis>``: the force felt is its
magnitude; with two wrench topics (one per palm) it is the mean of the two palms' magnitudes, the
second palm interpolated onto the first palm's timestamps.

**Position.** A ``geometry_msgs/msg/PoseStamped`` palm pose or one joint of a
``sensor_msgs/msg/JointState`` (:mod:`deformctl.measure.recording` says how it becomes the
compression).

**Alignment.** Streams are aligned by their header stamps; position is linearly interpolated
onto the force timestamps inside the overlap of the two streams. Samples outside the overlap are
dropped.

**Checks.** Every channel's encoding, message definition and every decoded message are checked
against the fields the reader needs; a recording whose sample rate, peak force, peak compression,
force axis or compression sign a unit, axis or sign mistake explains is refused with the likely
fix (:mod:`deformctl.plausibility`); one that a unit slip may explain but that can be right (a
peak force below 50 mN or above 3 kN, a peak compression below 20 µm, a secant stiffness above
5000 N/cm) is flagged with a warning line naming the unit (``recording_flags``).
"""

from __future__ import annotations

import contextlib
import io
import math
import struct
from collections.abc import Iterator, Mapping, Sequence
from os import PathLike
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
import zstandard

from deformctl.artifacts.io import note_input
from deformctl.artifacts.mcap.integrity import complete_prefix, locate_damage, tail_problem
from deformctl.errors import InputDataError, UsageError
from deformctl.measure.defects import Defect
from deformctl.measure.options import Axis, BagSource, Segmentation
from deformctl.measure.recording import (
    Recording,
    _check_stream,
    _compression,
    _rate_hz,
)
from deformctl.measure.rosbag2 import bag_parts, check_counts
from deformctl.measure.segment import (
    _detection_window_s,
    _to_squeezes,
)
from deformctl.plausibility import (
    Reading,
    check_force_axis,
    check_peak_compression,
    check_peak_force,
    check_sample_rate,
    unit_doubts,
)
from deformctl.series import FloatArray, SqueezeSeries
from deformctl.squeeze.flags import ENERGY_RETURNED
from deformctl.units import NS_PER_S

WRENCH_TYPE = "geometry_msgs/msg/WrenchStamped"
POSE_TYPE = "geometry_msgs/msg/PoseStamped"
JOINT_STATE_TYPE = "sensor_msgs/msg/JointState"


#: The fields each message type must have for the reader (dotted paths).
_REQUIRED_FIELDS: dict[str, tuple[str, ...]] = {
    WRENCH_TYPE: ("header.stamp.sec", "header.stamp.nanosec", "wrench.force"),
    POSE_TYPE: ("header.stamp.sec", "header.stamp.nanosec", "pose.position"),
    JOINT_STATE_TYPE: ("header.stamp.sec", "header.stamp.nanosec", "name", "position"),
}

#: The first two bytes of a ROS 2 CDR payload (the encapsulation kind): plain CDR, big or little
#: endian.
_CDR_KINDS = (b"\x00\x00", b"\x00\x01")

_MISSING = object()


def _field(msg: Any, dotted: str, where: str, path: Path) -> Any:
    """``msg.<dotted>``, or a one-line error naming the field the message definition lacks."""
    value = msg
    for part in dotted.split("."):
        value = getattr(value, part, _MISSING)
        if value is _MISSING:
            raise InputDataError(
                f"{where}: the message has no field {dotted!r} (its message definition does not "
                "match its type name)",
                path=path,
            )
    return value


def _number(value: Any, dotted: str, where: str, path: Path) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InputDataError(
            f"{where}: field {dotted!r} is a {type(value).__name__}, not a number", path=path
        )
    return float(value)


def _stamp_ns(msg: Any, where: str, path: Path) -> int:
    sec = _field(msg, "header.stamp.sec", where, path)
    nanosec = _field(msg, "header.stamp.nanosec", where, path)
    if not all(isinstance(v, int) and not isinstance(v, bool) for v in (sec, nanosec)):
        raise InputDataError(f"{where}: header.stamp is not (sec, nanosec) integers", path=path)
    return int(sec) * NS_PER_S + int(nanosec)


def _decoder(factory: Any, schema: Any, channel: Any, where: str, path: Path) -> Any:
    """The CDR decoder of ``channel``'s message definition, or a one-line error (exit 65)."""
    if channel.message_encoding != "cdr" or schema is None or schema.encoding != "ros2msg":
        got = f"{channel.message_encoding}/{getattr(schema, 'encoding', None)}"
        raise InputDataError(f"{where}: encoding {got}, expected cdr/ros2msg", path=path)
    try:  # the msgdef parser also prints its complaint to stderr: keep that to the one line
        with contextlib.redirect_stderr(io.StringIO()):
            return factory.decoder_for(channel.message_encoding, schema)
    except Exception as err:  # the msgdef parser raises many kinds of error on bad text
        raise InputDataError(
            f"{where}: unparseable message definition ({type(err).__name__}: "
            f"{' '.join(str(err).split())[:200]})",
            path=path,
        ) from None


def _decode(decode: Any, data: bytes, index: int, where: str, path: Path) -> Any:
    """One CDR payload decoded, or a one-line error naming the message (exit 65)."""
    if len(data) < 4 or bytes(data[:2]) not in _CDR_KINDS:
        raise InputDataError(
            f"{where}: message {index} has no CDR encapsulation header "
            f"(first bytes {bytes(data[:4]).hex() or 'none'})",
            path=path,
        )
    try:
        return decode(data)
    except Exception as err:  # a truncated payload raises struct, index, unicode... errors
        raise InputDataError(
            f"{where}: message {index} does not decode with its message definition "
            f"({type(err).__name__}: {' '.join(str(err).split())[:200]})",
            path=path,
        ) from None


def _read_topics(
    path: Path,
    roles: Mapping[str, tuple[str, ...]],
    joint: str | None,
    axis: Axis,
    *,
    crc_check: bool = True,
    notes: list[str] | None = None,
) -> dict[str, tuple[list[int], list[Any]]]:
    """Read ``(stamp_ns list, value list)`` per topic: the force vector, position.axis or joint.

    Each channel's encoding, message definition and every decoded message are checked against
    the fields the reader needs (:data:`_REQUIRED_FIELDS`) before use; a mismatch names the
    topic, the type and the field (exit 65).

    Integrity (:mod:`deformctl.artifacts.mcap.integrity`): the footer and the summary CRC are
    checked first, every chunk read is checked against its CRC by the mcap reader; a damaged or
    cut file is refused naming the byte offset of the damage. ``crc_check=False``
    (``--no-crc-check``) reads chunks whatever their CRC and reads a cut file up to its last
    complete record, with a line in ``notes``.

    Args:
        path: the bag.
        roles: topic → the message types accepted on it.
        joint: JointState joint name.
        axis: squeeze axis.
        crc_check: check CRCs (see above).
        notes: receives a warning line for a cut file read without CRC checks.
    """
    from mcap.exceptions import McapError

    topics = list(roles)
    out: dict[str, tuple[list[int], list[Any]]] = {t: ([], []) for t in topics}
    size = path.stat().st_size
    with path.open("rb") as fh:
        bag = _open_bag(fh, size, path, crc_check, notes)
        types: dict[str, str] = {}
        for ch in bag.channels.values():
            schema = bag.schemas.get(ch.schema_id)
            types[ch.topic] = schema.name if schema is not None else ""
        available = ", ".join(sorted(types)) or "none"
        for topic in topics:
            if topic not in types:
                raise InputDataError(
                    f"topic {topic!r} is not in the bag; topics: {available}", path=path
                )
        for topic in topics:
            want = types[topic]
            if want not in roles[topic]:
                raise InputDataError(
                    f"topic {topic!r} has type {want or 'unknown'}, expected "
                    f"{' or '.join(roles[topic])}",
                    path=path,
                )
            if want == JOINT_STATE_TYPE and joint is None:
                raise UsageError(f"topic {topic!r} is {JOINT_STATE_TYPE}: pass a joint name")
        from mcap_ros2.decoder import DecoderFactory

        factory = DecoderFactory()
        decoders: dict[int, Any] = {}
        counts = dict.fromkeys(topics, 0)
        try:
            for schema, channel, message in bag.messages(topics):
                where = f"topic {channel.topic!r} ({types[channel.topic]})"
                if channel.id not in decoders:
                    decoders[channel.id] = _decoder(factory, schema, channel, where, path)
                index = counts[channel.topic]
                counts[channel.topic] += 1
                msg = _decode(decoders[channel.id], message.data, index, where, path)
                stamps, values = out[channel.topic]
                stamps.append(_stamp_ns(msg, where, path))
                values.append(_extract(msg, types[channel.topic], axis, joint, where, path))
        except (  # a flipped length field (read without CRC checks) asks for 2**63 bytes
            McapError, ValueError, EOFError, OSError, OverflowError, MemoryError,
            zstandard.ZstdError, struct.error,
        ) as err:  # fmt: skip
            raise _damage_error(fh, size, path, crc_check, err) from None
    return out


class _Bag:
    """The channels, schemas and messages of a bag, from its summary or (cut file) its records."""

    def __init__(self, channels: dict[int, Any], schemas: dict[int, Any], reader: Any) -> None:
        self.channels = channels
        self.schemas = schemas
        self._reader = reader  # an mcap reader, or the list of (schema, channel, message)

    def messages(self, topics: Sequence[str]) -> Iterator[tuple[Any, Any, Any]]:
        """(schema, channel, message) of ``topics``, in log-time order."""
        if isinstance(self._reader, list):
            wanted = set(topics)
            chosen = [m for m in self._reader if m[1].topic in wanted]
            yield from sorted(chosen, key=lambda m: m[2].log_time)  # stable, as the reader's
            return
        yield from self._reader.iter_messages(topics=topics)


def _open_bag(
    fh: BinaryIO, size: int, path: Path, crc_check: bool, notes: list[str] | None
) -> _Bag:
    """The bag's index; a damaged footer or summary refused naming the offset (module doc)."""
    from mcap.exceptions import McapError
    from mcap.reader import make_reader

    try:
        problem = tail_problem(fh, size, check_crcs=crc_check)
    except (struct.error, OSError) as err:
        problem = f"unreadable end of file ({err})"
    if problem is not None:
        detail = locate_damage(fh, size, check_crcs=crc_check) or problem
        if crc_check or not detail.startswith("the file ends at byte"):
            raise InputDataError(_damage_text(detail, crc_check), path=path)
        return _cut_bag(fh, size, path, detail, notes)
    fh.seek(0)
    try:
        reader = make_reader(fh, validate_crcs=crc_check)
        summary = reader.get_summary()
    except (
        McapError,
        ValueError,
        OSError,
        struct.error,
        EOFError,
        OverflowError,
        MemoryError,
    ) as err:
        raise _damage_error(fh, size, path, crc_check, err) from None
    if summary is None:
        raise InputDataError("MCAP file has no summary (unindexed bag)", path=path)
    return _Bag(dict(summary.channels), dict(summary.schemas), reader)


def _cut_bag(fh: BinaryIO, size: int, path: Path, detail: str, notes: list[str] | None) -> _Bag:
    """``--no-crc-check`` on a cut bag: every record before the cut, read in file order."""
    from mcap.records import Channel, Message, Schema
    from mcap.stream_reader import StreamReader

    prefix = complete_prefix(fh, size)
    fh.seek(0)
    data = fh.read(prefix)
    channels: dict[int, Any] = {}
    schemas: dict[int, Any] = {}
    found: list[tuple[Any, Any, Any]] = []
    try:
        for record in StreamReader(io.BytesIO(data), validate_crcs=False).records:
            if isinstance(record, Schema):
                schemas[record.id] = record
            elif isinstance(record, Channel):
                channels[record.id] = record
            elif isinstance(record, Message) and record.channel_id in channels:
                channel = channels[record.channel_id]
                found.append((schemas.get(channel.schema_id), channel, record))
    except Exception as err:  # the end of the complete records, or a corrupt chunk in them
        from mcap.exceptions import EndOfFile

        if not isinstance(err, EndOfFile):
            more = locate_damage(io.BytesIO(data), len(data), check_crcs=False)
            raise InputDataError(_damage_text(more or _short(err), False), path=path) from None
    if not found:
        raise InputDataError(
            _damage_text(detail, False) + ": no complete chunk of messages before it", path=path
        )
    if notes is not None:
        notes.append(
            f"{path}: truncated bag read without CRC checks (--no-crc-check): {detail}; "
            f"read the {len(found)} messages before byte {prefix}"
        )
    return _Bag(channels, schemas, found)


def _damage_text(detail: str, crc_check: bool) -> str:
    """The one line of a damaged bag: what and where, and the way out when there is one."""
    if detail.startswith("not an MCAP file"):
        return "not a readable MCAP file (bad magic bytes)"
    cut = detail.startswith("the file ends at byte")
    what = "truncated MCAP file" if cut else "damaged MCAP file"
    hint = ""
    if crc_check and (cut or "CRC mismatch" in detail):
        hint = " (--no-crc-check reads it anyway, at your risk)"
    return f"{what}: {detail}{hint}"


def _damage_error(
    fh: BinaryIO, size: int, path: Path, crc_check: bool, err: BaseException
) -> InputDataError:
    """A read that failed: the damage located when the walk finds it, else the reader's words."""
    try:
        detail = locate_damage(fh, size, check_crcs=crc_check)
    except (OSError, struct.error):
        detail = None
    if detail is not None:
        return InputDataError(_damage_text(detail, crc_check), path=path)
    return InputDataError(f"not a readable MCAP file ({_short(err)})", path=path)


def _short(err: BaseException) -> str:
    text = " ".join(str(err).split()) or type(err).__name__
    return text if len(text) <= 160 else text[:157] + "..."


def _extract(
    msg: Any, type_name: str, axis: Axis, joint: str | None, where: str, path: Path
) -> Any:
    for dotted in _REQUIRED_FIELDS[type_name]:
        _field(msg, dotted, where, path)
    if type_name == WRENCH_TYPE:
        force = msg.wrench.force
        return tuple(
            _number(_field(force, a, where, path), f"wrench.force.{a}", where, path) for a in "xyz"
        )
    if type_name == POSE_TYPE:
        position = msg.pose.position
        return _number(_field(position, axis, where, path), f"pose.position.{axis}", where, path)
    try:
        names = [str(n) for n in msg.name]
        positions = list(msg.position)
    except TypeError:
        raise InputDataError(f"{where}: name and position must be arrays", path=path) from None
    if joint not in names:
        raise InputDataError(
            f"{where}: joint {joint!r} not in the JointState names {names}", path=path
        )
    i = names.index(joint)
    if i >= len(positions):
        raise InputDataError(
            f"{where}: joint {joint!r} has no position ({len(positions)} positions for "
            f"{len(names)} names)",
            path=path,
        )
    return _number(positions[i], "position", where, path)


def read_bag(
    path: str | PathLike[str],
    source: BagSource,
    object_id: str,
    segmentation: Segmentation,
    size_x_cm: float | None,
) -> Recording:
    """The ROS 2 bag source of :func:`deformctl.measure.stage.read_recording` (its door).

    The recording is checked for plausibility (:mod:`deformctl.plausibility`: sample rates, peak
    force, the force's axis, the compression's sign and size); every squeeze is cut at a rupture
    (recorded in the result) and reduced to the segmentation's phase
    (:mod:`deformctl.squeeze.rupture`).

    Args:
        path: the bag: one ``.mcap`` file, or a rosbag2 folder (``metadata.yaml`` and its
            ``.mcap`` files, read in order: :mod:`deformctl.measure.rosbag2`).
        source: the topics, axis and position signal
            (:class:`~deformctl.measure.options.BagSource`); with ``crc_check`` False
            (``--no-crc-check``) a damaged bag is read anyway, and a cut one up to its last
            complete record (``notes`` say so).
        object_id: catalog id written into every squeeze.
        segmentation: how the recording is cut (a bag is split into squeezes unless
            ``segmentation.segment`` is False).
        size_x_cm: the object's size along the squeeze axis, when known (a compression larger
            than it is refused).

    Returns:
        The squeezes (time in s from each squeeze's first sample, on the (first) wrench
        topic's timestamps inside the overlap with the position stream), the median sample
        rates of the first wrench topic and of the position topic, and the ruptures.

    Raises:
        MissingInputError: the bag does not exist, or a file its ``metadata.yaml`` lists.
        InputDataError: not an MCAP file, a SQLite (``.db3``) bag (with a converter to use), a
            folder without a readable rosbag2 ``metadata.yaml`` or whose files hold other
            message counts than it states, a topic not in the bag (the message lists those that
            are), a topic of the wrong type, a joint not in the JointState, NaN samples,
            non-monotonic header stamps, streams that do not overlap, no compression, no squeeze,
            or an implausible recording (the message names the likely cause).
        UsageError: a JointState topic without ``joint`` (the other options are checked when
            the :class:`BagSource` is built).
    """
    p = Path(path)
    parts = bag_parts(p)
    for f in parts.files:
        note_input(f)
    wrench_topics, position_topic = source.wrench_topics, source.position_topic
    joint, axis, phase = source.joint, source.axis, segmentation.phase
    crc_check = source.crc_check
    roles: dict[str, tuple[str, ...]] = dict.fromkeys(wrench_topics, (WRENCH_TYPE,))
    roles[position_topic] = (POSE_TYPE, JOINT_STATE_TYPE)
    notes: list[str] = []
    if not crc_check:
        notes.append(
            f"{p}: chunk CRCs not checked (--no-crc-check): a damaged chunk can change samples "
            "without an error"
        )
    data: dict[str, tuple[list[int], list[Any]]] = {t: ([], []) for t in roles}
    for f in parts.files:  # a rosbag2 folder's files, in recording order
        for topic, (stamps, values) in _read_topics(
            f, roles, joint, axis, crc_check=crc_check, notes=notes
        ).items():
            data[topic][0].extend(stamps)
            data[topic][1].extend(values)
    if parts.metadata is not None and crc_check:
        check_counts(parts, {t: len(data[t][0]) for t in data}, p)
    where = str(p)

    streams: list[tuple[FloatArray, FloatArray]] = []
    t_ref_ns = min((data[t][0][0] for t in data if data[t][0]), default=0)
    for topic in [*wrench_topics, position_topic]:
        stamps, values = data[topic]
        if not stamps:
            raise InputDataError(f"topic {topic!r} has no messages", path=p)
        t_s = (np.asarray(stamps, dtype=np.int64) - t_ref_ns).astype(np.float64) / NS_PER_S
        what = f"topic {topic!r}"
        if topic == position_topic:
            v = np.asarray(values, dtype=np.float64)
            _check_stream(what, t_s, v, where)
        else:
            vectors = np.asarray(values, dtype=np.float64).reshape(-1, 3)
            v = np.abs(vectors[:, "xyz".index(axis)])
            _check_stream(what, t_s, v, where)
            check_force_axis(vectors, axis, what=what, path=where)
            check_peak_force(
                float(np.max(v)), what=what, path=where, hint="is the wrench in newtons?"
            )
        if t_s.shape[0] >= 2:
            check_sample_rate(
                _rate_hz(t_s), what=what, path=where, hint="are its header stamps right?"
            )
        streams.append((t_s, v))

    pos_t, pos_v = streams[-1]
    force_streams = streams[:-1]
    lo = max(max(s[0][0] for s in force_streams), pos_t[0])
    hi = min(min(s[0][-1] for s in force_streams), pos_t[-1])
    if not hi > lo:
        spans = "; ".join(
            f"{name} {t[0]:.3f}..{t[-1]:.3f} s"
            for name, (t, _) in zip([*wrench_topics, position_topic], streams, strict=True)
        )
        raise InputDataError(f"force and position streams do not overlap in time: {spans}", path=p)
    t0, f0 = force_streams[0]
    keep = (t0 >= lo) & (t0 <= hi)
    time_s = t0[keep]
    force_n = f0[keep]
    if len(force_streams) == 2:
        t1, f1 = force_streams[1]
        force_n = 0.5 * (force_n + np.interp(time_s, t1, f1))
    position = np.interp(time_s, pos_t, pos_v)
    if time_s.shape[0] < 2:
        raise InputDataError("fewer than two force samples inside the overlap", path=p)
    compression_m = _compression(
        position,
        force_n,
        source.position_is,
        where,
        segmentation.force_threshold_frac,
        source.compression_zero,
        source.position_increases_when,
        f"topic {position_topic!r}",
    )
    check_peak_compression(
        float(np.max(compression_m)),
        size_x_cm=size_x_cm,
        what=f"topic {position_topic!r}",
        path=where,
        hint="is the position in metres? (ROS uses metres; convert a joint in mm or rad)",
    )
    doubts = [
        Defect(flag, line, numbers)
        for flag, line, numbers in unit_doubts(
            rate_hz=_rate_hz(time_s),
            peak_force_n=float(np.max(force_n)),
            peak_compression_m=float(np.max(compression_m)),
            readings={  # ROS messages are SI; the stamps are ns (the time unit is known)
                "time": Reading(f"topic {wrench_topics[0]!r}", "s", 1.0),
                "force": Reading(f"topic {wrench_topics[0]!r}", "N", 1.0),
                "length": Reading(f"topic {position_topic!r}", "m", 1.0),
            },
            path=where,
        )
    ]
    position_rate_hz = _rate_hz(pos_t)
    squeezes, ruptures = _to_squeezes(
        time_s,
        force_n,
        compression_m,
        object_id=object_id,
        segmentation=segmentation,
        segment=segmentation.segments(True),
        path=where,
        window_s=_detection_window_s(position_rate_hz),
        clock_origin_ns=t_ref_ns,
    )
    loop = _energy_returned(squeezes, f"topics {wrench_topics[0]!r} and {position_topic!r}")
    if loop is not None:
        doubts.append(loop)
    return Recording(
        squeezes,
        _rate_hz(force_streams[0][0]),
        position_rate_hz,
        source=source.kind,
        phase=phase,
        ruptures=tuple(ruptures),
        flags=tuple(d.flag for d in doubts),
        defects=tuple(d.as_dict() for d in doubts),
        warnings=(*notes, *(d.text for d in doubts)),
    )


#: ``energy_returned``: the squeezes' loop work, as a fraction of their loading work, below
#: minus this. A passive object dissipates (the loop work is >= 0: the fraction is about
#: +2 % for λ = 1.5 N·s/cm at D = 30 N/cm, 0 for an elastic one); the noise of a
#: recording moves it by a fraction of a percent. The same bag run backwards gives -2.3 %.
ENERGY_RETURNED_FRAC = 0.01


def _energy_returned(squeezes: Sequence[SqueezeSeries], what: str) -> Defect | None:
    """The ``energy_returned`` defect when the squeezes' force-compression loops give energy
    back (the loop work ∮ F dx < -ENERGY_RETURNED_FRAC × the loading work), else None."""
    loop = loading = 0.0
    for squeeze in squeezes:
        f = np.asarray(squeeze.force_n, dtype=np.float64)
        x = np.asarray(squeeze.compression_m, dtype=np.float64)
        if f.size < 2:
            continue
        dx = np.diff(x)
        mean_f = 0.5 * (f[1:] + f[:-1])
        loop += float(np.sum(mean_f * dx))
        loading += float(np.sum(mean_f * np.clip(dx, 0.0, None)))
    if not (loading > 0 and math.isfinite(loop) and loop < -ENERGY_RETURNED_FRAC * loading):
        return None
    frac = loop / loading
    return Defect(
        ENERGY_RETURNED,
        f"{what}: the squeezes give energy back (loop work {100 * frac:.2g} % of the loading "
        "work), which no passive object does: are the samples reversed in time, or does the "
        "force lag the position? λ is wrong (flagged energy_returned)",
        {"loop_work_frac": frac},
    )
