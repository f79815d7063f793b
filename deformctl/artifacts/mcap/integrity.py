"""Where an MCAP file is damaged: the byte offset of the first bad chunk or record.

The readers (:func:`deformctl.artifacts.mcap.load_mcap` for deformctl logs, the ROS 2 bag source of
``measure``) read with the mcap library's CRC validation on; when that (or anything else in the
read) fails, :func:`locate_damage` walks the file's records from the start and says where the
damage is, so the one error line names the file and the offset a user can look at (or cut at):

* a chunk whose data does not decompress (a corrupt ``zstd``/``lz4`` frame), or decompresses
  to another size or another CRC than the chunk header stores;
* a record that runs past the end of the file (a truncated file: a recorder that died, a copy
  cut short), or a file without its footer and closing magic;
* a data-section or summary CRC that does not match, when the chunks' own CRCs do (damage in a
  record outside every chunk);
* a record with the invalid opcode 0 or an impossible length.

A walk reads the file once (each chunk decompressed); it runs only after a read failed, never on
the way of a good file. A bag is read by the seeking reader, which checks the CRC of every chunk
it reads; :func:`tail_problem` checks its footer, closing magic and summary CRC first (cheap:
the summary is small), so a cut file is refused before the reader trusts a damaged index.
"""

from __future__ import annotations

import struct
import zlib
from typing import BinaryIO

import zstandard
from mcap.data_stream import ReadDataStream
from mcap.opcode import Opcode
from mcap.records import Chunk

__all__ = ["MCAP_MAGIC", "chunk_problem", "complete_prefix", "locate_damage", "tail_problem"]

MCAP_MAGIC = b"\x89MCAP0\r\n"
_HEAD = struct.Struct("<BQ")  # opcode, record length
_NAMES = {int(op): op.name.lower().replace("_", " ") for op in Opcode}
_BLOCK = 1 << 20


def _name(opcode: int) -> str:
    return _NAMES.get(opcode, f"opcode 0x{opcode:02x}")


def chunk_problem(body: bytes) -> str | None:
    """What is wrong with one chunk record's body (after opcode and length), or None.

    Checks that the body parses as a chunk, that its records decompress to the stored size and
    that their CRC32 matches the stored one (a stored CRC of 0 means none was written).
    """
    try:
        chunk = Chunk.read(ReadDataStream(_Exact(body)))  # type: ignore[arg-type]  # read() only
    except Exception as err:  # a damaged header: lengths that run past the record, bad text
        return f"unreadable chunk header ({type(err).__name__})"
    try:
        if chunk.compression == "zstd":
            data = zstandard.ZstdDecompressor().decompress(
                chunk.data, max_output_size=max(chunk.uncompressed_size, 1)
            )
        elif chunk.compression == "lz4":
            import lz4.frame  # an mcap dependency when lz4 bags are read at all

            data = lz4.frame.decompress(chunk.data)
        elif chunk.compression == "":
            data = chunk.data
        else:
            return f"unknown compression {chunk.compression[:20]!r}"
    except Exception as err:  # zstd / lz4 errors on a corrupt frame
        text = " ".join(str(err).split())[:120] or type(err).__name__
        return f"corrupt {chunk.compression} data ({text})"
    if len(data) != chunk.uncompressed_size:
        return (
            f"decompresses to {len(data)} bytes, its header says {chunk.uncompressed_size} "
            "(corrupt compressed data)"
        )
    if chunk.uncompressed_crc != 0:
        crc = zlib.crc32(data)
        if crc != chunk.uncompressed_crc:
            return f"CRC mismatch (stored 0x{chunk.uncompressed_crc:08x}, computed 0x{crc:08x})"
    return None


class _Exact:
    """A byte string as a stream that refuses to read past its end (a damaged length)."""

    def __init__(self, data: bytes) -> None:
        self._data = memoryview(data)
        self._pos = 0

    def read(self, size: int = -1) -> bytes:
        if size is None or size < 0:
            size = len(self._data) - self._pos
        if self._pos + size > len(self._data):
            raise EOFError("record runs past its length")
        out = bytes(self._data[self._pos : self._pos + size])
        self._pos += size
        return out


def _read_at(fh: BinaryIO, offset: int, size: int) -> bytes:
    fh.seek(offset)
    return fh.read(size)


