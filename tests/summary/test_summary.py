"""deformctl.summary.RunClock: the one line a long run ends with, exactly, and ``quiet``."""

from __future__ import annotations

import logging
import time
from types import SimpleNamespace

import pytest

from deformctl.summary import RunClock


def test_the_line_names_counts_wall_time_output_and_detail() -> None:
    clock = RunClock("lift", started_s=time.monotonic() - 12.34)
    line = clock.line(done=4, flagged=1, failed=0, output="lift.parquet", detail="2 skipped")
    assert (
        line == "lift: 4 object(s) done, 1 flagged, 0 failed in 12.3 s -> lift.parquet (2 skipped)"
    )
    plain = RunClock("train").line(done=73, flagged=0, failed=0, output="m.skops")
    assert plain == "train: 73 object(s) done, 0 flagged, 0 failed in 0.0 s -> m.skops"


def test_the_workers_auto_choice_made_during_the_run_is_told_once() -> None:
    clock = RunClock("measure")
    choice = SimpleNamespace(note=lambda: "--workers auto: 2 (load 0.5)")
    log = logging.getLogger("deformctl.parallel")
    log.info("chose", extra={"worker_choice": choice})
    log.info("no choice here")
    line = clock.line(done=2, flagged=0, failed=0, output="s.mcap", detail="d")
    assert line.endswith("-> s.mcap (d; --workers auto: 2 (load 0.5))")
    log.info("after the run", extra={"worker_choice": choice})  # the catcher is gone
    assert RunClock("lift").workers_note() == ""


def test_finish_prints_one_line_on_stderr_unless_quiet(capsys: pytest.CaptureFixture[str]) -> None:
    RunClock("characterize").finish(done=3, flagged=0, failed=1, output="c.parquet")
    out, err = capsys.readouterr()
    assert out == ""
    assert err.startswith("characterize: 3 object(s) done, 0 flagged, 1 failed in ")
    assert err.endswith(" s -> c.parquet\n")
    assert err.count("\n") == 1
    RunClock("characterize").finish(done=3, flagged=0, failed=1, output="c.parquet", quiet=True)
    assert capsys.readouterr() == ("", "")
