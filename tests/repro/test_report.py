"""The ``make reproduce`` path end to end: CLI commands into a run directory, then the report."""

from __future__ import annotations

import itertools
import re
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

from deformctl.cli import app
from deformctl.errors import MissingInputError
from deformctl.repro.calibrate import cube_side_cm, table3_cube_catalog
from deformctl.repro.golden import EXPECTED_PATH
from deformctl.repro.report import (
    RUN_FILES,
    ReportSummary,
    compare_landscape,
    gate_failures,
    main,
    write_report,
)

PAPER = Path(__file__).resolve().parents[2] / "datasets" / "paper"
runner = CliRunner()


def _run(*args: str) -> None:
    result = runner.invoke(app, list(args))
    assert result.exit_code == 0, f"{args}: {result.stderr}"


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    run = tmp_path_factory.mktemp("reproduce")
    catalog = str(EXPECTED_PATH.parent / "catalog.csv")
    r = str(run)
    _run("measure", "sim", catalog, "-o", f"{r}/squeeze.mcap")
    _run("characterize", f"{r}/squeeze.mcap", "-o", f"{r}/coefficients.parquet")
    _run("lift", "sim", catalog, "-o", f"{r}/lift.parquet")
    _run("table", f"{r}/coefficients.parquet", f"{r}/lift.parquet", "-o", f"{r}/index.parquet")
    _run(
        "train", f"{r}/index.parquet", "-o", f"{r}/model.skops", "--train-size", "6",
        "--metrics", f"{r}/metrics.json",
    )  # fmt: skip
    _run("predict", f"{r}/model.skops", f"{r}/index.parquet", "-o", f"{r}/predictions.parquet")
    paper = str(PAPER / "objects.csv")
    _run("measure", "sim", paper, "-o", f"{r}/paper_squeeze.mcap")
    _run("characterize", f"{r}/paper_squeeze.mcap", "-o", f"{r}/paper_coefficients.parquet")
    _run("lift", "sim", paper, "-o", f"{r}/paper_lift.parquet")
    # two of Table III's nine cubes keep the test short; the report shows the others as n/a
    cubes = pd.read_csv(PAPER / "table3_cubes.csv").iloc[[0, 1]]
    cubes.to_csv(run / "table3_cubes.csv", index=False)
    _run("lift", "sim", f"{r}/table3_cubes.csv", "-o", f"{r}/table3_lift.parquet")
    return run


def test_report_has_tables_and_plots(run_dir: Path) -> None:
    summary = write_report(run_dir)
    text = summary.report_path.read_text()
    for heading in ("## Table II", "## Table III", "## The landscape", "## Model metrics"):
        assert heading in text
    assert "## Plots" in text
    assert "median L_f/F_w × F_w" in text  # the constant-ratio baseline sits beside the network
    assert "| T3-1 |" in text
    assert "| T3-9 |" in text
    assert [p.name for p in summary.plots][-1] == "lf_over_fw_vs_zeta.png"
    assert summary.ratio_min <= summary.ratio_max
    assert -1.0 <= summary.ratio_zeta_spearman <= 1.0
    for oid, name in (("A", "sponge"), ("B", "cotton"), ("C", "sand"), ("D", "water")):
        assert f"| {oid} {name} |" in text
    assert len(summary.plots) == 3
    for png in summary.plots:
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # Our D for the Table I objects is the paper's within 5 % (the catalog carries Table II).
    assert (summary.table2["d_rel_diff"].abs() < 0.05).all()
    # The printed headline equals the test rows of the predictions.
    pred = pd.read_parquet(run_dir / "predictions.parquet")
    assert len(pred) == 8
    match = re.search(r"max relative error ([\d.]+) %", summary.text)
    assert match is not None
    assert float(match.group(1)) == pytest.approx(100 * summary.model_test_max_rel_error, abs=0.01)


