"""MCAP logs of squeezes and lift attempts: JSON messages with JSON Schemas, one sample per message.

Layout of a log written here (it opens in Foxglove):

* metadata record ``deformctl``: ``kind`` (``squeeze_log`` or ``lift_log``) and ``format_version``;
* metadata record ``provenance`` (see :class:`~deformctl.artifacts.provenance.Provenance`);
* one metadata record ``object`` per object: its catalog row, each value JSON-encoded;
* one channel per object, message encoding ``json``, schema encoding ``jsonschema`` with the
  schema files of ``schemas/``: ``/squeeze/<object_id>`` (``squeeze_sample``) in a squeeze log;
  ``/lift/<object_id>/attempt_sample`` (``lift_attempt_sample``) and
  ``/lift/<object_id>/attempt_result`` (``lift_attempt_result``) in a lift log. Logs of the first
  layout, every object on ``/squeeze`` or ``/lift/attempt_sample`` and ``/lift/attempt_result``,
  are still read; the readers go by each message's ``object_id``.

``log_time`` (ns since the Unix epoch) never decreases through a file. A squeeze or attempt
that carries its source's clock (``SqueezeSeries.start_time_ns``: a bag's header stamps or a
CSV's absolute times; ``TrialOutcome.start_time_ns``: a rig attempt's wall clock) is placed
there. The others (simulated ones) are laid end to end from a fixed epoch, :data:`LOG_EPOCH_NS`
(2000-01-01T00:00:00Z, or the writer's ``epoch_ns``), in write order with :data:`GAP_S` between
them, so the same inputs give the same bytes and a plot shows them one after another. The time
since the squeeze or attempt began, ``time_s``, is a message field and is what the readers
return.

Integrity: the writer enables the chunk CRCs, the data-section CRC and the summary CRC. Before the
mcap library parses anything, :func:`load_mcap` checks the closing magic, the footer and both
section CRCs, so a truncated file or any flipped byte is refused (exit 65) instead of decoding
into different numbers. Reading then goes through the mcap library's :class:`StreamReader`, which
checks every chunk CRC, and every message is validated against its JSON Schema.
:func:`read_squeeze_log` first tries a bulk reader that makes the same checks on all the samples
at once (several times faster on a sweep's logs) and falls back to that reference path for any
file it cannot vouch for, so what it returns and what it refuses are the reference path's.
"""

from __future__ import annotations

import io
import json
import math
import struct
import zlib
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import zstandard
from mcap.data_stream import ReadDataStream
from mcap.exceptions import McapError
from mcap.opcode import Opcode
from mcap.records import (
    Attachment,
    AttachmentIndex,
    Channel,
    Chunk,
    ChunkIndex,
    DataEnd,
    Footer,
    Header,
    Message,
    Metadata,
    MetadataIndex,
    Schema,
    Statistics,
    SummaryOffset,
)
from mcap.stream_reader import StreamReader
from mcap.writer import CompressionType, Writer

from deformctl import __version__, jsonsafe
from deformctl.artifacts.io import PathArg, atomic_output, display_name, read_input_bytes
from deformctl.artifacts.provenance import Provenance, _json_default
from deformctl.artifacts.schema import (
    json_schema_bytes,
    load_json_schema,
    message_columns,
    schema_version,
    validate_message,
)
from deformctl.errors import DeformctlError, InputDataError, SchemaError
from deformctl.lift.search import LiftAttempt
from deformctl.series import LiftAttemptSeries, SqueezeSeries, TrialOutcome
from deformctl.units import NS_PER_S

MCAP_MAGIC = b"\x89MCAP0\r\n"
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
#: first-layout topic → JSON Schema name
TOPIC_SCHEMAS = {
    SQUEEZE_TOPIC: SQUEEZE_SAMPLE,
    LIFT_SAMPLE_TOPIC: LIFT_SAMPLE,
    LIFT_RESULT_TOPIC: LIFT_RESULT,
}
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
        found = {topic_schema(c.topic) for c in self.channels.values() if c.topic}
        names = {f[0] if f else None for f in found}
        for kind, kind_schemas in KIND_SCHEMAS.items():
            if names and names <= set(kind_schemas):
                return kind
        return None

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


