"""``measure sim|csv|bag|images`` and ``lift sim|rig``: the old flag forms still run, print one
deprecation line and write the same bytes; every subcommand's help is short.

The logs and tables record the command line (``sys.argv``) in their provenance; under the test
runner it is the same for both forms, so their files can be compared byte for byte.
"""

from __future__ import annotations

import shlex
import sys
from pathlib import Path

import cv2
import pytest
from typer.testing import CliRunner

from deformctl.cli import app
from deformctl.vision.synth import box_scenes, render

runner = CliRunner()
REPO = Path(__file__).resolve().parents[2]
PAPER = str(REPO / "datasets" / "paper" / "objects.csv")
EXAMPLES = REPO / "datasets" / "examples"
RIG = shlex.join([sys.executable, str(REPO / "examples" / "threshold_rig.py")])
FAST_SQUEEZE = ["--objects", "A,C", "--squeezes", "1", "--ramp-s", "0.05", "--hold-s", "0.05",
                "--dt-s", "0.002", "--alpha-cm", "10", "--workers", "1"]  # fmt: skip
FAST_LIFT = ["--objects", "A", "--alpha-cm", "10", "--dt-s", "0.002", "--lift-hold-s", "0.05",
             "--workers", "1"]  # fmt: skip
BAG = ["--wrench-topic", "/left/wrench", "--wrench-topic", "/right/wrench", "--position-topic",
       "/left/palm_pose", "--object-id", "sponge", "--weight-n", "0.6"]  # fmt: skip
CSV = ["--object-id", "foam", "--weight-n", "2.9", "--size-cm", "6", "6", "4"]
#: The help of each subcommand, at most this many lines (at the test runner's width, 80).
HELP_LINES = 60
SUBCOMMANDS = [("measure", "sim"), ("measure", "csv"), ("measure", "bag"),
               ("measure", "images"), ("lift", "sim"), ("lift", "rig")]  # fmt: skip


def _photos(tmp_path: Path) -> list[str]:
    top, cam_top, side, cam_side = box_scenes((12.0, 7.0, 5.0), (40, 40, 200), marker_size_cm=5.0)
    paths = [tmp_path / "top.png", tmp_path / "side.png"]
    for path, scene, camera, seed in ((paths[0], top, cam_top, 1), (paths[1], side, cam_side, 2)):
        assert cv2.imwrite(str(path), render(scene, camera, seed=seed))
    return [str(p) for p in paths]


def _forms(tmp_path: Path, command: str, source: str) -> tuple[list[str], list[str], list[str]]:
    """(the old form, the new form, the outputs), the outputs named ``{out}`` in both."""
    squeeze, lift = ["-o", "{out}/s.mcap"], ["-o", "{out}/lift.parquet", "--log", "{out}/lift.mcap"]
    if (command, source) == ("measure", "sim"):
        old, new, rest = [PAPER, "--sim"], [PAPER], [*FAST_SQUEEZE, *squeeze]
    elif source in ("csv", "bag"):
        path = str(EXAMPLES / ("utm_export.csv" if source == "csv" else "gripper.mcap"))
        old, new, rest = (
            [f"--{source}", path],
            [path],
            [*(CSV if source == "csv" else BAG), *squeeze],
        )
    elif source == "images":
        photos = _photos(tmp_path)
        old, new = ["--images", *photos], photos
        rest = ["--marker-size-cm", "5", "--object-id", "box", "--weight-n", "2.5",
                "--friction-mu", "0.6", "-o", "{out}/catalog.csv"]  # fmt: skip
        return [*old, *rest], [source, *new, *rest], ["catalog.csv"]
    elif source == "sim":
        old, new, rest = [PAPER, "--sim"], [PAPER], [*FAST_LIFT, *lift]
        return [*old, *rest], [source, *new, *rest], ["lift.parquet", "lift.mcap"]
    else:  # a rig's attempts keep the wall clock: its table, and its attempts without the clock
        old, new, rest = (
            [PAPER, "--rig", RIG],
            [PAPER, "--command", RIG],
            ["--objects", "A,B", *lift],
        )
        return [*old, *rest], [source, *new, *rest], ["lift.parquet"]
    return [*old, *rest], [source, *new, *rest], ["s.mcap"]


