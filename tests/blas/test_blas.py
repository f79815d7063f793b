"""The BLAS record: what the model file says about the kernel and threads it was trained on."""

from __future__ import annotations

import json

from threadpoolctl import threadpool_info
from typer.testing import CliRunner

from deformctl.artifacts.model import load_model
from deformctl.blas import BLAS_INFO_KEYS, blas_info, blas_record, blas_summary
from deformctl.cli import app
from deformctl.repro.synthetic import synthetic_index_table


def _threadpoolctl_view() -> dict[str, tuple[str | None, str | None]]:
    return {
        lib["filepath"].rsplit("/", 1)[-1]: (lib.get("internal_api"), lib.get("architecture"))
        for lib in threadpool_info()
        if lib["user_api"] == "blas"
    }


def test_blas_info_is_what_threadpoolctl_reports() -> None:
    info = blas_info()
    assert info, "numpy brings a BLAS"
    for lib in info:
        assert tuple(lib) == BLAS_INFO_KEYS
    view = _threadpoolctl_view()
    assert {lib["library"]: (lib["internal_api"], lib["architecture"]) for lib in info} == view
    summary = blas_summary(info)
    assert summary.count(",") == len(info) - 1
    for lib in info:
        assert f"{lib['internal_api']} {lib['version']}" in summary
    assert blas_summary([]) == "no BLAS library loaded"


def test_model_file_records_the_kernel_and_one_thread(tmp_path) -> None:
    index = tmp_path / "index.parquet"
    synthetic_index_table(n=30).to_parquet(index)
    model_path, metrics_path = tmp_path / "model.skops", tmp_path / "metrics.json"
    result = CliRunner().invoke(
        app,
        ["train", str(index), "-o", str(model_path), "--train-size", "20",
         "--metrics", str(metrics_path)],
    )  # fmt: skip
    assert result.exit_code == 0, result.stderr
    _, metadata = load_model(model_path)
    metrics = json.loads(metrics_path.read_text())
    assert metadata["blas"] == metrics["blas"]
    view = _threadpoolctl_view()
    assert {lib["library"] for lib in metadata["blas"]} == set(view)
    for lib in metadata["blas"]:
        assert lib["num_threads"] == 1  # the fit runs on one BLAS thread, whatever the machine
        assert (lib["internal_api"], lib["architecture"]) == view[lib["library"]]
    shown = CliRunner().invoke(app, ["inspect", str(model_path)])
    assert shown.exit_code == 0, shown.stderr
    assert f"BLAS of the fit: {blas_summary(metadata['blas'])}" in shown.stdout
    assert " x1" in shown.stdout


def test_blas_record_keeps_only_plain_values() -> None:
    good = blas_info()
    assert blas_record(good) == good
    assert blas_record(None) is None
    assert blas_record("openblas") is None
    assert blas_record([{"library": "x"}, 3]) is None
    hostile = [{"library": ["a"], "num_threads": True, "architecture": "Haswell", "extra": 1}]
    assert blas_record(hostile) == [
        {key: ("Haswell" if key == "architecture" else None) for key in BLAS_INFO_KEYS}
    ]
