"""deformctl.errors: each class's exit code is the one docs/reference/exit-codes.md documents, and
a message is one line naming its file."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from deformctl import errors
from deformctl.errors import (
    DeformctlError,
    InputDataError,
    MissingInputError,
    OutputExistsError,
    RigError,
    SchemaError,
    SearchError,
    SimulationError,
    UsageError,
    error_context,
)

EXIT_CODES_DOC = Path(__file__).resolve().parents[2] / "docs" / "reference" / "exit-codes.md"


def _documented_codes() -> dict[int, str]:
    """The first table of exit-codes.md: code -> meaning."""
    rows = re.findall(r"^\| (\d+) \| (.+?) \|$", EXIT_CODES_DOC.read_text(), re.MULTILINE)
    return {int(code): meaning for code, meaning in rows}


@pytest.mark.parametrize(
    ("cls", "code", "meaning"),
    [
        (UsageError, 2, "usage error"),
        (InputDataError, 65, "bad input data"),
        (SchemaError, 65, "does not match its schema"),
        (MissingInputError, 66, "missing input file"),
        (OutputExistsError, 1, "output that exists without `--force`"),
        (SearchError, 1, "did not converge"),
        (RigError, 1, "failure"),
        (SimulationError, 1, "failure"),
    ],
)
def test_each_error_exits_with_its_documented_code(
    cls: type[DeformctlError], code: int, meaning: str
) -> None:
    assert cls.exit_code == code
    assert meaning in _documented_codes()[code]


def test_the_module_constants_are_the_documented_codes() -> None:
    documented = _documented_codes()
    assert set(documented) == {0, 1, 2, 65, 66}
    constants = [errors.EXIT_OK, errors.EXIT_FAILURE, errors.EXIT_USAGE, errors.EXIT_DATAERR,
                 errors.EXIT_NOINPUT]  # fmt: skip
    assert constants == sorted(documented)


def test_a_message_is_one_line_prefixed_by_its_path() -> None:
    err = InputDataError("peak force\n   is   implausible\t(N?)", path=Path("run/a.csv"))
    assert str(err) == "run/a.csv: peak force is implausible (N?)"
    assert str(UsageError("  --dt-s must be > 0 ")) == "--dt-s must be > 0"
    schema = SchemaError("must be > 0", path="c.csv", field="weight_n")
    assert str(schema) == "c.csv: field 'weight_n': must be > 0"
    assert schema.field == "weight_n"
    assert str(OutputExistsError("out.parquet")) == (
        "out.parquet: exists already, not overwriting (use --force)"
    )


def test_error_context_names_the_file_only_when_none_is_named() -> None:
    with pytest.raises(UsageError) as unnamed, error_context("table.parquet"):
        raise UsageError("no friction")
    assert str(unnamed.value) == "table.parquet: no friction"
    with pytest.raises(InputDataError) as named, error_context("table.parquet"):
        raise InputDataError("bad row", path="catalog.csv")
    assert str(named.value) == "catalog.csv: bad row"
    with pytest.raises(KeyError), error_context("table.parquet"):  # not ours: untouched
        raise KeyError("bug")