# ---------------------------------------------------------------------------------------- reading


def _verify_integrity(data: bytes, name: str) -> bool:
    """Check magic, footer, data-section CRC and summary CRC; return True when both CRCs exist."""
    if len(data) < len(MCAP_MAGIC) or data[: len(MCAP_MAGIC)] != MCAP_MAGIC:
        raise InputDataError("not an MCAP file (bad magic bytes)", path=name)
    min_len = 2 * len(MCAP_MAGIC) + _FOOTER_LEN + _DATA_END_LEN
    if len(data) < min_len or data[-len(MCAP_MAGIC) :] != MCAP_MAGIC:
        raise InputDataError("truncated or damaged MCAP file (no closing magic)", path=name)
    footer_start = len(data) - len(MCAP_MAGIC) - _FOOTER_LEN
    opcode, length, summary_start, _summary_offset_start, summary_crc = struct.unpack_from(
        "<BQQQI", data, footer_start
    )
    if opcode != Opcode.FOOTER or length != 20:
        raise InputDataError("damaged MCAP file (bad footer record)", path=name)
    data_end_stop = summary_start if summary_start else footer_start
    data_end_start = data_end_stop - _DATA_END_LEN
    if data_end_start < len(MCAP_MAGIC) or data_end_stop > footer_start:
        raise InputDataError("damaged MCAP file (bad summary offset)", path=name)
    de_opcode, de_length, data_crc = struct.unpack_from("<BQI", data, data_end_start)
    if de_opcode != Opcode.DATA_END or de_length != 4:
        raise InputDataError("damaged MCAP file (no data end record)", path=name)
    if data_crc != 0 and zlib.crc32(data[:data_end_start]) != data_crc:
        raise InputDataError("damaged MCAP file (data section CRC mismatch)", path=name)
    if summary_crc != 0:
        covered = data[(summary_start or footer_start) : footer_start + _FOOTER_LEN - 4]
        if zlib.crc32(covered) != summary_crc:
            raise InputDataError("damaged MCAP file (summary CRC mismatch)", path=name)
    return data_crc != 0 and summary_crc != 0


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
        raise InputDataError(f"damaged MCAP file ({_short(err)})", path=name) from None
    for msg in contents.messages:
        if msg.channel_id not in contents.channels:
            raise InputDataError(f"message on unknown channel {msg.channel_id}", path=name)
    return contents


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

    A message on an object's own channel must name that object.
    """
    channels = {
        cid: found for cid, found in _check_channels(contents).items() if found[0] == schema_name
    }
    out: list[dict[str, Any]] = []
    for i, msg in enumerate(contents.messages):
        found = channels.get(msg.channel_id)
        if found is None:
            continue
        topic = contents.channels[msg.channel_id].topic
        where = f"message {i} on {topic}"
        try:
            obj = jsonsafe.loads(msg.data)
        except ValueError as err:
            raise SchemaError(
                f"{where}: not valid JSON ({_short(err)})", path=contents.path, field=topic
            ) from None
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


def _group(
    messages: Iterable[dict[str, Any]], index_key: str
) -> dict[tuple[str, int], list[dict[str, Any]]]:
    groups: dict[tuple[str, int], list[dict[str, Any]]] = {}
    for m in messages:
        groups.setdefault((m["object_id"], m[index_key]), []).append(m)
    return groups


def _column(samples: list[dict[str, Any]], key: str) -> np.ndarray:
    return np.fromiter((s[key] for s in samples), dtype=np.float64, count=len(samples))


def _check_time(t: np.ndarray, label: str, path: str) -> None:
    if t.size and np.any(np.diff(t) < 0):
        raise SchemaError(f"{label}: time_s decreases", path=path, field="time_s")


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


# ------------------------------------------------------------------------ bulk squeeze-log reading
#
# A squeeze log holds one JSON message per sample: 3,753 per simulated object, 7.5 million in a
# 2,000-object sweep. Decoding them one by one (a Message record from the mcap library, a JSON
# document, a JSON-Schema check each) cost ~40 µs per sample, several times the fits themselves.
# The bulk reader below decodes a log in bulk: its own loop over the records (the mcap library's
# record readers for everything but messages), the samples parsed as one JSON array
# (jsonsafe.loads_objects) and checked against their schema a column at a time
# (schema.message_columns). It is an accelerator, not a second reader: it returns a result only
# when every check it makes is at least as strict as the reference path's (load_mcap, then
# squeezes_from_contents and decode_objects) and it gives the same objects and squeezes,
# bit for bit; on anything else (a damaged, unusual or hostile file, a message that does not
# match, an error of any kind) it gives up and the reference path reads the file again, so the
# refusals and their messages are the reference path's.


class _NotBulk(Exception):
    """The bulk reader cannot vouch for this log; the reference reader decides."""


class _ExactBytes(io.BytesIO):
    """A record's bytes for the mcap library's record readers: a read past the end refuses
    (the library reads on into the next record where the file stream has one)."""

    def read(self, size: int | None = -1) -> bytes:
        out = super().read(size)
        if size is None or size < 0 or len(out) != size:
            raise _NotBulk
        return out


_RECORD_HEAD = struct.Struct("<BQ")  # opcode, record length
_MESSAGE_HEAD = struct.Struct("<BQH")  # opcode, record length, channel id
_MESSAGE_FIXED = 22  # channel id, sequence, log time, publish time
_RECORD_TYPES: dict[int, Any] = {
    Opcode.HEADER: Header,
    Opcode.FOOTER: Footer,
    Opcode.SCHEMA: Schema,
    Opcode.CHANNEL: Channel,
    Opcode.CHUNK: Chunk,
    Opcode.METADATA: Metadata,
    Opcode.DATA_END: DataEnd,
    Opcode.CHUNK_INDEX: ChunkIndex,
    Opcode.METADATA_INDEX: MetadataIndex,
    Opcode.ATTACHMENT: Attachment,
    Opcode.ATTACHMENT_INDEX: AttachmentIndex,
    Opcode.STATISTICS: Statistics,
    Opcode.SUMMARY_OFFSET: SummaryOffset,
}
_BULK_BATCH = 65_536  # samples parsed per JSON array (bounds the transient dicts)


def _record(opcode: int, body: bytes | memoryview) -> Any:
    """One non-message record read by the mcap library's reader, which must use all its bytes."""
    stream = ReadDataStream(_ExactBytes(body))
    record = _RECORD_TYPES[opcode].read(stream)
    if stream.count != len(body):
        raise _NotBulk
    return record


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


