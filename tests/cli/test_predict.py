"""``deformctl predict``: from an index table, a coefficients table + catalog, or flags.

A model is trained once through the CLI on the synthetic index table (30 objects, 20 train);
what ``predict`` returns is compared with the per-object predictions ``train`` reported in its
metrics file, and the out-of-range warning with the training range recorded in the model.
"""

from __future__ import annotations

import io
import json
import os
import re
import shlex
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import skops.io as sio
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import FunctionTransformer
from typer.testing import CliRunner

from deformctl.artifacts import Provenance, read_table, sha256_file, write_catalog, write_table
from deformctl.artifacts.model import MODEL_FORMAT
from deformctl.cli import app
from deformctl.train import FEATURES
from tests._helpers.cli import _error, load_example, write_index

runner = CliRunner()
FLAG_NAMES = ("--weight-n", "--deformability-n-per-cm", "--damping-ns-per-cm")


@pytest.fixture(scope="module")
def setup(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """index.parquet, coefficients.parquet, objects.csv, model.skops and m.json in one dir."""
    d = tmp_path_factory.mktemp("predict")
    write_index(d / "index.parquet")
    catalog, coefficients, _ = load_example().synthetic_tables(30, 0)
    write_table(coefficients, d / "coefficients.parquet", "coefficients", provenance=None)
    write_catalog(catalog, d / "objects.csv")
    args = ["train", str(d / "index.parquet"), "-o", str(d / "model.skops")]
    result = runner.invoke(app, [*args, "--train-size", "20", "--metrics", str(d / "m.json")])
    assert result.exit_code == 0, result.stderr
    return {
        "dir": d,
        "index": d / "index.parquet",
        "coefficients": d / "coefficients.parquet",
        "catalog": d / "objects.csv",
        "model": d / "model.skops",
        "metrics": d / "m.json",
    }


def _reported(setup: dict[str, Path]) -> pd.DataFrame:
    """What ``train`` reported per object (its metrics file), indexed by object_id."""
    metrics = json.loads(setup["metrics"].read_text())
    return pd.DataFrame(metrics["predictions"]).set_index("object_id")


def test_training_rows_match_what_train_reported(setup: dict[str, Path], tmp_path: Path) -> None:
    out = tmp_path / "pred.parquet"
    result = runner.invoke(
        app, ["predict", str(setup["model"]), str(setup["index"]), "-o", str(out)]
    )
    assert result.exit_code == 0, result.stderr
    pred = read_table(out, "predictions").set_index("object_id")
    reported = _reported(setup)
    train_ids = reported.index[reported["split"] == "train"]
    got = pred.loc[train_ids, "predicted_lift_force_n"].to_numpy()
    want = reported.loc[train_ids, "predicted_lift_force_n"].to_numpy()
    np.testing.assert_allclose(got, want, rtol=0.01)  # the contract: within 1 %
    np.testing.assert_allclose(got, want, rtol=1e-12)  # in fact the same numbers
    # Every row, test rows too, is the same model's prediction.
    np.testing.assert_allclose(
        pred.loc[reported.index, "predicted_lift_force_n"],
        reported["predicted_lift_force_n"],
        rtol=1e-12,
    )
    assert not pred.loc[train_ids, "outside_training_range"].any()
    prov = pred.attrs["provenance"]
    assert prov.inputs == {
        str(setup["model"]): sha256_file(setup["model"]),
        str(setup["index"]): sha256_file(setup["index"]),
    }
    assert prov.seed == 0


def test_flags_give_the_same_number_on_stdout(setup: dict[str, Path]) -> None:
    index = read_table(setup["index"], "index_table").set_index("object_id")
    oid = "P05"
    args = ["predict", str(setup["model"])]
    for flag, feat in zip(FLAG_NAMES, FEATURES, strict=True):
        args += [flag, repr(float(index.loc[oid, feat]))]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.stderr
    assert result.stderr == ""
    csv = pd.read_csv(io.StringIO(result.stdout))
    assert list(csv.columns) == [*FEATURES, "predicted_lift_force_n", "outside_training_range"]
    want = _reported(setup).loc[oid, "predicted_lift_force_n"]
    assert csv["predicted_lift_force_n"][0] == pytest.approx(want, rel=1e-5)  # CSV has 6 digits


def test_coefficients_with_catalog_weights(setup: dict[str, Path]) -> None:
    result = runner.invoke(
        app,
        [
            "predict",
            str(setup["model"]),
            str(setup["coefficients"]),
            "--catalog",
            str(setup["catalog"]),
        ],
    )
    assert result.exit_code == 0, result.stderr
    csv = pd.read_csv(io.StringIO(result.stdout)).set_index("object_id")
    reported = _reported(setup)
    np.testing.assert_allclose(
        csv.loc[reported.index, "predicted_lift_force_n"],
        reported["predicted_lift_force_n"],
        rtol=1e-5,
    )


def test_coefficients_without_weights_need_a_catalog(
    setup: dict[str, Path], tmp_path: Path
) -> None:
    result = runner.invoke(app, ["predict", str(setup["model"]), str(setup["coefficients"])])
    assert _error(result, 65) == (
        f"error: {setup['coefficients']}: field 'weight_n': the table has no weight_n column (a "
        "coefficients table from before weights were copied, or from a log without --weight-n); "
        "pass --catalog OBJECTS to join the weights by object_id"
    )
    catalog = pd.read_csv(setup["catalog"], dtype={"object_id": str})
    write_catalog(catalog[~catalog["object_id"].isin(["P01", "P17"])], tmp_path / "few.csv")
    result = runner.invoke(
        app,
        [
            "predict",
            str(setup["model"]),
            str(setup["coefficients"]),
            "--catalog",
            str(tmp_path / "few.csv"),
            "-o",
            str(tmp_path / "p.parquet"),
        ],
    )
    assert _error(result, 65) == "error: 2 object(s) are not in the catalog: P01, P17"
    assert sorted(os.listdir(tmp_path)) == ["few.csv"]


def test_out_of_range_warning(setup: dict[str, Path]) -> None:
    lo, hi = json.loads(setup["metrics"].read_text())["training_range"]["weight_n"]
    args = ["predict", str(setup["model"]), "--weight-n", "100", "--deformability-n-per-cm", "40"]
    result = runner.invoke(app, [*args, "--damping-ns-per-cm", "5"])
    assert result.exit_code == 0, result.stderr
    assert result.stderr == (
        f"warning: row 0: outside the training range: weight_n = 100 not in [{lo:g}, {hi:g}]\n"
    )
    csv = pd.read_csv(io.StringIO(result.stdout))
    assert bool(csv["outside_training_range"][0]) is True
    assert csv["predicted_lift_force_n"][0] > 0


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        ([], "nothing to predict: give a COEFFICIENTS table or --weight-n"),
        (["c.parquet", "--weight-n", "40"], "give either a COEFFICIENTS table or the flags"),
        (["--weight-n", "40"], "missing --deformability-n-per-cm, --damping-ns-per-cm"),
        (["--weight-n", "40", "--deformability-n-per-cm", "40", "--damping-ns-per-cm", "5",
          "--catalog", "objects.csv"], "--catalog joins weights to a COEFFICIENTS table"),
        (["--weight-n", "nan", "--deformability-n-per-cm", "40", "--damping-ns-per-cm", "5"],
         "--weight-n must be a number in [0.001, 5000] N, got nan"),
    ],
)  # fmt: skip
def test_usage_errors(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, extra: list[str], message: str
) -> None:
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, ["predict", "model.skops", *extra, "-o", "p.parquet"])
    assert message in _error(result, 2)
    assert os.listdir(tmp_path) == []


