"""``measure --images`` and ``lift --rig ... --slip-from-frames`` through the CLI, rendered images.

The scenes are rendered here (deformctl.vision.synth) with known geometry: boxes of several sizes
and colours, a tilted top camera (up to 15 degrees), Gaussian noise and a lighting gradient.
Sizes must come back within 3 % or 2 mm, whichever is larger. The CLI has no camera
matrix option, so it assumes a 60-degree horizontal field of view; one case is rendered with a
different focal length (900 px, 56 degrees) to show that the guess only needs to be rough.
"""

from __future__ import annotations

import functools
import shlex
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pandas as pd
import pytest
from numpy.typing import NDArray
from typer.testing import CliRunner

from deformctl.artifacts import read_catalog, read_lift_log, read_table, write_catalog
from deformctl.cli import app
from deformctl.vision.synth import (
    Box,
    Gripper,
    Marker,
    box_scenes,
    camera_tilted_down,
    render,
)

REPO = Path(__file__).resolve().parents[2]
RIG = REPO / "examples" / "frames_render_rig.py"
MARKER_CM = 5.0
NOISE = {"noise_sigma": 4.0, "gradient": (0.75, 1.15)}

cli = CliRunner()


def run(*args: object) -> Any:
    return cli.invoke(app, [str(a) for a in args])


def one_line_error(result: Any) -> str:
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("error: ")
    assert "Traceback" not in result.stderr
    return str(lines[0])


def tolerance_cm(size_cm: float) -> float:
    return max(0.03 * size_cm, 0.2)


@dataclass(frozen=True)
class Case:
    name: str
    size_cm: tuple[float, float, float]
    color_bgr: tuple[int, int, int]
    yaw_deg: float
    tilt_deg: float
    azimuth_deg: float
    elevation_deg: float
    side_yaw_deg: float
    focal_px: float | None = None  # None: the 60-degree field of view the CLI assumes

    def setup(self) -> dict[str, Any]:
        return {
            "marker_size_cm": MARKER_CM,
            "yaw_deg": self.yaw_deg,
            "tilt_deg": self.tilt_deg,
            "azimuth_deg": self.azimuth_deg,
            "elevation_deg": self.elevation_deg,
            "side_yaw_deg": self.side_yaw_deg,
            "focal_px": self.focal_px,
        }


CASES = [
    Case("red", (12.0, 7.0, 5.0), (40, 40, 200), 8.0, 10.0, 30.0, 5.0, 0.0),
    Case("blue-tall", (8.0, 8.0, 10.0), (190, 60, 30), -20.0, 15.0, 120.0, 10.0, 0.0),
    Case("green-long", (20.0, 10.0, 4.0), (60, 150, 40), 5.0, 12.0, 250.0, 5.0, 10.0, 900.0),
    Case("brown-small", (6.0, 4.0, 3.0), (30, 50, 90), 25.0, 15.0, 45.0, -5.0, -8.0),
]


@pytest.fixture(scope="module")
def image_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("images")


def _write(path: Path, img: NDArray[np.uint8]) -> Path:
    assert cv2.imwrite(str(path), img)
    return path


@functools.cache
def _rendered(name: str) -> tuple[NDArray[np.uint8], NDArray[np.uint8]]:
    case = next(c for c in CASES if c.name == name)
    top, cam_top, side, cam_side = box_scenes(case.size_cm, case.color_bgr, **case.setup())
    seed = sum(map(ord, name))
    return render(top, cam_top, seed=seed, **NOISE), render(side, cam_side, seed=seed + 1, **NOISE)  # type: ignore[arg-type]


def images(image_dir: Path, name: str) -> tuple[Path, Path]:
    top, side = _rendered(name)
    t, s = image_dir / f"{name}_top.png", image_dir / f"{name}_side.png"
    if not t.exists():
        _write(t, top)
        _write(s, side)
    return t, s


def measure_args(top: Path, side: Path, out: Path, object_id: str = "box") -> list[object]:
    return [
        "measure", "images", top, side, "--marker-size-cm", MARKER_CM,
        "--object-id", object_id, "--weight-n", 2.5, "--friction-mu", 0.6, "-o", out,
    ]  # fmt: skip


