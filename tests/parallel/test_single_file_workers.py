"""Single-file outputs of ``measure --sim`` and ``lift --sim`` on several local processes.

The files must not depend on the number of workers: each object's squeezes depend only on the
seed and its catalog position, and each search only on the object, so one and two workers give
the same bytes. Errors raised in a worker reach the client whole (type, message, exit code).
"""

from __future__ import annotations

import pickle
from pathlib import Path

import pytest
from typer.testing import CliRunner

from deformctl.cli import app
from deformctl.errors import (
    EXIT_DATAERR,
    InputDataError,
    OutputExistsError,
    SchemaError,
    UsageError,
)
from deformctl.lift.runners.sim import sim_runner_factory
from deformctl.lift.stage import lift_catalog_files
from deformctl.measure import SimulateCatalogTask, SqueezeProtocol, simulate_catalog_file
from deformctl.parallel import MIN_PARALLEL_OBJECTS, map_in_order, single_file_workers
from deformctl.presets import sim_preset

runner = CliRunner()
HEADER = (
    "object_id,size_x_cm,size_y_cm,size_z_cm,weight_n,friction_mu,"
    "material_stiffness_n_per_cm,material_damping_ns_per_cm\n"
)


def _catalog(tmp_path: Path, n: int = 4) -> Path:
    path = tmp_path / "cat.csv"
    rows = [f"o{i},10,10,10,{2 + i},0.5,{10 + 5 * i},{0.2 * i}" for i in range(n)]
    path.write_text(HEADER + "\n".join(rows) + "\n")
    return path


def _fast_task() -> SimulateCatalogTask:
    preset = sim_preset().replace(settings={"alpha_cm": 5.0, "dt_s": 0.002})
    protocol = SqueezeProtocol(
        squeezes=2, strain=0.1, ramp_s=0.05, hold_s=0.1, noise_force_n=0.01
    )  # fmt: skip
    return SimulateCatalogTask(
        protocol=protocol, settings=preset.settings, seed=7, sim_preset=preset.name
    )


def test_measure_log_is_the_same_bytes_with_one_or_two_workers(tmp_path: Path) -> None:
    cat = _catalog(tmp_path)
    outs = []
    for workers in (1, 2):
        out = tmp_path / f"w{workers}" / "sq.mcap"
        out.parent.mkdir()
        objects, series = simulate_catalog_file(
            str(cat), _fast_task(), output=str(out), workers=workers
        )
        assert [o["object_id"] for o in objects] == ["o0", "o1", "o2", "o3"]
        assert [s.object_id for s in series] == ["o0", "o0", "o1", "o1", "o2", "o2", "o3", "o3"]
        outs.append(out.read_bytes())
    assert outs[0] == outs[1]


def test_lift_table_and_log_are_the_same_bytes_with_one_or_two_workers(tmp_path: Path) -> None:
    cat = _catalog(tmp_path)
    preset = sim_preset().replace(
        settings={"alpha_cm": 5.0, "dt_s": 0.002}, profile={"hold_s": 0.05}
    )
    files = []
    progress: list[list[tuple[str, int, int]]] = []
    for workers in (1, 2):
        d = tmp_path / f"w{workers}"
        d.mkdir()
        seen: list[tuple[str, int, int]] = []
        run = lift_catalog_files(
            str(cat), sim_runner_factory(preset=preset), output=str(d / "lift.parquet"),
            log=str(d / "lift.mcap"), workers=workers,
            progress=lambda oid, i, n, seen=seen: seen.append((oid, i, n)),
        )  # fmt: skip
        assert run.ok, run.error_message()
        assert list(run.table["object_id"]) == ["o0", "o1", "o2", "o3"]
        files.append(((d / "lift.parquet").read_bytes(), (d / "lift.mcap").read_bytes()))
        progress.append(seen)
    assert files[0] == files[1]
    assert progress[0] == progress[1] == [(f"o{i}", i + 1, 4) for i in range(4)]