FLAGS_OK = ["--weight-n", "40", "--deformability-n-per-cm", "40", "--damping-ns-per-cm", "5"]


def test_unexpected_type_in_model_file_is_refused(tmp_path: Path) -> None:
    evil = tmp_path / "evil.skops"
    payload = make_pipeline(FunctionTransformer(func=os.system))
    sio.dump({"format": MODEL_FORMAT, "metadata_json": "{}", "model": payload}, evil)
    result = runner.invoke(
        app, ["predict", str(evil), *FLAGS_OK, "-o", str(tmp_path / "p.parquet")]
    )
    msg = _error(result, 65)
    assert msg.startswith(f"error: {evil}: refusing to load: unexpected type(s) in the model file:")
    assert f"{os.system.__module__}.system" in msg
    assert "sklearn.preprocessing._function_transformer.FunctionTransformer" in msg
    assert sorted(os.listdir(tmp_path)) == ["evil.skops"]


def test_truncated_and_missing_model(setup: dict[str, Path], tmp_path: Path) -> None:
    data = setup["model"].read_bytes()
    cut = tmp_path / "cut.skops"
    cut.write_bytes(data[: int(len(data) * 0.8)])
    result = runner.invoke(app, ["predict", str(cut), *FLAGS_OK, "-o", str(tmp_path / "p.parquet")])
    assert (
        _error(result, 65)
        == f"error: {cut}: not a skops model file (truncated or not a zip archive)"
    )
    result = runner.invoke(app, ["predict", str(tmp_path / "none.skops"), *FLAGS_OK])
    assert _error(result, 66) == f"error: {tmp_path / 'none.skops'}: model file not found"
    result = runner.invoke(app, ["predict", str(setup["model"]), str(tmp_path / "none.parquet")])
    assert _error(result, 66) == f"error: {tmp_path / 'none.parquet'}: no such file"
    assert sorted(os.listdir(tmp_path)) == ["cut.skops"]


