"""Bags and deformctl logs are read with CRC checks; damage is named by offset.

Real MCAP files are written (``mcap_ros2`` / the project's log writer), damaged on disk (one bit
flipped inside a compressed chunk, a chunk's zstd frame overwritten, the file cut inside a chunk,
one bit flipped in the summary) and read back. Each damage gives one ``error:`` line naming the
file and the byte offset of the damaged chunk, exit 65 and no output; the good file reads without
a warning. ``--no-crc-check`` reads what can be read and says so.
"""

from __future__ import annotations

import functools
import io
from pathlib import Path

import mcap_ros2.writer
import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.stream_reader import CRCValidationError
from typer.testing import CliRunner

from deformctl.artifacts.mcap import write_squeeze_log
from deformctl.artifacts.mcap.integrity import locate_damage
from deformctl.cli import app
from deformctl.measure.recording import SqueezeSeries
from tests._helpers import ros2_bags
from tests._helpers.ros2_bags import LEFT, POSE, RIGHT, write_bag

runner = CliRunner()
#: Chunk record: opcode (1), length (8), start/end time (16), uncompressed size (8) and CRC (4),
#: compression (4 + 4 for "zstd"), records length (8): the compressed bytes start 53 bytes in.
ZSTD_DATA_AT = 53
CRC_HINT = " (--no-crc-check reads it anyway, at your risk)"


@pytest.fixture(scope="module")
def bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two squeezes at 250 Hz in chunks of 20 kB (several chunks, ~0.5 s to write)."""
    path = tmp_path_factory.mktemp("bag") / "squeeze.mcap"
    small_chunks = functools.partial(mcap_ros2.writer.Writer, chunk_size=20_000)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(ros2_bags, "Writer", small_chunks)
        write_bag(path, 30.02, 6.47, seed=1, force_rate_hz=250.0, n_squeezes=2)
    return path


def _chunks(path: Path) -> list[tuple[int, int]]:
    """(start offset, length) of every chunk, from the bag's own index."""
    with path.open("rb") as fh:
        summary = make_reader(fh).get_summary()
    assert summary is not None
    return [(c.chunk_start_offset, c.chunk_length) for c in summary.chunk_indexes]


def _measure(bag: Path, out: Path, *extra: str) -> tuple[int, str]:
    args = ["measure", "bag", str(bag), "--wrench-topic", LEFT, "--wrench-topic", RIGHT]
    args += ["--position-topic", POSE, "--object-id", "A", "--weight-n", "1", "-o", str(out)]
    res = runner.invoke(app, [*args, *extra])
    return res.exit_code, res.stderr


def _damaged(bag: Path, tmp_path: Path, edit: bytes, at: int) -> Path:
    data = bytearray(bag.read_bytes())
    data[at : at + len(edit)] = edit
    path = tmp_path / "damaged.mcap"
    path.write_bytes(bytes(data))
    return path


def _flip(bag: Path, tmp_path: Path, at: int) -> Path:
    return _damaged(bag, tmp_path, bytes([bag.read_bytes()[at] ^ 0x01]), at)


def test_good_bag_reads_without_a_warning(bag: Path, tmp_path: Path) -> None:
    assert len(_chunks(bag)) >= 4
    code, err = _measure(bag, tmp_path / "log.mcap")
    assert code == 0, err
    assert "warning" not in err
    assert locate_damage(io.BytesIO(bag.read_bytes()), bag.stat().st_size) is None


