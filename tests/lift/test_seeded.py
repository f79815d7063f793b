"""The seeded search (``lift --start-model`` / ``--start-table``) against threshold runners.

A threshold runner lifts iff the grip force is >= T, so the true minimum lifting force is
max(T, F_w); every claim is checked against it and against ``refine`` on the same runner.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from deformctl.catalog import CatalogObject
from deformctl.errors import InputDataError, UsageError
from deformctl.lift import (
    DEFAULT_START_MARGIN,
    DEFAULT_TOLERANCE_REL,
    LiftSearchResult,
    find_min_lift_force,
    find_min_lift_force_seeded,
)
from deformctl.lift.options import SearchOptions
from deformctl.lift.seeded import StartSeed, object_features
from deformctl.lift.stage import RunnerFactory, lift_catalog
from tests._helpers.lift import ThresholdRunner

# W = 10 N, mu = 0.5 -> F_w = 10 N; the object lifts from T = 17 N.
W_N, MU, T_N, TOL = 10.0, 0.5, 17.0, DEFAULT_TOLERANCE_REL


def _forces(result: LiftSearchResult) -> list[float]:
    return [t.grip_force_n for t in result.trials]


def _seeded(predicted_n: float, threshold_n: float = T_N, **kw: float) -> LiftSearchResult:
    return find_min_lift_force_seeded(
        ThresholdRunner(threshold_n),
        weight_n=W_N,
        friction_mu=MU,
        predicted_lift_force_n=predicted_n,
        object_id="A",
        **kw,  # type: ignore[arg-type]
    )


def _agrees_with_refine(seeded: LiftSearchResult, threshold_n: float = T_N) -> None:
    refine = find_min_lift_force(ThresholdRunner(threshold_n), weight_n=W_N, friction_mu=MU)
    assert seeded.converged
    assert refine.converged
    low, high = seeded.bracket_n
    assert low < threshold_n <= high == seeded.lift_force_n or high == seeded.f_w_n
    assert (high - low) / high <= TOL
    assert abs(seeded.lift_force_n - refine.lift_force_n) <= TOL * refine.lift_force_n


def test_a_good_prediction_costs_two_attempts_and_the_bisection() -> None:
    r = _seeded(17.1, margin=1.02)
    f = _forces(r)
    assert f[0] == pytest.approx(17.1 * 1.02)  # the start: prediction x margin, lifts
    assert f[1] == pytest.approx(17.1 / 1.02)  # the other edge of the band: slips
    # the band is 4 % wide: 3 bisections to 0.5 %
    assert r.attempts == 2 + math.ceil(math.log2((1 - 1.02**-2) / TOL)) == 5
    assert (r.protocol, r.start_source, r.start_in_training_range) == ("seeded", "model", True)
    assert r.predicted_lift_force_n == 17.1
    assert r.start_force_n == pytest.approx(17.1 * 1.02)
    assert "from the model's 17.1 N" in r.message
    _agrees_with_refine(r)
    refine = find_min_lift_force(ThresholdRunner(T_N), weight_n=W_N, friction_mu=MU)
    assert r.attempts <= refine.attempts / 2


def _steps(margin: float, n: int, growth: float = 1.2) -> list[float]:
    """The seeded search's step factors: margin**2, then each the square of the last, <= growth."""
    steps = [margin**2]
    while len(steps) < n:
        steps.append(min(growth, steps[-1] ** 2))
    return steps


def test_a_prediction_far_too_high_searches_down() -> None:
    r = _seeded(60.0, margin=1.02)
    f = _forces(r)
    lifted = [t.lifted for t in r.trials]
    first_slip = lifted.index(False)
    assert first_slip >= 4
    assert all(lifted[:first_slip])  # down while it lifts ...
    assert f[1] == pytest.approx(60.0 / 1.02)  # first to prediction / margin
    ratios = [a / b for a, b in itertools.pairwise(f[: first_slip + 1])]
    assert ratios == pytest.approx(_steps(1.02, first_slip))  # 1.0404, 1.0824, 1.17, 1.2, ...
    assert ratios[-1] == pytest.approx(1.2)  # ... then ÷ growth
    assert min(f) >= r.f_w_n
    _agrees_with_refine(r)


def test_a_prediction_far_too_low_ramps_up_to_growth() -> None:
    r = _seeded(11.0, margin=1.02)
    f = _forces(r)
    first_lift = [t.lifted for t in r.trials].index(True)
    assert f[0] == pytest.approx(11.22)
    ratios = [b / a for a, b in itertools.pairwise(f[: first_lift + 1])]
    assert ratios == pytest.approx(_steps(1.02, first_lift))
    _agrees_with_refine(r)
    # far below: the steps reach the paper's x growth
    r = find_min_lift_force_seeded(
        ThresholdRunner(200.0), weight_n=W_N, friction_mu=MU, predicted_lift_force_n=11.0
    )
    f = _forces(r)
    assert f[6] / f[5] == pytest.approx(1.2)
    _agrees_with_refine(r, 200.0)


