"""Flags travel to the robot: the safe window, characterize's quality and ``predict --strict``.

* ``window_ok`` is true only with a known safe force above L_f and its bound; null (with a
  warning) without one, false (with a warning naming the object) below.
* ``max_safe_force_n`` is the rupture force less the margin, so it never exceeds the onset force
  of a synthetic fruit collapse whose rupture the detector found.
* ``predict`` reads a ``characterize -o DIR/`` dataset directory and carries each object's
  ``quality``; ``--strict`` exits 1 naming every object that is not window-ok, guaranteed and
  quality-ok, and 0 when all are.
"""

from __future__ import annotations

import io
import math
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from deformctl.artifacts import read_table, write_table
from deformctl.cli import app
from deformctl.predict import strict_problems
from deformctl.squeeze.rupture import SAFE_FORCE_MARGIN
from deformctl.testing.fruit import fruit_squeeze

runner = CliRunner()


def _csv(path: Path, draw: int, shape: str | None = None) -> float:
    """One synthetic fruit squeeze as a CSV export; its onset force (NaN: no rupture)."""
    fs = fruit_squeeze(0, draw, shape=shape)
    s = fs.series
    frame = pd.DataFrame(
        {"Time (s)": s.time_s, "Load (N)": s.force_n, "Compression (mm)": 1e3 * s.compression_m}
    )
    frame.to_csv(path, index=False)
    return fs.onset_force_n


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, float]:
    """A characterize dataset directory of a fruit that yields then breaks (draw 9: peak 14.3 N,
    break 5.75 N) and a relaxation hold."""
    d = tmp_path_factory.mktemp("fruit")
    onset = _csv(d / "kiwi.csv", 9)
    _csv(d / "gel.csv", 0, shape="relaxation")
    logs, coef = d / "logs", d / "coef"
    result = runner.invoke(
        app,
        ["measure", "csv", str(d / "kiwi.csv"), str(d / "gel.csv"), "--weight-n", "1.0",
         "--friction-mu", "0.5", "-o", f"{logs}/"],
    )  # fmt: skip
    assert result.exit_code == 0, result.stderr
    # Kelvin-Voigt: the bundled model states no law mix, so it refuses a stiffening law's row
    result = runner.invoke(app, ["characterize", f"{logs}/", "-o", f"{coef}/", "--model", "kv"])
    assert result.exit_code == 0, result.stderr
    return coef, onset


def test_predict_reads_a_characterize_dataset_and_carries_the_flags(
    dataset: tuple[Path, float],
) -> None:
    coef, onset = dataset
    result = runner.invoke(app, ["predict", "grip", str(coef), "--coverage", "0.9"])
    assert result.exit_code == 0, result.stderr
    rows = pd.read_csv(io.StringIO(result.stdout)).set_index("object_id")
    assert set(rows.index) == {"kiwi", "gel"}
    # the safe force: the break's onset force less the margin, below the onset
    safe = rows.loc["kiwi", "max_safe_force_n"]
    assert safe == pytest.approx((1 - SAFE_FORCE_MARGIN) * onset, rel=0.1)
    assert safe <= onset
    assert "rupture" in rows.loc["kiwi", "quality"].split(",")
    # no rupture, no safe force: the window is unknown, not true
    assert math.isnan(rows.loc["gel", "max_safe_force_n"])
    assert math.isnan(rows.loc["gel", "window_ok"])
    assert rows.loc["gel", "quality"] != "ok"  # (λ not identifiable at one speed)
    err = result.stderr
    assert "warning: gel: no safe force known" in err
    assert "warning: kiwi: characterize flagged it: " in err
    assert "warning: gel: characterize flagged it: " in err


def test_strict_exits_1_naming_every_object(dataset: tuple[Path, float], tmp_path: Path) -> None:
    coef, _ = dataset
    out = tmp_path / "p.parquet"
    result = runner.invoke(
        app, ["predict", "grip", str(coef), "--coverage", "0.9", "--strict", "-o", str(out)]
    )
    assert result.exit_code == 1, result.stderr
    last = result.stderr.splitlines()[-1]
    assert last.startswith("error: predict --strict: 2 object(s) not safe to act on: ")
    assert "gel (no safe force known" in last
    assert "kiwi (" in last
    table = read_table(out, "predictions")  # written first, with the flags
    assert "quality" in table.columns
    assert table["window_ok"].isna().sum() == 1


