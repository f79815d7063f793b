"""``deformctl examples DIR``: the bundled samples and guide inputs, laid out as in a checkout."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from typer.testing import CliRunner

from deformctl.artifacts import read_squeeze_log
from deformctl.cli import COMMAND_NAMES, app
from deformctl.samples import copy_examples, example_files

REPO = Path(__file__).resolve().parents[2]
runner = CliRunner()
#: What the guides name (each must be copied, byte for byte, at that path).
GUIDE_INPUTS = (
    "datasets/examples/utm_export.csv",
    "datasets/examples/gripper.mcap",
    "datasets/examples/phantom/EF10_0T_A1.csv",
    "datasets/examples/phantom/DATA_LICENSE.md",  # the phantom recordings' credit travels along
    "datasets/paper/objects.csv",
    "examples/threshold_rig.py",
    "examples/frames_render_rig.py",
    "examples/render_scene.py",
    "examples/synthetic_index.py",
)


def _one_error(result: object, code: int) -> str:
    assert result.exit_code == code, result.stderr  # type: ignore[attr-defined]
    lines = result.stderr.strip().splitlines()  # type: ignore[attr-defined]
    assert len(lines) == 1, lines
    assert lines[0].startswith("error:")
    return lines[0]


def test_examples_is_a_command() -> None:
    assert "examples" in COMMAND_NAMES


def test_examples_copies_the_guide_inputs_byte_for_byte(tmp_path: Path) -> None:
    dest = tmp_path / "new" / "samples"  # parents are made
    result = runner.invoke(app, ["examples", str(dest)])
    assert result.exit_code == 0, result.stderr
    assert f"wrote {dest}: " in result.stderr
    copied = sorted(str(p.relative_to(dest)) for p in dest.rglob("*") if p.is_file())
    assert copied == sorted(str(rel) for _, rel in example_files())
    for rel in GUIDE_INPUTS:
        assert (dest / rel).read_bytes() == (REPO / rel).read_bytes(), rel
    assert not [p for p in copied if p.endswith("__init__.py") or "__pycache__" in p]
    assert not [p.name for p in tmp_path.joinpath("new").iterdir() if p.name != "samples"]


def test_a_guide_command_runs_from_the_copy(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    copy_examples(tmp_path / "s")
    monkeypatch.chdir(tmp_path / "s")
    args = ["measure", "csv", "datasets/examples/utm_export.csv", "--object-id", "foam",
            "--weight-n", "2.9", "-q", "-o", "foam.mcap"]  # fmt: skip
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.stderr
    objects, squeezes = read_squeeze_log("foam.mcap")
    assert [o["object_id"] for o in objects] == ["foam"]
    assert squeezes


def test_an_empty_existing_folder_is_filled(tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    written = copy_examples(tmp_path / "empty")
    assert len(written) == len(example_files())
    assert oct((tmp_path / "empty").stat().st_mode & 0o777) == oct(0o777 & ~_umask())


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def test_a_folder_with_files_is_refused_without_force(tmp_path: Path) -> None:
    dest = tmp_path / "mine"
    dest.mkdir()
    (dest / "notes.txt").write_text("keep me")
    line = _one_error(runner.invoke(app, ["examples", str(dest)]), 1)
    assert "--force" in line
    assert sorted(p.name for p in dest.iterdir()) == ["notes.txt"]  # untouched
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine"]  # no staging left
    (dest / "datasets" / "paper").mkdir(parents=True)
    (dest / "datasets" / "paper" / "objects.csv").write_text("edited")
    result = runner.invoke(app, ["examples", str(dest), "--force"])
    assert result.exit_code == 0, result.stderr
    assert (dest / "notes.txt").read_text() == "keep me"  # other files are kept
    assert (dest / "datasets/paper/objects.csv").read_bytes() == (
        REPO / "datasets/paper/objects.csv"
    ).read_bytes()  # the copy is written over
    assert not list(dest.rglob("*.tmp"))


@pytest.mark.parametrize("bad", ["file", "-"])
def test_a_file_or_stdout_is_a_usage_error(tmp_path: Path, bad: str) -> None:
    target = tmp_path / "f.txt"
    target.write_text("x")
    arg = str(target) if bad == "file" else "-"
    _one_error(runner.invoke(app, ["examples", arg]), 2)
    assert target.read_text() == "x"


def test_no_folder_is_a_usage_error() -> None:
    result = runner.invoke(app, ["examples"])
    assert result.exit_code == 2
