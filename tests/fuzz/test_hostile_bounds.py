"""Physical bounds and resource budgets, refused before numerics."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from deformctl.catalog import BOUNDS, CatalogObject
from deformctl.cli import app
from deformctl.errors import InputDataError, UsageError

runner = CliRunner()
SCHEMAS = Path(__file__).parents[2] / "schemas"


def _one_line(stderr: str) -> str:
    assert stderr.startswith("error: "), stderr
    assert stderr.count("\n") == 1, stderr
    return stderr


def test_the_catalog_spec_states_the_catalog_bounds() -> None:
    spec = json.loads((SCHEMAS / "catalog.columns.json").read_text())
    stated = {
        c["name"]: (c.get("minimum", c.get("exclusive_minimum")), c["maximum"])
        for c in spec["columns"]
        if "maximum" in c
    }
    assert stated == BOUNDS
    # μ's physical floor (quantities.FRICTION_MU: 0.01 <= μ <= 3), as the spec says
    mu = next(c for c in spec["columns"] if c["name"] == "friction_mu")
    assert "exclusive_minimum" not in mu
    assert mu["minimum"] == 0.01


EXTREMES = [
    (column, value)
    for column, (low, high) in BOUNDS.items()
    for value in (low / 10 if low > 0 else -1.0, high * 10, 1e-308, 1e308)
]


@pytest.mark.parametrize(("column", "value"), EXTREMES)
def test_out_of_bounds_rows_are_refused_by_every_reader(
    column: str, value: float, tmp_path: Path, catalog_row: dict[str, Any], write_catalog: Any
) -> None:
    low, high = BOUNDS[column]
    if low <= value <= high:
        pytest.skip("inside the bounds")
    path = write_catalog(tmp_path / "cat.csv", [{**catalog_row, column: value}])
    result = runner.invoke(app, ["inspect", str(path)])
    assert result.exit_code == 65
    assert column in _one_line(result.stderr)
    with pytest.raises(InputDataError, match="physical bounds"):
        CatalogObject.from_row({**catalog_row, column: value}).to_sim_spec()


def test_sim_settings_refuse_a_tiny_time_step(
    tmp_path: Path, catalog_row: dict[str, Any], write_catalog: Any
) -> None:
    from deformctl.sim import SimSettings

    with pytest.raises(UsageError, match="--dt-s"):
        SimSettings(dt_s=1e-12)
    cat = write_catalog(tmp_path / "cat.csv", [catalog_row])
    result = runner.invoke(app, ["measure", "sim", str(cat), "--dt-s", "1e-12", "-o", "x.mcap"])
    assert result.exit_code == 2
    assert "--dt-s" in _one_line(result.stderr)


@pytest.mark.parametrize("ramp", ["0", "-1", "nan"])
def test_a_squeeze_needs_a_force_ramp(
    ramp: str, tmp_path: Path, catalog_row: dict[str, Any], write_catalog: Any
) -> None:
    cat = write_catalog(tmp_path / "cat.csv", [catalog_row])
    out = tmp_path / "x.mcap"
    result = runner.invoke(app, ["measure", "sim", str(cat), "--ramp-s", ramp, "-o", str(out)])
    assert result.exit_code == 2
    assert "--ramp-s" in _one_line(result.stderr)
    assert not out.exists()


def test_steps_are_counted_before_they_are_allocated(catalog_row: dict[str, Any]) -> None:
    from deformctl.sim import SimSettings, squeeze

    spec = CatalogObject.from_row(catalog_row).to_sim_spec()
    with pytest.raises(UsageError, match=r"steps .* --memory-budget-gib"):
        squeeze(spec, peak_force_n=1.0, ramp_s=0.1, hold_s=1e6, settings=SimSettings(dt_s=1e-5))


def test_a_huge_single_log_is_refused_before_simulating(
    tmp_path: Path, catalog_row: dict[str, Any], write_catalog: Any
) -> None:
    # 5,000 objects x 3 squeezes x 1,251 steps x 400 bytes: 7.5 GB, over three times the 2 GiB
    # default budget (the refusal is the whole-log estimate, not each object's)
    rows = [{**catalog_row, "object_id": f"o{i}"} for i in range(5_000)]
    cat = write_catalog(tmp_path / "big.csv", rows)
    out = tmp_path / "x.mcap"
    result = runner.invoke(app, ["measure", "sim", str(cat), "-o", str(out)])
    assert result.exit_code == 2
    line = _one_line(result.stderr)
    assert "one squeeze log of 5,000 objects" in line
    assert "dataset directory" in line
    assert "--memory-budget-gib" in line
    assert not out.exists()


def test_a_huge_network_is_refused_before_training(tmp_path: Path) -> None:
    from deformctl.train import MAX_PARAMETERS, parameter_count

    assert parameter_count((2,)) == 11
    index = Path(__file__).parents[1] / "data" / "index_table.parquet"
    result = runner.invoke(app, ["train", str(index), "--hidden", "100000000", "-o", "m.skops"])
    assert result.exit_code == 2
    assert "--max-parameters" in _one_line(result.stderr)
    import inspect

    from deformctl.cli.train import train

    assert inspect.signature(train).parameters["max_parameters"].default.default == MAX_PARAMETERS


@pytest.mark.parametrize(
    "args",
    [
        ["--lift-hold-s", "1e5"],
        ["--lift-speed-m-s", "1e-300"],
        ["--lift-height-m", "1e308", "--lift-speed-m-s", "1e-10"],  # an infinite estimate
    ],
)
@pytest.mark.parametrize("output", ["l.parquet", "d/"])
def test_lift_steps_are_budgeted_before_any_attempt(
    args: list[str], output: str, tmp_path: Path, catalog_row: dict[str, Any], write_catalog: Any
) -> None:
    cat = write_catalog(tmp_path / "cat.csv", [catalog_row])
    out = tmp_path / output
    result = runner.invoke(app, ["lift", "sim", str(cat), *args, "-o", str(out)])
    assert result.exit_code == 2, result.stderr
    line = _one_line(result.stderr)
    assert "lift attempt" in line
    assert "--memory-budget-gib" in line
    assert not out.exists()


@pytest.mark.parametrize("output", ["x.mcap", "d/"])
def test_squeeze_steps_are_budgeted_before_simulating(
    output: str, tmp_path: Path, catalog_row: dict[str, Any], write_catalog: Any
) -> None:
    cat = write_catalog(tmp_path / "cat.csv", [catalog_row])
    out = tmp_path / output
    argv = ["measure", "sim", str(cat), "--ramp-s", "1e308", "--hold-s", "1e308"]
    result = runner.invoke(app, [*argv, "-o", str(out)])
    assert result.exit_code == 2, result.stderr
    assert "squeeze" in _one_line(result.stderr)
    assert not out.exists()


def test_out_of_memory_is_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, catalog_row: dict[str, Any], write_catalog: Any
) -> None:
    from deformctl.measure import stage

    def boom(*args: object, **kwargs: object) -> None:
        raise MemoryError("Unable to allocate 22.8 TiB")

    monkeypatch.setattr(stage, "squeeze_objects", boom)
    cat = write_catalog(tmp_path / "cat.csv", [catalog_row])
    out = tmp_path / "x.mcap"
    argv = ["measure", "sim", str(cat), "--memory-budget-gib", "1e9", "-o", str(out)]
    result = runner.invoke(app, argv)
    assert result.exit_code == 1
    assert "out of memory" in _one_line(result.stderr)
    assert not out.exists()


def _squeeze_log(path: Path, field: str, value: float) -> Path:
    import numpy as np

    from deformctl.artifacts import write_squeeze_log
    from deformctl.series import SqueezeSeries

    t = np.linspace(0.0, 1.0, 50)
    columns = {"force_n": 10.0 * t, "compression_m": 0.01 * t}
    columns[field] = columns[field].copy()
    columns[field][25] = value
    series = SqueezeSeries(object_id="A", squeeze_index=0, time_s=t, **columns)
    write_squeeze_log(path, [{"object_id": "A", "weight_n": 1.0}], [series], provenance=None)
    return path


@pytest.mark.parametrize("field", ["force_n", "compression_m"])
@pytest.mark.parametrize("value", [1e300, -1e300, 1e30])
@pytest.mark.parametrize("command", ["inspect", "characterize"])
def test_log_samples_beyond_their_physical_bounds_are_refused(
    field: str, value: float, command: str, tmp_path: Path
) -> None:
    log = _squeeze_log(tmp_path / "s.mcap", field, value)
    out = tmp_path / "c.parquet"
    argv = [command, str(log)] + (["-o", str(out)] if command == "characterize" else [])
    result = runner.invoke(app, argv)
    assert result.exit_code == 65, result.stderr
    line = _one_line(result.stderr)
    assert field in line
    assert "s.mcap" in line
    assert not out.exists()


def test_log_schemas_bound_every_number() -> None:
    for name in ("squeeze_sample", "lift_attempt_sample", "lift_attempt_result"):
        props = json.loads((SCHEMAS / f"{name}.schema.json").read_text())["properties"]
        for key, prop in props.items():
            types = prop.get("type")
            if types in ("number", "integer") or (isinstance(types, list) and "number" in types):
                assert "maximum" in prop, (name, key)
