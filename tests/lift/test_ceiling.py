"""A force ceiling for every rig request.

No attempt asks for more than the object's ceiling (the catalog's ``max_force_n``,
``--max-force-n``, or 10 x F_w lowered to a known rupture force); a search that would need more
stops with "no safe grip"; a seeded start above it is clamped and a warning says so; the rig
request carries ``max_force_n``. A search whose threshold lies below the ceiling is the same,
attempt for attempt, as one without a ceiling, and nothing is said about it.
"""

from __future__ import annotations

import json
import math
import shlex
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from deformctl.artifacts import read_table
from deformctl.catalog import catalog_objects
from deformctl.cli import app
from deformctl.errors import InputDataError
from deformctl.lift.ceiling import DEFAULT_CEILING_RATIO, force_ceiling
from deformctl.lift.search import find_min_lift_force, find_min_lift_force_seeded
from deformctl.lift.seeded import StartSeed
from deformctl.lift.stage import RunnerFactory, lift_catalog
from deformctl.series import TrialOutcome

cli = CliRunner()
RIGS = Path(__file__).resolve().parents[1] / "rigs"
HEADER = "object_id,size_x_cm,size_y_cm,size_z_cm,weight_n,friction_mu"
THRESHOLD_N = 17.0


class Threshold:
    """A runner that lifts at or above ``threshold_n`` and remembers every force asked."""

    def __init__(self, threshold_n: float) -> None:
        self.threshold_n = threshold_n
        self.asked: list[float] = []

    def __call__(self, grip_force_n: float, attempt_index: int) -> TrialOutcome:
        self.asked.append(grip_force_n)
        return TrialOutcome(grip_force_n, grip_force_n >= self.threshold_n, 0.0)


def test_a_ceiling_above_the_threshold_changes_nothing() -> None:
    free, capped = Threshold(THRESHOLD_N), Threshold(THRESHOLD_N)
    a = find_min_lift_force(free, weight_n=5.0, friction_mu=0.5)
    b = find_min_lift_force(capped, weight_n=5.0, friction_mu=0.5, max_force_n=50.0)
    assert free.asked == capped.asked
    assert (b.converged, b.lift_force_n, b.max_force_n) == (True, a.lift_force_n, 50.0)
    assert "ceiling" not in b.message


def test_the_ramp_tries_the_ceiling_once_then_stops_with_no_safe_grip() -> None:
    runner = Threshold(THRESHOLD_N)  # F_w = 5 N: ramp 5, 6, 7.2, 8.64, 10.37, 12.44, 14.93, 17.9
    result = find_min_lift_force(runner, weight_n=5.0, friction_mu=0.5, max_force_n=16.0)
    assert runner.asked[-1] == 16.0
    assert max(runner.asked) == 16.0
    assert result.attempts == 8  # seven ramp forces below 16 N, then 16 N itself
    assert not result.converged
    assert math.isnan(result.lift_force_n)
    assert result.message == (
        "object 'object': no safe grip below the force ceiling 16 N: the object slipped at the "
        "ceiling (F_w = 5 N, 8 attempts)"
    )


def test_f_w_above_the_ceiling_makes_no_attempt() -> None:
    runner = Threshold(THRESHOLD_N)
    result = find_min_lift_force(runner, weight_n=5.0, friction_mu=0.5, max_force_n=4.0)
    assert runner.asked == []
    assert "no safe grip below the force ceiling 4 N: F_w is above it" in result.message


def test_an_absurd_seeded_start_is_clamped() -> None:
    runner = Threshold(THRESHOLD_N)
    result = find_min_lift_force_seeded(
        runner, weight_n=5.0, friction_mu=0.5, predicted_lift_force_n=3.5e301, max_force_n=50.0
    )
    assert runner.asked[0] == 50.0
    assert max(runner.asked) == 50.0
    assert result.start_clamped
    assert result.converged
    assert THRESHOLD_N <= result.lift_force_n <= THRESHOLD_N / (1 - 0.005)
    assert "(clamped to the force ceiling)" in result.message
    good = find_min_lift_force_seeded(
        Threshold(THRESHOLD_N), weight_n=5.0, friction_mu=0.5, predicted_lift_force_n=17.1,
        max_force_n=50.0,
    )  # fmt: skip
    assert not good.start_clamped
    assert "clamped" not in good.message


def test_a_seeded_search_going_up_stops_at_the_ceiling() -> None:
    runner = Threshold(THRESHOLD_N)
    result = find_min_lift_force_seeded(
        runner, weight_n=5.0, friction_mu=0.5, predicted_lift_force_n=6.0, max_force_n=12.0
    )
    assert max(runner.asked) == 12.0
    assert "no safe grip below the force ceiling 12 N" in result.message


def test_where_the_ceiling_comes_from() -> None:
    ceiling = force_ceiling("A", 5.0)
    assert (ceiling.max_force_n, ceiling.source) == (DEFAULT_CEILING_RATIO * 5.0, "default")
    assert force_ceiling("A", 5.0, max_force_n=20.0).max_force_n == 20.0
    assert force_ceiling("A", 5.0, row={"max_force_n": 30.0}, max_force_n=20.0).source == "catalog"
    low = force_ceiling("A", 5.0, coefficients={"rupture_force_n": 12.0})
    assert (low.max_force_n, low.source) == (12.0, "rupture_force_n")
    assert "the object's rupture_force_n" in low.describe()
    high = force_ceiling("A", 5.0, coefficients={"rupture_force_n": 500.0})  # above 10 x F_w
    assert high.source == "default"
    with pytest.raises(InputDataError, match="object 'A': max_force_n must be a finite number"):
        force_ceiling("A", 5.0, row={"max_force_n": -3.0})


