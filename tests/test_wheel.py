"""The built wheel works without the checkout: bundled schemas and datasets come with it.

The wheel is built once per session from a clean copy of the source tree (no build isolation,
so no download: tests/_helpers/wheel.py), unpacked, and run with only the unpacked wheel on
``PYTHONPATH`` from a folder outside the checkout, or installed into a fresh venv; the
dependencies are the test environment's.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from deformctl.presets import paper_preset

pytestmark = pytest.mark.e2e

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="session")
def wheel_dir(wheel_file: Path) -> Path:
    """The unpacked wheel of the current source tree."""
    unpacked = wheel_file.parent.parent / "site"
    with zipfile.ZipFile(wheel_file) as zf:
        zf.extractall(unpacked)
    return unpacked


#: Runs beyond the first commands that must compile nothing after the warm-up: squeezes and
#: lift attempts of both presets and a fine cube (``particles_per_side=9``).
RUNS = """
from deformctl.presets import sim_preset
from deformctl.sim import ObjectSpec, SimSettings, lift_attempt, squeeze
bag = ObjectSpec("bag", (15.0, 12.0, 9.0), 10.0, 0.5, 20.0, 2.0)
for name in ("paper", "table"):
    preset = sim_preset(name)
    squeeze(bag, peak_force_n=5.0, ramp_s=0.01, hold_s=0.01, settings=preset.settings)
    preset.lift_attempt(bag, 12.0)
