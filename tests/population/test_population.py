"""Seeded population catalogs: ranges, determinism, the golden population."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from deformctl.errors import UsageError
from deformctl.population import (
    CATALOG_COLUMNS,
    PAPER_POPULATION_SIZE,
    golden_population,
    make_population,
    paper_population,
)


def test_paper_population_shape_ranges_and_columns() -> None:
    cat = paper_population(seed=3)
    assert len(cat) == PAPER_POPULATION_SIZE == 73
    assert tuple(cat.columns) == CATALOG_COLUMNS
    assert cat["object_id"].is_unique
    assert cat["weight_n"].between(20, 60).all()
    assert cat["material_stiffness_n_per_cm"].between(30, 50).all()
    assert cat["material_damping_ns_per_cm"].between(0, 13).all()
    assert (cat["friction_mu"] == 0.5).all()
    for col in ("size_x_cm", "size_y_cm", "size_z_cm"):
        assert (cat[col] > 0).all()
    for col in CATALOG_COLUMNS[1:]:
        assert cat[col].dtype == np.float64


def test_same_seed_same_catalog_other_seed_differs() -> None:
    a = make_population(20, seed=7)
    pd.testing.assert_frame_equal(a, make_population(20, seed=7))
    assert not np.allclose(a["weight_n"], make_population(20, seed=8)["weight_n"])


def test_values_are_the_documented_generator_stream() -> None:
    # The order of draws is documented: weight, deformability, damping, (friction), sizes x, y, z.
    cat = make_population(5, seed=11, friction_mu=(0.3, 0.9))
    rng = np.random.default_rng(11)
    np.testing.assert_array_equal(cat["weight_n"], rng.uniform(20, 60, 5))
    np.testing.assert_array_equal(cat["material_stiffness_n_per_cm"], rng.uniform(30, 50, 5))
    np.testing.assert_array_equal(cat["material_damping_ns_per_cm"], rng.uniform(0, 13, 5))
    np.testing.assert_array_equal(cat["friction_mu"], rng.uniform(0.3, 0.9, 5))
    np.testing.assert_array_equal(cat["size_x_cm"], rng.uniform(10, 20, 5))


def test_custom_ranges_and_prefix() -> None:
    cat = make_population(
        12, seed=1, weight_n=(1, 2), damping_ns_per_cm=(0, 0), id_prefix="Q", friction_mu=0.8
    )
    assert list(cat["object_id"][:2]) == ["Q00", "Q01"]
    assert cat["weight_n"].between(1, 2).all()
    assert (cat["material_damping_ns_per_cm"] == 0).all()
    assert (cat["friction_mu"] == 0.8).all()
    assert make_population(101, seed=0)["object_id"].iloc[-1] == "P100"


@pytest.mark.parametrize(
    ("kwargs", "fragment"),
    [
        ({"n": 0}, "population size"),
        ({"n": 3, "weight_n": (0.0, 10.0)}, "--weight-n must be a number in \\[0.001, 5000\\]"),
        ({"n": 3, "damping_ns_per_cm": (-1.0, 2.0)}, r"--damping-ns-per-cm must be .*\[0, 10000\]"),
        ({"n": 3, "deformability_n_per_cm": (50.0, 30.0)}, "low <= high"),
        ({"n": 3, "friction_mu": 0.0}, "--friction-mu must be a number in \\[0.01, 3\\]"),
    ],
)
def test_bad_ranges_are_usage_errors(kwargs: dict[str, object], fragment: str) -> None:
    n = kwargs.pop("n")
    with pytest.raises(UsageError, match=fragment):
        make_population(n, seed=0, **kwargs)  # type: ignore[arg-type]


def test_golden_population_is_fixed_and_in_range() -> None:
    g = golden_population()
    assert len(g) == 8
    assert tuple(g.columns) == CATALOG_COLUMNS
    pd.testing.assert_frame_equal(g, golden_population())
    assert g["weight_n"].between(20, 60).all()
    assert g["material_stiffness_n_per_cm"].between(30, 50).all()
    assert g["material_damping_ns_per_cm"].between(0, 13).all()
    # spans the paper's box: both ends of every attribute are present
    for col, lo, hi in (
        ("weight_n", 20, 60),
        ("material_stiffness_n_per_cm", 30, 50),
        ("material_damping_ns_per_cm", 0, 13),
    ):
        assert g[col].min() == lo
        assert g[col].max() == hi


def test_grip_population_spans_the_grip_ranges_and_keeps_only_grippable_objects() -> None:
    from deformctl.population import (
        GRIP_MAX_STRAIN_AT_F_W,
        grip_population,
        grip_strain_at_f_w,
    )

    cat = grip_population(400, seed=5)
    assert len(cat) == 400
    assert cat["object_id"].is_unique
    assert tuple(cat.columns) == CATALOG_COLUMNS
    assert cat["weight_n"].between(0.5, 80).all()
    assert cat["material_stiffness_n_per_cm"].between(5, 60).all()
    assert cat["material_damping_ns_per_cm"].between(0, 15).all()
    assert cat["friction_mu"].between(0.2, 1.0).all()
    strain = grip_strain_at_f_w(cat)
    assert strain.max() <= GRIP_MAX_STRAIN_AT_F_W
    # the ranges are spanned: log-uniform W puts about a tenth of the objects in each end decile
    # of log W (fewer at the heavy end, where the rule leaves out the soft and slippery ones)
    log_w = np.log(cat["weight_n"].to_numpy())
    edges = np.log([0.5, 0.5 * 1.66, 80 / 1.66, 80])
    assert np.mean(log_w < edges[1]) > 0.06
    assert np.mean(log_w > edges[2]) > 0.03
    # undamped-like objects (λ < 0.05 N·s/cm) and heavily damped ones (λ > 5) both occur
    lam = cat["material_damping_ns_per_cm"].to_numpy()
    assert np.mean(lam < 0.05) > 0.1
    assert np.mean(lam > 5) > 0.05


def test_grip_population_rule_leaves_out_what_cannot_be_gripped() -> None:
    """The same draws without the rule: exactly the objects with F_w / D > 0.25 size_x go."""
    from deformctl.population import grip_population, grip_strain_at_f_w

    a = grip_population(50, seed=11)
    pd.testing.assert_frame_equal(a, grip_population(50, seed=11))
    assert not np.allclose(a["weight_n"], grip_population(50, seed=12)["weight_n"])
    f_w = a["weight_n"] / (2 * a["friction_mu"])
    np.testing.assert_allclose(
        grip_strain_at_f_w(a), f_w / (a["material_stiffness_n_per_cm"] * a["size_x_cm"])
    )
    with pytest.raises(UsageError):
        grip_population(0, seed=1)
