"""``deformctl characterize``: squeeze log → coefficients table, its options, stdio and errors.

The logs are written here with ``write_squeeze_log`` from exact Kelvin–Voigt responses plus 1 %
force noise and 0.05 mm compression noise (``synthetic_kelvin_voigt_squeeze``), two objects of
the paper's range with two squeezes each. ``lsq`` must give D within 2 % and λ within 5 %; the
paper method's error is printed (its D carries damping by construction, see characterize.py).
"""

from __future__ import annotations

import io
import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from deformctl.artifacts import read_table, write_squeeze_log
from deformctl.cli import app
from deformctl.errors import EXIT_DATAERR, EXIT_FAILURE, EXIT_NOINPUT, EXIT_USAGE
from deformctl.series import SqueezeSeries
from deformctl.testing.kelvin_voigt import synthetic_kelvin_voigt_squeeze

runner = CliRunner()
#: object id → (D N/cm, λ N·s/cm): the paper's sponge and cotton bags (Table II)
TRUTH = {"A": (49.18, 6.47), "B": (13.03, 0.33)}


def _squeezes() -> list[SqueezeSeries]:
    out = []
    for k, (oid, (d, lam)) in enumerate(TRUTH.items()):
        for i in range(2):
            out.append(
                synthetic_kelvin_voigt_squeeze(
                    d,
                    lam,
                    profile="ramp_hold_release" if i == 0 else "sine",
                    duration_s=4.0,
                    seed=10 * k + i,
                    object_id=oid,
                    squeeze_index=i,
                )
            )
    return out


@pytest.fixture(scope="module")
def log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("log") / "squeeze.mcap"
    objects = [{"object_id": oid, "weight_n": 1.0} for oid in TRUTH]
    write_squeeze_log(path, objects, _squeezes(), provenance=None)
    return path


def _fails(args: list[str], code: int, match: str, out: Path, **kw: object) -> str:
    """Run, check the exit code, the one-line message and that nothing was written."""
    before = sorted(out.parent.iterdir())
    res = runner.invoke(app, args, **kw)  # type: ignore[arg-type]
    assert res.exit_code == code, (res.exit_code, res.stderr)
    assert res.stdout == ""
    lines = res.stderr.splitlines()
    assert len(lines) == 1, res.stderr
    assert lines[0].startswith("error: ")
    assert match in lines[0], lines[0]
    assert sorted(out.parent.iterdir()) == before
    return lines[0]


def test_lsq_recovers_every_object(log: Path, tmp_path: Path) -> None:
    out = tmp_path / "coefficients.parquet"
    res = runner.invoke(app, ["characterize", str(log), "-o", str(out)])
    assert res.exit_code == 0, res.stderr
    df = read_table(out, "coefficients")
    assert list(df["object_id"]) == list(TRUTH)  # log order
    for row in df.to_dict("records"):
        d, lam = TRUTH[row["object_id"]]
        assert row["deformability_n_per_cm"] == pytest.approx(d, rel=0.02)
        assert row["damping_ns_per_cm"] == pytest.approx(lam, rel=0.05)
        print(
            f"\nlsq, object {row['object_id']}: D {row['deformability_n_per_cm']:.3f} ({d}), "
            f"λ {row['damping_ns_per_cm']:.4f} ({lam})"
        )
        assert row["n_squeezes"] == 2
        assert row["deformability_se_n_per_cm"] > 0
        assert 0.99 < row["r2"] <= 1.0
    # the summary is on stdout: a header and one line per object, with the window used
    lines = res.stdout.splitlines()
    assert lines[0].split()[:4] == ["object", "model", "D", "(N/cm)"]
    assert [ln.split()[0] for ln in lines[1:]] == list(TRUTH)
    assert all(ln.endswith("0.2") for ln in lines[1:])  # no position rate in the log: default
    prov = df.attrs["provenance"]
    assert prov.settings["method"] == "lsq"
    assert prov.settings["window_s"] == {"A": 0.2, "B": 0.2}
    assert str(log) in prov.inputs


def test_paper_method_and_window_option(log: Path, tmp_path: Path) -> None:
    out = tmp_path / "paper.parquet"
    res = runner.invoke(
        app, ["characterize", str(log), "-o", str(out), "--method", "paper", "--window-s", "0.3"]
    )
    assert res.exit_code == 0, res.stderr
    df = read_table(out, "coefficients")
    assert set(df["method"]) == {"paper"}
    assert df.attrs["provenance"].settings["window_s"] == {"A": 0.3, "B": 0.3}
    for row in df.to_dict("records"):
        d, lam = TRUTH[row["object_id"]]
        err_d = row["deformability_n_per_cm"] / d - 1
        err_l = row["damping_ns_per_cm"] / lam - 1
        print(f"\npaper method, object {row['object_id']}: D error {err_d:+.1%}, λ {err_l:+.1%}")
        # looser than lsq: f/d mixes λ d'/d into D wherever the object is still moving
        assert abs(err_d) < 0.05
        assert abs(err_l) < 0.10


