"""``deformctl measure`` (ROS 2 bag and CSV sources) end to end through ``characterize``.

The bag is written here with ``mcap_ros2.writer`` (``tests/_helpers/ros2_bags.py``): two
``WrenchStamped`` palms at 1 kHz with 1 % force noise and one ``PoseStamped`` palm at 100 Hz with
0.05 mm noise, three ramp-hold-release squeezes of a Kelvin–Voigt object with D = 30.02 N/cm and
λ = 6.47 N·s/cm (the paper's sand bag D). ``measure`` then ``characterize`` with the default
window, chosen from the 100 Hz position rate stored in the log, must give D within 2 % and λ
within 5 %.
"""

from __future__ import annotations

import hashlib
import json
import re
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from deformctl.artifacts import read_squeeze_log, read_table
from deformctl.characterize import default_window_s
from deformctl.cli import app
from deformctl.errors import EXIT_DATAERR, EXIT_FAILURE, EXIT_NOINPUT, EXIT_USAGE
from tests._helpers.measure_cli import (
    D_CSV,
    D_TRUE,
    LAM_CSV,
    LAM_TRUE,
    _fails,
    _kv_csv_rows,
    bag_args,
    csv_args,
)
from tests._helpers.ros2_bags import LEFT, POSE, RIGHT, _backwards_force, _nan_force, write_bag

runner = CliRunner()


@pytest.fixture(scope="module")
def bag_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    """(bag, squeeze log, coefficients) of one measure → characterize run on the good bag."""
    d = tmp_path_factory.mktemp("bag")
    bag, log, coef = d / "run.mcap", d / "squeeze.mcap", d / "coefficients.parquet"
    write_bag(bag, D_TRUE, LAM_TRUE, seed=1)
    res = runner.invoke(app, bag_args(bag, log, "--size-cm", "11.4", "11.4", "9.5"))
    assert res.exit_code == 0, res.stderr
    assert res.stdout == ""
    assert res.stderr.startswith(f"{log}: 3 squeeze(s) of 'sand'")
    res = runner.invoke(app, ["characterize", str(log), "-o", str(coef)])
    assert res.exit_code == 0, res.stderr
    print("\n" + res.stdout)
    return bag, log, coef


def test_bag_log_holds_object_rates_and_provenance(bag_run: tuple[Path, Path, Path]) -> None:
    bag, log, _ = bag_run
    objects, squeezes = read_squeeze_log(log)
    assert [(s.object_id, s.squeeze_index) for s in squeezes] == [("sand", i) for i in range(3)]
    (obj,) = objects
    assert obj == {
        "object_id": "sand",
        "weight_n": 2.9,
        "size_x_cm": 11.4,
        "size_y_cm": 11.4,
        "size_z_cm": 9.5,
        "force_rate_hz": pytest.approx(1000.0, rel=1e-6),
        "position_rate_hz": pytest.approx(100.0, rel=1e-6),
        "source": "ros2_bag",  # characterize fits a rig recording with a preload by default
    }
    info = json.loads(runner.invoke(app, ["inspect", str(log), "--json"]).stdout)
    assert info["kind"] == "squeeze_log"
    assert info["squeezes"] == 3
    prov = info["provenance"]
    assert prov["inputs"] == {str(bag): hashlib.sha256(bag.read_bytes()).hexdigest()}
    settings = prov["settings"]
    assert settings["source"] == "ros2_bag"
    assert settings["wrench_topics"] == [LEFT, RIGHT]
    assert settings["position_topic"] == POSE
    assert settings["position_rate_hz"] == pytest.approx(100.0)


