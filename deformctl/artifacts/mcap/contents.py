"""What an MCAP log holds, verified: the layout's names, the CRC checks, the decoded records.

:func:`load_mcap` checks the closing magic, the footer and both section CRCs before the mcap library
parses anything (a truncated file or a flipped byte is refused, exit 65), then reads the records
through the library's :class:`StreamReader`, which checks every chunk CRC, into a
:class:`McapContents`. The checks every reader makes of a deformctl log (its ``kind`` and format
version, each channel's encoding and schema version, each message against its JSON Schema) and the
decoding of the ``object`` and ``provenance`` metadata records are here too.
"""

from __future__ import annotations

import io
import struct
import zlib
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import zstandard
from mcap.exceptions import McapError
from mcap.opcode import Opcode
from mcap.records import Channel, Header, Message, Metadata, Schema
from mcap.stream_reader import StreamReader

from deformctl import jsonsafe
from deformctl.artifacts.io import PathArg, display_name
from deformctl.artifacts.mcap.integrity import MCAP_MAGIC, locate_damage
from deformctl.artifacts.provenance import Provenance
from deformctl.artifacts.schema import (
    load_json_schema,
    message_columns,
    schema_version,
    validate_message,
)
from deformctl.errors import InputDataError, SchemaError
from deformctl.reprs import short_repr
from deformctl.units import NS_PER_S

KIND_SQUEEZE = "squeeze_log"
KIND_LIFT = "lift_log"
MCAP_KINDS = (KIND_SQUEEZE, KIND_LIFT)
FORMAT_VERSION = "1"
SQUEEZE_TOPIC = "/squeeze"  #: every object's squeezes in a first-layout log
LIFT_SAMPLE_TOPIC = "/lift/attempt_sample"  #: every object's samples in a first-layout log
LIFT_RESULT_TOPIC = "/lift/attempt_result"  #: every object's results in a first-layout log
SQUEEZE_SAMPLE = "squeeze_sample"
LIFT_SAMPLE = "lift_attempt_sample"
LIFT_RESULT = "lift_attempt_result"
PALM_CONTACT = "palm_contact"
PALMS_TOPIC = "/palms"  #: every object's palm contacts at the scene frames
SCENE_TOPIC = "/scene"  #: every object's scene, foxglove.SceneUpdate (not a deformctl schema)
#: first-layout topic → JSON Schema name
TOPIC_SCHEMAS = {
    SQUEEZE_TOPIC: SQUEEZE_SAMPLE,
    LIFT_SAMPLE_TOPIC: LIFT_SAMPLE,
    LIFT_RESULT_TOPIC: LIFT_RESULT,
    PALMS_TOPIC: PALM_CONTACT,
}
#: topics of a simulated log's scene: they say nothing about the log's kind
SCENE_TOPICS = (SCENE_TOPIC, PALMS_TOPIC)
KIND_SCHEMAS = {
    KIND_SQUEEZE: (SQUEEZE_SAMPLE,),
    KIND_LIFT: (LIFT_SAMPLE, LIFT_RESULT),
}
GAP_S = 1.0  #: log-time gap between consecutive squeezes / attempts laid end to end, s
LOG_EPOCH_NS = 946_684_800 * NS_PER_S  #: 2000-01-01T00:00:00Z: where simulated logs begin


def squeeze_topic(object_id: str) -> str:
    """``/squeeze/<object_id>``: the channel of one object's squeeze samples."""
    return f"{SQUEEZE_TOPIC}/{object_id}"


def lift_topic(object_id: str, schema_name: str) -> str:
    """``/lift/<object_id>/attempt_sample`` or ``.../attempt_result`` of one object."""
    return f"/lift/{object_id}/{schema_name.removeprefix('lift_')}"


