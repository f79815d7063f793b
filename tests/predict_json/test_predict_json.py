"""``predict --json``'s document: every predictions column in every record, in the contract's
order, null where a run has no value (checked against ``schemas/predict.schema.json``)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import jsonschema
import numpy as np

from deformctl.predict_json import ABSENT_FALSE, json_document, json_text, prediction_columns

REPO = Path(__file__).resolve().parents[2]
SCHEMA = json.loads((REPO / "schemas" / "predict.schema.json").read_text(encoding="utf-8"))
CONTRACT = json.loads((REPO / "schemas" / "predictions.columns.json").read_text(encoding="utf-8"))


def _minimal() -> dict[str, object]:
    """What one object given by flags, without μ or a coverage, gives."""
    return {
        "weight_n": np.array([2.9]),
        "deformability_n_per_cm": np.array([30.0]),
        "damping_ns_per_cm": np.array([0.47]),
        "predicted_lift_force_n": np.array([4.25]),
        "outside_training_range": np.array([False]),
    }


def test_the_columns_are_the_contract_s_in_its_order() -> None:
    assert [name for name, _ in prediction_columns()] == [c["name"] for c in CONTRACT["columns"]]
    assert dict(prediction_columns())["damping_ns_per_cm"] == "N·s/cm"


def test_a_minimal_run_has_every_column_null_or_false_where_absent() -> None:
    doc = json_document(_minimal())
    jsonschema.Draft202012Validator(SCHEMA).validate(doc)
    rec = doc["records"][0]
    assert list(rec) == [c["name"] for c in CONTRACT["columns"]]
    assert rec["predicted_lift_force_n"] == 4.25
    assert isinstance(rec["outside_training_range"], bool)
    for name in ("object_id", "friction_mu", "f_w_n", "lift_force_upper_n", "quality"):
        assert rec[name] is None, name
    for name in ABSENT_FALSE:
        assert rec[name] is False, name


def test_nan_is_null_and_an_extra_column_follows_the_contract() -> None:
    cols = {**_minimal(), "max_safe_force_n": np.array([math.nan]), "law": ["kelvin_voigt"]}
    doc = json_document(cols)
    jsonschema.Draft202012Validator(SCHEMA).validate(doc)
    rec = doc["records"][0]
    assert rec["max_safe_force_n"] is None
    assert list(rec)[-1] == "law"
    assert doc["units"]["law"] is None
    assert json.loads(json_text(cols)) == doc  # strict JSON: no NaN


def test_the_schema_requires_every_contract_column() -> None:
    names = [c["name"] for c in CONTRACT["columns"]]
    assert SCHEMA["properties"]["records"]["items"]["required"] == names
    assert SCHEMA["x-deformctl"] == {"name": "predict", "version": 1}
    bad = json_document(_minimal())
    del bad["records"][0]["coverage"]
    assert not jsonschema.Draft202012Validator(SCHEMA).is_valid(bad)
