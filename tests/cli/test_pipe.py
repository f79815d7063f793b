"""From a recording to a grip force in one pipe.

``measure … -o - | characterize - -o - | predict grip -``: characterize copies each object's
weight, size, μ and source from the squeeze log into the coefficients table, so predict needs no
catalog; a catalog still wins (with a warning naming each value that differs); a table without
weights, and an empty stdin, are one exit-65 line. (The shell pipe itself runs in the docs test,
docs/guide/gripper.md.)
"""

from __future__ import annotations

import io
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner, Result

from deformctl.artifacts import write_table
from deformctl.artifacts.tables import read_parquet_bytes
from deformctl.cli import app
from tests._helpers.cli import _error

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "datasets" / "examples"
UTM = EXAMPLES / "utm_export.csv"  # a Kelvin–Voigt foam block, D = 20 N/cm, λ = 3 N·s/cm
PHANTOM = EXAMPLES / "phantom" / "EF10_0T_A1.csv"  # one speed: λ not identifiable
runner = CliRunner()


def _ok(result: Result) -> Result:
    assert result.exit_code == 0, (result.exit_code, result.stderr)
    return result


def _coefficients(
    csv: Path, *extra: str, object_id: str = "foam", law: tuple[str, ...] = ()
) -> bytes:
    """The bytes of ``measure csv CSV … -o - | characterize - -o - [law]``."""
    log = _ok(runner.invoke(app, ["measure", "csv", str(csv), "--object-id", object_id,
                                  *extra, "-o", "-"])).stdout_bytes  # fmt: skip
    assert log[:5] == b"\x89MCAP"
    table = _ok(runner.invoke(app, ["characterize", "-", "-o", "-", *law], input=log)).stdout_bytes
    assert table[:4] == b"PAR1"
    return table


@pytest.fixture(scope="module")
def foam() -> bytes:
    return _coefficients(UTM, "--weight-n", "2.9", "--friction-mu", "0.6", "--size-cm", "5",
                         "6", "4")  # fmt: skip


def _frame(data: bytes) -> pd.DataFrame:
    from deformctl.artifacts.tables import _frame_from_arrow

    table, meta = read_parquet_bytes(data, "-")
    return _frame_from_arrow(table, meta, "coefficients", "-")


def _predict(data: bytes, *args: str) -> tuple[pd.DataFrame, Result]:
    result = _ok(runner.invoke(app, ["predict", "grip", "-", *args], input=data))
    return pd.read_csv(io.StringIO(result.stdout)), result


def _no_safe_force(object_id: str) -> str:
    """predict's line for an object without a rupture or yield force (window_ok null)."""
    return (
        f"warning: {object_id}: no safe force known (no rupture or yield force measured): "
        "whether the grip crushes it is unknown (window_ok = null)"
    )


def test_characterize_copies_the_object_and_its_source(foam: bytes) -> None:
    row = _frame(foam).iloc[0]
    assert (row["weight_n"], row["friction_mu"], row["source"]) == (2.9, 0.6, "csv")
    assert (row["size_x_cm"], row["size_y_cm"], row["size_z_cm"]) == (5.0, 6.0, 4.0)
    no_size = _frame(_coefficients(UTM, "--weight-n", "2.9")).iloc[0]
    assert math.isnan(no_size["size_x_cm"])
    assert math.isnan(no_size["friction_mu"])


def test_the_pipe_predicts_what_the_flags_predict(foam: bytes) -> None:
    got, result = _predict(foam, "--coverage", "0.9")
    assert result.stderr.splitlines() == [_no_safe_force("foam")]  # it never ruptured
    row = _frame(foam).iloc[0]
    flags = ["--weight-n", "2.9", "--friction-mu", "0.6", "--coverage", "0.9",
             "--deformability-n-per-cm", repr(float(row["deformability_n_per_cm"])),
             "--damping-ns-per-cm", repr(float(row["damping_ns_per_cm"]))]  # fmt: skip
    one = pd.read_csv(io.StringIO(_ok(runner.invoke(app, ["predict", "grip", *flags])).stdout))
    assert got.loc[0, "object_id"] == "foam"
    for col in ("predicted_lift_force_n", "lift_force_upper_n", "f_w_n"):
        assert got.loc[0, col] == pytest.approx(one.loc[0, col], rel=1e-6)
    assert got.loc[0, "lift_force_upper_n"] > got.loc[0, "predicted_lift_force_n"]