def _scan_chunk(chunk: Chunk, contents: McapContents, cids: list[int], texts: list[bytes]) -> None:
    """The schemas, channels and messages (channel id, data) of one chunk, in order."""
    if chunk.compression == "zstd":
        buf = zstandard.decompress(chunk.data, chunk.uncompressed_size)
    elif chunk.compression == "":
        buf = chunk.data
    else:
        raise _NotBulk
    if chunk.uncompressed_crc != 0 and zlib.crc32(buf) != chunk.uncompressed_crc:
        raise _NotBulk
    n = len(buf)
    off = 0
    head = _MESSAGE_HEAD.unpack_from
    add_cid, add_text = cids.append, texts.append
    while off < n:
        if off + _MESSAGE_HEAD.size > n:
            raise _NotBulk
        opcode, length, cid = head(buf, off)
        start = off + _RECORD_HEAD.size
        stop = start + length
        if stop > n:
            raise _NotBulk
        if opcode == Opcode.MESSAGE:
            if length < _MESSAGE_FIXED:
                raise _NotBulk
            add_cid(cid)
            add_text(buf[start + _MESSAGE_FIXED : stop])
        elif opcode in (Opcode.SCHEMA, Opcode.CHANNEL):
            _keep(_record(opcode, memoryview(buf)[start:stop]), contents)
        else:
            raise _NotBulk
        off = stop


