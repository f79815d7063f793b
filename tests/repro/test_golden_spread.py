"""``make golden-spread``'s pieces that run without subprocesses: environments and the table."""

from __future__ import annotations

import copy
import json
import math

import pytest

from deformctl.repro import golden_spread
from deformctl.repro.golden import EXPECTED_PATH, TOLERANCES, family, flatten
from deformctl.repro.golden_spread import Run, kernel_env, spread_rows


def test_kernel_env_sets_only_what_the_run_asks(monkeypatch: pytest.MonkeyPatch) -> None:
    # the variables are set in a copy for the subprocess; this process's environment is untouched
    monkeypatch.setenv("OPENBLAS_L2_SIZE", "1048576")
    env = kernel_env("Haswell", 1)
    assert env["OPENBLAS_CORETYPE"] == "Haswell"
    assert env["OPENBLAS_NUM_THREADS"] == "1"
    assert "OPENBLAS_L2_SIZE" not in env
    default = kernel_env("default", None)
    assert not {"OPENBLAS_CORETYPE", "OPENBLAS_L2_SIZE", "OPENBLAS_NUM_THREADS"} & set(default)
    assert default["PATH"] == env["PATH"]
    assert set(golden_spread.REQUIRED_KERNELS) - {"default"} <= set(golden_spread.CORETYPES)


def test_spread_rows_measure_the_spread_and_the_worst_move() -> None:
    expected = json.loads(EXPECTED_PATH.read_text())
    other = copy.deepcopy(expected)
    oid = sorted(other["objects"])[0]
    d = expected["objects"][oid]["deformability_n_per_cm"]
    other["objects"][oid]["deformability_n_per_cm"] = d * (1 + 2e-5)
    other["model"]["network_test_mae_n"] += 4.0
    runs = [
        Run("default", 1, "SkylakeX", "1", 1.0, expected),
        Run("Haswell", 1, "Haswell", "1", 1.0, other),
    ]
    rows = {r["family"]: r for r in spread_rows(runs, expected)}
    assert set(rows) == {family(k) for k in flatten(expected)}
    row = rows["objects.deformability_n_per_cm"]
    assert row["n"] == len(expected["objects"])
    assert row["abs"] == pytest.approx(2e-5 * d)
    assert row["rel"] == pytest.approx(2e-5, rel=1e-4)  # of the middle value
    allowed = TOLERANCES["objects.deformability_n_per_cm"].allowed(d)
    assert row["ratio"] == pytest.approx(allowed / (2e-5 * d))
    assert row["worst"] == pytest.approx(2e-5 * d / allowed)
    assert rows["objects.lift_force_n"]["abs"] == 0
    assert rows["objects.lift_force_n"]["ratio"] == math.inf
    assert rows["model.network_test_mae_n"]["tolerance"] == "not compared"
    assert rows["model.network_test_mae_n"]["abs"] == pytest.approx(4.0)