# ------------------------------------------------------------------------------------- sizes


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_sizes_within_tolerance(case: Case, image_dir: Path, tmp_path: Path) -> None:
    top, side = images(image_dir, case.name)
    out = tmp_path / ("catalog.csv" if case.name == "red" else "catalog.parquet")
    extra: list[object] = []
    if case.name == "blue-tall":
        extra = ["--debug-dir", tmp_path / "debug"]
    if case.name == "green-long":
        extra = ["--append"]  # to a catalog that does not exist yet: creates it
    result = run(*measure_args(top, side, out), *extra)
    assert result.exit_code == 0, result.stderr
    (row,) = read_catalog(out).to_dict("records")
    got = (row["size_x_cm"], row["size_y_cm"], row["size_z_cm"])
    errors = [g - s for g, s in zip(got, case.size_cm, strict=True)]
    print(f"\n{case.name}: measured {got}, true {case.size_cm}, errors cm {errors}")
    for err, size in zip(errors, case.size_cm, strict=True):
        assert abs(err) <= tolerance_cm(size), (case.name, got)
    assert (row["object_id"], row["weight_n"], row["friction_mu"]) == ("box", 2.5, 0.6)
    assert "'box'" in result.stderr
    if case.name == "blue-tall":
        names = {p.name for p in (tmp_path / "debug").glob("*.png")}
        assert {"top.png", "side.png", "top_mask.png", "side_mask.png"} <= names
        annotated = cv2.imread(str(tmp_path / "debug" / "top.png"))
        assert annotated.shape == _rendered(case.name)[0].shape
        assert not np.array_equal(annotated, _rendered(case.name)[0])  # drawn on


def test_append_to_csv_and_parquet(image_dir: Path, tmp_path: Path) -> None:
    top, side = images(image_dir, "red")
    first = {"object_id": "sponge", "size_x_cm": 8.0, "size_y_cm": 5.0, "size_z_cm": 4.0,
             "weight_n": 2.1, "friction_mu": 0.3, "name": "kitchen sponge"}  # fmt: skip
    for suffix in ("csv", "parquet"):
        path = tmp_path / f"objects.{suffix}"
        write_catalog(pd.DataFrame([first]), path)
        magic = path.read_bytes()[:4]
        result = run(*measure_args(top, side, path, "red-box"), "--append")
        assert result.exit_code == 0, result.stderr
        assert "2 row(s)" in result.stderr
        assert path.read_bytes()[:4] == magic  # the file keeps its format
        table = read_catalog(path)
        assert list(table["object_id"]) == ["sponge", "red-box"]
        kept = table.iloc[0]
        assert [kept[k] for k in first] == list(first.values())
        assert pd.isna(table.iloc[1]["name"])  # an extra column stays, empty for the new row
        assert abs(table.iloc[1]["size_x_cm"] - 12.0) <= tolerance_cm(12.0)
        # A duplicate object_id is refused before measuring; the file is unchanged.
        before = path.read_bytes()
        dup = run(*measure_args(top, side, path, "sponge"), "--append")
        assert dup.exit_code == 65
        assert "object_id 'sponge' is in the catalog already" in one_line_error(dup)
        assert path.read_bytes() == before
        assert not list(tmp_path.glob(".*.tmp"))


# ------------------------------------------------------------------------------- bad inputs


def _no_partial_output(tmp_path: Path, out: Path) -> None:
    assert not out.exists()
    assert not list(tmp_path.glob(".*.tmp"))


def test_no_marker_says_so_and_suggests_debug_dir(image_dir: Path, tmp_path: Path) -> None:
    case = CASES[0]
    top_scene, cam, _, _ = box_scenes(case.size_cm, case.color_bgr, **case.setup())
    top_scene.markers.clear()
    top = _write(tmp_path / "top.png", render(top_scene, cam, seed=5))
    _, side = images(image_dir, case.name)
    out = tmp_path / "c.csv"
    result = run(*measure_args(top, side, out), "--debug-dir", tmp_path / "dbg")
    assert result.exit_code == 65
    line = one_line_error(result)
    assert "no ArUco marker (DICT_4X4_50) found in the top image" in line
    assert "--debug-dir" in line
    assert str(top) in line
    assert (tmp_path / "dbg" / "top_failed.png").exists()
    _no_partial_output(tmp_path, out)


