"""The dataset regression: the golden population through the pipeline, against expected.json."""

from __future__ import annotations

import copy
import json

import pandas as pd

from deformctl.artifacts import read_catalog
from deformctl.golden import EXPECTED_PATH, compare, compute_golden
from deformctl.population import golden_population


def test_catalog_file_is_the_golden_population() -> None:
    on_disk = read_catalog(EXPECTED_PATH.parent / "catalog.csv").reset_index(drop=True)
    pd.testing.assert_frame_equal(on_disk, golden_population(), check_dtype=False)


def test_pipeline_reproduces_expected_numbers() -> None:
    expected = json.loads(EXPECTED_PATH.read_text())
    moved = compare(expected, compute_golden())
    assert not moved, "golden numbers moved:\n" + "\n".join(moved)


def test_compare_names_what_moved() -> None:
    expected = json.loads(EXPECTED_PATH.read_text())
    actual = copy.deepcopy(expected)
    oid = sorted(actual["objects"])[0]
    actual["objects"][oid]["lift_force_n"] *= 1.02
    actual["model"]["test_max_rel_error"] += 0.05
    moved = compare(expected, actual)
    assert len(moved) == 2
    assert moved[0].startswith(f"{oid} lift_force_n: expected")
    assert "+2.00 %" in moved[0]
    assert moved[1].startswith("model test_max_rel_error")
    within = copy.deepcopy(expected)
    within["objects"][oid]["lift_force_n"] *= 1.005
    assert compare(expected, within) == []
