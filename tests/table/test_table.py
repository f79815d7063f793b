"""Index table: join, refusals, lookup (nearest, standardized distance), interpolation."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from deformctl.errors import InputDataError, SchemaError, UsageError
from deformctl.table import (
    INDEX_COLUMNS,
    build_index_table,
    format_ids,
    interpolate,
    lookup,
    lookup_mapping,
    parse_lookup,
)


def _coefficients(ids: list[str]) -> pd.DataFrame:
    n = len(ids)
    return pd.DataFrame(
        {
            "object_id": ids,
            "deformability_n_per_cm": 30.0 + np.arange(n),
            "damping_ns_per_cm": 0.5 * np.arange(n),
            "weight_n": 20.0 + 2.0 * np.arange(n),
        }
    )


def _lift(ids: list[str], *, converged: list[bool] | None = None) -> pd.DataFrame:
    n = len(ids)
    weight = 20.0 + 2.0 * np.arange(n)
    mu = np.full(n, 0.5)
    return pd.DataFrame(
        {
            "object_id": ids,
            "lift_force_n": weight * 1.5,
            "f_w_n": weight / (2 * mu),
            "converged": [True] * n if converged is None else converged,
            "weight_n": weight,
            "friction_mu": mu,
            "attempts": 5,
        }
    )


IDS = ["B", "A", "C", "D"]


def test_join_columns_order_and_values() -> None:
    t = build_index_table(_coefficients(IDS), _lift(IDS))
    assert tuple(t.columns) == (*INDEX_COLUMNS, "source", "quality")
    assert set(t["quality"]) == {"ok"}  # coefficients without a quality column
    assert list(t["object_id"]) == ["A", "B", "C", "D"]  # sorted
    row_b = t.set_index("object_id").loc["B"]
    assert row_b["weight_n"] == 20.0
    assert row_b["deformability_n_per_cm"] == 30.0
    assert row_b["lift_force_n"] == 30.0
    assert row_b["f_w_n"] == 20.0
    assert t["converged"].dtype == bool


def test_join_matches_by_id_not_by_row_order() -> None:
    coef = _coefficients(IDS)
    lift = _lift(IDS).iloc[::-1].reset_index(drop=True)  # reversed rows
    t = build_index_table(coef, lift).set_index("object_id")
    for oid in IDS:
        c = coef.set_index("object_id").loc[oid]
        lr = lift.set_index("object_id").loc[oid]
        assert t.loc[oid, "deformability_n_per_cm"] == c["deformability_n_per_cm"]
        assert t.loc[oid, "lift_force_n"] == lr["lift_force_n"]


def test_f_w_computed_from_weight_and_mu_when_absent() -> None:
    lift = _lift(IDS).drop(columns=["f_w_n"])
    lift["friction_mu"] = [0.25, 0.5, 0.8, 1.0]
    lift["lift_force_n"] = lift["weight_n"] / (2 * lift["friction_mu"]) * 1.5  # L_f = 1.5 F_w
    t = build_index_table(_coefficients(IDS), lift).set_index("object_id")
    expected = lift.set_index("object_id")
    for oid in IDS:
        w, mu = expected.loc[oid, "weight_n"], expected.loc[oid, "friction_mu"]
        assert t.loc[oid, "f_w_n"] == pytest.approx(w / (2 * mu), rel=1e-15)


def test_missing_on_either_side_named() -> None:
    with pytest.raises(InputDataError) as exc:
        build_index_table(_coefficients(["A", "B", "C"]), _lift(["B", "C", "Z"]))
    msg = str(exc.value)
    assert "\n" not in msg
    assert "no lift result: A" in msg
    assert "no coefficients: Z" in msg


def test_many_missing_ids_are_abbreviated() -> None:
    ids = [f"O{i:02d}" for i in range(12)]
    with pytest.raises(
        InputDataError,
        match=r"12 object\(s\) have no lift result: "
        r"O00, O01, O02, O03, O04 and 7 more",
    ):
        build_index_table(_coefficients(ids), _lift(["X"]))


def test_unconverged_refused_unless_allowed() -> None:
    lift = _lift(IDS, converged=[True, False, True, False])
    with pytest.raises(InputDataError, match=r"2 object\(s\) did not converge: A, D"):
        build_index_table(_coefficients(IDS), lift)
    t = build_index_table(_coefficients(IDS), lift, allow_unconverged=True)
    assert len(t) == 4
    assert list(t.loc[~t["converged"], "object_id"]) == ["A", "D"]


def test_unconverged_without_force_still_refused_when_allowed() -> None:
    lift = _lift(IDS, converged=[True, False, True, True])
    lift.loc[1, "lift_force_n"] = math.nan  # nothing lifted
    with pytest.raises(InputDataError, match="lift_force_n not a finite number for A"):
        build_index_table(_coefficients(IDS), lift, allow_unconverged=True)


def test_duplicates_and_weight_mismatch_and_missing_column() -> None:
    coef = _coefficients(["A", "A", "B"])
    with pytest.raises(InputDataError, match="more than once: A"):
        build_index_table(coef, _lift(["A", "B"]))
    coef = _coefficients(IDS)
    coef.loc[2, "weight_n"] = 99.0
    with pytest.raises(InputDataError, match=r"weight_n differs .* for C"):
        build_index_table(coef, _lift(IDS))
    with pytest.raises(SchemaError, match="damping_ns_per_cm"):
        build_index_table(_coefficients(IDS).drop(columns=["damping_ns_per_cm"]), _lift(IDS))
    with pytest.raises(SchemaError, match="friction_mu"):
        build_index_table(_coefficients(IDS), _lift(IDS).drop(columns=["friction_mu", "f_w_n"]))


def test_format_ids() -> None:
    assert format_ids(["a", "b"]) == "a, b"
    assert format_ids([str(i) for i in range(8)], limit=3) == "0, 1, 2 and 5 more"


# --- lookup -------------------------------------------------------------------------------


@pytest.fixture
def table() -> pd.DataFrame:
    return pd.DataFrame(
        {
            "object_id": ["A", "B", "C", "D"],
            "weight_n": [20.0, 30.0, 40.0, 60.0],
            "deformability_n_per_cm": [30.0, 40.0, 35.0, 50.0],
            "damping_ns_per_cm": [0.0, 5.0, 10.0, 2.0],
            "lift_force_n": [30.0, 45.0, 55.0, 100.0],
        }
    )


def test_lookup_nearest_and_distance_in_standardized_units(table: pd.DataFrame) -> None:
    q = {"weight_n": 38.0, "deformability_n_per_cm": 36.0, "damping_ns_per_cm": 9.0}
    r = lookup(table, **q)
    # independent brute force: z-scores with the population std of each column
    cols = ["weight_n", "deformability_n_per_cm", "damping_ns_per_cm"]
    best, best_d = None, math.inf
    for _, row in table.iterrows():
        d2 = 0.0
        for c in cols:
            vals = list(table[c])
            mean = sum(vals) / len(vals)
            std = math.sqrt(sum((v - mean) ** 2 for v in vals) / len(vals))
            d2 += ((q[c] - row[c]) / std) ** 2
        if math.sqrt(d2) < best_d:
            best, best_d = row["object_id"], math.sqrt(d2)
    assert r.row["object_id"] == best == "C"
    assert r.distance == pytest.approx(best_d, rel=1e-12)
    assert r.row["lift_force_n"] == 55.0


def test_lookup_exact_entry_has_distance_zero(table: pd.DataFrame) -> None:
    r = lookup(table, weight_n=60.0, deformability_n_per_cm=50.0, damping_ns_per_cm=2.0)
    assert r.row["object_id"] == "D"
    assert r.distance == 0.0


def test_lookup_missing_key_is_usage_error(table: pd.DataFrame) -> None:
    with pytest.raises(UsageError) as exc:
        lookup(table, weight_n=30.0, deformability_n_per_cm=40.0)
    msg = str(exc.value)
    assert "missing damping_ns_per_cm" in msg
    assert "expected keys: weight_n, deformability_n_per_cm, damping_ns_per_cm" in msg


def test_parse_lookup_and_mapping(table: pd.DataFrame) -> None:
    q = parse_lookup("weight_n=60, deformability_n_per_cm=50,damping_ns_per_cm=2")
    assert q == {"weight_n": 60.0, "deformability_n_per_cm": 50.0, "damping_ns_per_cm": 2.0}
    assert lookup_mapping(table, q).row["object_id"] == "D"
    with pytest.raises(UsageError, match="missing deformability_n_per_cm; expected keys"):
        parse_lookup("weight_n=1,damping_ns_per_cm=2")
    with pytest.raises(UsageError, match="unknown lookup key 'mass_kg'; expected keys"):
        parse_lookup("mass_kg=1")
    with pytest.raises(UsageError, match="not a number"):
        parse_lookup("weight_n=abc,deformability_n_per_cm=1,damping_ns_per_cm=2")
    with pytest.raises(UsageError, match="unknown lookup key"):
        lookup_mapping(table, {"weight": 1.0})


def test_lookup_constant_column_uses_raw_units() -> None:
    t = pd.DataFrame(
        {
            "object_id": ["A", "B"],
            "weight_n": [20.0, 40.0],
            "deformability_n_per_cm": [30.0, 30.0],
            "damping_ns_per_cm": [1.0, 1.0],
            "lift_force_n": [1.0, 2.0],
        }
    )
    r = lookup(t, weight_n=20.0, deformability_n_per_cm=33.0, damping_ns_per_cm=1.0)
    assert r.row["object_id"] == "A"
    assert r.distance == pytest.approx(3.0)  # D has no spread: compared in N/cm


def test_interpolate_inverse_distance(table: pd.DataFrame) -> None:
    q = {"weight_n": 35.0, "deformability_n_per_cm": 38.0, "damping_ns_per_cm": 6.0}
    r = interpolate(table, k=2, power=2.0, **q)
    cols = ["weight_n", "deformability_n_per_cm", "damping_ns_per_cm"]
    std = table[cols].std(ddof=0)
    z = ((table[cols] - pd.Series(q)) / std) ** 2
    d = np.sqrt(z.sum(axis=1)).to_numpy()
    nearest = np.argsort(d)[:2]
    w = 1.0 / d[nearest] ** 2
    expected = float(np.sum(w * table["lift_force_n"].to_numpy()[nearest]) / w.sum())
    assert r.lift_force_n == pytest.approx(expected, rel=1e-12)
    assert r.object_ids == tuple(table["object_id"].to_numpy()[nearest])
    assert sum(r.weights) == pytest.approx(1.0)
    exact = interpolate(
        table, weight_n=20.0, deformability_n_per_cm=30.0, damping_ns_per_cm=0.0, k=3
    )
    assert exact.lift_force_n == 30.0
    with pytest.raises(UsageError, match="k must be >= 1"):
        interpolate(table, k=0, **q)


def test_lookup_and_interpolate_refuse_one_entry(table: pd.DataFrame) -> None:
    one = table.iloc[:1]
    q = {"weight_n": 1.0, "deformability_n_per_cm": 2.0, "damping_ns_per_cm": 3.0}
    with pytest.raises(InputDataError, match=r"has 1 row\(s\); a lookup needs at least 2"):
        lookup(one, **q)
    with pytest.raises(InputDataError, match=r"has 1 row\(s\); a lookup needs at least 2"):
        interpolate(one, k=1, **q)
    assert lookup(table.iloc[:2], **q).row["object_id"] in ("A", "B")


def test_keys_without_spread() -> None:
    from deformctl.table import keys_without_spread

    t = pd.DataFrame(
        {
            "weight_n": [1.0, 2.0],
            "deformability_n_per_cm": [3.0, 3.0],
            "damping_ns_per_cm": [0.0, 0.0],
        }
    )
    assert keys_without_spread(t) == ["deformability_n_per_cm", "damping_ns_per_cm"]
    t["damping_ns_per_cm"] = [0.0, 1e-9]
    assert keys_without_spread(t) == ["deformability_n_per_cm"]


def test_source_comes_from_the_lift_runner() -> None:
    lift = _lift(IDS)
    assert set(build_index_table(_coefficients(IDS), lift)["source"]) == {""}  # not recorded
    runners = ["sim", "rig"] * len(IDS)
    lift["runner"] = runners[: len(IDS)]
    got = build_index_table(_coefficients(IDS), lift).set_index("object_id")["source"]
    assert got.to_dict() == dict(zip(lift["object_id"], lift["runner"], strict=True))


def test_a_weight_the_squeeze_log_did_not_have_is_taken_from_the_lift() -> None:
    coefficients = _coefficients(IDS).assign(weight_n=np.nan)  # characterize without a weight
    t = build_index_table(coefficients, _lift(IDS)).set_index("object_id")
    lift = _lift(IDS).set_index("object_id")
    np.testing.assert_array_equal(t.loc[lift.index, "weight_n"], lift["weight_n"])
    coefficients.loc[0, "weight_n"] = 99.0  # a value that differs is still refused
    with pytest.raises(InputDataError, match="weight_n differs"):
        build_index_table(coefficients, _lift(IDS))