def locate_damage(fh: BinaryIO, size: int, *, check_crcs: bool = True) -> str | None:
    """The first damage in an MCAP file, as a clause naming its byte offset; None if none found.

    Args:
        fh: the file, open for binary reading (seekable).
        size: its length in bytes.
        check_crcs: check chunk, data-section and summary CRCs (else only the structure:
            truncation, lengths, decompression).

    Returns:
        e.g. ``"chunk at byte offset 70: CRC mismatch (stored 0x..., computed 0x...)"`` or
        ``"the file ends at byte 4096 inside the chunk at byte offset 70 (163528 bytes long)"``.
    """
    if _read_at(fh, 0, len(MCAP_MAGIC)) != MCAP_MAGIC:
        return "not an MCAP file (bad magic bytes)"
    offset = len(MCAP_MAGIC)
    crc = zlib.crc32(MCAP_MAGIC)
    previous = "header magic"
    while True:
        head = _read_at(fh, offset, _HEAD.size)
        if len(head) < _HEAD.size:
            return (
                f"the file ends at byte {size} after the {previous} "
                "(no footer: the recording was cut short)"
            )
        opcode, length = _HEAD.unpack(head)
        if opcode == 0:
            return f"record at byte offset {offset}: invalid opcode 0 (damaged bytes)"
        end = offset + _HEAD.size + length
        if end > size:
            return (
                f"the file ends at byte {size} inside the {_name(opcode)} record at byte offset "
                f"{offset} ({length} bytes long)"
            )
        if opcode == Opcode.CHUNK:
            problem = chunk_problem(_read_at(fh, offset + _HEAD.size, length))
            if problem is not None and (check_crcs or not problem.startswith("CRC mismatch")):
                return f"chunk at byte offset {offset}: {problem}"
        if opcode == Opcode.DATA_END:
            body = _read_at(fh, offset + _HEAD.size, length)
            stored = struct.unpack_from("<I", body)[0] if len(body) >= 4 else 0
            if check_crcs and stored != 0 and stored != crc:
                return (
                    f"data section CRC mismatch (stored 0x{stored:08x}, computed 0x{crc:08x}) "
                    f"in a record between byte offsets {len(MCAP_MAGIC)} and {offset} outside "
                    "every chunk (the chunks' own CRCs match)"
                )
        if opcode == Opcode.FOOTER:
            return _footer_problem(fh, offset, length, size, check_crcs)
        if opcode != Opcode.DATA_END:
            crc = _crc_range(fh, offset, end, crc)
        previous = f"{_name(opcode)} record at byte offset {offset}"
        offset = end


def tail_problem(fh: BinaryIO, size: int, *, check_crcs: bool = True) -> str | None:
    """The footer, the closing magic and the summary CRC (cheap: the summary is small).

    Returns None when they hold, else a clause (``"no footer ..."`` for a file that does not
    end in one: :func:`locate_damage` then says where it was cut).
    """
    footer_offset = size - len(MCAP_MAGIC) - _HEAD.size - 20
    if footer_offset < len(MCAP_MAGIC):
        return "no footer (the file is too short)"
    opcode, length = _HEAD.unpack(_read_at(fh, footer_offset, _HEAD.size))
    closing = _read_at(fh, size - len(MCAP_MAGIC), len(MCAP_MAGIC))
    if opcode != Opcode.FOOTER or length != 20 or closing != MCAP_MAGIC:
        return "no footer and closing magic at the end of the file"
    return _footer_problem(fh, footer_offset, length, size, check_crcs)


def complete_prefix(fh: BinaryIO, size: int) -> int:
    """The byte offset where the last complete data-section record of a cut file ends.

    Walks the records from the start (structure only) and stops at the first that runs past
    the end of the file, has opcode 0, or is the data end / footer.
    """
    offset = len(MCAP_MAGIC)
    while True:
        head = _read_at(fh, offset, _HEAD.size)
        if len(head) < _HEAD.size:
            return offset
        opcode, length = _HEAD.unpack(head)
        end = offset + _HEAD.size + length
        if opcode in (0, Opcode.DATA_END, Opcode.FOOTER) or end > size:
            return offset
        offset = end


def _crc_range(fh: BinaryIO, start: int, stop: int, crc: int) -> int:
    fh.seek(start)
    remaining = stop - start
    while remaining > 0:
        block = fh.read(min(_BLOCK, remaining))
        if not block:
            break
        crc = zlib.crc32(block, crc)
        remaining -= len(block)
    return crc


def _footer_problem(
    fh: BinaryIO, offset: int, length: int, size: int, check_crcs: bool
) -> str | None:
    end = offset + _HEAD.size + length
    if length != 20:
        return f"footer at byte offset {offset}: length {length}, expected 20 (damaged bytes)"
    if _read_at(fh, end, len(MCAP_MAGIC)) != MCAP_MAGIC or end + len(MCAP_MAGIC) != size:
        return f"no closing magic after the footer at byte offset {offset}"
    summary_start, _summary_offset_start, stored = struct.unpack(
        "<QQI", _read_at(fh, offset + _HEAD.size, 20)
    )
    if check_crcs and stored != 0:
        start = summary_start or offset
        if not len(MCAP_MAGIC) <= start <= offset:
            return f"footer at byte offset {offset}: summary start {summary_start} out of range"
        crc = _crc_range(fh, start, end - 4, 0)
        if crc != stored:
            return (
                f"summary CRC mismatch (stored 0x{stored:08x}, computed 0x{crc:08x}) in the "
                f"summary section at byte offsets {start}..{offset}"
            )
    return None
