"""Atomic writes, path checks, provenance, and the schema files themselves."""

from __future__ import annotations

import hashlib
import os
from pathlib import Path
from typing import Any

import jsonschema
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from deformctl import __version__
from deformctl.artifacts import (
    Provenance,
    atomic_output,
    check_input_path,
    check_output_path,
    load_json_schema,
    load_table_spec,
)
from deformctl.artifacts.schema import MESSAGE_SCHEMAS, TABLE_KINDS, fast_check, json_validator
from deformctl.errors import EXIT_NOINPUT, MissingInputError, OutputExistsError, SchemaError
from tests._helpers.builders import PAPER_OBJECTS


def test_atomic_output_success_and_failure(tmp_path: Path) -> None:
    dest = tmp_path / "out.bin"
    with atomic_output(dest) as tmp:
        assert tmp.parent == tmp_path
        assert not dest.exists()
        tmp.write_bytes(b"data")
    assert dest.read_bytes() == b"data"
    mask = os.umask(0)
    os.umask(mask)
    assert dest.stat().st_mode & 0o777 == 0o666 & ~mask

    def crash() -> None:
        with atomic_output(dest, force=True) as tmp:
            tmp.write_bytes(b"half")
            raise RuntimeError("writer crashed")

    with pytest.raises(RuntimeError):
        crash()
    assert dest.read_bytes() == b"data"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.bin"]


def test_atomic_output_refuses_a_file_created_meanwhile(tmp_path: Path) -> None:
    dest = tmp_path / "out.bin"

    def race() -> None:
        with atomic_output(dest) as tmp:
            tmp.write_bytes(b"new")
            dest.write_bytes(b"someone else")

    with pytest.raises(OutputExistsError):
        race()
    assert dest.read_bytes() == b"someone else"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.bin"]


def test_path_checks(tmp_path: Path) -> None:
    with pytest.raises(MissingInputError) as info:
        check_input_path(tmp_path / "missing.csv")
    assert info.value.exit_code == EXIT_NOINPUT
    with pytest.raises(MissingInputError, match="is a directory"):
        check_input_path(tmp_path)
    assert check_input_path("-") == "-"
    assert check_output_path("-", force=False) == "-"
    (tmp_path / "x").write_text("")
    with pytest.raises(OutputExistsError):
        check_output_path(tmp_path / "x", force=False)
    assert check_output_path(tmp_path / "x", force=True) == tmp_path / "x"


def test_provenance_hashes_and_round_trips() -> None:
    prov = Provenance.from_invocation(
        [PAPER_OBJECTS, "-"],
        seed=np.int64(3),  # type: ignore[arg-type]
        settings={"k": np.float64(0.5), "n": np.int64(2), "path": PAPER_OBJECTS},
        argv=["/opt/venv/bin/deformctl", "lift", "--seed", "3"],
    )
    assert prov.inputs[str(PAPER_OBJECTS)] == hashlib.sha256(PAPER_OBJECTS.read_bytes()).hexdigest()
    assert prov.inputs["<stdin>"] == "stdin"
    assert prov.command_line == ("deformctl", "lift", "--seed", "3")
    assert prov.tool_version == __version__
    assert prov.seed == 3
    assert prov.settings == {"k": 0.5, "n": 2, "path": str(PAPER_OBJECTS)}
    assert Provenance.from_dict(prov.to_dict()) == prov
    assert Provenance.from_mcap_metadata(prov.to_mcap_metadata()) == prov


def test_malformed_provenance() -> None:
    good = Provenance.from_invocation(argv=["deformctl"]).to_dict()
    with pytest.raises(SchemaError, match="provenance lacks 'seed'"):
        Provenance.from_dict({k: v for k, v in good.items() if k != "seed"}, path="f")
    with pytest.raises(SchemaError, match="malformed"):
        Provenance.from_dict({**good, "seed": "seven"}, path="f")


def test_schema_files_are_valid() -> None:
    for name in MESSAGE_SCHEMAS:
        schema = load_json_schema(name)
        jsonschema.Draft202012Validator.check_schema(schema)
        assert schema["$schema"].endswith("2020-12/schema")
        assert fast_check(name) is not None
    for kind in TABLE_KINDS:
        assert load_table_spec(kind).name == kind


def test_fixed_catalog_spelling() -> None:
    spec = load_table_spec("catalog")
    assert spec.required == (
        "object_id",
        "size_x_cm",
        "size_y_cm",
        "size_z_cm",
        "weight_n",
        "friction_mu",
    )
    assert [c.name for c in spec.columns if not c.required] == [
        "material_stiffness_n_per_cm",
        "material_damping_ns_per_cm",
        "material_stiffness_exponent",
        "material_arm_stiffness_n_per_cm",
        "material_relaxation_time_s",
    ]


_values = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-3, 3),
    st.floats(-2, 2, allow_nan=False),
    st.text(max_size=2),
    st.dictionaries(st.text(max_size=2), st.integers(), max_size=2),
)


@st.composite
def _messages(draw: Any) -> tuple[str, dict[str, Any]]:
    name = draw(st.sampled_from(MESSAGE_SCHEMAS))
    props = list(load_json_schema(name)["properties"])
    keys = draw(st.lists(st.sampled_from([*props, "extra"]), unique=True))
    return name, {k: draw(_values) for k in keys}


@settings(max_examples=300, deadline=None)
@given(_messages())
def test_fast_check_agrees_with_jsonschema(case: tuple[str, dict[str, Any]]) -> None:
    name, message = case
    check = fast_check(name)
    assert check is not None
    assert check(message) == json_validator(name).is_valid(message)
