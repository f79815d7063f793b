"""``deformctl population``: seeded catalogs through the CLI."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
from typer.testing import CliRunner

from deformctl.artifacts import read_catalog
from deformctl.cli import app
from deformctl.population import golden_population, make_population

runner = CliRunner()


def test_default_is_the_papers_population(tmp_path: Path) -> None:
    out = tmp_path / "pop.csv"
    result = runner.invoke(app, ["population", "--seed", "3", "-o", str(out)])
    assert result.exit_code == 0, result.stderr
    cat = read_catalog(out)
    pd.testing.assert_frame_equal(
        cat.reset_index(drop=True), make_population(73, seed=3), check_dtype=False
    )
    assert cat["weight_n"].between(20, 60).all()
    assert cat["material_stiffness_n_per_cm"].between(30, 50).all()
    assert cat["material_damping_ns_per_cm"].between(0, 13).all()


def test_ranges_and_parquet_output(tmp_path: Path) -> None:
    out = tmp_path / "pop.parquet"
    args = [
        "population",
        "-n",
        "5",
        "--weight-n",
        "1,2",
        "--friction-mu",
        "0.2,0.4",
        "-o",
        str(out),
    ]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.stderr
    cat = read_catalog(out)
    assert len(cat) == 5
    assert cat["weight_n"].between(1, 2).all()
    assert cat["friction_mu"].between(0.2, 0.4).all()


def test_golden(tmp_path: Path) -> None:
    out = tmp_path / "golden.csv"
    assert runner.invoke(app, ["population", "--golden", "-o", str(out)]).exit_code == 0
    assert list(read_catalog(out)["object_id"]) == list(golden_population()["object_id"])


def test_paper_writes_the_four_table_i_objects(tmp_path: Path) -> None:
    out = tmp_path / "p.csv"
    result = runner.invoke(app, ["population", "--paper", "-o", str(out)])
    assert result.exit_code == 0, result.stderr
    assert result.stderr == f"wrote 4 objects to {out}\n"
    cat = read_catalog(out).set_index("object_id")
    assert list(cat.index) == ["A", "B", "C", "D"]
    assert list(cat["interior"]) == ["sponge", "cotton", "sand", "water"]
    # Table I's weights and sizes, Table II's D and λ as the simulator's material values
    assert list(cat["weight_n"]) == [0.7, 1.4, 2.9, 4.9]
    assert list(cat.loc["C", ["size_x_cm", "size_y_cm", "size_z_cm"]]) == [11.4, 11.4, 9.5]
    assert list(cat["material_stiffness_n_per_cm"]) == [49.18, 13.03, 30.02, 10.52]
    assert list(cat["material_damping_ns_per_cm"]) == [6.47, 0.33, 0.47, 0.0]
    pq = tmp_path / "p.parquet"
    assert runner.invoke(app, ["population", "--paper", "-o", str(pq)]).exit_code == 0
    pd.testing.assert_frame_equal(read_catalog(pq), read_catalog(out))


def test_paper_and_golden_together_is_a_usage_error(tmp_path: Path) -> None:
    out = tmp_path / "p.csv"
    result = runner.invoke(app, ["population", "--paper", "--golden", "-o", str(out)])
    assert result.exit_code == 2
    assert (
        result.stderr
        == "error: give one of --golden, --paper and --grip, not --golden and --paper\n"
    )
    assert not out.exists()


def test_paper_refuses_to_overwrite(tmp_path: Path) -> None:
    out = tmp_path / "p.csv"
    out.write_text("mine\n")
    result = runner.invoke(app, ["population", "--paper", "-o", str(out)])
    assert result.exit_code == 1
    assert len(result.stderr.splitlines()) == 1
    assert result.stderr.startswith("error: ")
    assert out.read_text() == "mine\n"


def test_same_seed_same_bytes(tmp_path: Path) -> None:
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    for p in (a, b):
        assert (
            runner.invoke(app, ["population", "-n", "9", "--seed", "1", "-o", str(p)]).exit_code
            == 0
        )
    assert a.read_bytes() == b.read_bytes()


def test_bad_range_is_usage_error_and_writes_nothing(tmp_path: Path) -> None:
    out = tmp_path / "pop.csv"
    result = runner.invoke(app, ["population", "--weight-n", "60,20", "-o", str(out)])
    assert result.exit_code == 2
    assert result.stderr.count("\n") == 1
    assert result.stderr.startswith("error: ")
    assert "--weight-n" in result.stderr
    assert not out.exists()
    result = runner.invoke(app, ["population", "--damping-ns-per-cm", "a,b", "-o", str(out)])
    assert result.exit_code == 2
    assert "--damping-ns-per-cm" in result.stderr
    assert not out.exists()


def test_existing_output_needs_force(tmp_path: Path) -> None:
    out = tmp_path / "pop.csv"
    out.write_text("keep me\n")
    result = runner.invoke(app, ["population", "-o", str(out)])
    assert result.exit_code == 1
    assert "exists already" in result.stderr
    assert out.read_text() == "keep me\n"
    assert runner.invoke(app, ["population", "-o", str(out), "--force"]).exit_code == 0


def test_grip_writes_n_grippable_objects(tmp_path: Path) -> None:
    out = tmp_path / "grip.csv"
    result = runner.invoke(app, ["population", "--grip", "-n", "30", "--seed", "4", "-o", str(out)])
    assert result.exit_code == 0, result.output
    cat = read_catalog(out)
    assert len(cat) == 30
    assert cat["friction_mu"].nunique() == 30
    assert (cat["weight_n"] / (2 * cat["friction_mu"]) / cat["material_stiffness_n_per_cm"]
            <= 0.25 * cat["size_x_cm"]).all()  # fmt: skip
    result = runner.invoke(app, ["population", "--grip", "--paper", "-o", str(tmp_path / "x.csv")])
    assert result.exit_code == 2
    assert (
        result.stderr == "error: give one of --golden, --paper and --grip, not --paper and --grip\n"
    )
