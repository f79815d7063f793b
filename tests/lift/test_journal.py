"""No lost attempts. A rig run keeps its log and table on disk as it goes.

Two ways a run ends early, each checked against what the rig itself saw (its request log):

* ``kill -9`` of ``deformctl lift`` while the rig is in the middle of an attempt
  (``tests/rigs/stall_rig.py`` stalls at one attempt): every answered attempt is in the log, the
  finished object's row is final, the object under way is ``incomplete``, the rest ``not run``;
* a value refused after attempts were made (a row the lift_results spec refuses): exit 65 with
  one line that says what was kept, and the same files on disk.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import shlex
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

from deformctl.artifacts import read_lift_log, read_table
from deformctl.errors import SchemaError
from deformctl.lift.journal import NOT_RUN_YET
from deformctl.lift.runners.rig import rig_runner_factory
from deformctl.lift.search import LiftSearchResult
from deformctl.lift.stage import lift_catalog_files

REPO = Path(__file__).resolve().parents[2]
RIGS = REPO / "tests" / "rigs"
THRESHOLD_N = 17.0
# F_w = W / (2 mu): sponge 10 N, brick 16 N, anvil 40 N (as tests/cli/test_lift.py)
CATALOG = (
    "object_id,size_x_cm,size_y_cm,size_z_cm,weight_n,friction_mu\n"
    "sponge,8,5,4,10,0.5\nbrick,6,6,6,16,0.5\nanvil,5,5,5,40,0.5\n"
)


def _requests(path: Path) -> list[dict[str, object]]:
    if not path.exists():
        return []
    return [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines()]


def _attempts_match_requests(log: Path, requests: list[dict[str, object]]) -> None:
    """Every request the rig answered is in the log, in order, with its force; nothing else."""
    _, attempts = read_lift_log(log)
    got = [(a.object_id, a.attempt_index, a.outcome.grip_force_n) for a in attempts]
    want = [(r["object_id"], r["attempt_index"], r["grip_force_n"]) for r in requests]
    assert got == want
    for a in attempts:
        assert a.outcome.lifted is (a.outcome.grip_force_n >= THRESHOLD_N)


@pytest.mark.e2e
def test_kill_mid_search_keeps_every_attempt(tmp_path: Path) -> None:
    catalog = tmp_path / "objects.csv"
    catalog.write_text(CATALOG, encoding="utf-8")
    out, log, requests = tmp_path / "lift.parquet", tmp_path / "lift.mcap", tmp_path / "req.jsonl"
    stall = Path(f"{requests}.stalled")
    rig = shlex.join([sys.executable, str(RIGS / "stall_rig.py"), str(THRESHOLD_N),
                      str(requests), "brick", "3"])  # fmt: skip
    cmd = [sys.executable, "-m", "deformctl", "lift", "rig", str(catalog), "--command", rig,
           "-o", str(out), "--log", str(log)]  # fmt: skip
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 120
        while not stall.exists() or not stall.read_text():
            assert proc.poll() is None, proc.stderr.read() if proc.stderr else ""
            assert time.monotonic() < deadline, "the rig never stalled"
            time.sleep(0.05)
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        if stall.exists() and stall.read_text():
            with contextlib.suppress(ProcessLookupError):
                os.kill(int(stall.read_text()), signal.SIGKILL)  # the stalled rig (ours)
        if proc.stderr is not None:
            proc.stderr.close()
    answered = _requests(requests)
    # sponge's whole search (10 attempts), then brick's attempts 0-2 before the stall at 3
    assert [r["object_id"] for r in answered].count("brick") == 3
    _attempts_match_requests(log, answered)
    table = read_table(out, "lift_results")
    assert list(table["object_id"]) == ["sponge", "brick", "anvil"]
    sponge, brick, anvil = (table.iloc[i] for i in range(3))
    assert sponge["converged"]
    assert sponge["error"] is None
    assert sponge["attempts"] == sum(r["object_id"] == "sponge" for r in answered)
    assert THRESHOLD_N <= sponge["lift_force_n"] <= THRESHOLD_N / (1 - 0.005)
    assert not brick["converged"]
    assert math.isnan(brick["lift_force_n"])
    assert brick["attempts"] == 3
    assert brick["error"] == (
        "incomplete: the run ended during this object's search after 3 attempts "
        "(every one is in the lift log)"
    )
    assert anvil["attempts"] == 0
    assert anvil["error"] == NOT_RUN_YET


def test_a_refused_value_after_attempts_keeps_them(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    catalog = tmp_path / "objects.csv"
    catalog.write_text(CATALOG, encoding="utf-8")
    out, log, requests = tmp_path / "lift.parquet", tmp_path / "lift.mcap", tmp_path / "req.jsonl"
    rig = [sys.executable, str(RIGS / "threshold_rig.py"), str(THRESHOLD_N), str(requests)]
    table_row = LiftSearchResult.table_row

    def refused_for_brick(self: LiftSearchResult, **kwargs: Any) -> dict[str, object]:
        row = table_row(self, **kwargs)
        if self.object_id == "brick":  # a recorded value the lift_results spec refuses
            row["lift_force_n"] = -1.0
        return row

    monkeypatch.setattr(LiftSearchResult, "table_row", refused_for_brick)
    with pytest.raises(SchemaError) as info:
        lift_catalog_files(str(catalog), rig_runner_factory(rig, timeout_s=60), output=str(out),
                           log=str(log))  # fmt: skip
    answered = _requests(requests)
    n = len(answered)
    assert str(info.value) == (
        f"{catalog}: field 'lift_force_n': object 'brick': must be >= 0, got -1.0 "
        f"(kept: {n} attempts in {log}, 1 finished object in {out})"
    )
    assert info.value.exit_code == 65
    assert {r["object_id"] for r in answered} == {"sponge", "brick"}
    _attempts_match_requests(log, answered)
    table = read_table(out, "lift_results")
    assert list(table["converged"]) == [True, False, False]
    assert table["attempts"].iloc[1] == sum(r["object_id"] == "brick" for r in answered)
    assert table["error"].iloc[1].startswith("incomplete: ")
    assert table["error"].iloc[2] == NOT_RUN_YET