def test_a_catalog_wins_and_a_differing_value_is_a_warning(foam: bytes, tmp_path: Path) -> None:
    cat = tmp_path / "objects.csv"
    cat.write_text("object_id,size_x_cm,size_y_cm,size_z_cm,weight_n,friction_mu\n"
                   "foam,5,6,4,3.1,0.6\n")  # fmt: skip
    got, result = _predict(foam, "--catalog", str(cat))
    assert got.loc[0, "weight_n"] == 3.1
    assert result.stderr.splitlines() == [
        f"warning: stdin: weight_n differs between the table and {cat} for foam (2.9 vs 3.1); "
        "using the catalog's",
        _no_safe_force("foam"),
    ]
    same = tmp_path / "same.csv"
    same.write_text(cat.read_text().replace("3.1", "2.9"))
    got, result = _predict(foam, "--catalog", str(same))
    assert result.stderr.splitlines() == [_no_safe_force("foam")]
    assert got.loc[0, "weight_n"] == 2.9


def test_a_table_without_weights_names_the_catalog_flag(foam: bytes, tmp_path: Path) -> None:
    old = _frame(foam).drop(columns=["weight_n", "friction_mu", "source"])
    write_table(old, tmp_path / "old.parquet", "coefficients", provenance=None)
    result = runner.invoke(app, ["predict", "grip", str(tmp_path / "old.parquet")])
    line = _error(result, 65)
    assert "no weight_n column" in line
    assert "--catalog" in line
    blank = _frame(foam).assign(weight_n=np.nan)
    write_table(blank, tmp_path / "blank.parquet", "coefficients", provenance=None)
    result = runner.invoke(app, ["predict", "grip", str(tmp_path / "blank.parquet")])
    assert _error(result, 65) == (
        f"error: {tmp_path / 'blank.parquet'}: weight_n is missing for foam (measure without "
        "--weight-n); pass --catalog OBJECTS to join it by object_id"
    )


@pytest.mark.parametrize("command", [["predict", "grip", "-"], ["characterize", "-", "-o", "-"]])
def test_an_empty_stdin_is_one_line(command: list[str]) -> None:
    line = _error(runner.invoke(app, command, input=b""), 65)
    assert line.startswith("error: <stdin>: empty input: no ")
    assert line.endswith("on stdin (did the command before the pipe fail?)")


def test_unknown_damping_is_predicted_at_the_most_conservative(tmp_path: Path) -> None:
    # Kelvin-Voigt: the bundled model states no law mix, so it refuses a stiffening law's row
    phantom = _coefficients(PHANTOM, "--weight-n", "0.62", "--friction-mu", "0.6", object_id="ef10",
                            law=("--model", "kv"))  # fmt: skip
    assert math.isnan(_frame(phantom).loc[0, "damping_ns_per_cm"])
    got, result = _predict(phantom, "--coverage", "0.9")
    assert bool(got.loc[0, "damping_assumed"])
    assert got.loc[0, "damping_ns_per_cm"] == 0.0
    assert any("damping_ns_per_cm unknown" in ln for ln in result.stderr.splitlines())
    # the truth: the largest prediction over the model's λ range, here at λ = 0
    d = repr(float(_frame(phantom).loc[0, "deformability_n_per_cm"]))
    best = 0.0
    for lam in ("0", "0.5", "3", "15"):
        flags = ["--weight-n", "0.62", "--friction-mu", "0.6", "--deformability-n-per-cm", d,
                 "--damping-ns-per-cm", lam]  # fmt: skip
        one = pd.read_csv(io.StringIO(runner.invoke(app, ["predict", "grip", *flags]).stdout))
        best = max(best, float(one.loc[0, "predicted_lift_force_n"]))
    assert got.loc[0, "predicted_lift_force_n"] == pytest.approx(best, rel=1e-5)


FAST_SQUEEZE = ["--squeezes", "2", "--ramp-s", "0.05", "--hold-s", "0.1", "--dt-s", "0.002",
                "--alpha-cm", "10", "--noise-force-n", "0.01"]  # fmt: skip


def test_a_simulated_squeeze_travels_with_its_catalog_values() -> None:
    paper = ROOT / "datasets" / "paper" / "objects.csv"
    log = _ok(runner.invoke(app, ["measure", "sim", str(paper), "--objects", "C", *FAST_SQUEEZE,
                                  "-o", "-"])).stdout_bytes  # fmt: skip
    short = ["--window-s", "0.03"]  # the fast squeezes are short
    table = _ok(runner.invoke(app, ["characterize", "-", "-o", "-", *short], input=log))
    table = table.stdout_bytes
    row = _frame(table).iloc[0]
    assert row["source"] == "sim"
    assert [row[c] for c in ("size_x_cm", "size_y_cm", "size_z_cm", "weight_n", "friction_mu")] == [
        11.4,
        11.4,
        9.5,
        2.9,
        0.5,
    ]
    alone, result = _predict(table, "--coverage", "0.9")
    assert result.stderr.splitlines() == [_no_safe_force("C")]  # a simulated object never breaks
    joined, result = _predict(table, "--coverage", "0.9", "--catalog", str(paper))
    assert result.stderr.splitlines() == [_no_safe_force("C")]  # the same values: no other line
    pd.testing.assert_frame_equal(alone, joined)
