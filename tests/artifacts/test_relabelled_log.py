"""``inspect`` checks a log's content against its declared kind.

A squeeze log rewritten (with the mcap library, every CRC valid) so that its ``deformctl``
record says ``lift_log`` is refused with one line naming both kinds (exit 65); the log as
written is described as a squeeze log.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from mcap.reader import make_reader
from mcap.writer import Writer
from typer.testing import CliRunner

from deformctl.artifacts.mcap import write_squeeze_log
from deformctl.cli import app
from deformctl.measure.recording import SqueezeSeries

runner = CliRunner()


def _relabel(src: Path, dst: Path, kind: str) -> None:
    with src.open("rb") as fh_in, dst.open("wb") as fh_out:
        reader = make_reader(fh_in)
        summary = reader.get_summary()
        assert summary is not None
        writer = Writer(fh_out, enable_data_crcs=True)
        header = reader.get_header()
        writer.start(profile=header.profile, library=header.library)
        for schema in summary.schemas.values():
            writer.register_schema(schema.name, schema.encoding, schema.data)
        for channel in summary.channels.values():
            writer.register_channel(
                channel.topic, channel.message_encoding, channel.schema_id, channel.metadata
            )
        for record in reader.iter_metadata():
            data = dict(record.metadata)
            if record.name == "deformctl":
                data["kind"] = kind
            writer.add_metadata(record.name, data)
        for _, channel, message in reader.iter_messages():
            writer.add_message(channel.id, message.log_time, message.data, message.publish_time)
        writer.finish()


def test_a_relabelled_log_is_refused_and_the_real_one_described(tmp_path: Path) -> None:
    log = tmp_path / "squeeze.mcap"
    t = np.linspace(0.0, 1.0, 50)
    write_squeeze_log(log, [], [SqueezeSeries("A", 0, t, t, t * 1e-3)], provenance=None)
    res = runner.invoke(app, ["inspect", str(log)])
    assert res.exit_code == 0, res.stderr
    assert "kind: squeeze_log" in res.stdout
    fake = tmp_path / "fake.mcap"
    _relabel(log, fake, "lift_log")
    res = runner.invoke(app, ["inspect", str(fake)])
    assert res.exit_code == 65
    assert res.stderr == (
        f"error: {fake}: declares kind 'lift_log' but its channels are a squeeze_log's "
        "('/squeeze/A'): the content does not match the label\n"
    )