def test_a_prediction_below_f_w_starts_at_f_w() -> None:
    r = _seeded(4.0)
    assert _forces(r)[0] == r.start_force_n == r.f_w_n == 10.0
    _agrees_with_refine(r)
    # an object F_w lifts: one attempt, L_f = F_w, as in the other protocols
    easy = _seeded(9.0, threshold_n=5.0)
    assert (easy.attempts, easy.lift_force_n, easy.bracket_n) == (1, 10.0, (10.0, 10.0))


def test_going_down_stops_at_f_w() -> None:
    r = _seeded(30.0, threshold_n=9.0)  # F_w = 10 N lifts: never tries below it
    assert min(_forces(r)) == r.lift_force_n == r.f_w_n
    assert r.converged
    assert r.bracket_n == (10.0, 10.0)


def test_out_of_attempts() -> None:
    up = _seeded(11.0, max_attempts=2)
    assert not up.converged
    assert math.isnan(up.lift_force_n)
    assert "did not lift" in up.message
    down = _seeded(60.0, max_attempts=2)
    assert not down.converged
    assert down.lift_force_n == pytest.approx(60.0 / DEFAULT_START_MARGIN)
    assert "no bracket yet" in down.message
    bisect = _seeded(17.1, max_attempts=3)
    assert not bisect.converged
    assert "did not reach tolerance" in bisect.message


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({"margin": 0.9}, "--start-margin must be a finite number >= 1"),
        ({"margin": math.inf}, "--start-margin must be"),
        ({"predicted_lift_force_n": math.nan}, "predicted lifting force must be"),
        ({"predicted_lift_force_n": -1.0}, "predicted lifting force must be"),
        ({"growth": 1.0}, "growth"),
    ],
)
def test_bad_parameters(kw: dict[str, float], message: str) -> None:
    args: dict[str, float] = {"predicted_lift_force_n": 17.0, **kw}
    with pytest.raises(UsageError, match=message):
        find_min_lift_force_seeded(ThresholdRunner(T_N), weight_n=W_N, friction_mu=MU, **args)  # type: ignore[arg-type]


@settings(max_examples=200, deadline=None)
@given(
    threshold=st.floats(1.0, 200.0),
    ratio=st.floats(0.1, 10.0),
    margin=st.floats(1.0, 1.3),
)
def test_the_seeded_answer_is_refines_for_any_prediction(
    threshold: float, ratio: float, margin: float
) -> None:
    r = _seeded(threshold * ratio, threshold_n=threshold, margin=margin)
    assert min(_forces(r)) >= r.f_w_n
    _agrees_with_refine(r, threshold)


# ------------------------------------------------------------------ the stage with a seed


def _objects(*rows: dict[str, object]) -> list[CatalogObject]:
    base = {"size_x_cm": 8, "size_y_cm": 5, "size_z_cm": 4, "friction_mu": 0.5}
    return [CatalogObject.from_row({**base, **row}) for row in rows]


def _threshold_factory(thresholds: dict[str, float]) -> tuple[RunnerFactory, list[tuple]]:
    calls: list[tuple] = []

    def make(obj: CatalogObject, max_force_n: float) -> ThresholdRunner:
        runner = ThresholdRunner(thresholds[obj.object_id])
        runner.calls = calls  # every object's calls, in order
        return runner

    return RunnerFactory("rig", make), calls


INDEX = pd.DataFrame(
    {
        "object_id": ["i1", "i2", "i3"],
        "weight_n": [10.0, 20.0, 30.0],
        "deformability_n_per_cm": [30.0, 40.0, 50.0],
        "damping_ns_per_cm": [0.0, 5.0, 10.0],
        "lift_force_n": [17.0, 30.0, 42.0],
        "f_w_n": [10.0, 20.0, 30.0],
    }
)


