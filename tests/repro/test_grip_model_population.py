"""The grip model's population of every law (`grip_model population`)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from deformctl.catalog import ARM_COLUMN, EXPONENT_COLUMN, RELAXATION_COLUMN
from deformctl.population import catalog_laws, grip_population
from deformctl.repro.grip_model import LAW_ID_PREFIX, main, model_population


def test_the_kelvin_voigt_part_is_the_population_of_before_bit_for_bit() -> None:
    both = model_population(seed=1, kv_n=40, laws="hc=1,sls=1", laws_n=60, laws_seed=11)
    before = grip_population(40, seed=1)
    kv = both.iloc[:40]
    pd.testing.assert_frame_equal(kv[list(before.columns)], before)
    assert (kv[EXPONENT_COLUMN] == 1.0).all()
    assert (kv[ARM_COLUMN] == 0.0).all()
    assert kv[RELAXATION_COLUMN].isna().all()
    assert list(catalog_laws(kv)) == ["kv"] * 40


def test_the_other_laws_come_from_their_own_seed_with_their_own_ids() -> None:
    both = model_population(seed=1, kv_n=40, laws="hc=1,sls=1", laws_n=60, laws_seed=11)
    others = both.iloc[40:]
    assert len(others) == 60
    assert others["object_id"].str.startswith(LAW_ID_PREFIX).all()
    assert both["object_id"].is_unique
    laws = set(catalog_laws(others))
    assert laws == {"hc", "sls"}
    # not the Kelvin–Voigt objects' draws with another law
    kv_w = both["weight_n"].iloc[:40].to_numpy()
    assert not np.isin(others["weight_n"].to_numpy(), kv_w).any()
    again = model_population(seed=1, kv_n=40, laws="hc=1,sls=1", laws_n=60, laws_seed=11)
    pd.testing.assert_frame_equal(both, again)


def test_no_other_laws_is_the_kelvin_voigt_population() -> None:
    alone = model_population(seed=2, kv_n=30, laws="hc=1", laws_n=0, laws_seed=12)
    pd.testing.assert_frame_equal(alone, grip_population(30, seed=2))


def test_the_command_writes_the_catalog(tmp_path) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "population.csv"
    args = ["population", "--seed", "1", "--kv-n", "10", "--laws", "sls=1", "--laws-n", "5"]
    assert main([*args, "--laws-seed", "3", "-o", str(out)]) == 0
    frame = pd.read_csv(out)
    assert len(frame) == 15
    assert list(catalog_laws(frame)).count("sls") == 5


@pytest.mark.parametrize("laws", ["xx=1", "hc=-1"])
def test_a_bad_law_mix_is_one_error_line(tmp_path, capsys, laws) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "population.csv"
    args = ["population", "--seed", "1", "--kv-n", "10", "--laws", laws, "--laws-n", "5"]
    assert main([*args, "--laws-seed", "3", "-o", str(out)]) == 2
    assert capsys.readouterr().err.startswith("error: ")
    assert not out.exists()