squeeze(bag, peak_force_n=5.0, ramp_s=0.01, hold_s=0.01, settings=SimSettings(particles_per_side=9))
"""


@pytest.mark.slow
def test_a_fresh_venv_warms_up_and_runs_the_first_commands(
    fresh_venv: Path, tmp_path: Path
) -> None:
    """``pip install`` of the wheel; ``deformctl warmup`` (``make install`` runs it) compiles
    every kernel a run uses (the simulator's and the scene writer's) into a fresh numba cache,
    so ``population``, ``measure sim``, ``lift sim`` and squeezes and lifts of both presets and
    a fine cube add nothing to the cache afterwards. (One test, so the kernels compile once.)"""
    deformctl = str(fresh_venv / "bin" / "deformctl")
    python = str(fresh_venv / "bin" / "python")
    cache = tmp_path / "numba"
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env["NUMBA_CACHE_DIR"] = str(cache)

    def run(*args: str) -> subprocess.CompletedProcess[str]:
        proc = subprocess.run(args, cwd=tmp_path, env=env, capture_output=True, text=True,
                              check=False, timeout=900)  # fmt: skip
        assert proc.returncode == 0, proc.stderr
        return proc

    where = run(python, "-c", "import deformctl; print(deformctl.__file__)")
    assert Path(where.stdout.strip()).is_relative_to(fresh_venv)
    done = run(deformctl, "warmup")
    assert done.stdout == ""
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("deformctl: simulator kernels compiled or loaded in ")
    compiled = sorted(p.relative_to(cache) for p in cache.rglob("*.nbi"))
    assert len(compiled) >= 10, compiled

    run(deformctl, "population", "--paper", "-o", "p.csv")
    paper = (REPO / "datasets/paper/objects.csv").read_text().splitlines()
    written = (tmp_path / "p.csv").read_text().splitlines()
    assert [line.split(",")[0] for line in written] == [line.split(",")[0] for line in paper]
    run(deformctl, "measure", "sim", "p.csv", "-o", "s.mcap")
    info = json.loads(run(deformctl, "inspect", "s.mcap", "--json").stdout)
    assert info["kind"] == "squeeze_log"
    assert info["squeezes"] == 12  # 4 objects x 3 squeezes
    squeezes = {f"/squeeze/{o}" for o in "ABCD"}
    assert {c["topic"] for c in info["channels"]} == squeezes | {"/scene", "/palms"}  # Foxglove
    # the paper preset's calibration file comes with the wheel: a lift with it (the golden
    # population's first object)
    run(deformctl, "population", "--golden", "-o", "g.csv")
    first = (tmp_path / "g.csv").read_text().splitlines()[1].split(",")[0]
    run(deformctl, "lift", "sim", "g.csv", "--objects", first, "-o", "lift.parquet")
    assert (tmp_path / "lift.parquet").is_file()
    run(python, "-c", RUNS)
    after = sorted(p.relative_to(cache) for p in cache.rglob("*.nbi"))
    assert after == compiled, sorted(set(after) - set(compiled))


def _run(wheel_dir: Path, cwd: Path, *args: str) -> str:
    env = {**os.environ, "PYTHONPATH": str(wheel_dir)}
    proc = subprocess.run(
        [sys.executable, *args], cwd=cwd, env=env, capture_output=True, text=True, check=False
    )
    assert proc.returncode == 0, proc.stderr
    return proc.stdout


def test_the_wheel_brings_its_data(wheel_dir: Path, tmp_path: Path) -> None:
    where = _run(
        wheel_dir,
        tmp_path,
        "-c",
        "import deformctl, deformctl.repro.golden as g; "
        "from deformctl.resources import dataset_path; "
        "from deformctl.artifacts.schema import load_table_spec; load_table_spec('catalog'); "
        "print(deformctl.__file__); print(dataset_path('paper', 'table2.csv')); "
        "print(g.EXPECTED_PATH); print(dataset_path('examples', 'gripper.mcap')); "
        "print(dataset_path('examples', 'utm_export.csv')); "
        "from deformctl.grip.fast import resolve_model_path; print(resolve_model_path('grip')); "
        "from importlib.resources import files; from deformctl.artifacts.mcap import scene; "
        "scene.foxglove_schema(); print(files('deformctl.schemas') / 'foxglove' / 'LICENSE')",
    )
    for line in where.split():
        assert Path(line).is_relative_to(wheel_dir), line
        assert Path(line).is_file(), line
    assert not (wheel_dir / "deformctl" / "cli" / "_sweep.py").exists()  # no stale build files


def test_commands_run_from_the_wheel(wheel_dir: Path, tmp_path: Path) -> None:
    _run(wheel_dir, tmp_path, "-m", "deformctl", "population", "--golden", "-o", "g.csv")
    assert (tmp_path / "g.csv").read_text() == (REPO / "datasets/golden/catalog.csv").read_text()
    _run(wheel_dir, tmp_path, "-m", "deformctl", "population", "-n", "73", "--seed", "0",
         "-o", "population.csv")  # fmt: skip
    _run(wheel_dir, tmp_path, "-m", "deformctl", "inspect", "g.csv", "--json")
    shutil.copy(REPO / "tests/data/lift_results.parquet", tmp_path / "lift.parquet")
    table = _run(wheel_dir, tmp_path, "-m", "deformctl.repro.paper", "lift.parquet")
    assert "A (sponge)" in table
    grip = _run(wheel_dir, tmp_path, "-m", "deformctl", "predict", "grip", "--weight-n", "2.9",
                "--deformability-n-per-cm", "30", "--damping-ns-per-cm", "0.47",
                "--friction-mu", "0.5", "--coverage", "0.9")  # fmt: skip
    assert grip.splitlines()[0].startswith("weight_n,deformability_n_per_cm,")


def test_the_paper_preset_calibration_comes_with_the_wheel(wheel_dir: Path, tmp_path: Path) -> None:
    where = _run(
        wheel_dir,
        tmp_path,
        "-c",
        "from importlib.resources import files; from deformctl.presets import CALIBRATION_PARTS, "
        "paper_preset; print(files('deformctl.datasets').joinpath(*CALIBRATION_PARTS)); "
        "print(paper_preset().settings.shear_damping_ratio)",
    )
    path, ratio = where.split()
    assert Path(path).is_relative_to(wheel_dir)
    assert float(ratio) == paper_preset().settings.shear_damping_ratio
    # a lift with the calibrated preset runs in the fresh venv (its kernels compiled there once)