def _ok_table(path: Path, rupture_n: float, quality: str = "ok") -> None:
    frame = pd.DataFrame(
        {
            "object_id": ["a"], "deformability_n_per_cm": [20.0], "damping_ns_per_cm": [0.5],
            "quality": [quality], "rupture_force_n": [rupture_n], "weight_n": [5.0],
            "friction_mu": [0.5],
        }
    )  # fmt: skip
    write_table(frame, path, "coefficients", provenance=None)


@pytest.mark.parametrize(
    ("rupture_n", "quality", "coverage", "code"),
    [
        (1000.0, "ok", ["--coverage", "0.9"], 0),  # window ok, guaranteed, quality ok
        (1000.0, "ok", [], 1),  # no bound
        (1000.0, "rupture", ["--coverage", "0.9"], 1),  # flagged
        (9.0, "ok", ["--coverage", "0.9"], 1),  # L_f ≈ 7.2 N < 9 N, its margin 7.65 N: false
        (float("nan"), "ok", ["--coverage", "0.9"], 1),  # no safe force known
    ],
)
def test_strict(
    tmp_path: Path, rupture_n: float, quality: str, coverage: list[str], code: int
) -> None:
    _ok_table(tmp_path / "c.parquet", rupture_n, quality)
    args = ["predict", "grip", str(tmp_path / "c.parquet"), *coverage]
    plain = runner.invoke(app, args)
    assert plain.exit_code == 0, plain.stderr
    strict = runner.invoke(app, [*args, "--strict"])
    assert strict.exit_code == code, strict.stderr
    assert strict.stdout == plain.stdout  # the predictions are printed either way
    if code:
        assert strict.stderr.splitlines()[-1].startswith("error: predict --strict: 1 object(s)")


def test_strict_problems_names_the_causes() -> None:
    columns = {
        "object_id": ["a", "b", "c"],
        "predicted_lift_force_n": np.ones(3),
        "window_ok": np.array([True, False, None], dtype=object),
        "bound_guaranteed": np.array([True, True, False]),
        "quality": ["ok", "ok", "rupture"],
    }
    assert strict_problems(columns) == [
        "b (window_ok false)",
        "c (no safe force known, bound not guaranteed, quality rupture)",
    ]
    assert strict_problems(columns, ["d"])[0] == "d (not characterized)"
    no_window = {"predicted_lift_force_n": np.ones(1), "bound_guaranteed": np.array([True])}
    assert strict_problems(no_window) == ["row 0 (no safe force known)"]


def test_a_failed_object_of_the_dataset_is_named(
    dataset: tuple[Path, float], tmp_path: Path
) -> None:
    coef = tmp_path / "coef"
    shutil.copytree(dataset[0], coef)
    failures = next((coef / "_failures").glob("part-*.parquet"))
    schema = pq.read_schema(failures)
    row = {
        "object_id": ["ghost"],
        "cause": ["bad_input"],
        "error_message": ["no squeeze"],
    }
    pq.write_table(pa.table(row, schema=schema), failures)
    result = runner.invoke(app, ["predict", "grip", str(coef), "--coverage", "0.9", "--strict"])
    assert result.exit_code == 1
    assert "warning: " in result.stderr
    assert "ghost: no prediction: coefficients failed on it (no squeeze)" in result.stderr
    assert "ghost (not characterized)" in result.stderr.splitlines()[-1]


def test_another_dataset_or_directory_is_one_line(
    dataset: tuple[Path, float], tmp_path: Path
) -> None:
    logs = dataset[0].parent / "logs"
    result = runner.invoke(app, ["predict", "grip", f"{logs}/"])
    assert result.exit_code == 65
    assert result.stderr.strip().endswith(
        "is a squeeze_log dataset; predict reads coefficients, index_table, predictions tables"
    )
    (tmp_path / "empty").mkdir()
    result = runner.invoke(app, ["predict", "grip", str(tmp_path / "empty")])
    assert result.exit_code == 65
    assert result.stderr.count("\n") == 1
    assert "not a deformctl dataset directory" in result.stderr