def topic_schema(topic: str) -> tuple[str, str | None] | None:
    """``(JSON Schema name, object id or None)`` of a topic deformctl writes; None otherwise.

    The object id is None for the first layout's shared topics.
    """
    if topic in TOPIC_SCHEMAS:
        return TOPIC_SCHEMAS[topic], None
    if topic.startswith(SQUEEZE_TOPIC + "/") and len(topic) > len(SQUEEZE_TOPIC) + 1:
        return SQUEEZE_SAMPLE, topic[len(SQUEEZE_TOPIC) + 1 :]
    for name in (LIFT_SAMPLE, LIFT_RESULT):
        suffix = "/" + name.removeprefix("lift_")
        if topic.startswith("/lift/") and topic.endswith(suffix) and len(topic) > 6 + len(suffix):
            return name, topic[6 : -len(suffix)]
    return None


_FOOTER_LEN = 1 + 8 + 20  # opcode, record length, summary_start, summary_offset_start, crc
_DATA_END_LEN = 1 + 8 + 4  # opcode, record length, data_section_crc
_SQUEEZE_OPTIONAL = (
    "commanded_force_n",
    "force_left_n",
    "force_right_n",
    "palm_left_x_m",
    "palm_right_x_m",
)
_LIFT_FIELDS = ("palm_z_m", "object_com_z_m", "slip_m", "friction_force_n", "normal_force_n")


#: Everything decoding a damaged MCAP can raise inside the mcap / zstd / lz4 / json libraries.
_DECODE_ERRORS = (
    McapError,
    ValueError,  # includes CRCValidationError, UnicodeDecodeError, json.JSONDecodeError
    struct.error,
    EOFError,
    KeyError,
    IndexError,
    TypeError,
    OverflowError,
    MemoryError,
    RuntimeError,  # lz4.frame
    zstandard.ZstdError,
    AttributeError,
)


@dataclass
class McapContents:
    """What a CRC-verified MCAP holds, decoded by the mcap library (messages not yet parsed).

    Attributes:
        path: the file name used in messages.
        header: the MCAP header record.
        metadata: ``(name, key/value)`` of every metadata record, in file order.
        schemas: schema id → schema record.
        channels: channel id → channel record.
        messages: every message record, in file order.
        crcs_present: True when both the data-section and the summary CRC were written.
    """

    __repr__ = short_repr

    path: str
    header: Header | None = None
    metadata: list[tuple[str, dict[str, str]]] = field(default_factory=list)
    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    messages: list[Message] = field(default_factory=list)
    crcs_present: bool = False

    def metadata_named(self, name: str) -> list[dict[str, str]]:
        """The key/value maps of every metadata record called ``name``."""
        return [m for n, m in self.metadata if n == name]

    @property
    def kind(self) -> str | None:
        """``squeeze_log`` / ``lift_log`` from the ``deformctl`` record, else from the topics."""
        records = self.metadata_named("deformctl")
        if records:
            return records[0].get("kind")
        found = {
            topic_schema(c.topic)
            for c in self.channels.values()
            if c.topic and c.topic not in SCENE_TOPICS
        }
        names = {f[0] if f else None for f in found}
        for kind, kind_schemas in KIND_SCHEMAS.items():
            if names and names <= set(kind_schemas):
                return kind
        return None

    def kind_from_topics(self) -> str | None:
        """The kind the channels' topics make (whatever the ``deformctl`` record declares);
        None without channels or for topics of no deformctl kind."""
        found = {topic_schema(c.topic) for c in self.channels.values() if c.topic}
        names = {f[0] if f else None for f in found}
        for kind, kind_schemas in KIND_SCHEMAS.items():
            if names and names <= set(kind_schemas):
                return kind
        return None

    def check_declared_kind(self) -> None:
        """Refuse a log whose declared kind its channels contradict (a relabelled log).

        Raises:
            InputDataError: one line naming both kinds and a topic (exit 65).
        """
        declared, found = self.kind, self.kind_from_topics()
        names = {f[0] for f in (topic_schema(c.topic) for c in self.channels.values()) if f}
        present = [k for k, schemas in KIND_SCHEMAS.items() if names & set(schemas)]
        if found is None and present and (declared not in present or len(present) > 1):
            found = next(k for k in present if k != declared)  # beside other channels too
        if declared in MCAP_KINDS and found is not None and found != declared:
            schemas = set(KIND_SCHEMAS[found])
            topic = sorted(
                c.topic
                for c in self.channels.values()
                if c.topic and (topic_schema(c.topic) or ("",))[0] in schemas
            )[0]
            raise InputDataError(
                f"declares kind {declared!r} but its channels are a {found}'s ({topic!r}): "
                "the content does not match the label",
                path=self.path,
            )

    def message_counts(self) -> dict[str, int]:
        """Topic → number of messages."""
        counts = {c.topic: 0 for c in self.channels.values()}
        for msg in self.messages:
            channel = self.channels.get(msg.channel_id)
            if channel is not None:
                counts[channel.topic] += 1
        return counts

    def time_range_ns(self) -> tuple[int, int] | None:
        """(first, last) message ``log_time`` in ns, None without messages."""
        if not self.messages:
            return None
        times = [m.log_time for m in self.messages]
        return min(times), max(times)


