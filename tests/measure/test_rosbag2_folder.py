"""``measure bag`` on a rosbag2 folder as ``ros2 bag record`` writes it (``metadata.yaml`` plus
``.mcap`` files), and the one-line refusals of a SQLite bag and of a broken ``metadata.yaml``.

The folder is the known Kelvin–Voigt bag of tests/_helpers/ros2_bags.py split at a message
boundary into two MCAP files: read through its ``metadata.yaml`` it must give exactly the
squeezes the single file gives, and the D the bag was written with.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml
from mcap.reader import make_reader
from mcap.writer import Writer
from typer.testing import CliRunner

from deformctl.characterize import fit_lsq
from deformctl.cli import app
from deformctl.errors import InputDataError, MissingInputError
from deformctl.measure import BagSource, read_recording
from tests._helpers.cli import _error
from tests._helpers.ros2_bags import LEFT, POSE, RIGHT, write_bag

from ._errors import _err

runner = CliRunner()
TOPICS = BagSource(wrench_topics=(LEFT, RIGHT), position_topic=POSE)
CLI_TOPICS = ["--wrench-topic", LEFT, "--wrench-topic", RIGHT, "--position-topic", POSE,
              "--object-id", "sand", "--weight-n", "2.9"]  # fmt: skip


def split_bag(single: Path, folder: Path, n_files: int = 2) -> dict[str, int]:
    """Write ``single``'s messages into ``n_files`` MCAP files of ``folder`` (in log-time
    order, split at message boundaries) and its rosbag2 ``metadata.yaml``; return the counts."""
    with single.open("rb") as fh:
        messages = list(make_reader(fh).iter_messages())
    folder.mkdir()
    bounds = np.linspace(0, len(messages), n_files + 1).astype(int)
    names = [f"{folder.name}_{i}.mcap" for i in range(n_files)]
    counts: dict[str, int] = {}
    types: dict[str, str] = {}
    for name, lo, hi in zip(names, bounds[:-1], bounds[1:], strict=True):
        with (folder / name).open("wb") as out:
            w = Writer(out)
            w.start(profile="ros2", library="test")
            schema_ids: dict[int, int] = {}
            channel_ids: dict[int, int] = {}
            for schema, channel, message in messages[lo:hi]:
                if schema.id not in schema_ids:
                    schema_ids[schema.id] = w.register_schema(
                        schema.name, schema.encoding, schema.data
                    )
                if channel.id not in channel_ids:
                    channel_ids[channel.id] = w.register_channel(
                        channel.topic, channel.message_encoding, schema_ids[schema.id]
                    )
                w.add_message(
                    channel_ids[channel.id], message.log_time, message.data, message.publish_time
                )
                counts[channel.topic] = counts.get(channel.topic, 0) + 1
                types[channel.topic] = schema.name
            w.finish()
    write_metadata(folder, names, counts, types)
    return counts


def write_metadata(
    folder: Path,
    files: list[str],
    counts: dict[str, int],
    types: dict[str, str] | None = None,
    storage: str = "mcap",
) -> None:
    """A rosbag2 ``metadata.yaml`` (the layout ``ros2 bag record`` writes, version 5)."""
    info = {
        "version": 5,
        "storage_identifier": storage,
        "relative_file_paths": files,
        "message_count": sum(counts.values()),
        "topics_with_message_count": [
            {
                "topic_metadata": {
                    "name": t,
                    "type": (types or {}).get(t, ""),
                    "serialization_format": "cdr",
                    "offered_qos_profiles": "",
                },
                "message_count": n,
            }
            for t, n in counts.items()
        ],
        "compression_format": "",
        "compression_mode": "",
    }
    (folder / "metadata.yaml").write_text(yaml.safe_dump({"rosbag2_bagfile_information": info}))


@pytest.fixture(scope="module")
def bags(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, dict[str, int]]:
    root = tmp_path_factory.mktemp("rosbag2")
    single = root / "single.mcap"
    write_bag(single, 30.02, 6.47, seed=1, force_rate_hz=250.0)
    counts = split_bag(single, root / "run")
    return single, root / "run", counts


def _copy(folder: Path, tmp_path: Path) -> Path:
    dst = tmp_path / folder.name
    shutil.copytree(folder, dst)
    return dst


def test_a_folder_reads_as_its_single_file(bags: tuple[Path, Path, dict[str, int]]) -> None:
    single, folder, counts = bags
    assert len(list(folder.glob("*.mcap"))) == 2
    assert counts[LEFT] == counts[RIGHT] > 2_500  # 250 Hz over ~17 s, split mid-recording
    one = read_recording(single, TOPICS, "sand").squeezes
    split = read_recording(folder, TOPICS, "sand").squeezes
    assert len(split) == len(one) == 3
    for a, b in zip(one, split, strict=True):
        np.testing.assert_array_equal(a.time_s, b.time_s)
        np.testing.assert_array_equal(a.force_n, b.force_n)
        np.testing.assert_array_equal(a.compression_m, b.compression_m)
    fit = fit_lsq(split, window_s=0.5)
    assert fit.deformability_n_per_cm == pytest.approx(30.02, rel=0.05)


def test_measure_bag_cli_takes_the_folder(
    bags: tuple[Path, Path, dict[str, int]], tmp_path: Path
) -> None:
    _, folder, _ = bags
    out = tmp_path / "squeeze.mcap"
    res = runner.invoke(app, ["measure", "bag", str(folder), *CLI_TOPICS, "-o", str(out)])
    assert res.exit_code == 0, res.stderr
    assert "3 squeeze(s) of 'sand'" in res.stderr
    assert out.stat().st_size > 0


def test_files_listed_out_of_order_are_refused(
    bags: tuple[Path, Path, dict[str, int]], tmp_path: Path
) -> None:
    _, folder, counts = bags
    bad = _copy(folder, tmp_path)
    write_metadata(bad, ["run_1.mcap", "run_0.mcap"], counts)
    _err(
        lambda: read_recording(bad, TOPICS, "sand").squeezes,
        InputDataError,
        "non-monotonic timestamps",
    )


def test_a_file_left_out_is_caught_by_the_message_counts(
    bags: tuple[Path, Path, dict[str, int]], tmp_path: Path
) -> None:
    _, folder, counts = bags
    bad = _copy(folder, tmp_path)
    write_metadata(bad, ["run_0.mcap"], counts)  # the index still states both files' messages
    msg = _err(lambda: read_recording(bad, TOPICS, "sand").squeezes, InputDataError, "states")
    assert f"states {counts[LEFT]} messages on topic '{LEFT}'" in msg


def test_a_listed_file_that_is_missing_exits_66(
    bags: tuple[Path, Path, dict[str, int]], tmp_path: Path
) -> None:
    _, folder, _ = bags
    bad = _copy(folder, tmp_path)
    (bad / "run_1.mcap").unlink()
    _err(lambda: read_recording(bad, TOPICS, "sand").squeezes, MissingInputError, "run_1.mcap")
    res = runner.invoke(app, ["measure", "bag", str(bad), *CLI_TOPICS, "-o", str(tmp_path / "o")])
    assert "run_1.mcap" in _error(res, 66)


@pytest.mark.parametrize(
    ("text", "words"),
    [
        (None, "no metadata.yaml"),
        ("rosbag2_bagfile_information: [unclosed\n", "not readable as YAML"),
        ("just text\n", "no rosbag2_bagfile_information"),
        ("rosbag2_bagfile_information:\n  storage_identifier: mcap\n", "relative_file_paths"),
        (
            "rosbag2_bagfile_information:\n  storage_identifier: mcap\n"
            "  relative_file_paths: [run_0.mcap]\n  topics_with_message_count: [{a: 1}]\n",
            "lacks its name or count",
        ),
        (b"\xff\xfe\x00garbage", "not readable as YAML"),
    ],
    ids=["missing", "unclosed", "scalar", "no-files", "bad-count", "binary"],
)
def test_a_missing_or_garbled_metadata_is_one_line_exit_65(
    bags: tuple[Path, Path, dict[str, int]], tmp_path: Path, text: str | bytes | None, words: str
) -> None:
    _, folder, _ = bags
    bad = _copy(folder, tmp_path)
    meta = bad / "metadata.yaml"
    if text is None:
        meta.unlink()
    elif isinstance(text, bytes):
        meta.write_bytes(text)
    else:
        meta.write_text(text)
    res = runner.invoke(app, ["measure", "bag", str(bad), *CLI_TOPICS, "-o", str(tmp_path / "o")])
    assert words in _error(res, 65)
    assert not (tmp_path / "o").exists()


def test_a_sqlite_bag_points_to_a_converter(tmp_path: Path) -> None:
    db3 = tmp_path / "run_0.db3"
    db3.write_bytes(b"SQLite format 3\x00" + bytes(100))
    folder = tmp_path / "run"
    folder.mkdir()
    shutil.copy(db3, folder / db3.name)
    write_metadata(folder, [db3.name], {LEFT: 1}, storage="sqlite3")
    renamed = tmp_path / "export.bin"  # the header, not the name, says SQLite
    shutil.copy(db3, renamed)
    no_meta = tmp_path / "no_meta"
    no_meta.mkdir()
    shutil.copy(db3, no_meta / db3.name)
    for path in (db3, folder, renamed, no_meta):
        args = ["measure", "bag", str(path), *CLI_TOPICS, "-o", str(tmp_path / "o.mcap")]
        line = _error(runner.invoke(app, args), 65)
        assert "SQLite (.db3) ROS 2 bag" in line
        assert "rosbags-convert" in line
        assert "ros2 bag convert" in line


def test_another_storage_or_a_compressed_file_is_refused(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    folder.mkdir()
    write_metadata(folder, ["run_0.mcap"], {LEFT: 1}, storage="rosbag_v1")
    with pytest.raises(InputDataError, match="storage_identifier 'rosbag_v1'"):
        read_recording(folder, TOPICS, "sand")
    write_metadata(folder, ["run_0.mcap.zstd"], {LEFT: 1})
    _err(lambda: read_recording(folder, TOPICS, "sand").squeezes, InputDataError, "decompress")
    write_metadata(folder, ["../elsewhere.mcap"], {LEFT: 1})
    _err(lambda: read_recording(folder, TOPICS, "sand").squeezes, InputDataError, "outside the bag")
