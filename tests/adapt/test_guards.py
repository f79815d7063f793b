"""Guards for ``adapt``: the rig rows get the refusal list ``table``, ``train`` and
``table --lookup`` apply (:func:`deformctl.table.impossible_rows`, the one function), one exit-65
line naming the rows, nothing written; a prediction that is not a finite force > 0 is refused, never
stored or printed. Good rig rows are adapted without a word about them.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from deformctl.adapt import adapt_model
from deformctl.artifacts import write_table
from deformctl.cli import app
from deformctl.errors import InputDataError
from deformctl.grip.fast import Predictor

runner = CliRunner()


def _rig_rows(base: Predictor, n: int = 5) -> pd.DataFrame:
    """n rig rows whose L_f is the bundled model's prediction times 1.1 (a plausible gap)."""
    rng = np.random.default_rng(11)
    rows = pd.DataFrame({
        "object_id": [f"R{i:02d}" for i in range(n)], "weight_n": rng.uniform(1, 40, n),
        "deformability_n_per_cm": rng.uniform(8, 50, n), "damping_ns_per_cm": rng.uniform(0, 10, n),
        "friction_mu": rng.uniform(0.3, 0.9, n),
    })  # fmt: skip
    cols = [rows[c].to_numpy() for c in base.features]
    rows["lift_force_n"] = 1.1 * base.predict_many(*cols).lift_force_n
    rows["f_w_n"] = rows["weight_n"] / (2 * rows["friction_mu"])
    rows["converged"] = True
    rows["source"] = "rig"
    return rows


@pytest.fixture(scope="module")
def base() -> Predictor:
    return Predictor.load("grip")


def _set(column: str, values: dict[int, float]) -> Any:
    def change(t: pd.DataFrame) -> pd.DataFrame:
        t = t.copy()
        for i, v in values.items():
            t.loc[i, column] = v
        return t

    return change


def _below_f_w(t: pd.DataFrame) -> pd.DataFrame:
    t = t.copy()
    t.loc[1, "lift_force_n"] = 0.5 * t.loc[1, "f_w_n"]
    return t


L_F = "lift_force_n"
CASES = [
    (_set(L_F, {2: 0.0}), "R02", "lift_force_n <= 0 for R02 (0 N)"),
    (_set(L_F, {0: -3.0, 3: -1.0}), "R00", "lift_force_n <= 0 for R00, R03 (-3 N, ...)"),
    (_set(L_F, {4: math.inf}), "R04", "lift_force_n not a finite number for R04 (inf N)"),
    (_set(L_F, {3: 1e308}), "R03", "lift_force_n above 10 x F_w for R03 (1e+308 N, F_w "),
    (_below_f_w, "R01", "lift_force_n below F_w for R01"),
    (_set("deformability_n_per_cm", {0: -20.0}), "R00", "deformability_n_per_cm <= 0 for R00 (-20"),
    (_set("damping_ns_per_cm", {1: -5.0}), "R01", "damping_ns_per_cm < 0 for R01 (-5"),
]  # fmt: skip


@pytest.mark.parametrize(("change", "row", "message"), CASES)
def test_impossible_rig_rows_are_refused_naming_the_rows(
    base: Predictor, change: Any, row: str, message: str
) -> None:
    with pytest.raises(InputDataError) as info:
        adapt_model("grip", change(_rig_rows(base)), index_path="rig.parquet")
    assert str(info.value).startswith("rig.parquet: impossible rows in the rig rows: ")
    assert message in str(info.value)


@pytest.mark.parametrize(("change", "row", "message"), CASES)
def test_the_command_says_it_in_one_line_and_writes_nothing(
    base: Predictor, tmp_path: Path, change: Any, row: str, message: str
) -> None:
    """From the CLI the table's schema may refuse first (a negative or infinite L_f): either
    way one exit-65 line names the file and the row."""
    index = tmp_path / "rig.parquet"
    change(_rig_rows(base)).to_parquet(index)  # not through the writer, which refuses some
    out = tmp_path / "adapted.skops"
    res = runner.invoke(app, ["adapt", "grip", str(index), "-o", str(out)])
    assert res.exit_code == 65, res.stderr
    lines = res.stderr.splitlines()
    assert len(lines) == 1, res.stderr
    assert lines[0].startswith(f"error: {index}: "), res.stderr
    assert row in lines[0], lines[0]
    assert res.stdout == ""
    assert not out.exists()


def test_the_same_function_refuses_for_table_train_and_adapt(base: Predictor) -> None:
    """adapt's words are impossible_rows' words (one function for every command)."""
    from deformctl.table import impossible_rows

    rows = _set("lift_force_n", {3: 1e308})(_rig_rows(base))
    with pytest.raises(InputDataError) as info:
        adapt_model("grip", rows, index_path="rig.parquet")
    assert str(info.value) == (
        f"rig.parquet: impossible rows in the rig rows: {'; '.join(impossible_rows(rows))}"
    )


def test_a_non_positive_prediction_is_refused_not_printed(
    base: Predictor, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """A base model that predicts a negative or infinite L_f for a rig row (its own checks
    passed at its stored points) is refused naming the rows; nothing is fitted or written."""
    rows = _rig_rows(base)
    real = Predictor.predict_many

    def broken(self: Predictor, *args: Any, **kwargs: Any) -> Any:
        import dataclasses

        got = real(self, *args, **kwargs)
        lift = got.lift_force_n.copy()
        lift[[1, 2]] = [-4.0, math.inf]
        return dataclasses.replace(got, lift_force_n=lift)

    monkeypatch.setattr(Predictor, "predict_many", broken)
    with pytest.raises(InputDataError) as info:
        adapt_model("grip", rows, index_path="rig.parquet")
    assert "rows R01, R02: the base model's prediction is not a finite force > 0 (-4 N)" in str(
        info.value
    )


def test_good_rig_rows_are_adapted_silently(base: Predictor, tmp_path: Path) -> None:
    index = tmp_path / "rig.parquet"
    write_table(_rig_rows(base), index, "index_table", provenance=None)
    out = tmp_path / "adapted.skops"
    res = runner.invoke(app, ["adapt", "grip", str(index), "-o", str(out)])
    assert res.exit_code == 0, res.stderr
    assert "impossible" not in res.stderr
    assert "not a finite force" not in res.stderr
    assert out.exists()
