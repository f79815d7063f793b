"""``characterize`` on logs that are not (only) a Kelvin–Voigt squeeze: warnings, --strict,
negative D, --allow-flagged, --constrain-damping, --preload, and old coefficients files.

Each flag has its own one-object log (``tests/_helpers/doubtful_logs.py``), beside a clean
object: the run writes the table with the flag in ``quality`` and prints exactly one warning line
for the flagged object, naming the flag and its number; ``--strict`` exits 65 with one line and
writes nothing.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from deformctl.artifacts import read_table, write_squeeze_log, write_table
from deformctl.artifacts import tables as tables_module
from deformctl.artifacts.dataset import read_dataset, read_failures
from deformctl.cli import app
from deformctl.errors import EXIT_DATAERR, EXIT_USAGE
from deformctl.series import SqueezeSeries
from deformctl.table import build_index_table
from deformctl.testing.kelvin_voigt import synthetic_kelvin_voigt_squeeze
from tests._helpers.doubtful_logs import constant_rate, position_controlled, rupture

runner = CliRunner()


def _negative_force() -> list[SqueezeSeries]:
    s = position_controlled(20.0, 3.0, object_id="bad")
    return [SqueezeSeries("bad", 0, s.time_s, -s.force_n, s.compression_m)]


def _noise_force() -> list[SqueezeSeries]:
    s = synthetic_kelvin_voigt_squeeze(20.0, 3.0, seed=4, object_id="bad")
    rng = np.random.default_rng(0)
    return [
        SqueezeSeries(
            "bad", 0, s.time_s, 0.02 * s.force_n + rng.normal(0, 0.1, len(s)), s.compression_m
        )
    ]


def _negative_damping() -> list[SqueezeSeries]:
    return [position_controlled(20.0, -2.0, seed=i, index=i, object_id="bad") for i in range(2)]


#: flag → (the flagged object's squeezes, text the warning must contain)
CASES: dict[str, tuple[Callable[[], list[SqueezeSeries]], str]] = {
    # the lsq fits are bounded, so a negative λ is held at 0 and said so; only the
    # paper estimator (unbounded) writes λ < 0, flagged whatever its standard error
    "at_bound": (_negative_damping, "at_bound (damping_ns_per_m of the kv law at its bound)"),
    "negative_damping": (_negative_damping, "negative_damping (λ = -2"),
    "low_r2": (_noise_force, "low_r2 (R² = "),
    "damping_unidentifiable": (
        lambda: [constant_rate(20.0, 3.0, preload_n=0.5, object_id="bad")],
        "damping_unidentifiable (λ cannot be told from a preload",
    ),
    "rupture": (
        lambda: [rupture(13.0, 0.33, object_id="bad")],
        "rupture (1 squeeze(s); first at 1.99 s, 10.1 N",
    ),
    "few_samples": (
        lambda: [
            synthetic_kelvin_voigt_squeeze(
                20.0, 3.0, duration_s=0.5, profile="sine", object_id="bad"
            )
        ],
        "few_samples (501 samples < 4 windows of 201)",
    ),
    "negative_stiffness": (_negative_force, "negative_stiffness (D = 0 N/cm ≤ 0)"),
}
#: flag → extra arguments
ARGS: dict[str, list[str]] = {"negative_damping": ["--method", "paper"]}


def _log(path: Path, bad: list[SqueezeSeries]) -> Path:
    good = [
        position_controlled(20.0, 3.0, seed=10 + i, index=i, object_id="good") for i in range(2)
    ]
    objects = [{"object_id": "good", "weight_n": 1.0}, {"object_id": "bad", "weight_n": 1.0}]
    write_squeeze_log(path, objects, [*good, *bad], provenance=None)
    return path


def _one_error(res: object, code: int) -> str:
    assert res.exit_code == code, (res.exit_code, res.stderr)  # type: ignore[attr-defined]
    lines = res.stderr.splitlines()  # type: ignore[attr-defined]
    assert len(lines) == 1, lines
    assert lines[0].startswith("error: ")
    return str(lines[0])


@pytest.mark.parametrize("flag", list(CASES))
def test_each_flag_warns_once_and_strict_refuses(tmp_path: Path, flag: str) -> None:
    make, text = CASES[flag]
    log = _log(tmp_path / "log.mcap", make())
    out = tmp_path / "c.parquet"
    args = ["characterize", str(log), "-o", str(out), *ARGS.get(flag, [])]
    res = runner.invoke(app, args)
    if flag == "negative_stiffness":  # always an error, unless --allow-flagged
        line = _one_error(res, EXIT_DATAERR)
        assert f"error: {log}: object 'bad': {text}" in line
        assert "pass --allow-flagged" in line
        assert not out.exists()
        res = runner.invoke(app, [*args, "--allow-flagged"])
    assert res.exit_code == 0, res.stderr
    warnings = [ln for ln in res.stderr.splitlines() if ln.startswith("warning: ")]
    assert len(warnings) == 1, res.stderr
    assert warnings[0].startswith(f"warning: {log}: object 'bad': ")
    assert text in warnings[0], warnings[0]  # the flag and its number
    df = read_table(out, "coefficients").set_index("object_id")
    assert df.loc["good", "quality"] == "ok", df.loc["good", "quality"]
    assert flag in df.loc["bad", "quality"].split(",")
    assert df.attrs["schema_version"] == 3
    # the summary shows the quality column too
    assert "quality" in res.stdout.splitlines()[0].split()
    out.unlink()
    line = _one_error(runner.invoke(app, [*args, "--strict"]), EXIT_DATAERR)
    assert line.startswith(f"error: {log}: --strict: object 'bad' is flagged: ")
    assert text in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["log.mcap"]  # nothing written


def test_unidentifiable_damping_is_nan_in_the_table(tmp_path: Path) -> None:
    log = _log(tmp_path / "log.mcap", CASES["damping_unidentifiable"][0]())
    out = tmp_path / "c.parquet"
    assert runner.invoke(app, ["characterize", str(log), "-o", str(out)]).exit_code == 0
    row = read_table(out, "coefficients").set_index("object_id").loc["bad"]
    assert np.isnan(row["damping_ns_per_cm"])
    assert np.isnan(row["damping_se_ns_per_cm"])
    assert row["damping_excitation"] < 0.05


def test_constrain_damping_is_deprecated_and_changes_nothing(tmp_path: Path) -> None:
    # kept for old scripts: the lsq fits are always bounded, with or without it
    log = _log(tmp_path / "log.mcap", _negative_damping())
    out, plain = tmp_path / "c.parquet", tmp_path / "plain.parquet"
    res = runner.invoke(app, ["characterize", str(log), "-o", str(out), "--constrain-damping"])
    assert res.exit_code == 0, res.stderr
    notices = [line for line in res.stderr.splitlines() if "deprecated" in line]
    assert notices == [
        "deformctl: 'characterize --constrain-damping' is deprecated and has no effect: the lsq "
        "fits always bound λ >= 0"
    ]
    assert runner.invoke(app, ["characterize", str(log), "-o", str(plain)]).exit_code == 0
    columns = ["deformability_n_per_cm", "damping_ns_per_cm", "damping_bound_active", "quality"]
    same = read_table(plain, "coefficients")[columns]
    assert read_table(out, "coefficients")[columns].equals(same)
    help_text = runner.invoke(app, ["characterize", "--help"]).stdout
    options = [line.split()[0] for line in help_text.splitlines() if line.startswith("  -")]
    assert "--constrain-damping" not in options  # the help promises nothing it does not do
    df = read_table(out, "coefficients").set_index("object_id")
    assert df.loc["bad", "damping_ns_per_cm"] == 0.0
    assert bool(df.loc["bad", "damping_bound_active"])
    assert df.loc["bad", "quality"] == "at_bound"
    assert not bool(df.loc["good", "damping_bound_active"])
    assert df.loc["good", "quality"] == "ok"
    assert "at_bound (damping_ns_per_m of the kv law at its bound)" in res.stderr
    assert "constrain_damping" not in df.attrs["provenance"].settings  # a no-op is no setting


def test_preload_option_and_default(tmp_path: Path) -> None:
    squeezes = [
        position_controlled(20.0, 3.0, preload_n=0.5, seed=i, index=i, object_id="rig")
        for i in range(2)
    ]
    log = tmp_path / "log.mcap"
    # a rig recording (measure --csv/--bag stores its source) is fitted with a preload
    write_squeeze_log(
        log, [{"object_id": "rig", "weight_n": 1.0, "source": "csv"}], squeezes, provenance=None
    )
    out = tmp_path / "c.parquet"
    assert runner.invoke(app, ["characterize", str(log), "-o", str(out)]).exit_code == 0
    row = read_table(out, "coefficients").iloc[0]
    assert row["preload_n"] == pytest.approx(0.5, abs=0.02)
    assert row["deformability_n_per_cm"] == pytest.approx(20.0, rel=0.01)
    assert read_table(out, "coefficients").attrs["provenance"].settings["preload"] == {"rig": "fit"}
    res = runner.invoke(
        app, ["characterize", str(log), "-o", str(out), "--force", "--preload", "zero"]
    )
    assert res.exit_code == 0
    row = read_table(out, "coefficients").iloc[0]
    assert np.isnan(row["preload_n"])
    assert row["deformability_n_per_cm"] > 21.0  # the preload leaks into D


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        (["--preload", "auto"], "--preload must be fit or zero, got 'auto'"),
        (["--strict", "--allow-flagged"], "give --strict or --allow-flagged, not both"),
        (["--method", "paper", "--preload", "fit"], "the paper estimator has no preload"),
    ],
)
def test_bad_option_combinations(tmp_path: Path, extra: list[str], match: str) -> None:
    log = _log(tmp_path / "log.mcap", CASES["low_r2"][0]())
    out = tmp_path / "c.parquet"
    line = _one_error(
        runner.invoke(app, ["characterize", str(log), "-o", str(out), *extra]), EXIT_USAGE
    )
    assert match in line
    assert not out.exists()


def test_coefficients_v1_files_are_still_read(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A table written before the diagnostics (schema v1: nine columns) reads, inspects and
    joins as before; it has no quality column, and the policy does not judge it."""
    v1 = pd.DataFrame(
        {
            "object_id": ["A"],
            "deformability_n_per_cm": [49.2],
            "damping_ns_per_cm": [6.5],
            "method": ["lsq"],
            "deformability_se_n_per_cm": [0.02],
            "damping_se_ns_per_cm": [0.01],
            "r2": [0.999],
            "n_samples": [3000],
            "n_squeezes": [3],
        }
    )
    original = tables_module.table_metadata
    monkeypatch.setattr(
        tables_module,
        "table_metadata",
        lambda kind, prov: {**original(kind, prov), "schema_version": 1},
    )
    path = tmp_path / "old.parquet"
    write_table(v1, path, "coefficients", provenance=None)
    monkeypatch.undo()
    df = read_table(path, "coefficients")
    assert df.attrs["schema_version"] == 1
    assert "quality" not in df.columns
    info = json.loads(runner.invoke(app, ["inspect", str(path), "--json"]).stdout)
    assert info["schema"]["version"] == 1
    assert info["coefficients"] == [
        {
            "object_id": "A",
            "deformability_n_per_cm": 49.2,
            "damping_ns_per_cm": 6.5,
            "r2": 0.999,
            "quality": None,
        }
    ]
    lift = pd.DataFrame(
        {
            "object_id": ["A"],
            "weight_n": [0.7],
            "friction_mu": [0.5],
            "lift_force_n": [0.84],
            "converged": [True],
        }
    )
    assert build_index_table(df, lift)["damping_ns_per_cm"].tolist() == [6.5]


def test_sweep_writes_flagged_rows_warns_and_strict_fails_them(tmp_path: Path) -> None:
    logs = tmp_path / "squeeze"
    logs.mkdir()
    _log(logs / "part-00000.mcap", _negative_damping())
    out = tmp_path / "coef"
    res = runner.invoke(app, ["characterize", str(logs), "-o", f"{out}/", "--workers", "1"])
    assert res.exit_code == 0, res.stderr
    warnings = [ln for ln in res.stderr.splitlines() if ln.startswith("warning: ")]
    assert len(warnings) == 1
    assert "object 'bad': at_bound (" in warnings[0]
    df = read_dataset(out).set_index("object_id")
    assert df.loc["bad", "quality"] == "at_bound"
    strict = tmp_path / "strict"
    res = runner.invoke(
        app, ["characterize", str(logs), "-o", f"{strict}/", "--workers", "1", "--strict"]
    )
    assert res.exit_code == 1  # a sweep records the refused object as failed and goes on
    assert list(read_dataset(strict)["object_id"]) == ["good"]
    (failure,) = read_failures(strict).to_dict("records")
    assert "--strict: object 'bad' is flagged: at_bound" in str(failure)
