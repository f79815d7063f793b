"""Bulk squeeze-log reading: the same result as the reference reader, faster.

A squeeze log holds one JSON message per sample: 3,753 per simulated object, 7.5 million in a
2,000-object sweep. Decoding them one by one (a Message record from the mcap library, a JSON
document, a JSON-Schema check each) cost ~40 µs per sample, several times the fits themselves.
The bulk reader decodes a log in bulk: its own loop over the records (the mcap library's record
readers for everything but messages), the samples parsed as one JSON array
(``jsonsafe.loads_objects``) and checked against their schema a column at a time
(``schema.message_columns``). It is an accelerator, not a second reader: it returns a result only
when every check it makes is at least as strict as the reference path's (``load_mcap``, then
``squeezes_from_contents`` and ``decode_objects``) and it gives the same objects and squeezes, bit
for bit; on anything else (a damaged, unusual or hostile file, a message that does not match, an
error of any kind) it gives up and the reference path reads the file again, so the refusals and
their messages are the reference path's. The reference path now parses and checks flat
samples at once too (``contents._decoded_messages``); what the bulk reader saves over it is the
mcap library's record objects (about 1.7x on a four-object log).
"""

from __future__ import annotations

import io
import struct
import zlib
from typing import Any

import numpy as np
import zstandard
from mcap.data_stream import ReadDataStream
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
    Metadata,
    MetadataIndex,
    Schema,
    Statistics,
    SummaryOffset,
)

from deformctl import jsonsafe
from deformctl.artifacts.io import PathArg, display_name
from deformctl.artifacts.mcap.contents import (
    _DATA_END_LEN,
    _DECODE_ERRORS,
    _FOOTER_LEN,
    _SQUEEZE_OPTIONAL,
    KIND_SQUEEZE,
    MCAP_MAGIC,
    SQUEEZE_SAMPLE,
    McapContents,
    _check_channels,
    _check_kind,
    _keep,
    _verify_integrity,
    decode_objects,
)
from deformctl.artifacts.schema import message_columns
from deformctl.errors import DeformctlError
from deformctl.series import SqueezeSeries


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
