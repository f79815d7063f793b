"""Each option is checked once, where its options type is built, and each catalog value once,
where its row is read: runs of ``measure csv``, ``measure sim``, ``lift sim`` and ``train``
count the rule checks (:meth:`Quantity.ok`, which every check runs) of the quantities their
options types and catalog rows hold. Nothing below checks them again, and each object's
simulator spec is built once, in a single file run and in a sweep (the parent plans each object,
its worker runs the plan)."""

from __future__ import annotations

import collections
import pickle
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from deformctl.cli import app
from deformctl.quantities import Quantity

cli = CliRunner()
#: A fast simulated lift (coarse lattice, short hold), as the lift tests use.
FAST_LIFT = ["--alpha-cm", "10", "--dt-s", "0.002", "--hold-s", "0.05", "--lift-height-m", "0.01"]
FAST_SQUEEZE = ["--squeezes", "1", "--ramp-s", "0.05", "--hold-s", "0.05", "--scene-hz", "0"]
#: Two simulated objects: the counts below are per object.
TWO_OBJECTS = (
    "object_id,size_x_cm,size_y_cm,size_z_cm,weight_n,friction_mu,"
    "material_stiffness_n_per_cm,material_damping_ns_per_cm\n"
    "a,10,10,10,0.7,0.5,49.18,6.47\nb,8,9,10,0.9,0.6,30.0,4.0\n"
)


@pytest.fixture
def checks(monkeypatch: pytest.MonkeyPatch) -> collections.Counter[str]:
    """Every rule check from now on, counted by quantity name."""
    counted: collections.Counter[str] = collections.Counter()
    ok: Callable[[Quantity, object], bool] = Quantity.ok

    def counting(self: Quantity, value: object) -> bool:
        counted[self.name] += 1
        return ok(self, value)

    monkeypatch.setattr(Quantity, "ok", counting)
    return counted


def _run(argv: list[str]) -> None:
    res = cli.invoke(app, argv)
    assert res.exit_code == 0, res.output


def _second_run(argv: list[str], counted: collections.Counter[str]) -> None:
    """Run ``argv`` twice, counting the second run only: the first loads the modules (their
    default options are checked as they load) and fills the caches a process keeps."""
    _run(argv)
    counted.clear()
    _run([*argv, "--force"])


def test_the_counter_counts_a_check(checks: collections.Counter[str]) -> None:
    from deformctl.lift.options import SearchOptions

    SearchOptions(growth=1.5)
    assert checks["growth"] == 1
    assert checks["max_force_n"] == 0


def _measure_csv(tmp: Path) -> list[str]:
    t = np.arange(0.0, 2.0, 0.001)
    d = 0.003 * np.sin(np.pi * t / 2) ** 2
    f = 300.0 * d + 20.0 * np.gradient(d, t)
    export = tmp / "a.csv"
    rows = (f"{a:.6f},{b:.6f},{c:.8f}" for a, b, c in zip(t, f, d, strict=True))
    export.write_text("time_s,force_n,compression_m\n" + "\n".join(rows) + "\n")
    flags = ["--object-id", "a", "--weight-n", "1", "--memory-budget-gib", "1"]
    return ["measure", "csv", str(export), *flags, "-o", str(tmp / "m.mcap")]


def _catalog(tmp: Path, text: str = TWO_OBJECTS) -> str:
    catalog = tmp / "cat.csv"
    catalog.write_text(text)
    return str(catalog)


def _lift_sim(tmp: Path) -> list[str]:
    flags = [*FAST_LIFT, "--growth", "1.3", "--max-attempts", "20", "--max-force-n", "50"]
    flags += ["--memory-budget-gib", "1"]
    return ["lift", "sim", _catalog(tmp), *flags, "-o", str(tmp / "l.parquet")]


def _measure_sim(tmp: Path) -> list[str]:
    fast = ["--alpha-cm", "10", "--dt-s", "0.002", "--memory-budget-gib", "1", *FAST_SQUEEZE]
    return ["measure", "sim", _catalog(tmp), *fast, "-o", str(tmp / "m.mcap")]


def _train(tmp: Path) -> list[str]:
    from deformctl.artifacts import Provenance, write_table
    from deformctl.repro.synthetic import synthetic_index_table

    index = tmp / "index.parquet"
    provenance = Provenance.from_invocation(argv=["t"])
    write_table(synthetic_index_table(n=30), index, "index_table", provenance=provenance)
    flags = ["--train-size", "20", "--calibration-size", "5", "--hidden", "2", "--seed", "1"]
    return ["train", str(index), *flags, "-o", str(tmp / "m.skops")]


