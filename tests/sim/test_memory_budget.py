"""The memory estimate made before a model is built, and the budget that refuses oversized ones."""

from __future__ import annotations

import resource
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from deformctl.cli import app
from deformctl.errors import UsageError
from deformctl.sim import ObjectSpec, SimSettings
from deformctl.sim.engine import (
    GIB,
    build_model,
    memory_estimate_bytes,
    plan_run,
    run_model,
)
from deformctl.sim.multigrid import solve

CUBE = ObjectSpec("cube", (10.0, 10.0, 10.0), 5.0, 0.5, 30.0, 1.0)
CATALOG = (
    "object_id,size_x_cm,size_y_cm,size_z_cm,weight_n,friction_mu,"
    "material_stiffness_n_per_cm,material_damping_ns_per_cm\nA,10,10,10,1,0.5,10,1\n"
)


def test_estimate_grows_with_the_lattice_and_refuses_above_the_budget() -> None:
    small = memory_estimate_bytes(CUBE, SimSettings())
    fine = memory_estimate_bytes(CUBE, SimSettings(particles_per_side=21))
    assert small < 0.1 * GIB
    assert 0.1 * GIB < fine < 2.0 * GIB  # 9,261 particles fit the default budget
    plan_run(CUBE, SimSettings(particles_per_side=21), 0, "squeeze")
    with pytest.raises(UsageError) as err:
        plan_run(CUBE, SimSettings(particles_per_side=21, memory_budget_gib=0.1), 0, "squeeze")
    message = str(err.value)
    assert "\n" not in message
    assert "9,261 particles" in message
    assert "GiB" in message
    assert "budget of 0.1 GiB" in message
    # absurd lattices are refused without overflow
    with pytest.raises(UsageError, match="particles"):
        plan_run(CUBE, SimSettings(alpha_cm=1e-4), 0, "squeeze")


def test_estimate_is_above_what_a_build_really_takes() -> None:
    """The estimate of a 13^3 cube covers the resident-memory growth of building its model."""
    # compile the kernels of both solvers first (numba's compiler takes ~100 MB once)
    for solver in ("direct", "iterative"):
        small = build_model(CUBE, SimSettings(particles_per_side=4, solver=solver), gripped=True)
        run_model(small, np.full(3, 1.0), np.zeros(3))
    assert small.hierarchy is not None
    solve(small.hierarchy, np.zeros(small.n_dof, dtype=bool), np.ones(small.n_dof), rel_tol=1e-6)
    settings = SimSettings(particles_per_side=13)
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    build_model(CUBE, settings, gripped=True)
    after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    assert after - before < memory_estimate_bytes(CUBE, settings)


@pytest.mark.parametrize("command", ["measure", "lift"])
def test_cli_memory_budget_option_refuses_with_one_line(command: str, tmp_path: Path) -> None:
    catalog = tmp_path / "cat.csv"
    catalog.write_text(CATALOG)
    out = tmp_path / ("x.mcap" if command == "measure" else "x.parquet")
    argv = [command, "sim", str(catalog), "--alpha-cm", "0.5", "--memory-budget-gib", "0.05"]
    result = CliRunner().invoke(app, [*argv, "-o", str(out)])
    assert result.exit_code == 2
    assert result.stderr.startswith("error: ")
    assert result.stderr.count("\n") == 1
    assert "9,261 particles" in result.stderr
    assert "budget of 0.05 GiB" in result.stderr
    assert not out.exists()


def test_cli_memory_budget_needs_sim(tmp_path: Path) -> None:
    catalog = tmp_path / "cat.csv"
    catalog.write_text(CATALOG)
    argv = ["lift", "rig", str(catalog), "--command", "true", "--memory-budget-gib", "1", "-o",
            str(tmp_path / "x.parquet")]  # fmt: skip
    result = CliRunner().invoke(app, argv)
    assert result.exit_code == 2
    assert "lift rig: no such option: --memory-budget-gib" in result.stderr
