"""Property: damaged artifacts end in exit 65 with one line on stderr, never a traceback.

Hypothesis feeds truncations, byte flips, overwritten slices and random bytes of valid artifacts
(a squeeze log, a lift log, every Parquet table kind, the catalog CSV, a ``.skops`` model) to
``deformctl inspect`` (in-process through CliRunner) and to the matching library reader.

MCAP logs carry CRCs over every byte, so every corruption must be refused. Parquet has bytes
that no reader looks at (statistics, the writer's name, ...): a corrupted table may still be
accepted, but only when it reads back identical to the original (same columns, values, units and
provenance) — anything that changes what the reader returns is refused by the content digest.
A model file is a zip archive with a CRC per member; bytes outside the members (timestamps,
padding) may change without effect, so it too may be accepted only when it describes identically.
A CSV catalog has no checksum at all: a corruption may give another valid catalog (exit 0), which
the library reader must then accept too.
"""

from __future__ import annotations

import functools
import json
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from deformctl.artifacts import (
    read_catalog,
    read_lift_log,
    read_squeeze_log,
    read_table,
    write_lift_log,
    write_squeeze_log,
    write_table,
)
from deformctl.artifacts.describe import describe
from deformctl.artifacts.model import load_model, save_model
from deformctl.cli import app
from deformctl.errors import EXIT_DATAERR, DeformctlError
from deformctl.model import TrainOptions
from deformctl.population import make_population
from deformctl.train import train_model
from tests._helpers.builders import (
    PAPER_OBJECTS,
    make_attempts,
    make_provenance,
    make_squeezes,
    make_tables,
)

runner = CliRunner()
OBJECTS = [{"object_id": "A", "weight_n": 0.7, "friction_mu": 0.5}]


@functools.cache
def _artifacts() -> dict[str, tuple[bytes, str, Callable[[Path], Any]]]:
    """name → (valid bytes, format, library reader)."""
    with tempfile.TemporaryDirectory(prefix="deformctl-corrupt-") as tmp:
        return _write_artifacts(Path(tmp))


def _write_artifacts(d: Path) -> dict[str, tuple[bytes, str, Callable[[Path], Any]]]:
    """Write each valid artifact into ``d``; their bytes (``d`` may go once this returns)."""
    prov = make_provenance()
    write_squeeze_log(d / "s.mcap", OBJECTS, make_squeezes(3), provenance=prov)
    write_lift_log(d / "l.mcap", OBJECTS, make_attempts(3), provenance=prov)
    tables = make_tables()
    parquet = {}
    for kind in ("coefficients", "catalog", "lift_results", "index_table", "predictions"):
        write_table(tables[kind], d / f"{kind}.parquet", kind, provenance=prov)
        reader = read_catalog if kind == "catalog" else read_table
        parquet[f"{kind}_parquet"] = ((d / f"{kind}.parquet").read_bytes(), "parquet", reader)
    index = make_population(12, seed=0).rename(
        columns={
            "material_stiffness_n_per_cm": "deformability_n_per_cm",
            "material_damping_ns_per_cm": "damping_ns_per_cm",
        }
    )
    index["lift_force_n"] = index["weight_n"] * (1.2 + 0.01 * index["damping_ns_per_cm"])
    trained = train_model(index, TrainOptions(train_size=8, seed=0, restarts=1))
    save_model(d / "m.skops", trained.model, metadata={"seed": 0})
    return {
        **parquet,
        "model_skops": ((d / "m.skops").read_bytes(), "skops", load_model),
        "squeeze_mcap": ((d / "s.mcap").read_bytes(), "mcap", read_squeeze_log),
        "lift_mcap": ((d / "l.mcap").read_bytes(), "mcap", read_lift_log),
        "catalog_csv": (PAPER_OBJECTS.read_bytes(), "csv", read_catalog),
    }


@functools.cache
def _original_description(name: str) -> str:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "original"
        path.write_bytes(_artifacts()[name][0])
        info = describe(path)
    info.pop("path")
    return json.dumps(info, sort_keys=True)


@st.composite
def corruptions(draw: st.DrawFn) -> tuple[str, str, bytes]:
    name = draw(st.sampled_from(sorted(_artifacts())))
    data = _artifacts()[name][0]
    how = draw(st.sampled_from(["truncate", "flip", "overwrite", "random"]))
    if how == "truncate":
        out = data[: draw(st.integers(0, len(data) - 1))]
    elif how == "flip":
        flipped = bytearray(data)
        for _ in range(draw(st.integers(1, 4))):
            pos = draw(st.integers(0, len(data) - 1))
            flipped[pos] ^= draw(st.integers(1, 255))
        out = bytes(flipped)
    elif how == "overwrite":
        pos = draw(st.integers(0, len(data) - 1))
        chunk = draw(st.binary(min_size=1, max_size=16))
        out = data[:pos] + chunk + data[pos + len(chunk) :]
    else:
        out = draw(st.binary(max_size=1024))
    return name, how, out


@settings(
    max_examples=600,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(case=corruptions(), as_json=st.booleans())
def test_corrupted_artifacts_exit_65_with_one_line(
    tmp_path_factory: Any, case: tuple[str, str, bytes], as_json: bool
) -> None:
    name, how, data = case
    _, fmt, reader = _artifacts()[name]
    if data == _artifacts()[name][0]:
        return  # an overwrite with identical bytes is no corruption
    path = tmp_path_factory.mktemp("c") / f"damaged.{fmt}"
    path.write_bytes(data)
    result = runner.invoke(app, ["inspect", str(path), *(["--json"] if as_json else [])])
    assert result.exception is None or isinstance(result.exception, SystemExit), result.exception
    library_error: DeformctlError | None = None
    try:
        reader(path)
    except DeformctlError as err:
        library_error = err
    if library_error is not None:
        assert library_error.exit_code == EXIT_DATAERR
        assert "\n" not in str(library_error)
    library_ok = library_error is None
    if result.exit_code == EXIT_DATAERR:
        lines = result.stderr.splitlines()
        assert len(lines) == 1, result.stderr
        assert lines[0].startswith(f"error: {path}: ")
        assert result.stdout == ""
        event(f"{fmt}: refused")
        return
    # Accepted: never an MCAP log, never random bytes; a Parquet table only when unchanged.
    assert result.exit_code == 0, (result.exit_code, result.stderr)
    assert fmt != "mcap", f"{how} of {name} accepted"
    assert how != "random"
    assert library_ok
    if fmt in ("parquet", "skops"):
        info = describe(path)
        info.pop("path")
        assert json.dumps(info, sort_keys=True) == _original_description(name)
        event(f"{fmt}: accepted, identical content")
    else:
        event("csv: accepted as another valid catalog")


def test_a_footer_shifted_by_one_flipped_byte_is_refused_everywhere() -> None:
    """The case the fuzz test above found: byte 901 of a predictions table's footer flipped
    (0x26 -> 0x2d) makes the Thrift decoder read the base64 Arrow schema as ``created_by`` and no
    key/value metadata at all. ``inspect`` took it for a foreign table (kind from its columns)
    while ``read_table`` refused it; both now refuse it as damaged."""
    path = Path(__file__).resolve().parents[1] / "data/corrupt/predictions_footer_shifted.parquet"
    with pytest.raises(DeformctlError) as err:
        read_table(path)
    assert err.value.exit_code == EXIT_DATAERR
    assert "damaged table" in str(err.value)
    result = runner.invoke(app, ["inspect", str(path)])
    assert result.exit_code == EXIT_DATAERR
    assert result.stderr.splitlines() == [f"error: {err.value}"]
    assert result.stdout == ""
