"""The dataset regression: the golden population through the pipeline, against expected.json.

Besides the regression itself, the tolerances' claims are checked: a bisection step moves an L_f
by at most :data:`SEARCH_STEP_REL`, and L_f's moved that far move the baselines by no more than
their tolerances; a broken network (a changed target, hidden layer or seed) moves the reference
network's numbers beyond theirs.
"""

from __future__ import annotations

import copy
import json

import numpy as np
import pandas as pd
import pytest

from deformctl.artifacts import read_catalog
from deformctl.lift import DEFAULT_TOLERANCE_REL, find_min_lift_force
from deformctl.model import TrainOptions
from deformctl.population import golden_population
from deformctl.repro import golden
from deformctl.repro.golden import (
    EXPECTED_PATH,
    REPORTED_ONLY,
    SEARCH_STEP_REL,
    TOLERANCES,
    compare,
    compute_golden,
    family,
    flatten,
)
from deformctl.series import TrialOutcome
from deformctl.train import train_model


@pytest.fixture(scope="module")
def expected() -> dict:
    return json.loads(EXPECTED_PATH.read_text())


def test_catalog_file_is_the_golden_population() -> None:
    on_disk = read_catalog(EXPECTED_PATH.parent / "catalog.csv").reset_index(drop=True)
    pd.testing.assert_frame_equal(on_disk, golden_population(), check_dtype=False)


def test_pipeline_reproduces_expected_numbers(expected: dict) -> None:
    moved = compare(expected, compute_golden())
    assert not moved, "golden numbers moved:\n" + "\n".join(moved)


def test_every_number_has_a_measured_tolerance_or_is_reported_only(expected: dict) -> None:
    families = {family(k) for k in flatten(expected)}
    assert families - REPORTED_ONLY <= set(TOLERANCES)
    assert set(TOLERANCES) <= families  # no tolerance for a number that no longer exists
    for name, tol in TOLERANCES.items():
        assert tol.basis, name
        assert tol.abs >= 0, name
        assert tol.rel >= 0, name
    # the overfit network's test errors are what follows the BLAS: never compared
    assert {"model.network_test_max_rel_error", "model.network_test_mae_n"} <= REPORTED_ONLY


def test_compare_names_what_moved(expected: dict) -> None:
    actual = copy.deepcopy(expected)
    oid = sorted(actual["objects"])[0]
    actual["objects"][oid]["lift_force_n"] *= 1.02
    first_input = sorted(actual["reference_network"]["prediction_n"])[0]
    actual["reference_network"]["prediction_n"][first_input] *= 1.05
    actual["model"]["network_test_max_rel_error"] += 0.3  # reported only: never a failure
    actual["split"]["test"] = list(reversed(actual["split"]["test"]))
    moved = compare(expected, actual)
    assert len(moved) == 3, moved
    assert moved[0].startswith("split test ids: expected")
    assert moved[1].startswith(f"objects.{oid}.lift_force_n: expected")
    assert "(+2.000 %)" in moved[1]
    assert "1 search bracket" in moved[1]
    assert moved[2].startswith(f"reference_network.prediction_n.{first_input}: expected")

    within = copy.deepcopy(expected)
    within["objects"][oid]["lift_force_n"] *= 1 + 0.99 * SEARCH_STEP_REL
    assert compare(expected, within) == []

    missing = copy.deepcopy(expected)
    del missing["model"]["constant_ratio"]
    assert compare(expected, missing) == ["model.constant_ratio: missing from this run"]


class _Threshold:
    def __init__(self, threshold_n: float) -> None:
        self.threshold_n = threshold_n

    def __call__(self, grip_force_n: float, attempt_index: int, /) -> TrialOutcome:
        lifted = grip_force_n >= self.threshold_n
        return TrialOutcome(grip_force_n, lifted, 0.0 if lifted else 0.05)