def test_two_markers_are_refused(image_dir: Path, tmp_path: Path) -> None:
    case = CASES[0]
    top_scene, cam, _, _ = box_scenes(case.size_cm, case.color_bgr, **case.setup())
    top_scene.markers.append(Marker.flat(-14.0, -14.0, MARKER_CM, marker_id=7))
    top = _write(tmp_path / "top.png", render(top_scene, cam, seed=6))
    _, side = images(image_dir, case.name)
    out = tmp_path / "c.csv"
    result = run(*measure_args(top, side, out))
    assert result.exit_code == 65
    line = one_line_error(result)
    assert "found 2 ArUco markers (ids 0, 7) in the top image" in line
    assert "--marker-id" in line
    _no_partial_output(tmp_path, out)


def test_unreadable_and_non_image_files(
    image_dir: Path, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    top, _ = images(image_dir, "red")
    out = tmp_path / "c.csv"
    text = tmp_path / "notes.png"
    text.write_text("not an image\n")
    truncated = tmp_path / "cut.png"
    truncated.write_bytes(top.read_bytes()[:60])
    for bad in (text, truncated):
        result = run(*measure_args(top, bad, out))
        assert result.exit_code == 65, result.stderr
        line = one_line_error(result)
        assert f"{bad}: side image is not a readable image file" in line
        _no_partial_output(tmp_path, out)
    assert "WARN" not in capfd.readouterr().err  # OpenCV's own decoder warning is silenced


def test_object_touching_the_border(image_dir: Path, tmp_path: Path) -> None:
    case = CASES[0]
    scene, _, _, _ = box_scenes(case.size_cm, case.color_bgr, **case.setup())
    scene.boxes[0] = Box((0.0, 0.0), case.size_cm, case.color_bgr)
    scene.markers[0] = Marker.flat(14.0, -8.0, 4.0)
    cam = camera_tilted_down((10.0, 0.0), 30.0, 0.0, 0.0, focal_px=900.0)  # cuts the box off
    top = _write(tmp_path / "top.png", render(scene, cam, seed=7))
    _, side = images(image_dir, case.name)
    out = tmp_path / "c.csv"
    args = measure_args(top, side, out)
    args[args.index("--marker-size-cm") + 1] = 4.0
    result = run(*args)
    assert result.exit_code == 65
    assert "the object touches the border of the top image" in one_line_error(result)
    _no_partial_output(tmp_path, out)


def test_missing_image_and_existing_output(image_dir: Path, tmp_path: Path) -> None:
    top, side = images(image_dir, "red")
    out = tmp_path / "c.csv"
    missing = tmp_path / "nope.png"
    result = run(*measure_args(missing, side, out))
    assert result.exit_code == 66
    assert f"{missing}: no such file" in one_line_error(result)
    _no_partial_output(tmp_path, out)
    out.write_text("keep me\n")
    result = run(*measure_args(top, side, out))
    assert result.exit_code == 1
    line = one_line_error(result)
    assert "exists already" in line
    assert "--force" in line
    assert "--append" in line
    assert out.read_text() == "keep me\n"


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--bag", "x.mcap"], "measure images: no such option: --bag"),
        (["--size-cm", 1, 2, 3], "measure images: no such option: --size-cm"),
        (["--checkerboard", "7by5", "--square-size-cm", 2], None),
        (["--color-range", "100,50,50"], "--color-range: expected H,S,V:H,S,V"),
        (["--force", "--append"], "--append and --force cannot be used together"),
        (["--marker-size-cm", -1], "--marker-size-cm must be a finite number > 0 cm, got -1"),
    ],
)
def test_usage_errors(extra: list[object], message: str | None, tmp_path: Path) -> None:
    top = _write(tmp_path / "t.png", np.zeros((8, 8, 3), np.uint8))
    out = tmp_path / "c.csv"
    args = measure_args(top, top, out)
    if extra[0] in ("--checkerboard", "--marker-size-cm"):
        i = args.index("--marker-size-cm")
        del args[i : i + 2]
    result = run(*args, *extra)
    assert result.exit_code == 2, result.stderr
    line = one_line_error(result)
    assert (message or "--checkerboard: expected COLSxROWS") in line
    assert not out.exists()


