"""Seeded population catalogs: ranges, determinism, the golden population."""

from __future__ import annotations

import json
from pathlib import Path

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


def test_grip_population_draws_the_material_laws_of_its_mix() -> None:
    from deformctl.population import (
        GRIP_HC_EXPONENT,
        GRIP_SLS_ARM_RATIO,
        GRIP_SLS_RELAXATION_TIME_S,
        catalog_laws,
        grip_law_spec,
        grip_population,
    )

    # the default mix is Kelvin–Voigt alone: the catalog of before, bit for bit (same draws)
    pd.testing.assert_frame_equal(
        grip_population(60, seed=5), grip_population(60, seed=5, laws="kv=2")
    )
    cat = grip_population(600, seed=5, laws="kv=1,hc=1,sls=2")
    laws = catalog_laws(cat)
    share = {law: float(np.mean(laws == law)) for law in ("kv", "hc", "sls")}
    assert abs(share["kv"] - 0.25) < 0.06, share
    assert abs(share["sls"] - 0.5) < 0.06, share
    hc, sls = cat[laws == "hc"], cat[laws == "sls"]
    n = hc["material_stiffness_exponent"]
    assert n.between(*GRIP_HC_EXPONENT).all()
    assert n.min() < 1.2
    assert n.max() > 2.8
    assert (cat.loc[laws != "hc", "material_stiffness_exponent"] == 1.0).all()
    ratio = sls["material_arm_stiffness_n_per_cm"] / sls["material_stiffness_n_per_cm"]
    assert ratio.between(*GRIP_SLS_ARM_RATIO).all()
    assert ratio.max() / ratio.min() > 8
    tau = sls["material_relaxation_time_s"]
    assert tau.between(*GRIP_SLS_RELAXATION_TIME_S).all()
    assert tau.max() / tau.min() > 3
    assert (sls["material_damping_ns_per_cm"] == 0.0).all()  # the Zener solid itself
    assert cat.loc[laws != "sls", "material_relaxation_time_s"].isna().all()
    assert (cat.loc[laws != "sls", "material_arm_stiffness_n_per_cm"] == 0.0).all()
    # every row is a simulator object of its law
    from deformctl.catalog import catalog_objects

    specs = [o.to_sim_spec() for o in catalog_objects(cat)]
    assert [s.standard_linear_solid for s in specs] == list(laws == "sls")
    assert [s.hunt_crossley for s in specs] == list(laws == "hc")
    # the mix and every range, JSON-safe for a model's metadata
    spec = grip_law_spec("kv=1,hc=1,sls=2")
    assert json.loads(json.dumps(spec)) == spec
    assert spec["mix"] == {"kv": 0.25, "hc": 0.25, "sls": 0.5}
    assert spec["laws"]["hc"]["material_stiffness_exponent"][:2] == [1.0, 3.0]
    assert spec["laws"]["sls"]["material_relaxation_time_s"][:2] == [0.25, 1.0]
    assert set(grip_law_spec()["laws"]) == {"kv"}


@pytest.mark.parametrize(
    ("mix", "message"),
    [("kv=1,foo=2", "unknown law 'foo'"), ("hc=-1", "weight of hc"), ("kv=0", "no law"),
     ("kv,kv", "twice"), ("sls=nan", "weight of sls")],
)  # fmt: skip
def test_a_bad_law_mix_is_one_usage_line(mix: str, message: str, tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from deformctl.cli import app

    out = tmp_path / "p.csv"
    result = CliRunner().invoke(app, ["population", "--grip", "--laws", mix, "-o", str(out)])
    assert result.exit_code == 2
    assert result.stderr.startswith("error: --laws: ")
    assert message in result.stderr
    assert result.stderr.count("\n") == 1
    assert not out.exists()
    result = CliRunner().invoke(app, ["population", "--laws", "hc", "-o", str(out)])
    assert result.exit_code == 2
    assert "give --grip" in result.stderr


def test_the_grip_catalog_records_its_law_mix(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from deformctl.artifacts import read_catalog
    from deformctl.cli import app
    from deformctl.population import catalog_laws

    out = tmp_path / "p.parquet"
    args = ["population", "--grip", "-n", "20", "--laws", "hc=1,sls=1", "-o", str(out)]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert set(catalog_laws(read_catalog(out))) == {"hc", "sls"}
    import pyarrow.parquet as pq

    meta = json.loads(pq.read_schema(out).metadata[b"deformctl"])
    assert meta["provenance"]["settings"]["laws"]["mix"] == {"hc": 0.5, "sls": 0.5}