#: Per command: its arguments and the quantities each checked once per run (the simulator's
#: settings by one preset build, the search's and the training's by their options types).
ONCE: dict[str, tuple[Callable[[Path], list[str]], tuple[str, ...]]] = {
    "measure csv": (
        _measure_csv,
        ("force_threshold_frac", "min_gap_s", "min_squeeze_s", "memory_budget_gib"),
    ),
    "lift sim": (
        _lift_sim,
        (
            *("growth", "tolerance_rel", "max_attempts", "max_force_n"),
            *("alpha_cm", "dt_s", "memory_budget_gib", "scene_hz"),
            *("particles_per_side", "shear_damping_ratio", "grip_settle_s"),
            *("lift_accel_m_s2", "lift_speed_m_s", "lift_height_m", "lift_hold_s"),
            "slip_tolerance_m",
        ),
    ),
    "measure sim": (
        _measure_sim,
        ("squeezes", "ramp_s", "hold_s", "alpha_cm", "dt_s", "memory_budget_gib", "scene_hz"),
    ),
    "train": (
        _train,
        (
            "train_size",
            "calibration_size",
            "hidden",
            "seed",
            "restarts",
            "max_iter",
            "alpha",
            "tol",
        ),
    ),
}


@pytest.mark.parametrize("command", list(ONCE))
def test_each_option_is_checked_once_per_run(
    command: str, tmp_path: Path, checks: collections.Counter[str]
) -> None:
    argv, names = ONCE[command]
    _second_run(argv(tmp_path), checks)
    assert {name: checks[name] for name in names} == dict.fromkeys(names, 1), dict(checks)


#: Each catalog quantity's checks per object: one per value (three sizes).
CATALOG_CHECKS = {
    "size_cm": 3,
    "weight_n": 1,
    "friction_mu": 1,
    "deformability_n_per_cm": 1,
    "damping_ns_per_cm": 1,
}
SIMULATED = {"lift": _lift_sim, "measure": _measure_sim}


@pytest.fixture
def sim_specs(monkeypatch: pytest.MonkeyPatch) -> collections.Counter[str]:
    """Every simulator spec built from a catalog row from now on, counted by object id."""
    from deformctl.catalog import CatalogObject

    built: collections.Counter[str] = collections.Counter()
    to_sim_spec = CatalogObject.to_sim_spec

    def counting(self: CatalogObject, *, path: str | None = None) -> object:
        built[self.object_id] += 1
        return to_sim_spec(self, path=path)

    monkeypatch.setattr(CatalogObject, "to_sim_spec", counting)
    return built


@pytest.mark.parametrize("command", list(SIMULATED))
def test_a_simulated_run_builds_each_objects_spec_once(
    command: str, tmp_path: Path, sim_specs: collections.Counter[str]
) -> None:
    _second_run(SIMULATED[command](tmp_path), sim_specs)
    assert dict(sim_specs) == {"a": 1, "b": 1}


@pytest.mark.parametrize("command", list(SIMULATED))
def test_a_simulated_run_checks_each_catalog_value_once(
    command: str, tmp_path: Path, checks: collections.Counter[str]
) -> None:
    _second_run(SIMULATED[command](tmp_path), checks)
    for name, per_object in CATALOG_CHECKS.items():
        assert checks[name] == 2 * per_object, (name, dict(checks))


@pytest.mark.parametrize("command", list(SIMULATED))
def test_a_sweep_builds_each_objects_spec_once_in_parent_and_worker(
    command: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    sim_specs: collections.Counter[str],
) -> None:
    """A sweep (``-o DIR/``) plans each object in the parent; its worker, given the task and
    the item as a worker process receives them (pickled), runs the plan without building the
    spec again. (The executor is replaced: a worker process's calls cannot be counted here.)"""
    import deformctl.lift.runners.sim as lift_runner
    import deformctl.measure.stage as measure_stage

    outputs: list[Any] = []

    def in_workers(task: Any, items: list[dict[str, Any]], **_: Any) -> None:
        for item in items:
            worker_task, worker_item = pickle.loads(pickle.dumps((task, item)))
            outputs.append(worker_task(worker_item))

    module = lift_runner if command == "lift" else measure_stage
    monkeypatch.setattr(module, "run_sweep", in_workers)
    argv = SIMULATED[command](tmp_path)
    argv[argv.index("-o") + 1] = str(tmp_path / "out") + "/"
    cli.invoke(app, argv)  # the run's end needs the real executor's summary
    assert len(outputs) == 2
    assert all(out.error is None for out in outputs), outputs
    assert dict(sim_specs) == {"a": 1, "b": 1}