def test_wrong_table_kind_is_refused(setup: dict[str, Path], tmp_path: Path) -> None:
    _, _, lift = load_example().synthetic_tables(5, 0)
    write_table(
        lift,
        tmp_path / "lift.parquet",
        "lift_results",
        provenance=Provenance.from_invocation(argv=["t"]),
    )
    result = runner.invoke(app, ["predict", str(setup["model"]), str(tmp_path / "lift.parquet")])
    assert _error(result, 65) == (
        f"error: {tmp_path / 'lift.parquet'}: is a lift_results file; "
        "predict reads coefficients, index_table, predictions tables"
    )


def test_existing_output_needs_force(setup: dict[str, Path], tmp_path: Path) -> None:
    out = tmp_path / "p.parquet"
    out.write_bytes(b"old")
    result = runner.invoke(app, ["predict", str(setup["model"]), *FLAGS_OK, "-o", str(out)])
    assert _error(result, 1) == f"error: {out}: exists already, not overwriting (use --force)"
    assert out.read_bytes() == b"old"
    result = runner.invoke(
        app, ["predict", str(setup["model"]), *FLAGS_OK, "-o", str(out), "--force"]
    )
    assert result.exit_code == 0, result.stderr
    assert len(read_table(out, "predictions")) == 1
    assert sorted(os.listdir(tmp_path)) == ["p.parquet"]


def _readme_commands() -> list[list[str]]:
    """The shell commands of the simulator guide's table, train and predict sections, in words."""
    text = (Path(__file__).resolve().parents[2] / "docs" / "guide" / "simulator.md").read_text()
    start, end = text.index("\n## The index table"), text.index("\n## Looking at any artifact")
    commands: list[list[str]] = []
    for block in re.findall(r"```sh\n(.*?)```", text[start:end], flags=re.DOTALL):
        if "<<" in block:  # a here-document (Python inline): tests/test_docs.py runs it in a shell
            continue
        for command in block.replace("\\\n", " ").splitlines():
            words = shlex.split(command, comments=True)
            if words:
                commands.append(words)
    return commands


def test_readme_examples_run(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Docs are executed: every command of these sections, in order, in-process."""
    monkeypatch.chdir(tmp_path)
    commands = _readme_commands()
    assert [c[:2] for c in commands[:2]] == [
        ["python", "examples/synthetic_index.py"],
        ["deformctl", "table"],
    ]
    assert {c[1] for c in commands[1:]} == {"table", "train", "inspect", "predict"}
    for words in commands:
        if words[0] == "python":
            assert load_example().main(words[2:]) == 0
            continue
        assert words[0] == "deformctl"
        redirect = words.index(">") if ">" in words else None
        args = words[1:redirect] if redirect else words[1:]
        result = runner.invoke(app, args)
        assert result.exit_code == 0, (words, result.stderr)
        if redirect:
            Path(words[redirect + 1]).write_text(result.stdout)
    assert sorted(os.listdir(tmp_path / "demo")) == [
        "coefficients.parquet",
        "index.parquet",
        "lift.parquet",
        "metrics.json",
        "model.skops",
        "objects.csv",
        "predictions.csv",
        "predictions.parquet",
    ]
