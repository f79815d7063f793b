"""Each option is checked once, where its options type is built, and each catalog value once,
where its row is read: a run of ``measure csv``, ``lift sim`` and ``measure sim`` count the rule
checks (:meth:`Quantity.ok`, which every check runs) of the quantities their options types and
catalog rows hold. Nothing below checks them again, and each object's simulator spec is built
once."""

from __future__ import annotations

import collections
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from deformctl.cli import app
from deformctl.quantities import Quantity

cli = CliRunner()
#: A fast simulated lift (coarse lattice, short hold), as the lift tests use.
FAST_LIFT = ["--alpha-cm", "10", "--dt-s", "0.002", "--hold-s", "0.05", "--lift-height-m", "0.01"]


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


def test_the_counter_counts_a_check(checks: collections.Counter[str]) -> None:
    from deformctl.lift.options import SearchOptions

    SearchOptions(growth=1.5)
    assert checks["growth"] == 1
    assert checks["max_force_n"] == 0


def test_measure_csv_checks_each_segmentation_and_budget_value_once(
    tmp_path: Path, checks: collections.Counter[str]
) -> None:
    t = np.arange(0.0, 2.0, 0.001)
    d = 0.003 * np.sin(np.pi * t / 2) ** 2
    f = 300.0 * d + 20.0 * np.gradient(d, t)
    export = tmp_path / "a.csv"
    rows = (f"{a:.6f},{b:.6f},{c:.8f}" for a, b, c in zip(t, f, d, strict=True))
    export.write_text("time_s,force_n,compression_m\n" + "\n".join(rows) + "\n")
    flags = ["--object-id", "a", "--weight-n", "1", "--memory-budget-gib", "1"]
    argv = ["measure", "csv", str(export), *flags, "-o", str(tmp_path / "m.mcap")]
    _run(argv)  # the modules load (their default options are checked as they load)
    checks.clear()
    _run([*argv, "--force"])
    for name in ("force_threshold_frac", "min_gap_s", "min_squeeze_s", "memory_budget_gib"):
        assert checks[name] == 1, (name, dict(checks))


def test_lift_sim_checks_each_search_value_and_the_ceiling_once(
    tmp_path: Path, checks: collections.Counter[str]
) -> None:
    catalog = tmp_path / "cat.csv"
    catalog.write_text(
        "object_id,size_x_cm,size_y_cm,size_z_cm,weight_n,friction_mu,"
        "material_stiffness_n_per_cm,material_damping_ns_per_cm\na,10,10,10,0.7,0.5,49.18,6.47\n"
    )
    flags = [*FAST_LIFT, *["--growth", "1.3", "--max-attempts", "20", "--max-force-n", "50"]]
    argv = ["lift", "sim", str(catalog), *flags, "-o", str(tmp_path / "l.parquet")]
    _run(argv)
    checks.clear()
    _run([*argv, "--force"])
    for name in ("growth", "tolerance_rel", "max_attempts", "max_force_n"):
        assert checks[name] == 1, (name, dict(checks))


#: Two simulated objects: the counts below are per object.
TWO_OBJECTS = (
    "object_id,size_x_cm,size_y_cm,size_z_cm,weight_n,friction_mu,"
    "material_stiffness_n_per_cm,material_damping_ns_per_cm\n"
    "a,10,10,10,0.7,0.5,49.18,6.47\nb,8,9,10,0.9,0.6,30.0,4.0\n"
)
#: Each catalog quantity's checks per object: one per value (three sizes).
CATALOG_CHECKS = {
    "size_cm": 3,
    "weight_n": 1,
    "friction_mu": 1,
    "deformability_n_per_cm": 1,
    "damping_ns_per_cm": 1,
}
FAST_SQUEEZE = ["--squeezes", "1", "--ramp-s", "0.05", "--hold-s", "0.05", "--scene-hz", "0"]


def _sim_argv(command: str, tmp_path: Path) -> list[str]:
    catalog = tmp_path / "cat.csv"
    catalog.write_text(TWO_OBJECTS)
    if command == "lift":
        return ["lift", "sim", str(catalog), *FAST_LIFT, "-o", str(tmp_path / "l.parquet")]
    fast = ["--alpha-cm", "10", "--dt-s", "0.002", *FAST_SQUEEZE]
    return ["measure", "sim", str(catalog), *fast, "-o", str(tmp_path / "m.mcap")]


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


@pytest.mark.parametrize("command", ["lift", "measure"])
def test_a_simulated_run_builds_each_objects_spec_once(
    command: str, tmp_path: Path, sim_specs: collections.Counter[str]
) -> None:
    argv = _sim_argv(command, tmp_path)
    _run(argv)
    sim_specs.clear()
    _run([*argv, "--force"])
    assert dict(sim_specs) == {"a": 1, "b": 1}


@pytest.mark.parametrize("command", ["lift", "measure"])
def test_a_simulated_run_checks_each_catalog_value_once(
    command: str, tmp_path: Path, checks: collections.Counter[str]
) -> None:
    argv = _sim_argv(command, tmp_path)
    _run(argv)
    checks.clear()
    _run([*argv, "--force"])
    for name, per_object in CATALOG_CHECKS.items():
        assert checks[name] == 2 * per_object, (name, dict(checks))
