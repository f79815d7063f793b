"""Logs on a real clock: ``log_time`` keeps a recording's own timestamps, simulated logs start
at a fixed epoch, and each object has its own channel.

A ROS 2 bag written here (``tests/_helpers/ros2_bags.py``) logs every message 20 ms after
its header stamp, as a recorder does; the squeeze log made from it must carry the header stamps,
not the receive times. The wrench and position topics share their stamps (both 1 kHz from the
same instant), so the squeeze log of the whole recording (``--no-segment``) spans exactly the
bag's stamp range.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from typer.testing import CliRunner

from deformctl.artifacts import read_squeeze_log
from deformctl.artifacts.mcap import LOG_EPOCH_NS
from deformctl.cli import app
from deformctl.errors import EXIT_USAGE
from tests._helpers.ros2_bags import EPOCH_NS, LEFT, POSE, RIGHT, write_bag

runner = CliRunner()
RECEIVE_DELAY_S = 0.02


def _bag_stamps(bag: Path) -> dict[str, list[int]]:
    """Header stamps (ns) per topic, decoded from the bag with mcap-ros2-support."""
    out: dict[str, list[int]] = {}
    with bag.open("rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        for _, channel, _, msg in reader.iter_decoded_messages():
            stamp = msg.header.stamp
            out.setdefault(channel.topic, []).append(stamp.sec * 1_000_000_000 + stamp.nanosec)
    return out


def _log_times(path: Path) -> list[tuple[str, int]]:
    with path.open("rb") as fh:
        return [(c.topic, m.log_time) for _, c, m in make_reader(fh).iter_messages()]


@pytest.fixture(scope="module")
def bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("clock") / "run.mcap"
    write_bag(path, 30.0, 0.5, seed=4, force_rate_hz=250.0, pose_rate_hz=250.0, pose_offset_s=0.0,
              receive_delay_s=RECEIVE_DELAY_S)  # fmt: skip
    return path


def _measure_bag(bag: Path, out: Path, *extra: str) -> None:
    args = ["measure", "bag", str(bag), "--wrench-topic", LEFT, "--wrench-topic", RIGHT,
            "--position-topic", POSE, "--object-id", "sand", "--weight-n", "2.9",
            "-o", str(out)]  # fmt: skip
    res = runner.invoke(app, [*args, *extra])
    assert res.exit_code == 0, res.stderr


def test_a_converted_bags_log_time_range_is_the_bags_stamp_range(bag: Path, tmp_path: Path) -> None:
    stamps = _bag_stamps(bag)
    assert stamps[LEFT] == stamps[RIGHT] == stamps[POSE]  # one clock for every topic
    out = tmp_path / "squeeze.mcap"
    _measure_bag(bag, out, "--no-segment")
    logged = _log_times(out)
    times = [ns for _, ns in logged]
    assert (min(times), max(times)) == (min(stamps[LEFT]), max(stamps[LEFT]))
    assert times == stamps[LEFT]  # every sample at its force message's header stamp
    assert min(times) == EPOCH_NS  # not the receive time, 20 ms later
    assert {topic for topic, _ in logged} == {"/squeeze/sand"}
    _, (squeeze,) = read_squeeze_log(out)
    assert squeeze.time_s[0] == 0.0  # the readers still return time since the squeeze began
    assert squeeze.time_s[-1] == pytest.approx((times[-1] - times[0]) / 1e9)


def test_segmented_squeezes_sit_at_their_stamps(bag: Path, tmp_path: Path) -> None:
    stamps = _bag_stamps(bag)[LEFT]
    out = tmp_path / "squeeze.mcap"
    _measure_bag(bag, out)  # cut into its three squeezes
    times = [ns for _, ns in _log_times(out)]
    assert times == sorted(times)
    assert set(times) <= set(stamps)
    _, squeezes = read_squeeze_log(out)
    assert [s.squeeze_index for s in squeezes] == [0, 1, 2]
    first = 0
    for s in squeezes:  # each squeeze's samples are a contiguous run of the bag's stamps
        start = stamps.index(times[first])
        expect = [stamps[start] + round(t * 1e9) for t in s.time_s]
        assert times[first : first + len(s)] == pytest.approx(expect, abs=1)
        first += len(s)


def _csv(path: Path, t0_s: float) -> None:
    t = np.arange(0.0, 2.0, 0.01)
    force = 10.0 * np.sin(np.pi * t / 2.0)
    rows = np.column_stack([t0_s + t, force, force / 2000.0 * 1000.0])  # compression in mm
    np.savetxt(path, rows, delimiter=",", header="t,load,pos", comments="", fmt="%.6f")


def _measure_csv(csv: Path, out: Path, *extra: str) -> int:
    res = runner.invoke(app, ["measure", "csv", str(csv), "--columns",
                              "time=t,force=load,compression=pos", "--units", "compression=mm",
                              "--object-id", "foam", "--weight-n", "0.7", "-o", str(out),
                              *extra])  # fmt: skip
    assert res.exit_code == 0, res.stderr
    return res.exit_code


def test_csv_with_unix_times_keeps_them_and_relative_times_start_at_the_epoch(
    tmp_path: Path,
) -> None:
    unix = tmp_path / "unix.csv"
    _csv(unix, 1_717_243_200.0)  # 2024-06-01T12:00:00Z
    _measure_csv(unix, tmp_path / "unix.mcap")
    times = [ns for _, ns in _log_times(tmp_path / "unix.mcap")]
    assert times[0] == 1_717_243_200 * 10**9
    assert times[-1] == pytest.approx((1_717_243_200 + 1.99) * 1e9, abs=1e3)
    relative = tmp_path / "relative.csv"
    _csv(relative, 0.0)
    _measure_csv(relative, tmp_path / "relative.mcap")
    times = [ns for _, ns in _log_times(tmp_path / "relative.mcap")]
    assert times[0] == LOG_EPOCH_NS
    assert times == sorted(times)


CATALOG = (
    "object_id,weight_n,size_x_cm,size_y_cm,size_z_cm,friction_mu,"
    "material_stiffness_n_per_cm,material_damping_ns_per_cm\n"
    "a,1.0,4,4,4,0.5,20,1\n"
    "b,1.5,4,4,4,0.5,30,2\n"
)


def _measure_sim(tmp_path: Path, out: str, *extra: str) -> list[tuple[str, int]]:
    catalog = tmp_path / "objects.csv"
    catalog.write_text(CATALOG)
    res = runner.invoke(app, ["measure", "sim", str(catalog), "--squeezes", "2",
                              "--alpha-cm", "2", "--hold-s", "0.1", "-o", str(tmp_path / out),
                              *extra])  # fmt: skip
    assert res.exit_code == 0, res.stderr
    return _log_times(tmp_path / out)


def test_simulated_logs_start_at_a_fixed_epoch_one_channel_per_object(tmp_path: Path) -> None:
    logged = _measure_sim(tmp_path, "sim.mcap")
    assert logged[0][1] == LOG_EPOCH_NS == 946_684_800 * 10**9  # 2000-01-01T00:00:00Z
    times = [ns for _, ns in logged]
    assert times == sorted(times)
    # one channel per object, beside the scene's two shared topics (deformctl.artifacts.mcap.scene)
    assert {t for t, _ in logged} == {"/squeeze/a", "/squeeze/b", "/scene", "/palms"}
    # squeezes one after another: b's first sample comes after a's last
    last_a = max(ns for t, ns in logged if t == "/squeeze/a")
    assert min(ns for t, ns in logged if t == "/squeeze/b") == last_a + 10**9
    again = _measure_sim(tmp_path, "again.mcap")
    assert again == logged  # deterministic
    iso = _measure_sim(tmp_path, "iso.mcap", "--log-epoch", "2024-05-01T12:00:00Z")
    seconds = _measure_sim(tmp_path, "seconds.mcap", "--log-epoch", "1714564800")
    shift = 1_714_564_800 * 10**9 - LOG_EPOCH_NS
    assert [ns for _, ns in iso] == [ns for _, ns in seconds] == [ns + shift for ns in times]


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ("yesterday", "--log-epoch must be an ISO 8601 time or seconds since 1970"),
        ("inf", "--log-epoch must be a finite time, got 'inf'"),
        ("-5", "--log-epoch must lie between 1970 and 2500, got '-5'"),
        ("1969-12-31T23:59:59Z", "--log-epoch must lie between 1970 and 2500"),
        ("3000-01-01", "--log-epoch must lie between 1970 and 2500"),
    ],
)
def test_bad_log_epoch_is_a_usage_error(tmp_path: Path, value: str, message: str) -> None:
    catalog = tmp_path / "objects.csv"
    catalog.write_text(CATALOG)
    res = runner.invoke(app, ["measure", "sim", str(catalog), "--log-epoch", value, "-o",
                              str(tmp_path / "s.mcap")])  # fmt: skip
    assert res.exit_code == EXIT_USAGE
    assert res.stderr.startswith("error: " + message)
    assert len(res.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "s.mcap").exists()


def test_log_epoch_is_only_for_simulated_logs(bag: Path, tmp_path: Path) -> None:
    res = runner.invoke(app, ["measure", "bag", str(bag), "--wrench-topic", LEFT,
                              "--position-topic", POSE, "--object-id", "s", "--weight-n", "1",
                              "--log-epoch", "0", "-o", str(tmp_path / "s.mcap")])  # fmt: skip
    assert res.exit_code == EXIT_USAGE
    assert "--log-epoch" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
