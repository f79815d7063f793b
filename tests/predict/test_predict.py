"""deformctl.predict, the library call behind ``deformctl predict``: the bundled model on the
paper's four objects, the conservative λ for an unknown damping, and the table it writes."""

from __future__ import annotations

import io

import numpy as np
import pandas as pd
import pytest

from deformctl.predict import (
    assume_damping,
    csv_text,
    load_predictor,
    output_columns,
    predict_objects,
)
from deformctl.quantities import MAX_LIFT_RATIO
from deformctl.resources import dataset_path


@pytest.fixture(scope="module")
def paper() -> tuple[list[str], dict[str, np.ndarray]]:
    """The paper's objects A–D (W, D, λ, μ from the bundled catalog)."""
    cat = pd.read_csv(dataset_path("paper", "objects.csv"))
    inputs = {
        "weight_n": cat["weight_n"].to_numpy(),
        "deformability_n_per_cm": cat["material_stiffness_n_per_cm"].to_numpy(),
        "damping_ns_per_cm": cat["material_damping_ns_per_cm"].to_numpy(),
        "friction_mu": cat["friction_mu"].to_numpy(),
    }
    return list(cat["object_id"]), inputs


def test_the_bundled_model_gives_a_lifting_force_above_f_w(
    paper: tuple[list[str], dict[str, np.ndarray]],
) -> None:
    names, inputs = paper
    est = predict_objects(load_predictor("grip"), inputs, coverage=0.9, names=names)
    f_w = inputs["weight_n"] / (2.0 * inputs["friction_mu"])  # F_w = W / (2 μ)
    np.testing.assert_allclose(est.f_w_n, f_w, rtol=1e-12)
    assert np.all(np.isfinite(est.lift_force_n))
    assert np.all(est.lift_force_n >= f_w)  # L_f = F_w + F_d, F_d >= 0
    assert np.all(est.lift_force_n <= MAX_LIFT_RATIO * f_w)
    assert np.all(est.lift_force_upper_n >= est.lift_force_n)
    assert list(est.names) == names
    assert not est.outside_training_range.any()  # the paper's objects lie inside
    assert est.warnings == []


def test_an_unknown_damping_gets_the_most_conservative_lambda_of_the_range(
    paper: tuple[list[str], dict[str, np.ndarray]],
) -> None:
    names, inputs = paper
    predictor = load_predictor("grip")
    lam = inputs["damping_ns_per_cm"].copy()
    lam[[0, 2]] = np.nan
    filled, assumed, lines = assume_damping(predictor, {**inputs, "damping_ns_per_cm": lam}, names)
    assert assumed.tolist() == [True, False, True, False]
    np.testing.assert_array_equal(filled["damping_ns_per_cm"][[1, 3]], lam[[1, 3]])
    lo, hi = predictor.ranges["damping_ns_per_cm"]
    for i in (0, 2):
        chosen = filled["damping_ns_per_cm"][i]
        assert lo <= chosen <= hi
        at = {k: np.full(9, v[i]) for k, v in inputs.items() if k != "damping_ns_per_cm"}
        grid = np.linspace(lo, hi, 9)
        others = predictor.predict_many(
            at["weight_n"], at["deformability_n_per_cm"], grid, at["friction_mu"]
        ).lift_force_n
        mine = predictor.predict_many(
            at["weight_n"][:1], at["deformability_n_per_cm"][:1], np.array([chosen]),
            at["friction_mu"][:1],
        ).lift_force_n[0]  # fmt: skip
        assert mine >= others.max() - 1e-12  # no λ of the range asks for more force
    assert [line.split(":")[0] for line in lines] == ["A", "C"]
    assert all("(damping_assumed = true)" in line for line in lines)
    same, none, no_lines = assume_damping(predictor, inputs)
    assert not none.any()
    assert no_lines == []
    np.testing.assert_array_equal(same["damping_ns_per_cm"], inputs["damping_ns_per_cm"])


def test_the_table_has_its_columns_in_order_and_reads_back(
    paper: tuple[list[str], dict[str, np.ndarray]],
) -> None:
    names, inputs = paper
    est = predict_objects(load_predictor("grip"), inputs, names=names)
    cols = output_columns(est, inputs, object_ids=names, damping_assumed=[False] * 4)
    assert list(cols) == [
        "object_id", "weight_n", "deformability_n_per_cm", "damping_ns_per_cm", "friction_mu",
        "f_w_n", "predicted_lift_force_n", "outside_training_range",
    ]  # fmt: skip
    back = pd.read_csv(io.StringIO(csv_text(cols)))
    np.testing.assert_allclose(back["predicted_lift_force_n"], est.lift_force_n, rtol=1e-5)
    assert list(back["object_id"]) == names


def test_csv_cells() -> None:
    text = csv_text({"id": ["a,b", "c"], "x": [1 / 3, np.nan], "ok": [np.True_, False]})
    assert text == 'id,x,ok\n"a,b",0.333333,True\nc,,False\n'
