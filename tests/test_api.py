"""The package's face: one library call per command, with the command's defaults; short reprs.

For every command the command line is run with only its required arguments while the library
call it ends in is replaced by a recorder; what the command passed is then compared with what
the exported library call uses when given nothing. (The CLI used to fit rig recordings with a
preload the Python API left at zero, moving D by 4.9 %, and ``SimSettings()`` was the table
preset while the command defaults to the paper preset.)
"""

from __future__ import annotations

import inspect
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import deformctl
from deformctl.cli import app

runner = CliRunner()
DATA = Path(__file__).resolve().parent / "data"


class _Called(Exception):
    """Raised by a recorder once it has the arguments (nothing runs further)."""


def _record(monkeypatch: pytest.MonkeyPatch, target: str) -> dict[str, Any]:
    seen: dict[str, Any] = {}

    def recorder(*args: Any, **kwargs: Any) -> Any:
        seen.update(kwargs)
        seen["args"] = args
        raise _Called

    monkeypatch.setattr(target, recorder)
    return seen


def _run(argv: list[str]) -> None:
    result = runner.invoke(app, argv)
    assert isinstance(result.exception, _Called), (argv, result.stderr, result.exception)


def _defaults(function: Any) -> dict[str, Any]:
    return {
        name: p.default
        for name, p in inspect.signature(function).parameters.items()
        if p.default is not inspect.Parameter.empty
    }


def test_every_command_has_its_library_call() -> None:
    for name in (
        "make_population",
        "simulate_squeezes",
        "read_recording",
        "measure_images",
        "read_and_characterize",
        "lift_catalog",
        "sim_runner_factory",
        "build_index_table",
        "train_model",
        "load_predictor",
        "predict_objects",
        "describe",
    ):
        assert callable(getattr(deformctl, name)), name
    assert set(deformctl.__all__) <= set(dir(deformctl))


