"""A law-aware predictions table written through the CLI: material_law and law_assumed columns.

The predictions schema is read from ``deformctl.schemas``; with the shared editable install that
is /work/main's copy, so run this file with this tree's schemas on the path (the columns are in
this tree's schemas/predictions.columns.json). Extra columns are accepted by either copy.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from deformctl.artifacts import read_table, write_table
from deformctl.cli import app
from tests.grip._synthetic import law_index
from tests.grip._synthetic import train_cli as _train

runner = CliRunner()


@pytest.fixture(scope="module")
def model(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    d = tmp_path_factory.mktemp("lawcli")
    path = _train(d, law_index(360, seed=3, noise=0.01), "mixed")
    rows = law_index(12, seed=21, noise=0.01, prefix="Q")
    rows.loc[0, "model"] = None  # characterize could not tell
    write_table(rows, d / "rows.parquet", "index_table", provenance=None)
    return path, d


def test_predictions_table_names_the_law_of_every_row(model: tuple[Path, Path]) -> None:
    path, d = model
    out = d / "pred.parquet"
    result = runner.invoke(
        app, ["predict", str(path), str(d / "rows.parquet"), "--coverage", "0.9", "-o", str(out)]
    )
    assert result.exit_code == 0, result.stderr
    table = read_table(out, "predictions")
    rows = read_table(d / "rows.parquet")
    assert table["law_assumed"].tolist() == [True] + [False] * 11
    stated = rows["model"].tolist()[1:]
    assert table["material_law"].tolist()[1:] == stated
    assert not bool(table["bound_guaranteed"].iloc[0])
    assert np.all(np.isfinite(table["lift_force_upper_n"]))
    assert "law_assumed = true" in result.stderr