def _scan(data: bytes, name: str) -> tuple[McapContents, list[int], list[bytes]]:
    """The records :func:`load_mcap` keeps, and every message's channel id and data.

    Stricter than the mcap library: every record must be one the library reads, use exactly its
    length (no padding, no reading into the next one) and end inside the file, the data-end
    record must be the one :func:`_verify_integrity` checked and the footer the last record.
    """
    crcs = _verify_integrity(data, name)
    contents = McapContents(path=name, crcs_present=crcs)
    footer_start = len(data) - len(MCAP_MAGIC) - _FOOTER_LEN
    (summary_start,) = struct.unpack_from("<Q", data, footer_start + 9)
    data_end_start = (summary_start or footer_start) - _DATA_END_LEN
    cids: list[int] = []
    texts: list[bytes] = []
    view = memoryview(data)
    end = len(data) - len(MCAP_MAGIC)
    pos = len(MCAP_MAGIC)
    while True:
        if pos + _RECORD_HEAD.size > end:
            raise _NotBulk
        opcode, length = _RECORD_HEAD.unpack_from(data, pos)
        start = pos + _RECORD_HEAD.size
        stop = start + length
        if stop > end:
            raise _NotBulk
        if opcode == Opcode.MESSAGE_INDEX:  # ignored by load_mcap; the library reads 16-byte pairs
            if length < 6 or struct.unpack_from("<I", data, start + 2)[0] != length - 6:
                raise _NotBulk
            if (length - 6) % 16:
                raise _NotBulk
        elif opcode == Opcode.CHUNK:
            _scan_chunk(_record(opcode, view[start:stop]), contents, cids, texts)
        elif opcode in _RECORD_TYPES:
            if opcode == Opcode.DATA_END and pos != data_end_start:
                raise _NotBulk
            _keep(_record(opcode, view[start:stop]), contents)
        else:  # a message outside a chunk, or a record the library skips
            raise _NotBulk
        pos = stop
        if opcode == Opcode.FOOTER:
            break
    if pos != end:
        raise _NotBulk
    return contents, cids, texts


def _bulk_columns(texts: list[bytes]) -> dict[str, Any]:
    """The squeeze-sample columns of the messages ``texts`` (all valid), in order; a key some
    messages lack is a masked array (see :func:`message_columns`)."""
    parts: list[dict[str, Any]] = []
    for b in range(0, max(len(texts), 1), _BULK_BATCH):
        messages = jsonsafe.loads_objects(texts[b : b + _BULK_BATCH])
        columns = None if messages is None else message_columns(SQUEEZE_SAMPLE, messages)
        if columns is None:
            raise _NotBulk
        parts.append(columns)
    sizes = [len(p["object_id"]) for p in parts]
    out: dict[str, Any] = {}
    for key in parts[0]:
        chunks = [p[key] for p in parts]
        if all(c is None for c in chunks):
            out[key] = None
        elif isinstance(chunks[0], list):
            out[key] = [v for c in chunks for v in c]
        elif all(type(c) is np.ndarray for c in chunks):
            out[key] = np.concatenate(chunks)
        else:  # in some messages only
            out[key] = np.ma.concatenate(
                [
                    np.ma.masked_all(size) if c is None else c
                    for c, size in zip(chunks, sizes, strict=True)
                ]
            )
    return out


def _group_column(column: Any, rows: np.ndarray) -> np.ndarray | None:
    """One squeeze's samples of an optional column: None when it has none of them."""
    if column is None:
        return None
    if type(column) is np.ndarray:
        return column[rows]
    absent = np.ma.getmaskarray(column)[rows]
    if absent.all():
        return None
    if absent.any():  # in some of the squeeze's samples: the reference reader says so
        raise _NotBulk
    return np.asarray(np.ma.getdata(column)[rows], dtype=np.float64)


