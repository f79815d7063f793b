"""The force ceiling on ``lift --sim -o DIR/`` (the dataset/sweep path), and
``max_force_n`` as one quantity (:data:`deformctl.quantities.MAX_FORCE_N`).

The sweep task carries ``--max-force-n`` (:class:`~deformctl.lift.runners.sim.LiftTask`) into
each object's search: no simulated attempt asks for more, the parts' ``max_force_n`` column holds
it, and a search that needs more stops with "no safe grip" (recorded as a failure, the others go
on). Without the flag the default ceiling (10 x F_w) applies, as for a single-file output. A bad
value gets the same rule and the same words through every command and library call that takes it.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from deformctl.artifacts import read_lift_log
from deformctl.artifacts.dataset import read_failures, read_table_any
from deformctl.cli import app
from deformctl.errors import EXIT_USAGE, InputDataError, UsageError
from deformctl.lift.ceiling import DEFAULT_CEILING_RATIO, force_ceiling
from deformctl.lift.options import SearchOptions
from deformctl.lift.search import find_min_lift_force, find_min_lift_force_seeded
from deformctl.quantities import MAX_FORCE_N
from deformctl.series import TrialOutcome

cli = CliRunner()
#: A fast simulated lift (coarse lattice, short hold), as the sweep tests use.
FAST_LIFT = [
    "--alpha-cm", "10", "--dt-s", "0.002", "--hold-s", "0.05", "--lift-height-m", "0.01",
    "--max-attempts", "20",
]  # fmt: skip
HEADER = (
    "object_id,size_x_cm,size_y_cm,size_z_cm,weight_n,friction_mu,"
    "material_stiffness_n_per_cm,material_damping_ns_per_cm"
)
#: Two sponge-like cubes: F_w = 0.7 N and 1.4 N.
ROWS = ("a,10,10,10,0.7,0.5,49.18,6.47", "b,10,10,10,1.4,0.5,49.18,6.47")
RULE = "must be a finite number > 0 N, got "


def _catalog(tmp_path: Path, *rows: str, header: str = HEADER) -> Path:
    path = tmp_path / "cat.csv"
    path.write_text("\n".join([header, *rows]) + "\n")
    return path


def _lifts(_force: float, _i: int) -> TrialOutcome:
    return TrialOutcome(_force, True, 0.0)


# ---------------------------------------------------------------------------- the one rule


def test_the_rule_holds_at_its_edges() -> None:
    for good in (1e-9, 0.5, 1e6):
        assert MAX_FORCE_N.check(good) == good
    for bad in (0.0, -1.0, math.nan, math.inf, -math.inf, True, "5", None):
        with pytest.raises(UsageError) as info:
            MAX_FORCE_N.check(bad)
        assert str(info.value).startswith(f"--max-force-n {RULE}"), bad
    assert MAX_FORCE_N.rule == "a finite number > 0 N"


BAD: list[Any] = [0.0, -3.0, math.nan]


@pytest.mark.parametrize("value", BAD)
def test_every_library_entry_gives_the_rule_s_words(value: float) -> None:
    expected = f"{RULE}{MAX_FORCE_N.problem(value).split('got ')[1]}"  # type: ignore[union-attr]
    calls = {
        "SearchOptions": lambda: SearchOptions(max_force_n=value),
        "find_min_lift_force": lambda: find_min_lift_force(
            _lifts, weight_n=1.0, friction_mu=0.5, object_id="A", max_force_n=value
        ),
        "find_min_lift_force_seeded": lambda: find_min_lift_force_seeded(
            _lifts,
            weight_n=1.0,
            friction_mu=0.5,
            predicted_lift_force_n=2.0,
            object_id="A",
            max_force_n=value,
        ),
    }
    for name, call in calls.items():
        with pytest.raises(UsageError) as info:
            call()
        assert str(info.value).endswith(expected), (name, str(info.value))
        assert "max-force-n" in str(info.value) or "max_force_n" in str(info.value), name


@pytest.mark.parametrize("value", ["0", "-3", "abc", "inf"])
def test_the_catalog_column_gets_the_rule_as_a_data_error(value: str) -> None:
    """(An empty cell, NaN, is no value: the default ceiling applies.)"""
    with pytest.raises(InputDataError) as info:
        force_ceiling("A", 1.0, row={"max_force_n": value if value == "abc" else float(value)})
    assert info.value.exit_code == 65
    assert str(info.value).startswith(f"object 'A': max_force_n {RULE}"), str(info.value)


@pytest.mark.parametrize("value", ["0", "-3", "nan", "inf"])
@pytest.mark.parametrize("output", ["lift.parquet", "out/"])
def test_every_lift_output_refuses_a_bad_flag_with_one_line(
    tmp_path: Path, value: str, output: str
) -> None:
    catalog = _catalog(tmp_path, *ROWS)
    runner = ["sim", *FAST_LIFT] if output.endswith("/") else ["rig", "--command", "true"]
    res = cli.invoke(
        app,
        ["lift", runner[0], str(catalog), *runner[1:], "--max-force-n", value, "-o",
         str(tmp_path / output)],
    )  # fmt: skip
    assert res.exit_code == EXIT_USAGE, res.stderr
    lines = res.stderr.strip().splitlines()
    assert lines == [f"error: --max-force-n {RULE}{float(value):g}"], res.stderr
    assert not (tmp_path / output).exists()


# ---------------------------------------------------------------------------- the sweep path


def test_the_sweep_path_applies_the_ceiling(tmp_path: Path) -> None:
    """``--max-force-n 1.5``: object a (F_w 0.7 N, L_f about 1.2 N) lifts below it; object b
    (F_w 1.4 N, L_f above 1.5 N) stops with no safe grip. No attempt asks for more than 1.5 N."""
    catalog = _catalog(tmp_path, *ROWS)
    out = tmp_path / "out"
    res = cli.invoke(
        app,
        ["lift", "sim", str(catalog), *FAST_LIFT, "--max-force-n", "1.5", "-o", f"{out}/",
         "--workers", "1"],
    )  # fmt: skip
    assert res.exit_code == 1, res.stderr  # b does not converge
    rows = read_table_any(str(out), "lift_results").set_index("object_id")
    assert list(rows["max_force_n"]) == [1.5, 1.5]
    assert bool(rows.loc["a", "converged"])
    assert rows.loc["a", "lift_force_n"] <= 1.5
    assert not bool(rows.loc["b", "converged"])
    assert "no safe grip below the force ceiling 1.5 N" in str(rows.loc["b", "error"])
    assert list(read_failures(out)["object_id"]) == ["b"]
    forces = [
        a.outcome.grip_force_n
        for log in sorted((out / "_logs").glob("part-*.mcap"))
        for a in read_lift_log(log)[1]
    ]
    assert max(forces, default=0.0) == 1.5  # none above; b tried the ceiling once


def test_the_catalog_column_or_the_default_sets_the_ceiling_on_the_sweep_path(
    tmp_path: Path,
) -> None:
    """Without the flag: b's catalog ``max_force_n`` (1.5 N, no safe grip), a's default
    (10 x F_w, lifted), as for a single-file output."""
    catalog = _catalog(tmp_path, ROWS[1] + ",1.5", ROWS[0] + ",", header=HEADER + ",max_force_n")
    out = tmp_path / "out"
    res = cli.invoke(app, ["lift", "sim", str(catalog), *FAST_LIFT, "-o", f"{out}/"])
    assert res.exit_code == 1, res.stderr
    rows = read_table_any(str(out), "lift_results").set_index("object_id")
    assert rows.loc["b", "max_force_n"] == 1.5  # the catalog's
    assert rows.loc["a", "max_force_n"] == pytest.approx(DEFAULT_CEILING_RATIO * 0.7)  # default
    assert bool(rows.loc["a", "converged"])
    assert not bool(rows.loc["b", "converged"])