def test_flipped_bit_in_a_chunk_is_refused_naming_its_offset(bag: Path, tmp_path: Path) -> None:
    start, length = _chunks(bag)[2]
    damaged = _flip(bag, tmp_path, start + ZSTD_DATA_AT + length // 2)
    with damaged.open("rb") as fh, pytest.raises(CRCValidationError):  # the mcap library agrees
        list(make_reader(fh, validate_crcs=True).iter_messages())
    out = tmp_path / "log.mcap"
    code, err = _measure(damaged, out)
    assert code == 65
    line = f"error: {damaged}: damaged MCAP file: chunk at byte offset {start}: CRC mismatch"
    assert err.startswith(line)
    assert err.endswith(CRC_HINT + "\n")
    assert err.count("\n") == 1
    assert not out.exists()


def test_no_crc_check_reads_the_flipped_bag_and_warns(bag: Path, tmp_path: Path) -> None:
    start, length = _chunks(bag)[2]
    damaged = _flip(bag, tmp_path, start + ZSTD_DATA_AT + length // 2)
    out = tmp_path / "log.mcap"
    code, err = _measure(damaged, out, "--no-crc-check")
    assert code == 0, err
    assert err.startswith(f"warning: {damaged}: chunk CRCs not checked (--no-crc-check)")
    assert out.exists()


def test_corrupt_compressed_chunk_is_refused_even_without_crc_check(
    bag: Path, tmp_path: Path
) -> None:
    start, _ = _chunks(bag)[1]
    damaged = _damaged(bag, tmp_path, b"\0\0\0\0", start + ZSTD_DATA_AT)  # the zstd frame magic
    for extra in ((), ("--no-crc-check",)):
        out = tmp_path / "log.mcap"
        code, err = _measure(damaged, out, *extra)
        assert code == 65
        assert (
            f"error: {damaged}: damaged MCAP file: chunk at byte offset {start}: corrupt zstd"
            in err
        )
        assert "Traceback" not in err
        assert not out.exists()


def test_truncated_bag_is_refused_and_read_up_to_the_cut_on_request(
    bag: Path, tmp_path: Path
) -> None:
    chunks = _chunks(bag)
    start, length = chunks[-2]
    cut = start + length // 2
    damaged = tmp_path / "cut.mcap"
    damaged.write_bytes(bag.read_bytes()[:cut])
    out = tmp_path / "log.mcap"
    code, err = _measure(damaged, out)
    assert code == 65
    assert err == (
        f"error: {damaged}: truncated MCAP file: the file ends at byte {cut} inside the chunk "
        f"record at byte offset {start} ({length - 9} bytes long){CRC_HINT}\n"
    )
    assert not out.exists()
    code, err = _measure(damaged, out, "--no-crc-check")
    assert code == 0, err
    assert f"warning: {damaged}: truncated bag read without CRC checks" in err
    assert f"messages before byte {start}\n" in err
    assert out.exists()


def test_flipped_bit_in_the_summary_is_refused(bag: Path, tmp_path: Path) -> None:
    size = bag.stat().st_size
    damaged = _flip(bag, tmp_path, size - 200)  # inside the summary section (indexes)
    code, err = _measure(damaged, tmp_path / "log.mcap")
    assert code == 65
    assert err.startswith(f"error: {damaged}: damaged MCAP file: summary CRC mismatch")
    assert err.count("\n") == 1


def test_deformctl_log_damage_is_named_by_chunk_offset(tmp_path: Path) -> None:
    log = tmp_path / "squeeze.mcap"
    t = np.linspace(0.0, 1.0, 200)
    write_squeeze_log(log, [], [SqueezeSeries("A", 0, t, t * 1e-3, t)], provenance=None)
    assert runner.invoke(app, ["inspect", str(log)]).exit_code == 0
    with log.open("rb") as fh:
        summary = make_reader(fh).get_summary()
    assert summary is not None
    start = summary.chunk_indexes[0].chunk_start_offset
    length = summary.chunk_indexes[0].chunk_length
    damaged = _flip(log, tmp_path, start + length - 3)
    res = runner.invoke(app, ["inspect", str(damaged)])
    assert res.exit_code == 65
    assert res.stderr.startswith(f"error: {damaged}: damaged MCAP file (data section CRC mismatch)")
    assert f": chunk at byte offset {start}: " in res.stderr
    assert res.stderr.count("\n") == 1