def test_bag_measure_characterize_recovers_d_and_lambda(bag_run: tuple[Path, Path, Path]) -> None:
    _, _, coef = bag_run
    df = read_table(coef, "coefficients")
    (row,) = df.to_dict("records")
    assert row["object_id"] == "sand"
    assert row["method"] == "lsq"
    assert row["n_squeezes"] == 3
    assert row["deformability_n_per_cm"] == pytest.approx(D_TRUE, rel=0.02)
    assert row["damping_ns_per_cm"] == pytest.approx(LAM_TRUE, rel=0.05)
    assert row["quality"] == "ok"
    assert abs(row["preload_n"]) < 0.1  # fitted (a rig recording), and small: no preload
    # the window came from the 100 Hz position rate stored by measure
    settings = df.attrs["provenance"].settings
    assert settings["window_s"] == {"sand": pytest.approx(default_window_s(100.0))}
    assert default_window_s(100.0) == pytest.approx(0.2 * 10 ** (1 / 3))
    print(
        f"\nbag → measure → characterize: D {row['deformability_n_per_cm']:.3f} ({D_TRUE}), "
        f"λ {row['damping_ns_per_cm']:.3f} ({LAM_TRUE}) ± {row['damping_se_ns_per_cm']:.3f}"
    )
    info = json.loads(runner.invoke(app, ["inspect", str(coef), "--json"]).stdout)
    assert info["kind"] == "coefficients"
    assert info["rows"] == 1


# --- CSV ------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def plain_csv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    t, f, gap = _kv_csv_rows(noise=True)
    path = tmp_path_factory.mktemp("csv") / "export.csv"
    lines = ["t,load,width"] + [
        f"{a:.4f},{b:.5f},{c * 1e3:.5f}" for a, b, c in zip(t, f, gap, strict=True)
    ]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_csv_plain_with_units_through_characterize(plain_csv: Path, tmp_path: Path) -> None:
    log, coef = tmp_path / "sq.mcap", tmp_path / "c.parquet"
    res = runner.invoke(
        app,
        csv_args(
            plain_csv,
            log,
            "time=t,force=load,position=width",
            "--units",
            "time=s,force=N,position=mm",
            "--friction-mu",
            "0.5",
        ),
    )
    assert res.exit_code == 0, res.stderr
    objects, squeezes = read_squeeze_log(log)
    assert objects[0]["friction_mu"] == 0.5
    assert objects[0]["position_rate_hz"] == pytest.approx(1000.0)
    assert len(squeezes) == 1
    res = runner.invoke(app, ["characterize", str(log), "-o", str(coef)])
    assert res.exit_code == 0, res.stderr
    (row,) = read_table(coef, "coefficients").to_dict("records")
    assert row["deformability_n_per_cm"] == pytest.approx(D_CSV, rel=0.02)
    assert row["damping_ns_per_cm"] == pytest.approx(LAM_CSV, rel=0.05)
    assert row["quality"] == "ok"
    assert res.stderr.count("warning:") == 0
    print(
        f"\nCSV → measure → characterize: D {row['deformability_n_per_cm']:.3f} ({D_CSV}), "
        f"λ {row['damping_ns_per_cm']:.3f} ({LAM_CSV})"
    )


def test_csv_two_header_rows_units_from_file(tmp_path: Path) -> None:
    t, f, gap = _kv_csv_rows(noise=False, rate_hz=200.0)
    path = tmp_path / "machine.csv"
    lines = ["Zeit,Kraft,Weg", "ms,[kN],(mm)"] + [
        f"{a * 1e3:.6f},{b / 1e3:.12f},{c * 1e3:.12f}" for a, b, c in zip(t, f, gap, strict=True)
    ]
    path.write_text("\n".join(lines) + "\n")
    log = tmp_path / "sq.mcap"
    res = runner.invoke(app, csv_args(path, log, "time=Zeit,force=Kraft,gap=Weg"))
    assert res.exit_code == 0, res.stderr
    _, (sq,) = read_squeeze_log(log)
    np.testing.assert_allclose(sq.time_s, t, atol=1e-9)
    np.testing.assert_allclose(sq.force_n, f, atol=1e-8)
    np.testing.assert_allclose(sq.compression_m, gap[0] - gap, atol=1e-12)


# --- bad inputs ------------------------------------------------------------------------------


def test_topic_not_in_bag_lists_topics(bag_run: tuple[Path, Path, Path], tmp_path: Path) -> None:
    bag = bag_run[0]
    out = tmp_path / "o.mcap"
    args = bag_args(bag, out)
    args[args.index(LEFT)] = "/ft"
    msg = _fails(args, EXIT_DATAERR, "topic '/ft' is not in the bag", out)
    assert msg.endswith(f"topics: {POSE}, {LEFT}, {RIGHT}")


