"""``deformctl table``: building the index table, looking it up, and every refusal.

Inputs come from ``examples/synthetic_index.py`` (the paper's population with a closed-form
lifting force), so this file also runs that example. Lookups are checked against a nearest
neighbour and an inverse-distance weighting computed here with plain numpy.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from deformctl.artifacts import Provenance, read_table, sha256_file, write_table
from deformctl.cli import app
from tests._helpers.cli import _error, load_example

runner = CliRunner()
ROOT = Path(__file__).resolve().parents[2]
KEYS = ["weight_n", "deformability_n_per_cm", "damping_ns_per_cm"]


def _prov() -> Provenance:
    return Provenance.from_invocation(argv=["test"])


@pytest.fixture
def inputs(tmp_path: Path) -> tuple[Path, Path]:
    """coefficients.parquet and lift.parquet for 12 objects, written by the example script."""
    assert load_example().main([str(tmp_path), "--n", "12", "--seed", "4"]) == 0
    return tmp_path / "coefficients.parquet", tmp_path / "lift.parquet"


def test_build_joins_by_object_id(inputs: tuple[Path, Path], tmp_path: Path) -> None:
    coef_path, lift_path = inputs
    out = tmp_path / "index.parquet"
    result = runner.invoke(app, ["table", str(coef_path), str(lift_path), "-o", str(out)])
    assert result.exit_code == 0, result.stderr
    assert result.stderr == f"wrote {out}: 12 objects\n"
    index = read_table(out, "index_table")
    coef = read_table(coef_path, "coefficients").set_index("object_id")
    lift = read_table(lift_path, "lift_results").set_index("object_id")
    assert list(index["object_id"]) == sorted(coef.index)
    idx = index.set_index("object_id")
    for col, src in (
        ("deformability_n_per_cm", coef),
        ("damping_ns_per_cm", coef),
        ("weight_n", lift),
        ("lift_force_n", lift),
        ("friction_mu", lift),
        ("f_w_n", lift),
    ):
        np.testing.assert_array_equal(idx[col].to_numpy(), src.loc[idx.index, col].to_numpy())
    assert idx["converged"].all()
    prov = index.attrs["provenance"]
    assert prov.inputs == {
        str(coef_path): sha256_file(coef_path),
        str(lift_path): sha256_file(lift_path),
    }
    assert prov.settings == {"allow_unconverged": False, "allow_flagged": False}


def _index(inputs: tuple[Path, Path], tmp_path: Path) -> tuple[Path, pd.DataFrame]:
    out = tmp_path / "index.parquet"
    result = runner.invoke(app, ["table", *map(str, inputs), "-o", str(out)])
    assert result.exit_code == 0, result.stderr
    return out, read_table(out, "index_table")


def _standardized(index: pd.DataFrame, query: list[float]) -> np.ndarray:
    values = index[KEYS].to_numpy()
    std = values.std(axis=0)  # population std, as the module promises
    return np.sqrt((((values - np.array(query)) / std) ** 2).sum(axis=1))


def test_lookup_json_nearest_and_interpolation(inputs: tuple[Path, Path], tmp_path: Path) -> None:
    path, index = _index(inputs, tmp_path)
    query = [41.0, 37.5, 6.25]
    text = ",".join(f"{k}={v}" for k, v in zip(KEYS, query, strict=True))
    result = runner.invoke(
        app, ["table", str(path), "--lookup", text, "--interpolate", "3", "--json"]
    )
    assert result.exit_code == 0, result.stderr
    out = json.loads(result.stdout)
    dist = _standardized(index, query)
    i = int(np.argmin(dist))
    assert out["query"] == dict(zip(KEYS, query, strict=True))
    assert out["nearest"]["object_id"] == index["object_id"][i]
    assert out["nearest"]["lift_force_n"] == index["lift_force_n"][i]
    assert out["distance_std"] == pytest.approx(dist[i], rel=1e-12)
    # Inverse-distance (power 2) weights over the 3 nearest, computed independently.
    order = np.argsort(dist)[:3]
    w = 1.0 / dist[order] ** 2
    expected = float(np.dot(w / w.sum(), index["lift_force_n"].to_numpy()[order]))
    assert out["interpolated"]["lift_force_n"] == pytest.approx(expected, rel=1e-12)
    assert [n["object_id"] for n in out["interpolated"]["neighbours"]] == list(
        index["object_id"].to_numpy()[order]
    )


def test_lookup_text_on_an_entry_has_distance_zero(
    inputs: tuple[Path, Path], tmp_path: Path
) -> None:
    path, index = _index(inputs, tmp_path)
    row = index.iloc[5]
    text = ",".join(f"{k}={float(row[k])!r}" for k in KEYS)
    result = runner.invoke(app, ["table", str(path), "--lookup", text])
    assert result.exit_code == 0, result.stderr
    first = result.stdout.splitlines()[0]
    assert first == f"nearest: {row['object_id']} (distance 0 std units)"
    assert f"lift_force_n             {row['lift_force_n']:.6g}" in result.stdout


def test_missing_objects_on_either_side_are_named(
    inputs: tuple[Path, Path], tmp_path: Path
) -> None:
    coef_path, lift_path = inputs
    coef = read_table(coef_path, "coefficients")
    lift = read_table(lift_path, "lift_results")
    write_table(
        coef[coef["object_id"] != "P03"], coef_path, "coefficients", provenance=_prov(), force=True
    )
    write_table(
        lift[lift["object_id"] != "P07"], lift_path, "lift_results", provenance=_prov(), force=True
    )
    before = sorted(os.listdir(tmp_path))
    result = runner.invoke(
        app, ["table", str(coef_path), str(lift_path), "-o", str(tmp_path / "i.parquet")]
    )
    msg = _error(result, 65)
    assert msg == (
        f"error: {coef_path} + {lift_path}: "
        "1 object(s) have no lift result: P07; 1 object(s) have no coefficients: P03"
    )
    assert sorted(os.listdir(tmp_path)) == before


def test_unconverged_refused_unless_allowed(inputs: tuple[Path, Path], tmp_path: Path) -> None:
    coef_path, lift_path = inputs
    lift = read_table(lift_path, "lift_results")
    lift.loc[lift["object_id"].isin(["P02", "P09"]), "converged"] = False
    write_table(lift, lift_path, "lift_results", provenance=_prov(), force=True)
    out = tmp_path / "i.parquet"
    result = runner.invoke(app, ["table", str(coef_path), str(lift_path), "-o", str(out)])
    assert _error(result, 65) == (
        f"error: {coef_path} + {lift_path}: "
        "2 object(s) did not converge: P02, P09 (use --allow-unconverged to keep them)"
    )
    assert not out.exists()
    result = runner.invoke(
        app, ["table", str(coef_path), str(lift_path), "-o", str(out), "--allow-unconverged"]
    )
    assert result.exit_code == 0, result.stderr
    assert "2 unconverged kept" in result.stderr
    index = read_table(out, "index_table")
    assert sorted(index["object_id"][~index["converged"]]) == ["P02", "P09"]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["C"], "got 1 input(s); to build the index table use"),
        (["C", "L"], "building the index table needs -o/--output"),
        (["C", "L", "X", "-o", "O"], "got 3 input(s)"),
        (["C", "L", "--lookup", "weight_n=1"], "--lookup takes exactly one index table, got 2"),
        (["C", "--lookup", "weight_n=1", "-o", "O"], "-o/--output is for building"),
        (["C", "--lookup", "weight_n=1", "--allow-unconverged"], "--allow-unconverged is for"),
        (["C", "L", "-o", "O", "--interpolate", "3"], "--interpolate needs --lookup"),
        (["C", "--lookup", "weight_n=1,deformability_n_per_cm=2,damping_ns_per_cm=3",
          "--interpolate", "0"], "--interpolate must be >= 1, got 0"),
        (["C", "--lookup", "weight_n=40,damping_ns_per_cm=5"],
         "lookup is missing deformability_n_per_cm; expected keys:"),
        (["C", "--lookup", "weight_n=40,deformability_n_per_cm=40,damping_ns_per_cm=5,mass=3"],
         "unknown lookup key 'mass'"),
        (["C", "--lookup", "weight_n=x,deformability_n_per_cm=40,damping_ns_per_cm=5"],
         "lookup value of weight_n is not a number: 'x'"),
    ],
)  # fmt: skip
def test_usage_errors_exit_2(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, args: list[str], message: str
) -> None:
    # Usage is checked before any file is opened: the names need not exist.
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, ["table", *args])
    assert message in _error(result, 2)
    assert os.listdir(tmp_path) == []


def test_missing_input_66_and_existing_output_needs_force(
    inputs: tuple[Path, Path], tmp_path: Path
) -> None:
    coef_path, lift_path = inputs
    out = tmp_path / "i.parquet"
    missing = tmp_path / "nope.parquet"
    result = runner.invoke(app, ["table", str(coef_path), str(missing), "-o", str(out)])
    assert _error(result, 66) == f"error: {missing}: no such file"
    result = runner.invoke(
        app,
        [
            "table",
            str(missing),
            "--lookup",
            "weight_n=1,deformability_n_per_cm=2,damping_ns_per_cm=3",
        ],
    )
    assert _error(result, 66) == f"error: {missing}: no such file"
    assert not out.exists()

    out.write_bytes(b"keep")
    result = runner.invoke(app, ["table", str(coef_path), str(lift_path), "-o", str(out)])
    assert _error(result, 1) == f"error: {out}: exists already, not overwriting (use --force)"
    assert out.read_bytes() == b"keep"
    result = runner.invoke(
        app, ["table", str(coef_path), str(lift_path), "-o", str(out), "--force"]
    )
    assert result.exit_code == 0, result.stderr
    assert len(read_table(out, "index_table")) == 12


def test_inputs_in_the_wrong_order_are_refused(inputs: tuple[Path, Path], tmp_path: Path) -> None:
    coef_path, lift_path = inputs
    out = tmp_path / "i.parquet"
    result = runner.invoke(app, ["table", str(lift_path), str(coef_path), "-o", str(out)])
    assert _error(result, 65) == (
        f"error: {lift_path}: field 'deformctl': is a lift_results table, expected coefficients"
    )
    assert not out.exists()


def test_lookup_refuses_a_one_row_table(inputs: tuple[Path, Path], tmp_path: Path) -> None:
    _, index = _index(inputs, tmp_path)
    one = tmp_path / "one.parquet"
    write_table(index.iloc[:1], one, "index_table", provenance=_prov())
    for extra in ([], ["--interpolate", "2"], ["--json"]):
        result = runner.invoke(
            app,
            [
                "table",
                str(one),
                "--lookup",
                "weight_n=1,deformability_n_per_cm=2,damping_ns_per_cm=3",
                *extra,
            ],
        )
        msg = _error(result, 65)
        assert msg == (
            "error: the index table has 1 row(s); a lookup needs at least 2 (distances are "
            "standardized by the spread over the table)"
        )
        assert result.stdout == ""


LOOKUP = "weight_n=40,deformability_n_per_cm=40,damping_ns_per_cm=5"


def test_lookup_refuses_a_table_from_another_tool(
    inputs: tuple[Path, Path], tmp_path: Path
) -> None:
    """Same columns and dtypes, written by pandas: no deformctl metadata, so no provenance."""
    _, index = _index(inputs, tmp_path)
    foreign = tmp_path / "foreign.parquet"
    plain = pd.DataFrame({c: index[c].to_numpy() for c in index.columns})
    plain.to_parquet(foreign)
    msg = _error(runner.invoke(app, ["table", str(foreign), "--lookup", LOOKUP]), 65)
    assert msg.startswith(
        f"error: {foreign}: not a deformctl index_table (no 'deformctl' metadata)"
    )
    assert msg.endswith("build one with `deformctl table COEFFICIENTS LIFT -o INDEX`")


@pytest.mark.parametrize("which", [0, 1])
def test_lookup_refuses_a_table_of_another_kind(
    inputs: tuple[Path, Path], tmp_path: Path, which: int
) -> None:
    other = inputs[which]
    kind = ("coefficients", "lift_results")[which]
    msg = _error(runner.invoke(app, ["table", str(other), "--lookup", LOOKUP]), 65)
    assert f"is a {kind} table, expected index_table" in msg


def test_lookup_warns_and_flags_keys_without_spread(tmp_path: Path) -> None:
    table = pd.DataFrame(
        {
            "object_id": ["A", "B", "C"],
            "weight_n": [20.0, 40.0, 30.0],
            "deformability_n_per_cm": [30.0, 30.0, 30.0],
            "damping_ns_per_cm": [1.0, 1.0, 1.0],
            "lift_force_n": [15.0, 30.0, 22.0],
            "friction_mu": [1.0, 1.0, 1.0],
            "f_w_n": [10.0, 20.0, 15.0],
            "converged": [True, True, True],
        }
    )
    path = tmp_path / "flat.parquet"
    write_table(table, path, "index_table", provenance=_prov())
    result = runner.invoke(app, ["table", str(path), "--lookup", LOOKUP, "--json"])
    assert result.exit_code == 0, result.stderr
    assert result.stderr == (
        "warning: deformability_n_per_cm, damping_ns_per_cm have no spread over the index "
        "table: compared in raw units, not standard deviations\n"
    )
    out = json.loads(result.stdout)
    assert out["keys_in_raw_units"] == ["deformability_n_per_cm", "damping_ns_per_cm"]
    assert out["nearest"]["object_id"] == "B"
    # D is 10 N/cm from every entry in raw units, W is 0 std from B, λ 4 N·s/cm raw.
    assert out["distance_std"] == pytest.approx(float(np.hypot(10.0, 4.0)), rel=1e-12)


def test_lookup_without_flat_keys_flags_none(inputs: tuple[Path, Path], tmp_path: Path) -> None:
    path, _ = _index(inputs, tmp_path)
    result = runner.invoke(app, ["table", str(path), "--lookup", LOOKUP, "--json"])
    assert result.exit_code == 0, result.stderr
    assert result.stderr == ""
    assert json.loads(result.stdout)["keys_in_raw_units"] == []
