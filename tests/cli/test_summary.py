"""Progress and the summary line: a bar with done/total, elapsed and ETA on a
terminal only; one summary line at the end of ``measure --sim`` and ``lift`` (objects done,
flagged, failed, wall time, output), dropped by ``--quiet``."""

from __future__ import annotations

import io
import re
from pathlib import Path
from types import SimpleNamespace

import pandas as pd
from rich.console import Console
from typer.testing import CliRunner

from deformctl.cli import app
from deformctl.cli._common import progress_bar
from deformctl.cli._lift_start import run_counts
from deformctl.cli._summary import RunClock

REPO = Path(__file__).resolve().parents[2]
PAPER = str(REPO / "datasets" / "paper" / "objects.csv")
FAST_LIFT = ["--objects", "A,B", "--alpha-cm", "10", "--dt-s", "0.002", "--lift-hold-s", "0.05",
             "--lift-height-m", "0.01", "--protocol", "paper", "--sim-preset", "table"]  # fmt: skip
FAST_SQUEEZE = ["--objects", "A,B", "--squeezes", "1", "--ramp-s", "0.05", "--hold-s", "0.05",
                "--dt-s", "0.002", "--alpha-cm", "10"]  # fmt: skip
LINE = re.compile(
    r"^(?P<cmd>\w+): (?P<done>\d+) object\(s\) done, (?P<flagged>\d+) flagged, "
    r"(?P<failed>\d+) failed in (?P<wall>\d+\.\d) s -> (?P<out>[^ ]+(, [^ ]+)?)( \(.*\))?$"
)
runner = CliRunner()


def test_the_bar_shows_done_total_elapsed_and_eta_on_a_terminal_only() -> None:
    out = io.StringIO()
    console = Console(file=out, force_terminal=True, width=120)
    with progress_bar(console, "lift") as advance:
        assert advance is not None
        for done in range(1, 4):
            advance("A", done, 4)
    text = out.getvalue()
    assert "3/4" in text
    assert "ETA" in text
    quiet = io.StringIO()
    with progress_bar(Console(file=quiet, force_terminal=False), "lift") as advance:
        assert advance is None  # not a terminal: no bar, nothing written
    assert quiet.getvalue() == ""


def test_the_line_says_what_was_done() -> None:
    line = RunClock("lift").line(done=3, flagged=1, failed=1, output="lift.parquet", detail="x")
    m = LINE.match(line)
    assert m is not None, line
    assert (m["cmd"], m["done"], m["flagged"], m["failed"]) == ("lift", "3", "1", "1")


def test_lift_counts_flagged_and_failed_objects() -> None:
    table = pd.DataFrame(
        {"object_id": list("ABCD"), "start_in_training_range": [True, False, None, False]}
    )
    run = SimpleNamespace(table=table, failures=("D",), not_run=())
    assert run_counts(run) == (3, 2, 1)  # type: ignore[arg-type]
    clean = SimpleNamespace(table=table.drop(columns="start_in_training_range"), failures=(),
                            not_run=())  # fmt: skip
    assert run_counts(clean) == (4, 0, 0)  # type: ignore[arg-type]


def _summary(stderr: str) -> re.Match[str]:
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr  # not a terminal: no bar, only the summary line
    m = LINE.match(lines[0])
    assert m is not None, lines[0]
    return m


def test_measure_and_lift_end_with_one_line_and_quiet_drops_it(tmp_path: Path) -> None:
    log = tmp_path / "squeeze.mcap"
    base = ["measure", "sim", PAPER, *FAST_SQUEEZE, "-o", str(log)]
    result = runner.invoke(app, base)
    assert result.exit_code == 0, result.stderr
    m = _summary(result.stderr)
    assert (m["cmd"], m["done"], m["flagged"], m["failed"]) == ("measure", "2", "0", "0")
    assert m["out"] == str(log)
    quiet = runner.invoke(app, [*base, "--force", "--quiet"])
    assert quiet.exit_code == 0
    assert quiet.stderr == ""
    out, lift_log = tmp_path / "lift.parquet", tmp_path / "lift.mcap"
    base = ["lift", "sim", PAPER, *FAST_LIFT, "--scene-hz", "0", "-o", str(out)]
    base += ["--log", str(lift_log)]
    result = runner.invoke(app, base)
    assert result.exit_code == 0, result.stderr
    m = _summary(result.stderr)
    assert (m["cmd"], m["done"], m["flagged"], m["failed"]) == ("lift", "2", "0", "0")
    assert m["out"] == f"{out}, {lift_log}"
    quiet = runner.invoke(app, [*base, "--force", "-q"])
    assert quiet.exit_code == 0
    assert quiet.stderr == ""
    assert quiet.stdout == result.stdout  # the per-object lines stay