def test_stdin_to_stdout(log: Path, tmp_path: Path) -> None:
    res = runner.invoke(app, ["characterize", "-", "-o", "-"], input=log.read_bytes())
    assert res.exit_code == 0, res.stderr
    assert res.stdout_bytes[:4] == b"PAR1"
    table = pq.read_table(io.BytesIO(res.stdout_bytes))
    assert table.column("object_id").to_pylist() == list(TRUTH)
    # the summary moved to stderr so stdout stays the table
    assert res.stderr.splitlines()[0].startswith("object")
    meta = json.loads(table.schema.metadata[b"deformctl"])
    assert meta["provenance"]["inputs"] == {"<stdin>": "stdin"}


def test_console_script_pipes(log: Path, tmp_path: Path) -> None:
    exe = shutil.which("deformctl", path=str(Path(sys.executable).parent))
    assert exe is not None
    with log.open("rb") as stdin:
        proc = subprocess.run(
            [exe, "characterize", "-", "-o", "-"], stdin=stdin, capture_output=True, check=False
        )
    assert proc.returncode == 0, proc.stderr
    table = pq.read_table(io.BytesIO(proc.stdout))
    assert table.num_rows == len(TRUTH)
    meta = json.loads(table.schema.metadata[b"deformctl"])
    assert meta["provenance"]["command_line"] == ["deformctl", "characterize", "-", "-o", "-"]


def test_no_compression(tmp_path: Path) -> None:
    path = tmp_path / "in.mcap"
    t = np.arange(0.0, 2.0, 1e-3)
    flat = SqueezeSeries("X", 0, t, 5.0 + 0.0 * t, 0.0 * t)  # the palms never moved
    write_squeeze_log(path, [{"object_id": "X", "weight_n": 1.0}], [flat], provenance=None)
    out = tmp_path / "c.parquet"
    msg = _fails(["characterize", str(path), "-o", str(out)], EXIT_DATAERR, "squeeze 'X' #0", out)
    assert msg.startswith(f"error: {path}: ")
    assert "no compression (peak compression 0 m" in msg


@pytest.mark.parametrize(
    ("extra", "code", "match"),
    [
        (["--method", "ols"], EXIT_USAGE, "--method must be lsq or paper, got 'ols'"),
        (["--window-s", "0"], EXIT_USAGE, "--window-s must be a finite number > 0 s, got 0"),
    ],
    ids=["method", "window"],
)
def test_bad_options(log: Path, tmp_path: Path, extra: list[str], code: int, match: str) -> None:
    out = tmp_path / "c.parquet"
    _fails(["characterize", str(log), "-o", str(out), *extra], code, match, out)


def test_not_a_squeeze_log_and_damaged(log: Path, tmp_path: Path) -> None:
    coef = tmp_path / "in" / "c.parquet"
    coef.parent.mkdir()
    assert runner.invoke(app, ["characterize", str(log), "-o", str(coef)]).exit_code == 0
    out = tmp_path / "o.parquet"
    _fails(["characterize", str(coef), "-o", str(out)], EXIT_DATAERR, "not an MCAP file", out)
    cut = tmp_path / "in" / "cut.mcap"
    cut.write_bytes(log.read_bytes()[:-100])
    _fails(["characterize", str(cut), "-o", str(out)], EXIT_DATAERR, "truncated or damaged", out)


def test_existing_output_and_missing_input(log: Path, tmp_path: Path) -> None:
    out = tmp_path / "c.parquet"
    out.write_bytes(b"old")
    _fails(["characterize", str(log), "-o", str(out)], EXIT_FAILURE, "exists already", out)
    assert out.read_bytes() == b"old"
    missing = tmp_path / "missing.mcap"
    _fails(
        ["characterize", str(missing), "-o", str(tmp_path / "x.parquet")],
        EXIT_NOINPUT,
        f"{missing}: no such file",
        out,
    )
    res = runner.invoke(app, ["characterize", str(log), "-o", str(out), "--force"])
    assert res.exit_code == 0, res.stderr
    assert len(read_table(out, "coefficients")) == len(TRUTH)


def test_every_command_help_ends_with_an_example() -> None:
    for command in ("measure", "characterize"):
        res = runner.invoke(app, [command, "--help"])
        assert res.exit_code == 0
        body = res.stdout.split("Options:")[0].rstrip().splitlines()
        example = [i for i, ln in enumerate(body) if "Example:" in ln]
        assert example, res.stdout
        assert f"deformctl {command} " in "\n".join(body[example[-1] :])