def _verify_integrity(data: bytes, name: str) -> bool:
    """Check magic, footer, data-section CRC and summary CRC; return True when both CRCs exist."""
    if not data:
        what = "no log on stdin (did the command before the pipe fail?)"
        message = f"empty input: {what}" if name == "<stdin>" else "empty file"
        raise InputDataError(message, path=name)
    if len(data) < len(MCAP_MAGIC) or data[: len(MCAP_MAGIC)] != MCAP_MAGIC:
        raise InputDataError("not an MCAP file (bad magic bytes)", path=name)
    min_len = 2 * len(MCAP_MAGIC) + _FOOTER_LEN + _DATA_END_LEN
    if len(data) < min_len or data[-len(MCAP_MAGIC) :] != MCAP_MAGIC:
        raise _damaged(data, name, "truncated or damaged MCAP file (no closing magic)")
    footer_start = len(data) - len(MCAP_MAGIC) - _FOOTER_LEN
    opcode, length, summary_start, _summary_offset_start, summary_crc = struct.unpack_from(
        "<BQQQI", data, footer_start
    )
    if opcode != Opcode.FOOTER or length != 20:
        raise _damaged(data, name, "damaged MCAP file (bad footer record)")
    data_end_stop = summary_start if summary_start else footer_start
    data_end_start = data_end_stop - _DATA_END_LEN
    if data_end_start < len(MCAP_MAGIC) or data_end_stop > footer_start:
        raise _damaged(data, name, "damaged MCAP file (bad summary offset)")
    de_opcode, de_length, data_crc = struct.unpack_from("<BQI", data, data_end_start)
    if de_opcode != Opcode.DATA_END or de_length != 4:
        raise _damaged(data, name, "damaged MCAP file (no data end record)")
    if data_crc != 0 and zlib.crc32(data[:data_end_start]) != data_crc:
        raise _damaged(data, name, "damaged MCAP file (data section CRC mismatch)")
    if summary_crc != 0:
        covered = data[(summary_start or footer_start) : footer_start + _FOOTER_LEN - 4]
        if zlib.crc32(covered) != summary_crc:
            raise _damaged(data, name, "damaged MCAP file (summary CRC mismatch)")
    return data_crc != 0 and summary_crc != 0


def _damaged(data: bytes, name: str, what: str) -> InputDataError:
    """The one line of a damaged log: what failed, and where the walk of
    :func:`~deformctl.artifacts.mcap.integrity.locate_damage` finds the first damage."""
    try:
        where = locate_damage(io.BytesIO(data), len(data))
    except (OSError, struct.error):
        where = None
    return InputDataError(what if where is None else f"{what}: {where}", path=name)