def test_stage_seeds_inside_the_range_and_falls_back_outside() -> None:
    objects = _objects(
        {"object_id": "in", "weight_n": 10.0, "deformability_n_per_cm": 30.0,
         "damping_ns_per_cm": 0.0},
        {"object_id": "out", "weight_n": 50.0, "deformability_n_per_cm": 30.0,
         "damping_ns_per_cm": 0.0},
    )  # fmt: skip
    factory, calls = _threshold_factory({"in": 17.0, "out": 60.0})
    warnings: list[str] = []
    seed = StartSeed.from_index_table(INDEX, margin=DEFAULT_START_MARGIN)
    run = lift_catalog(objects, factory, seed=seed, warn=warnings.append)
    assert run.ok
    table = run.table.set_index("object_id")
    assert list(table["protocol"]) == ["seeded", "refine"]
    assert list(table["start_in_training_range"]) == [True, False]
    assert list(table["start_source"]) == ["table", "table"]
    assert table.loc["in", "predicted_lift_force_n"] == pytest.approx(17.0)  # i1's ratio x F_w
    assert table.loc["in", "start_force_n"] == pytest.approx(17.0 * DEFAULT_START_MARGIN)
    assert table.loc["out", "start_force_n"] == table.loc["out", "f_w_n"] == 50.0
    assert table.loc["out", "predicted_lift_force_n"] == pytest.approx(30.0 / 20.0 * 50.0)  # i2
    # the fallback is refine from F_w, attempt for attempt
    refine = find_min_lift_force(ThresholdRunner(60.0), weight_n=50.0, friction_mu=0.5)
    assert table.loc["out", "attempts"] == refine.attempts
    assert table.loc["out", "lift_force_n"] == refine.lift_force_n
    assert warnings == [
        "object 'out': outside the index table's range: weight_n = 50 not in [10, 30]; "
        "starting at F_w (refine)"
    ]
    # the runner was only ever asked (grip force, attempt index)
    assert all(len(c) == 2 for c in calls)


def test_stage_without_seed_has_empty_start_columns() -> None:
    factory, _ = _threshold_factory({"A": 17.0})
    run = lift_catalog(_objects({"object_id": "A", "weight_n": 10.0}), factory)
    # the columns are there (a table's columns do not depend on the run), and empty
    assert run.table[["predicted_lift_force_n", "start_force_n"]].isna().all().all()
    assert run.table[["start_in_training_range", "start_source"]].isna().all().all()
    assert not run.results[0].seeded


def test_stage_refuses_a_seeded_paper_protocol() -> None:
    factory, _ = _threshold_factory({"A": 17.0})
    seed = StartSeed.from_index_table(INDEX)
    with pytest.raises(UsageError, match="protocol 'paper' cannot start from a prediction"):
        lift_catalog(_objects({"object_id": "A", "weight_n": 10.0}), factory,
                     search=SearchOptions(protocol="paper"), seed=seed)  # fmt: skip


def test_features_come_from_coefficients_then_the_catalog_then_material() -> None:
    objects = _objects(
        {"object_id": "c", "weight_n": 1.0, "material_stiffness_n_per_cm": 9.0,
         "material_damping_ns_per_cm": 9.0},
        {"object_id": "k", "weight_n": 2.0, "deformability_n_per_cm": 20.0,
         "damping_ns_per_cm": 2.0, "material_stiffness_n_per_cm": 9.0,
         "material_damping_ns_per_cm": 9.0},
        {"object_id": "m", "weight_n": 3.0, "material_stiffness_n_per_cm": 30.0,
         "material_damping_ns_per_cm": 3.0},
    )  # fmt: skip
    coefficients = pd.DataFrame(
        {"object_id": ["c"], "deformability_n_per_cm": [10.0], "damping_ns_per_cm": [1.0]}
    )
    f = object_features(objects, coefficients=coefficients, use_material=True)
    assert list(f["feature_source"]) == ["coefficients", "catalog", "material"]
    np.testing.assert_array_equal(f["deformability_n_per_cm"], [10.0, 20.0, 30.0])
    np.testing.assert_array_equal(f["damping_ns_per_cm"], [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(f["weight_n"], [1.0, 2.0, 3.0])
    # a rig: material values are no measurement
    with pytest.raises(InputDataError, match=r"object 'm': no D and λ .* pass --coefficients"):
        object_features(objects, coefficients=coefficients, use_material=False)
    nan_lambda = coefficients.assign(damping_ns_per_cm=[math.nan])
    with pytest.raises(InputDataError, match="object 'c': damping_ns_per_cm from the "
                       "coefficients is not a finite number"):  # fmt: skip
        object_features(objects[:1], coefficients=nan_lambda)


def test_table_interpolation_weights_the_nearest_ratios() -> None:
    query = pd.DataFrame(
        {"object_id": ["q"], "weight_n": [10.0], "deformability_n_per_cm": [30.0],
         "damping_ns_per_cm": [0.0]}
    )  # fmt: skip
    nearest = StartSeed.from_index_table(INDEX).estimate(query, f_w_n=[12.0])["q"]
    assert nearest.predicted_lift_force_n == pytest.approx(17.0 / 10.0 * 12.0)
    two = StartSeed.from_index_table(INDEX, k=2).estimate(query, f_w_n=[12.0])["q"]
    assert two.predicted_lift_force_n == pytest.approx(17.0 / 10.0 * 12.0)  # d = 0: exact
    query["weight_n"] = 15.0
    two = StartSeed.from_index_table(INDEX, k=2).estimate(query, f_w_n=[15.0])["q"]
    assert 1.5 * 15.0 < two.predicted_lift_force_n < 1.7 * 15.0