def _bulk_squeezes(
    contents: McapContents, cids: list[int], texts: list[bytes]
) -> list[SqueezeSeries]:
    """:func:`squeezes_from_contents` of a scanned log, its samples decoded in bulk."""
    if not set(cids) <= contents.channels.keys():
        raise _NotBulk
    _check_kind(contents, KIND_SQUEEZE)
    channels = {
        cid: found for cid, found in _check_channels(contents).items() if found[0] == SQUEEZE_SAMPLE
    }
    if not set(cids) <= channels.keys():  # messages on other topics are not samples
        keep = [i for i, c in enumerate(cids) if c in channels]
        cids, texts = [cids[i] for i in keep], [texts[i] for i in keep]
    columns = _bulk_columns(texts)
    oids: list[str] = columns["object_id"]
    owners = [channels[c][1] for c in cids]  # the object of each message's channel
    if None in owners:
        if any(o is not None and o != oid for o, oid in zip(owners, oids, strict=True)):
            raise _NotBulk
    elif owners != oids:
        raise _NotBulk
    keys = list(zip(oids, columns["squeeze_index"].tolist(), strict=True))
    groups = {k: g for g, k in enumerate(dict.fromkeys(keys))}  # in order of first sample
    codes = np.fromiter(map(groups.__getitem__, keys), dtype=np.intp, count=len(keys))
    order = np.argsort(codes, kind="stable")
    bounds = np.concatenate([[0], np.cumsum(np.bincount(codes, minlength=len(groups)))])
    out: list[SqueezeSeries] = []
    for g, (oid, idx) in enumerate(groups):
        rows = order[bounds[g] : bounds[g + 1]]
        t = columns["time_s"][rows]
        if t.size and np.any(np.diff(t) < 0):
            raise _NotBulk
        optional = {key: _group_column(columns[key], rows) for key in _SQUEEZE_OPTIONAL}
        out.append(
            SqueezeSeries(
                object_id=oid,
                squeeze_index=idx,
                time_s=t,
                force_n=columns["force_n"][rows],
                compression_m=columns["compression_m"][rows],
                commanded_force_n=optional["commanded_force_n"],
                palm_left_x_m=optional["palm_left_x_m"],
                palm_right_x_m=optional["palm_right_x_m"],
            )
        )
    return out


def _bulk_squeeze_log(
    data: bytes, path: PathArg
) -> tuple[list[dict[str, Any]], list[SqueezeSeries]] | None:
    """:func:`read_squeeze_log` of a log's bytes, read in bulk; None to read it the reference
    way (any file this cannot vouch for, and every file the reference path refuses)."""
    try:
        contents, cids, texts = _scan(data, display_name(path))
        squeezes = _bulk_squeezes(contents, cids, texts)
        objects = decode_objects(contents)
    except (_NotBulk, DeformctlError, *_DECODE_ERRORS, RecursionError):
        return None
    return objects, squeezes


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


# ---------------------------------------------------------------------------------------- writing


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
        self._w.start(profile="", library=f"deformctl {__version__}")
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
        self._next_ns = last_ns + round(GAP_S * NS_PER_S)

    def add_objects(self, objects: Iterable[Mapping[str, Any]], path: str) -> None:
        for obj in objects:
            oid = obj.get("object_id")
            if not isinstance(oid, str) or not oid:
                raise InputDataError("object without a string object_id", path=path)
            data = {str(k): json.dumps(v, default=_json_default) for k, v in obj.items()}
            self._w.add_metadata("object", data)

    def channel(self, topic: str) -> int:
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
    ) -> None:
        """One message per sample: ``base`` plus sample i of every column (finite floats).

        The JSON text is built from a template instead of ``json.dumps`` per sample: the bytes are
        the same (a finite float's ``repr`` is its JSON form) and a long series encodes several
        times faster.
        """
        head = json.dumps(dict(base), separators=(",", ":"), allow_nan=False)[:-1]
        fields = ",".join(f"{json.dumps(k)}:%r" for k in columns)
        template = f"{head},{fields}}}" if base else f"{{{fields}}}"
        for log_time, row in zip(times_ns, zip(*columns.values(), strict=True), strict=True):
            self.add_encoded(topic, log_time, (template % row).encode())

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
            times = _time_line_ns(sq.time_s, log.start_ns(sq.start_time_ns))
            base = {"object_id": sq.object_id, "squeeze_index": int(sq.squeeze_index)}
            log.add_samples(squeeze_topic(sq.object_id), times, base, columns)
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
                log.add_samples(lift_topic(att.object_id, LIFT_SAMPLE), times, base, columns)
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