def test_topic_of_wrong_type(bag_run: tuple[Path, Path, Path], tmp_path: Path) -> None:
    out = tmp_path / "o.mcap"
    args = bag_args(bag_run[0], out)
    args[args.index(POSE)] = RIGHT
    args[args.index(RIGHT)] = POSE  # the first RIGHT (a wrench topic) becomes the pose topic
    _fails(
        args,
        EXIT_DATAERR,
        f"topic '{POSE}' has type geometry_msgs/msg/PoseStamped, expected "
        "geometry_msgs/msg/WrenchStamped",
        out,
    )


def _shift_pose(tp: np.ndarray, pos: np.ndarray) -> None:
    tp += 100.0


def _still_pose(tp: np.ndarray, pos: np.ndarray) -> None:
    pos[:] = -0.05


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        ({"edit_pose": _shift_pose}, "force and position streams do not overlap in time"),
        ({"edit_force": _backwards_force}, f"topic '{LEFT}': non-monotonic timestamps"),
        ({"edit_force": _nan_force}, f"topic '{LEFT}': 1 NaN/inf sample(s)"),
        ({"edit_pose": _still_pose}, "no compression: the position signal never moves"),
    ],
    ids=["no_overlap", "non_monotonic", "nan", "zero_displacement"],
)
def test_bad_streams(
    tmp_path: Path, edit: dict[str, Callable[[np.ndarray, np.ndarray], None]], match: str
) -> None:
    bag = tmp_path / "in" / "bad.mcap"
    bag.parent.mkdir()
    # one squeeze at 250 Hz force / 50 Hz pose: enough samples for every edit, quick to write
    write_bag(bag, 20.0, 1.0, n_squeezes=1, force_rate_hz=250.0, pose_rate_hz=50.0, **edit)
    out = tmp_path / "o.mcap"
    msg = _fails(bag_args(bag, out), EXIT_DATAERR, match, out)
    assert msg.startswith(f"error: {bag}: ")


def test_csv_missing_mapped_column(plain_csv: Path, tmp_path: Path) -> None:
    out = tmp_path / "o.mcap"
    _fails(
        csv_args(plain_csv, out, "time=t,force=Force,position=width"),
        EXIT_DATAERR,
        "--columns force='Force' names no column of the header (line 1: 't', 'load', 'width'); "
        "if the header is another line, pass --skip-rows N",
        out,
    )


def test_csv_unknown_unit(plain_csv: Path, tmp_path: Path) -> None:
    out = tmp_path / "o.mcap"
    _fails(
        csv_args(plain_csv, out, "time=t,force=load,position=width", "--units", "force=kgm"),
        EXIT_USAGE,
        "--units: unknown force unit 'kgm' for force; known: N, kN, mN, daN, lbf, ozf, kgf, gf",
        out,
    )
    machine = tmp_path / "in" / "m.csv"
    machine.parent.mkdir()
    machine.write_text("Zeit,Kraft,Weg\ns,furlong,mm\n0,0,0\n1,1,1\n")
    _fails(
        csv_args(machine, out, "time=Zeit,force=Kraft,gap=Weg"),
        EXIT_DATAERR,
        "column 'Kraft' (force): unit 'furlong' in the units row is not a known force unit",
        out,
    )


def test_existing_output_without_force(plain_csv: Path, tmp_path: Path) -> None:
    out = tmp_path / "o.mcap"
    out.write_bytes(b"keep me")
    args = csv_args(plain_csv, out, "time=t,force=load,position=width", "--units", "position=mm")
    _fails(args, EXIT_FAILURE, "exists already, not overwriting (use --force)", out)
    assert out.read_bytes() == b"keep me"
    res = runner.invoke(app, [*args, "--force"])
    assert res.exit_code == 0, res.stderr
    assert read_squeeze_log(out)[1][0].object_id == "foam"


