"""``-q`` with every ``measure`` source (sim, csv, bag, images): the summary line goes, warnings
and errors stay; ``measure sim``'s progress counts objects, not squeezes."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import cv2
import pytest
from typer.testing import CliRunner

from deformctl.cli import app
from deformctl.measure import SimulateCatalogTask, SqueezeProtocol, simulate_catalog_file
from deformctl.presets import sim_preset
from deformctl.vision.synth import box_scenes, render

REPO = Path(__file__).resolve().parents[2]
EXAMPLES = REPO / "datasets" / "examples"
HEADER = (
    "object_id,size_x_cm,size_y_cm,size_z_cm,weight_n,friction_mu,"
    "material_stiffness_n_per_cm,material_damping_ns_per_cm\n"
)
runner = CliRunner()


def _catalog(tmp_path: Path, n: int) -> Path:
    path = tmp_path / "cat.csv"
    rows = [f"o{i},10,10,10,{2 + i},0.5,{10 + 5 * i},{0.2 * i}" for i in range(n)]
    path.write_text(HEADER + "\n".join(rows) + "\n")
    return path


def _images(tmp_path: Path) -> list[str]:
    top, cam_top, side, cam_side = box_scenes((12.0, 7.0, 5.0), (40, 40, 200), marker_size_cm=5.0)
    paths = [tmp_path / "top.png", tmp_path / "side.png"]
    for path, scene, cam, seed in ((paths[0], top, cam_top, 1), (paths[1], side, cam_side, 2)):
        assert cv2.imwrite(str(path), render(scene, cam, seed=seed))
    return [str(p) for p in paths]


def _sources(tmp_path: Path) -> dict[str, list[str]]:
    """Each source's command line (without -q), writing into ``tmp_path``."""
    fast = ["--squeezes", "2", "--alpha-cm", "5", "--dt-s", "0.002", "--ramp-s", "0.05",
            "--hold-s", "0.1", "--workers", "1"]  # fmt: skip
    return {
        "sim": ["measure", "sim", str(_catalog(tmp_path, 2)), *fast],
        "csv": [
            "measure",
            "csv",
            str(EXAMPLES / "utm_export.csv"),
            "--object-id",
            "foam",
            "--weight-n",
            "2.9",
        ],
        "bag": [
            "measure",
            "bag",
            str(EXAMPLES / "gripper.mcap"),
            "--wrench-topic",
            "/left/wrench",
            "--position-topic",
            "/left/palm_pose",
            "--axis",
            "x",
            "--object-id",
            "sponge",
            "--weight-n",
            "0.6",
        ],
        "images": [
            "measure",
            "images",
            *_images(tmp_path),
            "--marker-size-cm",
            "5",
            "--object-id",
            "box",
            "--weight-n",
            "2.9",
            "--friction-mu",
            "0.5",
        ],
    }


def _run(args: list[str]) -> Any:
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.stderr
    return result


@pytest.mark.parametrize("source", ["sim", "csv", "bag", "images"])
def test_quiet_drops_the_summary_line_of_every_source(source: str, tmp_path: Path) -> None:
    args = _sources(tmp_path)[source]
    suffix = ".csv" if source == "images" else ".mcap"
    loud = _run([*args, "-o", str(tmp_path / f"loud{suffix}")])
    quiet = _run([*args, "-q", "-o", str(tmp_path / f"quiet{suffix}")])
    summary = [line for line in loud.stderr.splitlines() if str(tmp_path / "loud") in line]
    assert summary, loud.stderr  # without -q: a line naming the output
    assert str(tmp_path / "quiet") not in quiet.stderr
    assert [w for w in quiet.stderr.splitlines() if w.startswith("warning:")] == [
        w.replace("loud", "quiet") for w in loud.stderr.splitlines() if w.startswith("warning:")
    ]  # warnings still print
    assert (tmp_path / f"quiet{suffix}").stat().st_size > 0
    if source != "images":  # the same log either way (the provenance names its output)
        assert (tmp_path / f"quiet{suffix}").stat().st_size == (
            tmp_path / f"loud{suffix}"
        ).stat().st_size


def test_quiet_with_the_old_source_flags(tmp_path: Path) -> None:
    csv = ["--csv", str(EXAMPLES / "utm_export.csv"), "--object-id", "foam", "--weight-n", "2.9"]
    result = _run(["measure", *csv, "-q", "-o", str(tmp_path / "o.mcap")])
    assert "deprecated" in result.stderr
    assert str(tmp_path / "o.mcap") not in result.stderr


def test_quiet_keeps_an_error_line(tmp_path: Path) -> None:
    result = runner.invoke(
        app,
        [
            "measure",
            "csv",
            str(tmp_path / "none.csv"),
            "--object-id",
            "a",
            "--weight-n",
            "1",
            "-q",
            "-o",
            str(tmp_path / "o.mcap"),
        ],
    )
    assert result.exit_code == 66
    assert result.stderr.startswith("error:")


@pytest.mark.parametrize("workers", [1, 2])
def test_progress_counts_objects_not_squeezes(tmp_path: Path, workers: int) -> None:
    preset = sim_preset().replace(settings={"alpha_cm": 5.0, "dt_s": 0.002})
    task = SimulateCatalogTask(
        protocol=SqueezeProtocol(squeezes=3, strain=0.1, ramp_s=0.05, hold_s=0.1),
        settings=preset.settings,
        seed=7,
        sim_preset=preset.name,
    )
    seen: list[tuple[str, int, int]] = []
    _objects, series = simulate_catalog_file(
        str(_catalog(tmp_path, 4)),
        task,
        output=str(tmp_path / "sq.mcap"),
        workers=workers,
        progress=lambda oid, done, total: seen.append((oid, done, total)),
    )
    assert len(series) == 12  # 4 objects x 3 squeezes
    assert seen == [(f"o{i}", i + 1, 4) for i in range(4)]  # one step per object