def test_population_defaults(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    # the library's defaults before the recorder replaces the function (names load lazily)
    api = _defaults(deformctl.make_population)
    seen = _record(monkeypatch, "deformctl.population.make_population")
    _run(["population", "-o", str(tmp_path / "c.csv")])
    assert seen["args"] == (api["n"],)
    for name in ("seed", "weight_n", "deformability_n_per_cm", "damping_ns_per_cm", "friction_mu"):
        assert seen[name] == api[name], name


def test_measure_sim_defaults(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    # the library's defaults before the recorder replaces the function (names load lazily)
    api = _defaults(deformctl.simulate_squeezes)
    seen = _record(monkeypatch, "deformctl.measure.stage.simulate_catalog_file")
    _run(["measure", "sim", str(tmp_path / "cat.csv"), "-o", str(tmp_path / "s.mcap")])
    task = seen["args"][1]
    assert task.protocol == api["protocol"]
    assert api["settings"] is None  # the default preset's, as the command's:
    assert task.settings == deformctl.sim_preset().settings
    assert task.sim_preset == "paper"
    assert task.seed == api["seed"]


def test_measure_bag_defaults(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    seen = _record(monkeypatch, "deformctl.measure.stage.measure_recording")
    _run(["measure", "bag", str(tmp_path / "r.mcap"), "--wrench-topic", "/w",
          "--position-topic", "/p", "--object-id", "a", "--weight-n", "1",
          "-o", str(tmp_path / "s.mcap")])  # fmt: skip
    assert seen["args"][1] == deformctl.BagSource(wrench_topics=("/w",), position_topic="/p")
    assert seen["segmentation"] == _defaults(deformctl.read_recording)["segmentation"]
    assert seen["segmentation"] == deformctl.Segmentation()


def test_measure_csv_defaults(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    seen = _record(monkeypatch, "deformctl.measure.csv.batch.measure_csv_files")
    columns = "time=t,force=f,compression=c"
    _run(["measure", "csv", str(tmp_path / "r.csv"), "--columns", columns,
          "--object-id", "a", "--weight-n", "1", "-o", str(tmp_path / "s.mcap")])  # fmt: skip
    task = seen["args"][1]
    assert task.options == deformctl.CsvOptions(
        columns={"time": "t", "force": "f", "compression": "c"}
    )
    assert task.options.dialect == deformctl.CsvDialect()
    assert task.segmentation == _defaults(deformctl.read_recording)["segmentation"]
    assert task.segmentation == deformctl.Segmentation()


def test_predict_defaults(monkeypatch: pytest.MonkeyPatch) -> None:
    # the library's defaults before the recorder replaces the function (names load lazily)
    api = _defaults(deformctl.predict_objects)
    seen = _record(monkeypatch, "deformctl.predict.predict_objects")
    _run(["predict", "grip", "--weight-n", "2.9", "--deformability-n-per-cm", "30",
          "--damping-ns-per-cm", "0.5", "--friction-mu", "0.5"])  # fmt: skip
    assert seen["coverage"] == api["coverage"] is None
    assert seen["args"][0].path == deformctl.load_predictor("grip").path


def test_characterize_defaults(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    # the library's defaults before the recorder replaces the function (names load lazily)
    api = _defaults(deformctl.read_and_characterize)
    seen = _record(monkeypatch, "deformctl.characterize.stage.characterize_file")
    _run(["characterize", str(tmp_path / "s.mcap"), "-o", str(tmp_path / "c.parquet")])
    _, fit, policy = seen["args"]
    assert fit == api["options"] == deformctl.FitOptions()
    assert fit.preload is None  # per object: fitted for rig recordings, as the command does
    assert policy == api["policy"] == deformctl.QualityPolicy()


def test_lift_defaults(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    seen = _record(monkeypatch, "deformctl.lift.stage.lift_catalog_files")
    _run(["lift", "sim", str(tmp_path / "cat.csv"), "-o", str(tmp_path / "l.parquet")])
    assert seen["search"] == _defaults(deformctl.lift_catalog)["search"]
    assert seen["search"] == deformctl.SearchOptions()
    factory = seen["args"][1]
    # the scene is written into a lift log: without --log the command records none (0 Hz)
    assert factory.settings == deformctl.sim_runner_factory(scene_hz=0.0).settings
    assert factory.settings["sim_preset"] == "paper"
    log = ["--log", str(tmp_path / "l.mcap")]
    _run(["lift", "sim", str(tmp_path / "cat.csv"), "-o", str(tmp_path / "l.parquet"), *log])
    assert seen["args"][1].settings == deformctl.sim_runner_factory().settings


def test_table_defaults(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    # the library's defaults before the recorder replaces the function (names load lazily)
    api = _defaults(deformctl.build_index_table)
    seen = _record(monkeypatch, "deformctl.table.build_index_table")
    inputs = [str(DATA / "coefficients.parquet"), str(DATA / "lift_results.parquet")]
    _run(["table", *inputs, "-o", str(tmp_path / "i.parquet")])
    for name, value in api.items():
        assert seen.get(name, value) == value, name


def test_train_defaults(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    # the library's defaults before the recorder replaces the function (names load lazily)
    api = _defaults(deformctl.train_model)
    seen = _record(monkeypatch, "deformctl.train.train_model")
    _run(["train", str(DATA / "index_table.parquet"), "-o", str(tmp_path / "m.skops")])
    assert seen["args"][1] == api["options"] == deformctl.TrainOptions()
    assert seen.get("form", api["form"]) == api["form"] is None


# ---------------------------------------------------------------------------- reprs


def _short(obj: object) -> str:
    text = repr(obj)
    assert "\n" not in text, type(obj).__name__
    assert len(text) <= 600, (type(obj).__name__, len(text))
    return text


def test_results_print_on_a_few_lines(kv_squeeze: Any, small_lattice: Any) -> None:
    from deformctl.lift.stage import RunnerFactory, lift_catalog
    from deformctl.measure.recording import Recording
    from deformctl.series import TrialOutcome

    assert f"time_s=array[{len(kv_squeeze.time_s)}]" in _short(kv_squeeze)
    _short(Recording([kv_squeeze] * 20, 1000.0, 1000.0, source="csv"))
    assert "positions_m=array[60 x 3]" in _short(small_lattice)  # was 32,098 characters
    catalog = pd.DataFrame(
        {
            "object_id": [f"o{i}" for i in range(40)],
            "size_x_cm": 10.0,
            "size_y_cm": 10.0,
            "size_z_cm": 8.0,
            "weight_n": np.linspace(1, 40, 40),
            "friction_mu": 0.5,
        }
    )

    def make(obj: Any, max_force_n: float) -> Any:
        return lambda f, i: TrialOutcome(f, f >= 1.3 * obj.f_w_n(), 0.0)

    run = lift_catalog(catalog, RunnerFactory("test", make))
    assert "table=DataFrame[40 x" in _short(run)
    assert "trials=(" in _short(run.results[0])
    _short(run.attempts[0])


def test_the_predictor_and_the_csv_options_print_on_a_few_lines() -> None:
    from deformctl.measure.csv.batch import CsvFileTask

    predictor = deformctl.load_predictor("grip")
    assert "weights=(array[" in _short(predictor)  # was 19,648 characters of metadata
    many = predictor.predict_many([10.0] * 50, [20.0] * 50, [1.0] * 50, [0.5] * 50)
    assert "lift_force_n=array[50]" in _short(many)
    _short(predictor.predict(10.0, 20.0, 1.0, 0.5))
    _short(CsvFileTask(deformctl.CsvOptions(), deformctl.Segmentation()))
    _short(deformctl.SearchOptions())
    _short(deformctl.FitOptions())


def test_the_library_reads_an_export_as_the_command_does(kv_csv: Path, tmp_path: Path) -> None:
    """``measure --csv`` and ``characterize`` with no options, and the library calls with none:
    the same squeeze and the same D (the known 20 N/cm within 2 %)."""
    from deformctl.artifacts import read_squeeze_log, read_table

    log, table = tmp_path / "kv.mcap", tmp_path / "kv.parquet"
    argv = ["measure", "csv", str(kv_csv), "--object-id", "kv", "--weight-n", "1", "-o", str(log)]
    assert runner.invoke(app, argv).exit_code == 0
    assert runner.invoke(app, ["characterize", str(log), "-o", str(table)]).exit_code == 0
    rec = deformctl.read_recording(str(kv_csv), deformctl.CsvOptions(), "kv")
    (cli_squeeze,) = read_squeeze_log(log)[1]
    np.testing.assert_allclose(rec.squeezes[0].force_n, cli_squeeze.force_n)
    np.testing.assert_allclose(rec.squeezes[0].compression_m, cli_squeeze.compression_m)
    cli_d = float(read_table(table, "coefficients")["deformability_n_per_cm"].iloc[0])
    api_d = float(deformctl.read_and_characterize(log).table["deformability_n_per_cm"].iloc[0])
    assert api_d == cli_d
    assert cli_d == pytest.approx(20.0, rel=0.02)