@pytest.mark.parametrize("source", ["bag", "csv"])
def test_missing_input(tmp_path: Path, source: str) -> None:
    out = tmp_path / "o.mcap"
    missing = tmp_path / "nope.file"
    args = csv_args(missing, out, "time=t,force=f,position=p")
    if source == "bag":
        args = bag_args(missing, out)
    _fails(args, EXIT_NOINPUT, f"{missing}: no such file", out)


@pytest.mark.parametrize(
    ("change", "match"),
    [
        (lambda a: a[:1] + a[3:], "measure: no such option: --wrench-topic"),
        (lambda a: [*a, "--csv", "x.csv"], "measure bag: no such option: --csv"),
        (lambda a: [*a, "--columns", "time=t"], "measure bag: no such option: --columns"),
        (lambda a: [x for x in a if x != POSE and x != "--position-topic"], "--position-topic"),
        (lambda a: [*a[:-2], "--weight-n", "0", *a[-2:]], "--weight-n must be a number in [0.001"),
        (lambda a: [x for x in a if x not in ("--object-id", "sand")], "needs --object-id"),
        (lambda a: [*a, "--axis", "w"], "axis must be x, y or z"),
    ],
    ids=["none", "two", "csv_option", "no_position", "weight", "no_object", "axis"],
)
def test_usage_errors(
    bag_run: tuple[Path, Path, Path],
    tmp_path: Path,
    change: Callable[[list[str]], list[str]],
    match: str,
) -> None:
    out = tmp_path / "o.mcap"
    _fails(change(bag_args(bag_run[0], out)), EXIT_USAGE, match, out)


def test_csv_columns_syntax(plain_csv: Path, tmp_path: Path) -> None:
    out = tmp_path / "o.mcap"
    _fails(
        csv_args(plain_csv, out, "time=t,force"),
        EXIT_USAGE,
        "--columns: expected key=value[,key=value...], got 'force'",
        out,
    )


def test_default_window_matters_for_100_hz_positions(bag_run: tuple[Path, Path, Path]) -> None:
    """The 1 kHz default window (0.2 s) on 100 Hz positions: λ biased low, as documented (the
    window fit halves the bias of the pointwise derivative: -4.9 %, was < -10 %)."""
    _, log, coef = bag_run
    out = coef.parent / "w02.parquet"
    res = runner.invoke(app, ["characterize", str(log), "-o", str(out), "--window-s", "0.2"])
    assert res.exit_code == 0, res.stderr
    (row,) = read_table(out, "coefficients").to_dict("records")
    (default,) = read_table(coef, "coefficients").to_dict("records")
    err_02 = row["damping_ns_per_cm"] / LAM_TRUE - 1
    err_default = default["damping_ns_per_cm"] / LAM_TRUE - 1
    print(f"\nλ error at 100 Hz positions: window 0.2 s {err_02:+.1%}, default {err_default:+.1%}")
    assert err_02 < -0.03
    assert abs(err_default) < abs(err_02) / 3


def _readme_invocations(command: str) -> list[list[str]]:
    repo = Path(__file__).resolve().parents[2]
    generated = repo / "docs" / "reference" / "cli.md"
    pages = [repo / "README.md", *sorted(set((repo / "docs").rglob("*.md")) - {generated})]
    text = "\n".join(p.read_text(encoding="utf-8") for p in pages)
    text = re.sub(r"<!--.*?-->", "", text, flags=re.S)  # a docs-test marker quotes commands
    joined = text.replace("\\\n", " ")
    out = []
    for line in joined.splitlines():
        start = line.find(f"deformctl {command} ")
        if start >= 0:
            words = line[start:].split("#")[0].split("|")[0].split(">")[0].split()
            out.append(words[1:])
    return out


@pytest.mark.parametrize("command", ["measure", "characterize"])
def test_readme_examples_parse(command: str) -> None:
    """Every invocation of the command in the README and docs/ uses options the command has."""
    import typer.main

    group = typer.main.get_command(app)
    invocations = _readme_invocations(command)
    assert len(invocations) >= 2
    for args in invocations:
        cmd = group.commands[args[0]]  # type: ignore[attr-defined]
        cmd.make_context(command, args[1:])  # raises click.UsageError on an unknown option
