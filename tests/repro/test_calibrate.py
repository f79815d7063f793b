"""``make calibrate`` (``python -m deformctl.repro.calibrate``) ends with the commands' summary
line: the points done, the points flagged (left out of the fit, the refit
misses them by more than the worst in-sample error; a warning names them), 0 failed, the wall
time and the record written; ``--quiet`` drops the line and keeps the warning.

The calibration itself takes many minutes of simulation; here ``calibrate`` returns the record
that ``make calibrate`` wrote (datasets/calibration/paper.json: three points are flagged in it)
and the same record with its leave-one-out errors shrunk under the in-sample worst (none).
"""

from __future__ import annotations

import copy
import json
import re
from pathlib import Path
from typing import Any

import pytest

from deformctl.repro import calibrate as calibration
from deformctl.resources import dataset_path

LINE = re.compile(
    r"^calibrate: (?P<done>\d+) object\(s\) done, (?P<flagged>\d+) flagged, (?P<failed>\d+) "
    r"failed in \d+\.\d s -> (?P<out>\S+)$"
)


def _recorded() -> dict[str, Any]:
    path = dataset_path("calibration") / "paper.json"
    record: dict[str, Any] = json.loads(Path(path).read_text(encoding="utf-8"))
    return record


def _clean(record: dict[str, Any]) -> dict[str, Any]:
    clean = copy.deepcopy(record)
    for q in clean["leave_one_out"]["points"]:
        q["error"] = q["error"] / 2.0  # within the worst in-sample error 0.12: |LOO| <= 0.09
    return clean


def _main(monkeypatch: pytest.MonkeyPatch, record: dict[str, Any], *args: str) -> int:
    monkeypatch.setattr(calibration, "calibrate", lambda **_: record)
    return calibration.main(list(args))


def test_the_recorded_calibration_flags_the_points_it_leans_on() -> None:
    record = _recorded()
    worst = record["worst_error"]
    flagged = calibration.flagged_points(record)
    expected = [q for q in record["leave_one_out"]["points"] if abs(q["error"]) > worst]
    assert [f.split(" ")[0] for f in flagged] == [q["point"] for q in expected]
    assert flagged == ["sponge (+14.7%)", "cotton (-12.3%)", "water (-17.3%)"]
    assert calibration.flagged_points(_clean(record)) == []


@pytest.mark.parametrize(("clean", "flagged"), [(False, "3"), (True, "0")])
def test_calibrate_ends_with_one_line_and_quiet_drops_it(
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    tmp_path: Path,
    clean: bool,
    flagged: str,
) -> None:
    record = _clean(_recorded()) if clean else _recorded()
    out = tmp_path / "paper.json"
    assert _main(monkeypatch, record, "--write", str(out)) == 0
    captured = capsys.readouterr()
    assert "worst error 12.0%" in captured.out
    lines = captured.err.strip().splitlines()
    warnings = [line for line in lines if line.startswith("warning: ")]
    assert len(warnings) == (0 if clean else 1)
    if not clean:
        assert "sponge (+14.7%), cotton (-12.3%), water (-17.3%)" in warnings[0]
    m = LINE.match(lines[-1])
    assert m is not None, lines[-1]
    assert (m["done"], m["flagged"], m["failed"], m["out"]) == ("13", flagged, "0", str(out))
    assert json.loads(out.read_text(encoding="utf-8")) == record

    assert _main(monkeypatch, record, "--quiet") == 0
    quiet = capsys.readouterr()
    assert quiet.err.strip().splitlines() == warnings  # the warning stays, the line goes