def test_one_flipped_trial_moves_lf_by_at_most_one_search_bracket() -> None:
    # Two simulators that differ in the last bits lift at thresholds a hair apart; wherever a
    # trial lands between them, the two answers differ by at most SEARCH_STEP_REL.
    assert pytest.approx(DEFAULT_TOLERANCE_REL / (1 - DEFAULT_TOLERANCE_REL)) == SEARCH_STEP_REL
    worst = 0.0
    for t in np.linspace(20.0, 120.0, 4001):
        a = find_min_lift_force(_Threshold(t), weight_n=20.0, friction_mu=0.5)
        b = find_min_lift_force(_Threshold(t * (1 + 1e-12)), weight_n=20.0, friction_mu=0.5)
        worst = max(worst, abs(a.lift_force_n - b.lift_force_n) / a.lift_force_n)
    assert 0.5 * SEARCH_STEP_REL < worst <= SEARCH_STEP_REL * (1 + 1e-9)


def _golden_index(expected: dict) -> pd.DataFrame:
    cat = golden_population().set_index("object_id")
    rows = []
    for oid, o in sorted(expected["objects"].items()):
        rows.append(
            {
                "object_id": oid,
                "weight_n": cat.loc[oid, "weight_n"],
                "deformability_n_per_cm": o["deformability_n_per_cm"],
                "damping_ns_per_cm": o["damping_ns_per_cm"],
                "lift_force_n": o["lift_force_n"],
                "friction_mu": cat.loc[oid, "friction_mu"],
                "f_w_n": o["f_w_n"],
            }
        )
    return pd.DataFrame(rows)


def _baselines(index: pd.DataFrame) -> dict[str, float]:
    # the baselines do not depend on the network: one short fit keeps this fast
    m = train_model(
        index,
        TrainOptions(
            train_size=golden.GOLDEN_TRAIN_SIZE, seed=golden.GOLDEN_SEED, restarts=1, max_iter=5
        ),
        form="paper",  # as compute_golden: the paper's network although the objects' μ varies
    )
    out = {"constant_ratio": float(m.metrics["constant_ratio"])}
    for name in ("nearest", "f_w", "constant_ratio"):
        out[f"baseline_{name}_test_max_rel_error"] = m.metrics[f"baseline_{name}"]["test"][
            "max_rel_error"
        ]
    return out


def test_baseline_tolerances_cover_lf_moved_by_one_search_bracket(expected: dict) -> None:
    index = _golden_index(expected)
    assert _baselines(index) == pytest.approx(
        {k: v for k, v in expected["model"].items() if k in _baselines(index)}, rel=1e-12
    )
    train = index["object_id"].isin(expected["split"]["train"]).to_numpy()
    worst = 0.0
    # every L_f at an edge of its bracket: the training rows (which the nearest and the constant
    # ratio predict from) one way and the test rows the other is the worst case of the bound
    for up_train, up_test in ((1, -1), (-1, 1), (1, 1), (-1, -1)):
        signs = np.where(train, up_train, up_test)
        moved = index.assign(lift_force_n=index["lift_force_n"] * (1 + signs * SEARCH_STEP_REL))
        for key, value in _baselines(moved).items():
            tol = TOLERANCES[f"model.{key}"]
            e = expected["model"][key]
            worst = max(worst, abs(value - e) / tol.allowed(e))
    # covered (the bound is reached: 1 up to rounding), and not by a tolerance wider than needed
    assert 0.99 < worst <= 1.0 + 1e-9


def test_a_broken_network_moves_the_reference_numbers(expected: dict) -> None:
    # the network learning L_f itself instead of L_f / W (the paper's plain network)
    broken = {**expected, "reference_network": golden.reference_network(target="direct")}
    moved = compare(expected, broken)
    assert moved
    assert all(line.startswith("reference_network.") for line in moved), moved
    assert any(line.startswith("reference_network.prediction_n.") for line in moved)


def test_help_and_unknown_arguments_stop_before_the_pipeline(
    capsys: pytest.CaptureFixture[str],
) -> None:
    for args, code in ((["--help"], 0), (["--bogus"], 2)):
        with pytest.raises(SystemExit) as stop:
            golden.main(args)
        assert stop.value.code == code
    out = capsys.readouterr()
    assert "usage: python -m deformctl.repro.golden" in out.out + out.err
    assert "unrecognized arguments: --bogus" in out.err