@pytest.mark.parametrize(("command", "source"), SUBCOMMANDS)
def test_the_old_form_writes_the_same_bytes_with_one_notice(
    tmp_path: Path, command: str, source: str
) -> None:
    old, new, outputs = _forms(tmp_path, command, source)
    written = {}
    for name, args in (("old", old), ("new", new)):
        out = tmp_path / name
        out.mkdir()
        argv = [command, *(a.replace("{out}", str(out)) for a in args)]
        res = runner.invoke(app, argv)
        assert res.exit_code == 0, (name, res.stderr)
        notices = [line for line in res.stderr.splitlines() if "deprecated" in line]
        flag = "--" + source
        want = [f"deformctl: '{command} {flag}' is deprecated; use '{command} {source}'"]
        assert notices == (want if name == "old" else []), res.stderr
        written[name] = [(out / o).read_bytes() for o in outputs]
        assert all(written[name]), outputs
        if source == "rig":
            written[name].append(_attempts(out / "lift.mcap"))
    assert written["old"] == written["new"]


def _attempts(log: Path) -> bytes:
    """A rig lift log's attempts (object, index, force, outcome) without their clock."""
    from deformctl.artifacts import read_lift_log

    _, attempts = read_lift_log(log)
    rows = [(a.object_id, a.attempt_index, a.outcome.grip_force_n, a.outcome.lifted,
             a.outcome.slip_m) for a in attempts]  # fmt: skip
    assert rows
    return repr(rows).encode()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["measure", "x.csv", "--sim", "--csv", "y.csv"], "several sources (--csv, --sim)"),
        (["lift", "x.csv", "--sim", "--rig", "true"], "several sources (--rig, --sim)"),
        (["measure", "x.csv"], "'x.csv' is not a source: give one of sim, csv, bag, images"),
        (["lift", "x.csv", "-o", "l.parquet"], "'x.csv' is not a source: give one of sim, rig"),
    ],
)
def test_an_old_form_that_names_no_or_several_sources_is_one_error(
    tmp_path: Path, argv: list[str], message: str
) -> None:
    res = runner.invoke(app, argv)
    assert res.exit_code == 2
    assert res.stdout == ""
    lines = res.stderr.splitlines()
    assert len(lines) == 1, res.stderr
    assert lines[0].startswith("error: ")
    assert message in lines[0]


def test_the_old_form_takes_an_equals_sign_and_keeps_the_file_order(tmp_path: Path) -> None:
    from deformctl.cli._sources import MeasureGroup, rewrite

    flags, names = MeasureGroup.OLD_FLAGS, ["sim", "csv", "bag", "images"]
    assert rewrite("measure", ["b.csv", "--csv=a.csv", "-o", "x"], flags, names) == (
        ["csv", "a.csv", "b.csv", "-o", "x"],
        "deformctl: 'measure --csv' is deprecated; use 'measure csv'",
    )
    assert rewrite("measure", ["csv", "a.csv", "--sim"], flags, names) is None  # the new form
    assert rewrite("measure", ["--help"], flags, names) is None


@pytest.mark.parametrize(("command", "source"), SUBCOMMANDS)
def test_each_subcommand_help_is_short(command: str, source: str) -> None:
    res = runner.invoke(app, [command, source, "--help"])
    assert res.exit_code == 0, res.stderr
    assert f"Usage: deformctl {command} {source}" in res.stdout
    assert "Example: deformctl " in res.stdout
    assert len(res.stdout.splitlines()) <= HELP_LINES, res.stdout


@pytest.mark.parametrize("command", ["measure", "lift"])
def test_the_command_help_lists_its_subcommands(command: str) -> None:
    res = runner.invoke(app, [command, "--help"])
    assert res.exit_code == 0
    listed = [s for c, s in SUBCOMMANDS if c == command]
    assert all(f"  {s} " in res.stdout for s in listed), res.stdout
    assert len(res.stdout.splitlines()) <= HELP_LINES