def _short(err: BaseException) -> str:
    text = " ".join(str(err).split()) or type(err).__name__
    return text if len(text) <= 160 else text[:157] + "..."


def load_mcap(data: bytes, path: PathArg) -> McapContents:
    """Verify an MCAP's CRCs and decode its records with the mcap library.

    Args:
        data: the whole file.
        path: the file name for error messages (``-`` shows as ``<stdin>``).

    Raises:
        InputDataError: not MCAP, truncated, a CRC mismatch or any decoding failure (exit 65).
    """
    name = display_name(path)
    crcs = _verify_integrity(data, name)
    contents = McapContents(path=name, crcs_present=crcs)
    try:
        reader = StreamReader(io.BytesIO(data), validate_crcs=True, record_size_limit=len(data))
        for record in reader.records:
            if isinstance(record, Message):
                contents.messages.append(record)
            else:
                _keep(record, contents)
    except _DECODE_ERRORS as err:
        raise _damaged(data, name, f"damaged MCAP file ({_short(err)})") from None
    for msg in contents.messages:
        if msg.channel_id not in contents.channels:
            raise InputDataError(f"message on unknown channel {msg.channel_id}", path=name)
    return contents


def _keep(record: Any, contents: McapContents) -> None:
    """What :func:`load_mcap` keeps of a record."""
    if isinstance(record, Header):
        contents.header = record
    elif isinstance(record, Metadata):
        contents.metadata.append((record.name, dict(record.metadata)))
    elif isinstance(record, Schema):
        contents.schemas[record.id] = record
    elif isinstance(record, Channel):
        contents.channels[record.id] = record


def _check_kind(contents: McapContents, kind: str) -> None:
    """Refuse a log without the ``deformctl`` record, of another kind (a missing, bogus or
    other ``kind``), of a format it cannot read, or without its CRCs."""
    name = contents.path
    records = contents.metadata_named("deformctl")
    if not records:
        raise SchemaError(
            f"no 'deformctl' metadata record (the log's kind); expected a {kind} written by "
            "deformctl",
            path=name,
            field="deformctl",
        )
    found = contents.kind
    if found != kind:
        what = f"a {found}" if found else "not a deformctl log"
        raise SchemaError(f"is {what}, expected a {kind}", path=name, field="deformctl")
    if records[0].get("format_version") != FORMAT_VERSION:
        raise SchemaError(
            f"format version {records[0].get('format_version')!r} not supported "
            f"(this deformctl reads {FORMAT_VERSION})",
            path=name,
            field="format_version",
        )
    if not contents.crcs_present:
        raise SchemaError("written without CRCs; cannot be trusted", path=name, field="crc")


def _check_channels(contents: McapContents) -> dict[int, tuple[str, str | None]]:
    """Map channel id → (JSON Schema name, object id or None) for deformctl topics, checking
    encodings and versions."""
    name = contents.path
    out: dict[int, tuple[str, str | None]] = {}
    for cid, channel in contents.channels.items():
        found = topic_schema(channel.topic)
        if found is None:
            continue
        schema_name = found[0]
        ours = load_json_schema(schema_name)
        schema = contents.schemas.get(channel.schema_id)
        if channel.message_encoding != "json":
            raise SchemaError(
                f"channel {channel.topic}: message encoding {channel.message_encoding!r}, "
                "expected 'json'",
                path=name,
                field=channel.topic,
            )
        if schema is None or schema.encoding != "jsonschema" or schema.name != ours["title"]:
            got = None if schema is None else f"{schema.name} ({schema.encoding})"
            raise SchemaError(
                f"channel {channel.topic}: schema {got!r}, expected {ours['title']!r}",
                path=name,
                field=channel.topic,
            )
        try:
            embedded = jsonsafe.loads(schema.data)
        except ValueError as err:
            raise SchemaError(
                f"channel {channel.topic}: embedded JSON Schema is not JSON ({_short(err)})",
                path=name,
                field=channel.topic,
            ) from None
        version = schema_version(embedded) if isinstance(embedded, dict) else 0
        if version < 1 or version > schema_version(ours):
            raise SchemaError(
                f"channel {channel.topic}: schema version {version} not supported "
                f"(this deformctl reads {schema_version(ours)})",
                path=name,
                field=channel.topic,
            )
        out[cid] = found
    return out