def test_image_options_refused_with_other_sources(tmp_path: Path) -> None:
    result = run("measure", "csv", tmp_path / "x.csv", "--marker-size-cm", 5,
                 "--object-id", "a", "--weight-n", 1, "-o", tmp_path / "o.mcap")  # fmt: skip
    assert result.exit_code == 2
    assert "measure csv: no such option: --marker-size-cm" in one_line_error(result)
    result = run("measure", "images", "a.png", "b.png", "--marker-size-cm", 5,
                 "--object-id", "a", "--weight-n", 1, "-o", tmp_path / "o.csv")  # fmt: skip
    assert result.exit_code == 2
    assert "measure images needs --friction-mu" in one_line_error(result)


# ------------------------------------------------------------------------ slip from frames


THRESHOLD_N = 3.0
PARTIAL_FROM_N = 2.6
PALM_RISE_M = 0.03


def expected_slip_m(force_n: float) -> float:
    """What the rig renders (examples/frames_render_rig.py): the object's lag behind the palms."""
    if force_n >= THRESHOLD_N:
        return 0.002
    return PALM_RISE_M - (0.015 if force_n >= PARTIAL_FROM_N else 0.0)


def _lift_catalog(tmp_path: Path) -> Path:
    row = {
        "object_id": "box",
        "size_x_cm": 8.0,
        "size_y_cm": 6.0,
        "size_z_cm": 6.0,
        "weight_n": 2.0,
        "friction_mu": 0.5,
    }  # fmt: skip  F_w = 2 N
    path = tmp_path / "objects.csv"
    write_catalog(pd.DataFrame([row]), path)
    return path


def rig_command(*args: object) -> str:
    argv = [sys.executable, str(RIG), str(THRESHOLD_N), str(PARTIAL_FROM_N), *map(str, args)]
    return shlex.join(argv)


@pytest.mark.parametrize("palms", ["markers", "regions"])
def test_lift_with_slip_from_frames(
    palms: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)  # the rig writes frames/ in its working directory
    catalog = _lift_catalog(tmp_path)
    if palms == "markers":
        palm_args: list[object] = ["--palm-marker-ids", "1,2"]
        search: list[object] = ["--tolerance", 0.05]  # refine to 5 %
        rig = rig_command()
    else:
        regions = Gripper(palm_markers=False, width=800, height=600).palm_regions()
        palm_args = ["--palm-regions", ";".join(",".join(map(str, r)) for r in regions)]
        search = ["--protocol", "paper"]  # the ramp only: 2, 2.4, 2.88, 3.456 N
        rig = rig_command("--regions")
    result = run(
        "lift", "rig", catalog, "--command", rig, "--slip-from-frames", *palm_args,
        "--frame-marker-size-cm", 2.4, "--slip-tolerance-m", 0.005, *search,
        "-o", "lift.parquet", "--log", "lift.mcap",
    )  # fmt: skip
    assert result.exit_code == 0, result.stderr
    _, attempts = read_lift_log("lift.mcap")
    statuses = set()
    for a in attempts:
        force_n = a.outcome.grip_force_n
        assert a.outcome.lifted == (force_n >= THRESHOLD_N), force_n
        assert a.outcome.slip_m == pytest.approx(expected_slip_m(force_n), abs=0.7e-3)
        assert a.outcome.details["slip_source"] == "frames"
        statuses.add(round(expected_slip_m(force_n), 3))
    assert statuses == {0.002, 0.015, 0.03}  # lifted, partial slip and dropped all occurred
    (row,) = read_table("lift.parquet", "lift_results").to_dict("records")
    assert row["converged"]
    assert row["slip_criterion"] == "frames"
    assert row["slip_tolerance_m"] == 0.005
    assert row["bracket_low_n"] < THRESHOLD_N <= row["lift_force_n"]
    if palms == "markers":
        assert row["lift_force_n"] <= THRESHOLD_N / 0.95


