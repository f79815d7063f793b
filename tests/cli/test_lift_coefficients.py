"""``lift coefficients.parquet --sim`` lifts the measured object.

The coefficients table of a simulated squeeze carries the catalog's size, weight and μ
(characterize copies them) and the measured D and λ, which become the object's material: its
L_f must be the catalog's within 1 % (the measured D and λ are the material's within the fit's
error, and the search's own tolerance is 0.5 %). A table without a size or a weight is one
exit-65 line naming the column and the ``measure`` flag that records it.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner, Result

from deformctl.artifacts import read_table
from deformctl.cli import app
from tests._helpers.cli import _error

ROOT = Path(__file__).resolve().parents[2]
PAPER = ROOT / "datasets" / "paper" / "objects.csv"
runner = CliRunner()
#: a coarser lattice and a shorter lift (both lifts alike: the comparison is of the objects)
FAST_LIFT = ["--alpha-cm", "10", "--dt-s", "0.002", "--lift-hold-s", "0.05"]


def _ok(result: Result) -> Result:
    assert result.exit_code == 0, (result.exit_code, result.stderr)
    return result


def test_lift_from_coefficients_reproduces_the_catalog_lift(tmp_path: Path) -> None:
    log, coef = tmp_path / "squeeze.mcap", tmp_path / "coefficients.parquet"
    _ok(runner.invoke(app, ["measure", "sim", str(PAPER), "--objects", "C", "-o", str(log)]))
    _ok(runner.invoke(app, ["characterize", str(log), "-o", str(coef)]))
    measured = read_table(coef, "coefficients").iloc[0]
    assert measured["deformability_n_per_cm"] != 30.02  # measured, not the catalog's material
    out = {}
    for name, source in (("catalog", PAPER), ("coefficients", coef)):
        out[name] = tmp_path / f"lift_{name}.parquet"
        _ok(
            runner.invoke(
                app,
                ["lift", "sim", str(source), "--objects", "C", *FAST_LIFT, "-o", str(out[name])],
            )
        )
    by_catalog = read_table(out["catalog"], "lift_results").iloc[0]
    by_table = read_table(out["coefficients"], "lift_results").iloc[0]
    assert bool(by_table["converged"])
    assert (by_table["weight_n"], by_table["friction_mu"]) == (2.9, 0.5)
    assert by_table["lift_force_n"] == pytest.approx(by_catalog["lift_force_n"], rel=0.01)


@pytest.mark.parametrize(("drop", "flag"), [("size_y_cm", "--size-cm"), ("weight_n", "--weight-n")])
def test_a_missing_size_or_weight_names_the_column_and_the_flag(
    tmp_path: Path, drop: str, flag: str
) -> None:
    from deformctl.artifacts import write_table

    table = pd.DataFrame({"object_id": ["A", "B"], "deformability_n_per_cm": [30.0, 20.0],
                          "damping_ns_per_cm": [0.5, 1.0], "weight_n": [2.9, 1.0],
                          "size_x_cm": [6.0, 5.0], "size_y_cm": [6.0, 5.0],
                          "size_z_cm": [8.0, 5.0], "friction_mu": [0.6, 0.5]})  # fmt: skip
    table.loc[1, drop] = float("nan")
    path = tmp_path / "coefficients.parquet"
    write_table(table, path, "coefficients", provenance=None)
    out = tmp_path / "lift.parquet"
    line = _error(runner.invoke(app, ["lift", "sim", str(path), "-o", str(out)]), 65)
    assert line == (
        f"error: {path}: {drop} is missing for B: a coefficients table lifts only objects whose "
        f"squeeze log recorded it (measure {flag}, or a catalog with it to measure sim)"
    )
    assert not out.exists()
    write_table(table.drop(columns=[drop]), path, "coefficients", provenance=None, force=True)
    line = _error(runner.invoke(app, ["lift", "sim", str(path), "-o", str(out)]), 65)
    assert f"{drop} is missing for A, B" in line
    assert flag in line