def test_an_error_in_a_worker_reaches_the_client_whole(tmp_path: Path) -> None:
    """A row the simulator refuses, squeezed in a worker: the client raises the same error."""
    task = _fast_task()
    good = {"object_id": "ok", "size_x_cm": 10.0, "size_y_cm": 10.0, "size_z_cm": 10.0,
            "weight_n": 2.0, "friction_mu": 0.5, "material_stiffness_n_per_cm": 10.0,
            "material_damping_ns_per_cm": 0.5}  # fmt: skip
    bad = {**good, "object_id": "no-material", "material_stiffness_n_per_cm": None}
    items = [{**good, "_position": 0}, {**bad, "_position": 1}, {**good, "_position": 2}]
    with pytest.raises(InputDataError) as in_process:
        map_in_order(task, items, workers=1)
    with pytest.raises(InputDataError) as in_worker:
        map_in_order(task, items, workers=2)
    assert str(in_worker.value) == str(in_process.value)
    assert "no-material" in str(in_worker.value)
    assert in_worker.value.exit_code == EXIT_DATAERR


@pytest.mark.parametrize(
    "err",
    [
        SchemaError("bad unit", path="t.parquet", field="weight_n"),
        OutputExistsError("out.mcap"),
        UsageError("--workers must be >= 1, got 0"),
    ],
)
def test_errors_pickle_with_their_message_and_exit_code(err: Exception) -> None:
    back = pickle.loads(pickle.dumps(err))
    assert type(back) is type(err)
    assert str(back) == str(err)
    assert back.exit_code == err.exit_code  # type: ignore[attr-defined]


def test_single_file_workers_rule(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("deformctl.parallel.sweep._available_cores", lambda: 2)
    # not given: auto measures (tests/parallel/test_auto.py); one object runs here
    assert single_file_workers(None, MIN_PARALLEL_OBJECTS - 1) == "auto"
    assert single_file_workers(None, 1) == 1
    assert single_file_workers(4, 3) == 3  # never more workers than objects
    assert single_file_workers(1, 100) == 1
    assert single_file_workers(3, 100) == 3


def _error_line(args: list[str], code: int) -> str:
    result = runner.invoke(app, args)
    assert result.exit_code == code, result.stderr
    err = result.stderr.strip()
    assert err.startswith("error: "), err
    assert "\n" not in err, err
    return err


def test_workers_flag_on_a_single_file(tmp_path: Path) -> None:
    cat = _catalog(tmp_path, 2)
    rig = ["lift", "rig", str(cat), "--command", "true", "-o", str(tmp_path / "r.parquet")]
    err = _error_line([*rig, "--workers", "2"], 2)
    assert "lift rig: no such option: --workers" in err
    err = _error_line(["characterize", str(cat), "-o", str(tmp_path / "c.parquet"),
                       "--workers", "2"], 2)  # fmt: skip
    assert "--workers needs a dataset directory output" in err
    err = _error_line(["measure", "sim", str(cat), "-o", str(tmp_path / "s.mcap"),
                       "--workers", "0"], 2)  # fmt: skip
    assert "--workers must be >= 1, got 0" in err
    assert not any(tmp_path.glob("*.mcap"))
    assert not any(tmp_path.glob("*.parquet"))
    result = runner.invoke(
        app, ["measure", "sim", str(cat), "-o", str(tmp_path / "s.mcap"), "--workers", "2",
              "--alpha-cm", "5", "--dt-s", "0.002", "--squeezes", "1", "--ramp-s", "0.05",
              "--hold-s", "0.05"],
    )  # fmt: skip
    assert result.exit_code == 0, result.stderr
    assert "2 simulated squeeze(s) of 2 object(s)" in result.stderr


def test_cli_logs_with_one_and_two_workers_hold_the_same_squeezes(tmp_path: Path) -> None:
    """Through the command line: only the recorded command line (``--workers N``) differs."""
    from deformctl.artifacts import read_squeeze_log

    cat = _catalog(tmp_path, MIN_PARALLEL_OBJECTS)
    fast = ["--alpha-cm", "5", "--dt-s", "0.002", "--squeezes", "1", "--ramp-s", "0.05",
            "--hold-s", "0.05", "--noise-force-n", "0.01"]  # fmt: skip
    logs = []
    for workers in ("1", "2"):
        out = tmp_path / f"s{workers}.mcap"
        result = runner.invoke(
            app, ["measure", "sim", str(cat), "-o", str(out), "--workers", workers, *fast]
        )
        assert result.exit_code == 0, result.stderr
        logs.append(read_squeeze_log(out))
    (objects1, series1), (objects2, series2) = logs
    assert objects1 == objects2
    assert len(series1) == len(series2) == MIN_PARALLEL_OBJECTS
    for a, b in zip(series1, series2, strict=True):
        assert a.object_id == b.object_id
        assert (a.force_n == b.force_n).all()
        assert (a.compression_m == b.compression_m).all()