def test_frames_of_different_sizes_fail_the_rig_attempt(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    catalog = _lift_catalog(tmp_path)
    result = run(
        "lift", "rig", catalog, "--command", rig_command("--after-size", "640x480"),
        "--slip-from-frames", "--palm-marker-ids", "1,2", "--frame-marker-size-cm", 2.4, "-o",
        "lift.parquet",
    )  # fmt: skip
    assert result.exit_code == 1
    line = one_line_error(result)
    assert "attempt_index 0" in line
    assert "the before frame is 800x600 px but the after frame is 640x480 px" in line
    # lift's contract for a failed rig attempt: the table is written, the row says what failed.
    (row,) = read_table("lift.parquet", "lift_results").to_dict("records")
    assert not row["converged"]
    assert "640x480" in row["error"]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--palm-marker-ids", "1,2"], "--palm-marker-ids needs --slip-from-frames"),
        (["--slip-from-frames", "--frame-marker-size-cm", 2.4],
         "needs one of --palm-marker-ids or --palm-regions"),
        (["--slip-from-frames", "--palm-marker-ids", "1,2"], "needs --frame-marker-size-cm"),
        (["--slip-from-frames", "--palm-regions", "1,2,3", "--frame-marker-size-cm", 2],
         "--palm-regions: expected x,y,w,h;x,y,w,h"),
    ],
)  # fmt: skip
def test_frame_option_errors(args: list[object], message: str, tmp_path: Path) -> None:
    result = run("lift", "rig", _lift_catalog(tmp_path), "--command", rig_command(), *args,
                 "-o", tmp_path / "lift.parquet")  # fmt: skip
    assert result.exit_code == 2
    assert message in one_line_error(result)
    assert not (tmp_path / "lift.parquet").exists()


# ---------------------------------------------------------------------------------- README


def test_readme_measure_images_example_runs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The gripper guide's ``measure --images`` block, run as written (python: this interpreter)."""
    guide = (REPO / "docs" / "guide" / "gripper.md").read_text(encoding="utf-8")
    section = guide.split("\n## Measuring the object's size from photos", 1)[1].split("\n## ", 1)[0]
    block = section.split("```sh\n", 1)[1].split("```", 1)[0].replace("\\\n", " ")
    commands = [line.split("#")[0].strip() for line in block.splitlines() if line.strip()]
    assert commands[0].startswith("python examples/render_scene.py")
    (tmp_path / "examples").symlink_to(REPO / "examples")
    monkeypatch.chdir(tmp_path)
    for command in commands:
        argv = shlex.split(command)
        if argv[0] in ("python", "python3"):
            subprocess.run([sys.executable, *argv[1:]], check=True, capture_output=True)
        else:
            assert argv[0] == "deformctl"
            result = run(*argv[1:])
            assert result.exit_code == 0, (command, result.stderr)
            guessed = "--camera-matrix" not in argv
            assert ("no --camera-matrix: assumed a 60°" in result.stderr) == guessed, command
    table = read_catalog("objects.csv").set_index("object_id")
    assert list(table.index) == ["red-box", "red-box-45", "red-box-2"]
    true_size = (12.0, 7.0, 5.0)
    for size, column in zip(true_size, ("size_x_cm", "size_y_cm", "size_z_cm"), strict=True):
        for oid in ("red-box", "red-box-2"):  # the 60° camera: its own matrix, or the guess
            assert abs(table.loc[oid, column] - size) <= tolerance_cm(size), (oid, column)
    # a 45° lens read with the 60° guess: its footprint comes out too small
    assert table.loc["red-box-45", "size_x_cm"] < 0.98 * true_size[0]
    assert (tmp_path / "debug" / "top.png").exists()
