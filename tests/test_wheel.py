"""The built wheel works without the checkout: bundled schemas and datasets come with it.

The wheel is built once per session from a clean copy of the source tree (no build isolation,
so no download: tests/_helpers/wheel.py), unpacked, and run with only the unpacked wheel on
``PYTHONPATH`` from a folder outside the checkout, or installed into a fresh venv; the
dependencies are the test environment's.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from deformctl.presets import paper_preset
from tests._helpers.wheel import made_once

pytestmark = pytest.mark.e2e

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="session")
def wheel_dir(wheel_file: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The unpacked wheel of the current source tree."""

    def unpack(site: Path) -> None:
        with zipfile.ZipFile(wheel_file) as zf:
            zf.extractall(site)

    return made_once(tmp_path_factory, "site", unpack)


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
#: what numba prints with ``NUMBA_DEBUG_CACHE=1``, one stdout line per cache file it reads or
#: writes: ``[cache] data loaded from '.../direct.integrate-36.py311.1.nbc'`` (matched anywhere:
#: a command's worker processes write to the same pipe)
CACHE_LINE = re.compile(r"\[cache\] (index|data) (loaded from|saved to) '([^']*)'\n?")
#: the kernels every run starts from: the direct and the iterative step loops, the scene writer
STEP_LOOPS = {"direct.integrate", "iterative.integrate_iterative", "_scene_text._messages"}


def _cache_use(stdout: str) -> tuple[set[Path], set[Path], str]:
    """The compiled kernels (numba's data files: one per kernel and argument types) a process
    loaded and the cache files it saved, from its ``NUMBA_DEBUG_CACHE`` lines; its stdout
    without them."""
    lines = CACHE_LINE.findall(stdout)
    loaded = {Path(f) for kind, verb, f in lines if (kind, verb) == ("data", "loaded from")}
    saved = {Path(f) for _, verb, f in lines if verb == "saved to"}
    return loaded, saved, CACHE_LINE.sub("", stdout)


def _symbol(data_file: Path) -> bytes:
    """The start of the linker symbol of the kernel a numba data file holds, as numba mangles
    it: ``.../site-packages/deformctl/sim/multigrid/__pycache__/cg.pcg-38.py311.1.nbc`` holds
    ``deformctl.sim.multigrid.cg.pcg``, ``_ZN9deformctl3sim9multigrid2cg3pcg``. A compiled
    kernel carries the symbols of every kernel it calls (compiled into it)."""
    parts = data_file.parts
    package = parts[parts.index("site-packages") + 1 : -2]
    module, function = data_file.name.split("-")[0].split(".", 1)
    return ("_ZN" + "".join(f"{len(x)}{x}" for x in (*package, module, function))).encode()


@pytest.mark.slow
def test_a_fresh_venv_warms_up_and_runs_the_first_commands(warm_venv: Path, tmp_path: Path) -> None:
    """``pip install`` of the wheel; ``deformctl warmup`` (``make install`` runs it) prepares
    every kernel a run uses (the simulator's and the scene writer's), so ``population``,
    ``measure sim``, ``lift sim`` and squeezes and lifts of both presets and a fine cube compile
    nothing afterwards and load only compiled kernels the warm-up loaded: numba says what each
    process (and each of its workers) loads and saves (``NUMBA_DEBUG_CACHE``). The venv's cache
    holds the checkout's compiled kernels (:func:`warm_venv`), so a kernel the warm-up missed
    shows as loaded only later, or as compiled; compiling them all from nothing (a minute of
    CPU, announced on one stderr line: tests/sim/test_warmup.py) is what ``.ci/run`` does, with
    the README's first example in a clean venv of the wheel."""
    deformctl = str(warm_venv / "bin" / "deformctl")
    python = str(warm_venv / "bin" / "python")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env.pop("NUMBA_CACHE_DIR", None)  # numba's cache beside the venv's sources, as a user's
    env |= {"NUMBA_DEBUG_CACHE": "1", "PYTHONUNBUFFERED": "1"}  # each line written at once

    def run(*args: str) -> subprocess.CompletedProcess[str]:
        proc = subprocess.run(args, cwd=tmp_path, env=env, capture_output=True, text=True,
                              check=False, timeout=900)  # fmt: skip
        assert proc.returncode == 0, proc.stderr
        return proc

    where = run(python, "-c", "import deformctl; print(deformctl.__file__)")
    assert Path(where.stdout.strip()).is_relative_to(warm_venv)
    done = run(deformctl, "warmup")
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("deformctl: simulator kernels compiled or loaded in ")
    loaded, saved, out = _cache_use(done.stdout)
    assert out == ""
    warm = loaded | {f for f in saved if f.suffix == ".nbc"}  # loaded, or compiled now
    assert all(f.is_relative_to(warm_venv) for f in warm), warm
    assert {f.name.split("-")[0] for f in warm} >= STEP_LOOPS, sorted(warm)
    warm_code = b"".join(f.read_bytes() for f in sorted(warm))

    def run_warm(*args: str) -> str:
        """``args`` run; it compiled nothing and loaded only kernels the warm-up prepared (one
        it loaded or one compiled into one of those)."""
        loaded, saved, out = _cache_use(run(*args).stdout)
        assert not saved, f"{args[1:3]} compiled after the warm-up: {sorted(saved)}"
        missed = sorted(f.name for f in loaded if _symbol(f) not in warm_code)
        assert not missed, f"{args[1:3]} loaded kernels the warm-up did not prepare: {missed}"
        return out

    run_warm(deformctl, "population", "--paper", "-o", "p.csv")
    paper = (REPO / "datasets/paper/objects.csv").read_text().splitlines()
    written = (tmp_path / "p.csv").read_text().splitlines()
    assert [line.split(",")[0] for line in written] == [line.split(",")[0] for line in paper]
    run_warm(deformctl, "measure", "sim", "p.csv", "-o", "s.mcap")
    info = json.loads(run_warm(deformctl, "inspect", "s.mcap", "--json"))
    assert info["kind"] == "squeeze_log"
    assert info["squeezes"] == 12  # 4 objects x 3 squeezes
    squeezes = {f"/squeeze/{o}" for o in "ABCD"}
    assert {c["topic"] for c in info["channels"]} == squeezes | {"/scene", "/palms"}  # Foxglove
    # the paper preset's calibration file comes with the wheel: a lift with it (the golden
    # population's first object)
    run_warm(deformctl, "population", "--golden", "-o", "g.csv")
    first = (tmp_path / "g.csv").read_text().splitlines()[1].split(",")[0]
    run_warm(deformctl, "lift", "sim", "g.csv", "--objects", first, "-o", "lift.parquet")
    assert (tmp_path / "lift.parquet").is_file()
    run_warm(python, "-c", RUNS)


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