def test_missing_run_file_is_one_line_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(MissingInputError, match=RUN_FILES["paper_squeeze"]):
        write_report(tmp_path)
    assert main([str(tmp_path)]) == 66
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert err.startswith("error: ")


def test_required_max_test_error_gates_the_run(
    run_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    error = write_report(run_dir).model_test_max_rel_error
    assert (
        main([str(run_dir), "--require-max-test-error", f"{min(0.99, error * 1.01 + 1e-9)}"]) == 0
    )
    capsys.readouterr()
    assert main([str(run_dir), "--require-max-test-error", f"{error * 0.99}"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("error: the network's max relative test error")
    assert err.count("\n") == 1
    assert main([str(run_dir), "--require-max-test-error", "abc"]) == 2


def test_table3_cube_catalog_is_the_checked_in_file() -> None:
    checked_in = pd.read_csv(PAPER / "table3_cubes.csv")
    pd.testing.assert_frame_equal(checked_in, table3_cube_catalog(), check_exact=False, rtol=1e-9)
    # a cube of W = 9.80665 N at 1 g/cm³ is 1 kg, a 10 cm cube
    assert cube_side_cm(9.80665, 1.0) == pytest.approx(10.0)


def test_landscape_compares_the_13_points(run_dir: Path) -> None:
    landscape = compare_landscape(
        pd.read_csv(PAPER / "table2.csv"),
        pd.read_parquet(run_dir / "paper_lift.parquet"),
        pd.read_csv(PAPER / "table3.csv"),
        pd.read_parquet(run_dir / "table3_lift.parquet"),
    )
    assert len(landscape) == 13
    # the paper's own ratios at mu = 0.5 (F_w = W): sponge 1.00, water 2.27
    by_point = landscape.set_index("point")
    assert by_point.loc["sponge", "ratio_paper"] == pytest.approx(1.0)
    assert by_point.loc["water", "ratio_paper"] == pytest.approx(2.27, abs=0.01)
    assert by_point.loc["water", "zeta"] == 0.0
    assert landscape["lift_force_ours_n"].notna().sum() == 4 + 2  # the cubes not run are NaN


def _summary(**numbers: float) -> ReportSummary:
    base = {
        "model_test_max_rel_error": 0.03, "model_test_median_rel_error": 0.01,
        "constant_ratio_test_max_rel_error": 0.20, "constant_ratio_test_median_rel_error": 0.06,
        "ratio_min": 1.1, "ratio_max": 1.9, "ratio_zeta_spearman": -0.8,
    }  # fmt: skip
    base.update(numbers)
    return ReportSummary(Path("r.md"), (), pd.DataFrame(), text="", **base)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("numbers", "expected"),
    [
        ({}, []),
        ({"model_test_max_rel_error": 0.06}, ["exceeds 5.00 %"]),
        ({"model_test_max_rel_error": 0.045, "constant_ratio_test_max_rel_error": 0.08},
         ["more than half"]),
        ({"model_test_median_rel_error": 0.021}, ["more than a third"]),
        ({"ratio_max": 1.6}, ["spans 1.100 to 1.600"]),
        ({"ratio_min": 1.25}, ["spans 1.250"]),
        ({"ratio_zeta_spearman": 0.1}, ["does not fall with zeta"]),
    ],
)  # fmt: skip
def test_reproduce_gates(numbers: dict[str, float], expected: list[str]) -> None:
    failures = gate_failures(
        _summary(**numbers), max_test_error=0.05, beat_constant_ratio=True, ratio_span=(1.2, 1.7)
    )
    assert len(failures) == len(expected)
    for message, fragment in zip(failures, expected, strict=True):
        assert fragment in message


def _tables(text: str) -> list[list[str]]:
    """The header cells of every Markdown table in ``text``."""
    lines = text.splitlines()
    return [
        [c.strip() for c in line.strip("|").split("|")]
        for line, below in itertools.pairwise(lines)
        if line.startswith("|") and below.startswith("|---")
    ]


def test_the_report_says_how_it_was_made_and_what_each_column_is(run_dir: Path) -> None:
    """Version, commit, date, command line; the calibration (which parameters,
    to which of the paper's points, the leave-one-out error); a source on every column with a
    unit; and no point left out of a plot without a note naming it."""
    from datetime import UTC, datetime

    from deformctl import __version__
    from deformctl.presets import paper_calibration
    from deformctl.repro.disclosure import LABELS

    argv = ["python", "-m", "deformctl.repro.report", str(run_dir)]
    summary = write_report(run_dir, argv=argv)
    text = summary.report_path.read_text()
    # provenance
    made = text.split("## How this report was made", 1)[1].split("\n## ", 1)[0]
    assert f"deformctl {__version__}, commit " in made
    assert re.search(r"commit ([0-9a-f]{40}|unknown)", made)
    assert datetime.now(UTC).strftime("%Y-%m-%d") in made
    assert f"`{' '.join(argv)}`" in made
    for artifact in ("lift", "index", "predictions", "paper_lift", "table3_lift"):
        assert f"| {artifact}.parquet | `" in made  # the command line each was written by
    # the calibration: every fitted parameter, the 13 points, in-sample and leave-one-out errors
    calibration = paper_calibration()
    section = text.split("## Calibration", 1)[1].split("\n## ", 1)[0]
    assert "The simulator ran with the `paper` preset." in section
    for name, value in calibration["fitted"].items():
        assert f"`{name}` = {value:g}" in section
    for point in calibration["points"]:
        in_sample = f"{100 * point['error']:+.1f} %"
        assert f"| {point['point']} | {point['lift_force_paper_n']:.2f} | {in_sample} |" in section
    loo = 100 * calibration["leave_one_out"]["worst"]
    assert f"leave-one-out (each point predicted with the parameters fitted to the other 12): " \
        f"worst {loo:.1f} %" in section  # fmt: skip
    assert (
        f"In-sample worst error over the 13 points: {100 * calibration['worst_error']:.1f} %"
        in (section)
    )
    # every column that holds a quantity with a unit says where its numbers come from
    headers = [cell for table in _tables(text) for cell in table]
    with_units = [c for c in headers if re.search(r"\((N|N/cm|N·s/cm)\)", c)]
    assert len(with_units) >= 25
    unlabelled = [c for c in with_units if not any(label in c for label in LABELS.values())]
    assert not unlabelled
    assert "D (N/cm), measured (the paper's rig)" in headers
    assert "L_f (N), the paper's simulation" in headers
    assert "NN L_f (N), the paper's network" in headers
    # the two Table III cubes lifted here are drawn; the seven others have no L_f: named
    zeta_note = next(n for n in summary.plot_notes if "lf_over_fw_vs_zeta" in n)
    for i in range(3, 10):
        assert f"T3-{i} (ours: no value)" in zeta_note
    assert "T3-1 (ours" not in zeta_note
    assert "`predicted_vs_measured.png`: every point is shown." in summary.plot_notes
    for note in summary.plot_notes:
        assert f"- {note}" in text


def test_a_point_outside_the_axes_is_named() -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from deformctl.repro.plots import Plot, hidden_points

    fig, ax = plt.subplots()
    ax.scatter([0.5, 1.0, -0.2], [1.0, 1.2, 1.1])
    ax.set_xlim(left=0.0)
    hidden = hidden_points(ax, ["a", "b", "c"], [0.5, 1.0, -0.2], [1.0, 1.2, 1.1], "zeta")
    hidden += hidden_points(ax, ["d"], [float("nan")], [1.0], "zeta")
    plt.close(fig)
    assert hidden == ["c (zeta: x -0.2, y 1.1 outside the axes)", "d (zeta: no value)"]
    note = Plot(Path("p.png"), tuple(hidden)).note()
    assert note.startswith("`p.png`: 2 point(s) not shown: c (zeta")