def test_the_stage_warns_for_a_clamped_start_and_gives_the_runner_the_ceiling() -> None:
    catalog = pd.DataFrame(
        {"object_id": ["A", "B"], "size_x_cm": [5.0] * 2, "size_y_cm": [5.0] * 2,
         "size_z_cm": [5.0] * 2, "weight_n": [5.0, 5.0], "friction_mu": [0.5, 0.5],
         "deformability_n_per_cm": [10.0] * 2, "damping_ns_per_cm": [1.0] * 2}
    )  # fmt: skip
    runners: dict[str, Threshold] = {}
    seen: dict[str, float] = {}

    def make(obj: object, max_force_n: float) -> Threshold:
        oid = obj.object_id  # type: ignore[attr-defined]
        seen[oid] = max_force_n
        runners[oid] = Threshold(THRESHOLD_N)
        return runners[oid]

    def predictor(features: pd.DataFrame, f_w: np.ndarray) -> tuple[np.ndarray, ...]:
        n = len(features)
        no_bound = np.full(n, np.nan)  # a model without calibration scores
        return np.array([3.5e301, 17.1][:n]), np.zeros(n, dtype=bool), [None] * n, no_bound

    seed = StartSeed("model", predictor, margin=1.005)  # type: ignore[arg-type]
    warnings: list[str] = []
    run = lift_catalog(
        catalog_objects(catalog), RunnerFactory("test", make), seed=seed, warn=warnings.append
    )
    assert seen == {"A": 50.0, "B": 50.0}
    assert max(runners["A"].asked) == 50.0
    assert warnings == [
        "object 'A': the model's start 3.5175e+301 N is above its force ceiling 50 N "
        "(10 x F_w): clamped to the ceiling"
    ]
    assert list(run.table["max_force_n"]) == [50.0, 50.0]
    assert run.table["start_force_n"].iloc[0] == 50.0
    assert bool(run.table["converged"].all())


def _rig(requests: Path) -> str:
    script = RIGS / "threshold_rig.py"
    return shlex.join([sys.executable, str(script), str(THRESHOLD_N), str(requests)])


def test_cli_no_request_exceeds_the_ceiling(tmp_path: Path) -> None:
    catalog = tmp_path / "objects.csv"
    catalog.write_text(f"{HEADER}\nsponge,8,5,4,10,0.5\nbrick,6,6,6,16,0.5\n", encoding="utf-8")
    out, requests = tmp_path / "lift.parquet", tmp_path / "req.jsonl"
    res = cli.invoke(
        app,
        [
            "lift",
            "rig",
            str(catalog),
            "--command",
            _rig(requests),
            "--max-force-n",
            "15",
            "-o",
            str(out),
        ],
    )
    assert res.exit_code == 1
    assert res.stderr.splitlines()[0] == (
        "warning: object 'brick': F_w = 16 N is above its force ceiling 15 N (--max-force-n): "
        "no safe grip, not lifted"
    )
    sent = [json.loads(line) for line in requests.read_text().splitlines()]
    assert [r["grip_force_n"] for r in sent] == pytest.approx([10.0, 12.0, 14.4, 15.0])
    assert all(r["max_force_n"] == 15.0 for r in sent)
    table = read_table(out, "lift_results").set_index("object_id")
    assert list(table["max_force_n"]) == [15.0, 15.0]
    assert table.loc["sponge", "error"].startswith(
        "object 'sponge': no safe grip below the force ceiling 15 N"
    )
    assert table.loc["brick", "attempts"] == 0


def test_cli_silent_when_the_ceiling_is_not_reached(tmp_path: Path) -> None:
    catalog = tmp_path / "objects.csv"
    catalog.write_text(f"{HEADER}\nsponge,8,5,4,10,0.5\n", encoding="utf-8")
    out, requests = tmp_path / "lift.parquet", tmp_path / "req.jsonl"
    res = cli.invoke(
        app, ["lift", "rig", str(catalog), "--command", _rig(requests), "-o", str(out)]
    )
    assert res.exit_code == 0, res.stderr
    assert "ceiling" not in res.stderr
    assert "warning" not in res.stderr
    assert all(json.loads(r)["max_force_n"] == 100.0 for r in requests.read_text().splitlines())


@pytest.mark.parametrize("value", ["0", "-5", "nan", "inf"])
def test_cli_a_bad_max_force_is_a_usage_error_naming_the_flag(tmp_path: Path, value: str) -> None:
    catalog = tmp_path / "objects.csv"
    catalog.write_text(f"{HEADER}\nsponge,8,5,4,10,0.5\n", encoding="utf-8")
    out = tmp_path / "lift.parquet"
    res = cli.invoke(
        app,
        ["lift", "rig", str(catalog), "--command", "true", "--max-force-n", value, "-o", str(out)],
    )
    assert res.exit_code == 2
    assert res.stderr.startswith("error: --max-force-n must be a finite number > 0 N, got ")
    assert res.stderr.count("\n") == 1
    assert not out.exists()