def _decoded_messages(contents: McapContents, schema_name: str) -> list[dict[str, Any]]:
    """Parse and JSON-Schema-validate every message of ``schema_name``, in file order.

    A message on an object's own channel must name that object. When every message parses (flat
    objects in one parse, :func:`deformctl.jsonsafe.loads_objects`) and passes the column check
    (:func:`~deformctl.artifacts.schema.message_columns`, which vouches for a flat schema's
    messages in one pass), none is checked again one by one; otherwise each
    is, in file order, so the first bad message is the one named.
    """
    channels = {
        cid: found for cid, found in _check_channels(contents).items() if found[0] == schema_name
    }
    picked = [
        (i, msg, found)
        for i, msg in enumerate(contents.messages)
        if (found := channels.get(msg.channel_id)) is not None
    ]
    try:  # any failure here is found again, and named, message by message below
        texts = [msg.data for _, msg, _ in picked]
        parsed = jsonsafe.loads_objects(texts)  # flat objects: one parse for them all
        if parsed is None:
            parsed = [jsonsafe.loads(text) for text in texts]
        valid = message_columns(schema_name, parsed) is not None
    except Exception:  # the loop below raises what the first bad message raises
        parsed, valid = None, False
    out: list[dict[str, Any]] = []
    for k, (i, msg, found) in enumerate(picked):
        topic = contents.channels[msg.channel_id].topic
        where = f"message {i} on {topic}"
        if parsed is not None:
            obj = parsed[k]
        else:
            try:
                obj = jsonsafe.loads(msg.data)
            except ValueError as err:
                raise SchemaError(
                    f"{where}: not valid JSON ({_short(err)})", path=contents.path, field=topic
                ) from None
        if not valid:
            validate_message(schema_name, obj, path=contents.path, where=where)
        if found[1] is not None and obj["object_id"] != found[1]:
            raise SchemaError(
                f"{where}: object_id {obj['object_id']!r} on the channel of {found[1]!r}",
                path=contents.path,
                field="object_id",
            )
        out.append(obj)
    return out


def decode_objects(contents: McapContents) -> list[dict[str, Any]]:
    """The catalog rows stored as ``object`` metadata records, values JSON-decoded."""
    objects: list[dict[str, Any]] = []
    seen: set[str] = set()
    for record in contents.metadata_named("object"):
        try:
            obj = {k: jsonsafe.loads(v, allow_nan=True) for k, v in record.items()}
        except ValueError as err:
            raise SchemaError(
                f"object metadata is not JSON ({_short(err)})", path=contents.path, field="object"
            ) from None
        oid = obj.get("object_id")
        if not isinstance(oid, str) or not oid:
            raise SchemaError(
                "object metadata without an object_id", path=contents.path, field="object"
            )
        if oid in seen:
            raise SchemaError(f"object {oid!r} stored twice", path=contents.path, field="object_id")
        seen.add(oid)
        objects.append(obj)
    return objects


def decode_provenance(contents: McapContents) -> Provenance | None:
    """The ``provenance`` metadata record, None when the log has none."""
    records = contents.metadata_named("provenance")
    if not records:
        return None
    return Provenance.from_mcap_metadata(records[0], path=contents.path)


def _check_time(t: np.ndarray, label: str, path: str) -> None:
    if t.size and np.any(np.diff(t) < 0):
        raise SchemaError(f"{label}: time_s decreases", path=path, field="time_s")
