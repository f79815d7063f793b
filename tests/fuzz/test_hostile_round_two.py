"""The defects of the second hostile run: one ``error:`` line and the documented exit code each.

* a 79 kB catalog of 10,010 columns kept ``inspect`` busy for over 120 s (2.2 GB): a column
  budget refuses it at once, and a wide table within the budget is described in linear time;
* a short catalog row was read with NaN for its missing fields;
* a table without rows made ``predict`` exit 2 with "needs friction";
* a catalog μ of 1e-308 made ``lift`` exit 2 with "max_force_n ... got inf";
* ``measure --bag /dev/zero`` exited 66 with "no such bag file";
* ``measure --bag --no-crc-check`` on a bag with one flipped bit raised OverflowError;
* ``inspect`` described a relabelled log as the kind it claimed when other channels sat
  beside the real ones.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from mcap.reader import make_reader
from mcap.writer import Writer
from typer.testing import CliRunner

from deformctl.artifacts import write_table
from deformctl.artifacts.mcap import write_squeeze_log
from deformctl.artifacts.tables import MAX_COLUMNS
from deformctl.cli import app
from deformctl.measure.recording import SqueezeSeries
from tests._helpers.ros2_bags import write_bag

runner = CliRunner()
HEADER = ["object_id", "size_x_cm", "size_y_cm", "size_z_cm", "weight_n", "friction_mu"]
ROW = ["A", "8", "5", "4", "2", "0.5"]


def _one_error(args: list[str], code: int, words: str) -> str:
    res = runner.invoke(app, args)
    assert res.exit_code == code, (args, res.stdout, res.stderr)
    lines = [ln for ln in res.stderr.splitlines() if not ln.startswith("warning: ")]
    assert len(lines) == 1, res.stderr
    assert lines[0].startswith("error: ")
    assert words in lines[0], lines[0]
    return lines[0]


def _wide(path: Path, extra: int) -> Path:
    cols = HEADER + [f"n{i}" for i in range(extra)]
    path.write_text(",".join(cols) + "\n" + ",".join(ROW + ["1"] * extra) + "\n")
    return path


def test_a_catalog_of_ten_thousand_columns_is_refused_at_once(tmp_path: Path) -> None:
    wide = _wide(tmp_path / "wide.csv", 10_004)
    assert wide.stat().st_size < 90_000
    started = time.perf_counter()
    _one_error(["inspect", str(wide)], 65, f"10010 columns, more than the {MAX_COLUMNS}")
    assert time.perf_counter() - started < 10.0
    frame = pd.DataFrame({f"c{i}": [1.0] for i in range(MAX_COLUMNS + 1)})
    frame.to_parquet(tmp_path / "wide.parquet")
    _one_error(["inspect", str(tmp_path / "wide.parquet")], 65, "columns, more than the")


def test_a_catalog_within_the_budget_is_described_in_linear_time(tmp_path: Path) -> None:
    started = time.perf_counter()
    res = runner.invoke(app, ["inspect", str(_wide(tmp_path / "w.csv", MAX_COLUMNS - 6))])
    assert res.exit_code == 0, res.stderr
    assert time.perf_counter() - started < 30.0  # was quadratic: 36 s profiled


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("A,8,5,4,2,0.5,1\nB,8,5,4,2,0.5\n", "line 3: 6 fields, the header has 7"),
        ("A,8,5,4,2,0.5,1\nB,8,5,4,2,0.5,1,9\n", "line 3: 8 fields, the header has 7"),
    ],
)
def test_a_short_or_long_catalog_row_is_refused(text: str, words: str, tmp_path: Path) -> None:
    path = tmp_path / "cat.csv"
    path.write_text(",".join([*HEADER, "material_damping_ns_per_cm"]) + "\n" + text)
    _one_error(["inspect", str(path)], 65, words)


def test_a_table_without_rows_is_a_data_error(tmp_path: Path) -> None:
    coef = pd.DataFrame(
        {"object_id": ["A"], "deformability_n_per_cm": [30.0], "damping_ns_per_cm": [1.0],
         "quality": ["ok"], "weight_n": [2.0]}
    )  # fmt: skip
    path = tmp_path / "coef.parquet"
    write_table(coef.iloc[:0], path, "coefficients", provenance=None)
    _one_error(["predict", "grip", str(path)], 65, "no rows")


@pytest.mark.parametrize("mu", ["1e-308", "1e-9", "0.001"])
def test_a_tiny_mu_is_refused_by_its_rule(mu: str, tmp_path: Path) -> None:
    path = tmp_path / "cat.csv"
    path.write_text(",".join(HEADER) + "\n" + ",".join([*ROW[:5], mu]) + "\n")
    _one_error(["inspect", str(path)], 65, "friction_mu")
    line = _one_error(["lift", str(path), "--rig", "true", "-o", str(tmp_path / "l.pq")], 65,
                      "friction_mu")  # fmt: skip
    assert "inf" not in line
    _one_error(["predict", "grip", "--weight-n", "2", "--deformability-n-per-cm", "30",
                "--damping-ns-per-cm", "1", "--friction-mu", mu], 2, "--friction-mu")  # fmt: skip


def test_a_device_is_not_a_missing_bag(tmp_path: Path) -> None:
    args = ["--wrench-topic", "/left/wrench", "--position-topic", "/left/palm_pose",
            "--object-id", "A", "--weight-n", "1", "-o", str(tmp_path / "o.mcap")]  # fmt: skip
    _one_error(["measure", "--bag", "/dev/zero", *args], 65, "not a regular file")
    _one_error(["measure", "--bag", str(tmp_path / "none.mcap"), *args], 66, "no such")


def test_a_flipped_length_without_crc_checks_is_a_data_error(tmp_path: Path) -> None:
    bag = tmp_path / "bag.mcap"
    write_bag(bag, 30.0, 6.0, seed=1, force_rate_hz=200.0, n_squeezes=2)
    data = bag.read_bytes()
    args = ["--no-crc-check", "--wrench-topic", "/left/wrench", "--position-topic",
            "/left/palm_pose", "--object-id", "A", "--weight-n", "1"]  # fmt: skip
    rng = np.random.default_rng(0)
    flips = [(39235, 2)] + [(int(rng.integers(len(data))), int(rng.integers(8))) for _ in range(40)]
    for at, bit in flips:
        damaged = bytearray(data)
        damaged[at % len(data)] ^= 1 << bit
        path = tmp_path / "flip.mcap"
        path.write_bytes(bytes(damaged))
        out = tmp_path / "o.mcap"
        res = runner.invoke(app, ["measure", "--bag", str(path), *args, "-o", str(out), "--force"])
        assert res.exception is None or isinstance(res.exception, SystemExit), (at, bit)
        assert res.exit_code in (0, 65), (at, bit, res.stderr)


def _relabel_with_extra(src: Path, dst: Path, kind: str) -> None:
    """``src`` with its declared kind replaced and a foreign channel added beside its own."""
    with src.open("rb") as fh_in, dst.open("wb") as fh_out:
        reader = make_reader(fh_in)
        summary = reader.get_summary()
        assert summary is not None
        writer = Writer(fh_out, enable_data_crcs=True)
        header = reader.get_header()
        writer.start(profile=header.profile, library=header.library)
        ids = {}
        for schema in summary.schemas.values():
            writer.register_schema(schema.name, schema.encoding, schema.data)
        for channel in summary.channels.values():
            ids[channel.id] = writer.register_channel(
                channel.topic, channel.message_encoding, channel.schema_id, channel.metadata
            )
        writer.register_channel("/camera/notes", "json", 0)
        for record in reader.iter_metadata():
            data = dict(record.metadata)
            if record.name == "deformctl":
                data["kind"] = kind
            writer.add_metadata(record.name, data)
        for _, channel, message in reader.iter_messages():
            writer.add_message(ids[channel.id], message.log_time, message.data,
                               message.publish_time)  # fmt: skip
        writer.finish()


def test_a_relabelled_log_beside_foreign_channels_is_refused(tmp_path: Path) -> None:
    log = tmp_path / "squeeze.mcap"
    t = np.linspace(0.0, 1.0, 50)
    write_squeeze_log(log, [], [SqueezeSeries("A", 0, t, t, t * 1e-3)], provenance=None)
    fake = tmp_path / "fake.mcap"
    _relabel_with_extra(log, fake, "lift_log")
    _one_error(["inspect", str(fake)], 65, "declares kind 'lift_log' but its channels are a")