def test_quiet_is_an_option_of_measure_csv_too(tmp_path: Path) -> None:
    csv = REPO / "datasets" / "examples" / "phantom" / "EF10_0T_A1.csv"
    out = tmp_path / "x.mcap"
    args = ["measure", "csv", str(csv), "--weight-n", "0.62", "-o", str(out)]
    result = runner.invoke(app, [*args, "--quiet"])
    assert result.exit_code == 0, result.stderr
    assert str(out) not in result.stderr  # no summary line naming the log
    assert out.stat().st_size > 0


def test_characterize_counts_its_flagged_objects(tmp_path: Path) -> None:
    # force noise of 0.7 N flags B's fit (low R², its force rises about 1.5 N; A's rises more);
    # the clean squeezes flag none
    for noise, flagged in (("0", "0"), ("0.7", "1")):
        log, out = tmp_path / f"sq{noise}.mcap", tmp_path / f"c{noise}.parquet"
        args = ["measure", "sim", PAPER, "--objects", "A,B", "--squeezes", "2", "--dt-s",
                "0.002", "--alpha-cm", "10", "--noise-force-n", noise, "--seed", "1", "-q",
                "-o", str(log)]  # fmt: skip
        assert runner.invoke(app, args).exit_code == 0
        result = runner.invoke(app, ["characterize", str(log), "-o", str(out)])
        assert result.exit_code == 0, result.stderr
        lines = result.stderr.strip().splitlines()
        warnings = [line for line in lines if line.startswith("warning: ")]
        assert len(warnings) == int(flagged)
        m = LINE.match(lines[-1])
        assert m is not None, lines[-1]
        assert (m["cmd"], m["done"], m["flagged"], m["failed"]) == (
            "characterize",
            "2",
            flagged,
            "0",
        )
        quiet = runner.invoke(app, ["characterize", str(log), "-o", str(out), "--force", "-q"])
        assert quiet.exit_code == 0
        assert quiet.stderr.strip().splitlines() == warnings  # warnings stay, the line goes


def test_train_counts_the_flagged_rows_it_learns_from(tmp_path: Path) -> None:
    # an index table kept with `table --allow-flagged` / `--allow-unconverged` carries rows whose
    # coefficients or search are doubtful: train's line counts them; a clean table flags none
    from deformctl.artifacts import Provenance, write_table
    from deformctl.repro.synthetic import synthetic_index_table

    clean = synthetic_index_table(n=12)
    clean["quality"] = "ok"
    doubtful = clean.copy()
    doubtful.loc[3, "quality"] = "low_r2"
    doubtful.loc[7, "converged"] = False
    for table, flagged in ((clean, "0"), (doubtful, "2")):
        index, model = tmp_path / f"index{flagged}.parquet", tmp_path / f"m{flagged}.skops"
        write_table(table, index, "index_table", provenance=Provenance.from_invocation(argv=["t"]))
        args = ["train", str(index), "-o", str(model), "--train-size", "8"]
        result = runner.invoke(app, args)
        assert result.exit_code == 0, result.stderr
        m = LINE.match(result.stderr.strip().splitlines()[-1])
        assert m is not None, result.stderr
        assert (m["cmd"], m["done"], m["flagged"], m["failed"], m["out"]) == (
            "train",
            "12",
            flagged,
            "0",
            str(model),
        )
    quiet = runner.invoke(app, [*args, "--force", "--quiet"])  # the doubtful table again
    assert quiet.exit_code == 0, quiet.stderr
    assert "object(s) done" not in quiet.stderr
