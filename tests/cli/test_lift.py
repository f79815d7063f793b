"""``deformctl lift --rig``: rows, logs, failures, bad inputs; scripted rigs from tests/rigs.

Expected forces are worked out by hand from the protocol (F_w = W / (2 mu), ramp F_w * 1.2**k,
bisection to 1 %) against the rigs' threshold, not taken from the search code.
"""

from __future__ import annotations

import json
import math
import re
import shlex
import sys
import time
from collections.abc import Mapping
from functools import partial
from pathlib import Path
from typing import Any

import pytest
from rich.console import Console
from typer.testing import CliRunner

from deformctl.artifacts import read_catalog, read_lift_log, read_table, validate_message
from deformctl.artifacts.schema import fast_check, json_validator
from deformctl.catalog import select_objects
from deformctl.cli import app
from deformctl.errors import SchemaError, SimulationError
from deformctl.lift.runners.rig import parse_rig_response
from deformctl.lift.search import DEFAULT_TOLERANCE_REL, TrialRunner
from deformctl.lift.stage import RunnerFactory, lift_catalog
from deformctl.series import TrialOutcome
from tests._helpers.lift import HEADER, THRESHOLD_N, listing, one_line_error, rig, run

cli = CliRunner()
REPO = Path(__file__).resolve().parents[2]
RIGS = REPO / "tests" / "rigs"
# F_w = W / (2 mu): sponge 10 N (ramp 10, 12, 14.4, 17.28), brick 16 N (16, 19.2), anvil 40 N.
CATALOG = HEADER + "sponge,8,5,4,10,0.5\nbrick,6,6,6,16,0.5\nanvil,5,5,5,40,0.5\n"
F_W_N = {"sponge": 10.0, "brick": 16.0, "anvil": 40.0}
PAPER_L_F_N = {"sponge": 17.28, "brick": 19.2, "anvil": 40.0}  # first ramp force >= 17 N
PAPER_ATTEMPTS = {"sponge": 4, "brick": 2, "anvil": 1}
PAPER_LOW_N = {"sponge": 14.4, "brick": 16.0, "anvil": 40.0}


@pytest.fixture
def catalog(tmp_path: Path) -> Path:
    path = tmp_path / "objects.csv"
    path.write_text(CATALOG, encoding="utf-8")
    return path


# ------------------------------------------------------------------------ well-behaved rig


def test_refine_rows_and_log_match_the_threshold(catalog: Path, tmp_path: Path) -> None:
    out, log, requests = tmp_path / "lift.parquet", tmp_path / "lift.mcap", tmp_path / "req.jsonl"
    result = run("rig", catalog, "--command", rig("threshold_rig.py", THRESHOLD_N, requests),
                 "-o", out, "--log", log)  # fmt: skip
    assert result.exit_code == 0, result.stderr
    # no progress bar when stderr is not a terminal: only the summary line
    assert result.stderr.startswith("lift: 3 object(s) done, 0 flagged, 0 failed in ")
    assert len(result.stderr.splitlines()) == 1
    assert len(result.stdout.splitlines()) == 3
    table = read_table(out, "lift_results")
    assert list(table["object_id"]) == ["sponge", "brick", "anvil"]
    assert table["converged"].all()
    assert set(table["runner"]) == {"rig"}
    assert set(table["slip_criterion"]) == {"rig"}
    assert table["error"].isna().all()
    assert (table["tolerance_rel"] == DEFAULT_TOLERANCE_REL).all()
    for row in table.itertuples():
        f_w = F_W_N[row.object_id]
        assert row.f_w_n == pytest.approx(f_w, rel=1e-12)
        assert row.f_d_n == pytest.approx(row.lift_force_n - f_w, rel=1e-12)
        if f_w >= THRESHOLD_N:  # F_w itself lifts: one attempt, L_f = F_w, bracket (F_w, F_w)
            assert (row.lift_force_n, row.attempts) == (f_w, 1)
            assert row.bracket_low_n == row.bracket_high_n == f_w
            continue
        # the threshold lies in the bracket, the bracket meets the 0.5 % default, L_f is its top
        assert row.bracket_low_n < THRESHOLD_N <= row.bracket_high_n == row.lift_force_n
        width = (row.bracket_high_n - row.bracket_low_n) / row.bracket_high_n
        assert width <= DEFAULT_TOLERANCE_REL
        # refine's answer lies inside the paper protocol's last bracket
        assert PAPER_LOW_N[row.object_id] < row.lift_force_n <= PAPER_L_F_N[row.object_id]

    objects, attempts = read_lift_log(log)
    assert [o["object_id"] for o in objects] == ["sponge", "brick", "anvil"]
    assert len(attempts) == table["attempts"].sum()
    for oid, n in zip(table["object_id"], table["attempts"], strict=True):
        mine = [a for a in attempts if a.object_id == oid]
        assert [a.attempt_index for a in mine] == list(range(n))
    for a in attempts:
        lifted = a.outcome.grip_force_n >= THRESHOLD_N
        assert a.outcome.lifted is lifted
        assert a.outcome.slip_m == (0.0 if lifted else 0.05)
        assert a.outcome.details["message"] == "stand-in rig"
        assert a.outcome.series is None  # a rig that records no time series
    sponge = [a.outcome.grip_force_n for a in attempts if a.object_id == "sponge"]
    assert sponge[:4] == pytest.approx([10.0, 12.0, 14.4, 17.28])  # the paper ramp first
    assert sponge[4] == pytest.approx((14.4 + 17.28) / 2)  # then bisection

    # What crossed the rig boundary matches schemas/rig_request.schema.json.
    sent = [json.loads(line) for line in requests.read_text().splitlines()]
    assert len(sent) == len(attempts)
    for request in sent:
        validate_message("rig_request", request)
    assert sent[0] == {
        "object_id": "sponge",
        "attempt_index": 0,
        "grip_force_n": 10.0,
        "weight_n": 10.0,
        "friction_mu": 0.5,
        "size_cm": [8.0, 5.0, 4.0],
        "max_force_n": 100.0,  # the default ceiling, 10 x F_w
    }
    assert all(r["grip_force_n"] <= r["max_force_n"] for r in sent)

    info = json.loads(cli.invoke(app, ["inspect", str(out), "--json"]).stdout)
    assert (info["kind"], info["rows"]) == ("lift_results", 3)
    assert info["provenance"]["settings"]["runner"] == "rig"
    info = json.loads(cli.invoke(app, ["inspect", str(log), "--json"]).stdout)
    assert info["kind"] == "lift_log"
    assert info["attempts"] == len(attempts)
    assert info["lifted"] == sum(a.outcome.lifted for a in attempts)


def test_paper_protocol_through_the_cli(catalog: Path, tmp_path: Path) -> None:
    out, log = tmp_path / "lift.parquet", tmp_path / "lift.mcap"
    result = run("rig", catalog, "--command", rig("threshold_rig.py", THRESHOLD_N), "--protocol",
                 "paper", "-o", out, "--log", log, "--objects", "anvil,sponge")  # fmt: skip
    assert result.exit_code == 0, result.stderr
    table = read_table(out, "lift_results").set_index("object_id")
    assert list(table.index) == ["anvil", "sponge"]  # the --objects order
    for oid in table.index:
        assert table.loc[oid, "lift_force_n"] == pytest.approx(PAPER_L_F_N[oid], rel=1e-12)
        assert table.loc[oid, "attempts"] == PAPER_ATTEMPTS[oid]
        assert table.loc[oid, "bracket_low_n"] == pytest.approx(PAPER_LOW_N[oid], rel=1e-12)
    assert (table["protocol"] == "paper").all()
    assert table["tolerance_rel"].isna().all()  # paper does not use a tolerance
    assert len(read_lift_log(log)[1]) == 5


def test_progress_bar_draws_on_a_terminal(
    catalog: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import deformctl.cli.lift as lift_cli

    terminal = partial(Console, stderr=True, force_terminal=True)
    monkeypatch.setattr(lift_cli, "stderr_console", terminal)
    result = run(
        "rig", catalog, "--command", rig("threshold_rig.py", 1.0), "-o", tmp_path / "o.parquet"
    )
    assert result.exit_code == 0, result.stderr
    assert "3/3" in result.stderr  # the bar reached the last object, on stderr
    assert "3/3" not in result.stdout


def test_force_overwrites(catalog: Path, tmp_path: Path) -> None:
    out = tmp_path / "lift.parquet"
    args = [
        "rig",
        catalog,
        "--command",
        rig("threshold_rig.py", 1.0),
        "-o",
        out,
        "--objects",
        "anvil",
    ]
    assert run(*args).exit_code == 0
    assert run(*args, "--force").exit_code == 0
    assert len(read_table(out, "lift_results")) == 1


# ---------------------------------------------------------------------------- failures


def test_rig_crash_keeps_attempts_and_stops_the_run(catalog: Path, tmp_path: Path) -> None:
    out, log = tmp_path / "lift.parquet", tmp_path / "lift.mcap"
    result = run(
        "rig", catalog, "--command", rig("crash_rig.py", THRESHOLD_N), "-o", out, "--log", log
    )
    assert result.exit_code == 1
    assert one_line_error(result) == (
        "error: search aborted, 2 attempts kept: rig: object 'sponge' attempt_index 2 at "
        "14.4 N: exited with status 3: MotorFault: left palm encoder lost (2 later objects not run)"
    )
    table = read_table(out, "lift_results").set_index("object_id")
    assert not table["converged"].any()
    assert table.loc["sponge", "attempts"] == 2
    assert math.isnan(table.loc["sponge", "lift_force_n"])
    assert table.loc["sponge", "bracket_low_n"] == pytest.approx(12.0)
    assert "MotorFault" in table.loc["sponge", "error"]
    for oid in ("brick", "anvil"):
        assert table.loc[oid, "attempts"] == 0
        assert table.loc[oid, "error"].startswith("not run: the run stopped at object 'sponge'")
    _, attempts = read_lift_log(log)
    assert [(a.object_id, a.outcome.grip_force_n) for a in attempts] == [
        ("sponge", 10.0),
        ("sponge", 12.0),
    ]


def test_garbage_mid_search_keeps_attempts(catalog: Path, tmp_path: Path) -> None:
    script = tmp_path / "chatty_rig.py"
    script.write_text(
        "import json, sys\n"
        "q = json.load(sys.stdin)\n"
        "if q['attempt_index'] == 1:\n"
        "    print('motor ok'); print('done'); sys.exit(0)\n"
        "print(json.dumps({'lifted': q['grip_force_n'] >= 17, 'slip_m': 0.0}))\n",
        encoding="utf-8",
    )
    out, log = tmp_path / "lift.parquet", tmp_path / "lift.mcap"
    result = run("rig", catalog, "--command", shlex.join([sys.executable, str(script)]), "-o", out,
                 "--log", log, "--objects", "sponge")  # fmt: skip
    assert result.exit_code == 1
    line = one_line_error(result)
    assert line.startswith(
        "error: search aborted, 1 attempt kept: rig: object 'sponge' attempt_index 1 at 12 N: "
        "answer is not valid JSON"
    )
    assert "motor ok" in line
    assert [a.outcome.grip_force_n for a in read_lift_log(log)[1]] == [10.0]
    assert read_table(out, "lift_results")["attempts"].tolist() == [1]


def test_garbage_rig(catalog: Path, tmp_path: Path) -> None:
    out = tmp_path / "lift.parquet"
    result = run(
        "rig", catalog, "--command", rig("garbage_rig.py"), "-o", out, "--objects", "sponge"
    )
    assert result.exit_code == 1
    assert "attempt_index 0 at 10 N: answer is not valid JSON" in one_line_error(result)
    table = read_table(out, "lift_results")
    assert table["attempts"].tolist() == [0]
    assert not table["converged"].any()


def test_rig_timeout(catalog: Path, tmp_path: Path) -> None:
    out, log = tmp_path / "lift.parquet", tmp_path / "lift.mcap"
    start = time.monotonic()
    result = run("rig", catalog, "--command", rig("sleepy_rig.py", 30), "--rig-timeout", "0.5",
                 "-o", out, "--log", log, "--objects", "sponge")  # fmt: skip
    assert time.monotonic() - start < 15
    assert result.exit_code == 1
    assert one_line_error(result).endswith(
        "rig: object 'sponge' attempt_index 0 at 10 N: no answer within 0.5 s (killed)"
    )
    assert read_lift_log(log)[1] == []
    assert read_table(out, "lift_results")["error"].str.contains("killed").all()


def test_never_lifts_within_max_attempts(catalog: Path, tmp_path: Path) -> None:
    out, log = tmp_path / "lift.parquet", tmp_path / "lift.mcap"
    result = run("rig", catalog, "--command", rig("threshold_rig.py", 1000), "--max-attempts", 3,
                 "-o", out, "--log", log, "--objects", "sponge,brick")  # fmt: skip
    assert result.exit_code == 1
    # The first object that failed is named with its last force; the second still ran.
    assert one_line_error(result) == (
        "error: object 'sponge': did not lift within 3 attempts; last force tried 14.4 N slipped "
        "(F_w = 10 N) (1 more object did not converge)"
    )
    table = read_table(out, "lift_results").set_index("object_id")
    assert table["attempts"].tolist() == [3, 3]
    assert not table["converged"].any()
    assert table["lift_force_n"].isna().all()
    assert table["bracket_high_n"].isna().all()
    assert table.loc["sponge", "bracket_low_n"] == pytest.approx(14.4)
    assert table.loc["brick", "bracket_low_n"] == pytest.approx(16 * 1.2**2)
    assert "last force tried 23.04 N" in table.loc["brick", "error"]
    assert len(read_lift_log(log)[1]) == 6


# --------------------------------------------------------------------------- bad inputs


@pytest.mark.parametrize(
    ("options", "exit_code", "message"),
    [
        (["--tolerance", "0"], 2, "error: --tolerance must be a number in (0, 1), got 0"),
        (["--tolerance", "-0.01"], 2, "error: --tolerance must be a number in (0, 1), got -0.01"),
        (["--tolerance", "1"], 2, "error: --tolerance must be a number in (0, 1), got 1"),
        (["--growth", "1"], 2, "error: --growth must be a finite number > 1, got 1"),
        (["--growth", "0.5"], 2, "error: --growth must be a finite number > 1, got 0.5"),
        (["--growth", "nan"], 2, "error: --growth must be a finite number > 1, got nan"),
        (["--max-attempts", "0"], 2, "error: --max-attempts must be an integer >= 1, got 0"),
        (["--protocol", "fast"], 2, "error: --protocol must be one of refine, paper, got 'fast'"),
        (["--objects", "sponge,cube"], 2, "error: unknown object id 'cube' (the catalog has: "),
        (["--objects", "sponge,,anvil"], 2, "error: --objects has an empty id"),
        (["--rig-timeout", "0"], 2, "error: --rig-timeout must be a finite number > 0 s, got 0"),
    ],
)
def test_bad_options_are_usage_errors(
    catalog: Path, tmp_path: Path, options: list[str], exit_code: int, message: str
) -> None:
    requests = tmp_path / "req.jsonl"
    before = listing(tmp_path)
    result = run("rig", catalog, "--command", rig("threshold_rig.py", 17, requests), "-o",
                 tmp_path / "lift.parquet", "--log", tmp_path / "lift.mcap", *options)  # fmt: skip
    assert result.exit_code == exit_code
    assert one_line_error(result).startswith(message)
    assert listing(tmp_path) == before  # no output, and the rig never ran


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ([], "error: deformctl lift: 'CATALOG' is not a source: give one of sim, rig"),
        (["rig", "CATALOG"], "error: deformctl lift rig: missing option '--command'"),
        (["sim", "CATALOG", "--rig-timeout", "5"], "error: deformctl lift sim: no such option"),
        (["rig", "CATALOG", "--command", ""], "error: rig command is empty"),
        (
            ["rig", "CATALOG", "--command", "python3 'unclosed"],
            "error: rig command cannot be parsed (No closing",
        ),
    ],
)
def test_runner_choice(catalog: Path, tmp_path: Path, args: list[str], message: str) -> None:
    args = [catalog if a == "CATALOG" else a for a in args] if args else [catalog]
    result = run(*args, "-o", tmp_path / "lift.parquet")
    message = message.replace("'CATALOG'", repr(str(catalog)))
    assert result.exit_code == 2
    assert one_line_error(result).startswith(message)
    assert not (tmp_path / "lift.parquet").exists()


@pytest.mark.parametrize(
    ("mu", "message"),
    [
        ("0", "field 'friction_mu': object 'flat': must be >= 0.01, got 0.0"),
        ("-0.1", "field 'friction_mu': object 'flat': must be >= 0.01, got -0.1"),
        ("3.5", "field 'friction_mu': object 'flat': must be <= 3, got 3.5"),
    ],
)  # fmt: skip
def test_friction_not_positive_is_bad_input_data(tmp_path: Path, mu: str, message: str) -> None:
    # Bad values in the catalog are bad input data (65), not a usage error: the file is wrong.
    cat = tmp_path / "objects.csv"
    cat.write_text(HEADER + f"sponge,8,5,4,10,0.5\nflat,8,5,4,10,{mu}\n", encoding="utf-8")
    requests = tmp_path / "req.jsonl"
    result = run("rig", cat, "--command", rig("threshold_rig.py", 17, requests), "-o",
                 tmp_path / "lift.parquet", "--log", tmp_path / "lift.mcap")  # fmt: skip
    assert result.exit_code == 65
    assert one_line_error(result) == f"error: {cat}: {message}"
    assert listing(tmp_path) == ["objects.csv"]  # the rig never ran; nothing written


def test_zero_friction_object_not_selected_is_still_refused(tmp_path: Path) -> None:
    # friction_mu = 0 is outside the catalog's physical bounds: the file is wrong,
    # whichever objects are selected.
    cat = tmp_path / "objects.csv"
    cat.write_text(HEADER + "sponge,8,5,4,10,0.5\nflat,8,5,4,10,0\n", encoding="utf-8")
    out = tmp_path / "lift.parquet"
    result = run(
        "rig", cat, "--command", rig("threshold_rig.py", 1), "-o", out, "--objects", "sponge"
    )
    assert result.exit_code == 65, result.stderr
    assert "friction_mu" in one_line_error(result)


def test_missing_catalog(tmp_path: Path) -> None:
    result = run("rig", tmp_path / "nope.csv", "--command", rig("threshold_rig.py", 1), "-o",
                 tmp_path / "lift.parquet")  # fmt: skip
    assert result.exit_code == 66
    assert one_line_error(result) == f"error: {tmp_path / 'nope.csv'}: no such file"
    assert listing(tmp_path) == []


@pytest.mark.parametrize("existing", ["lift.parquet", "lift.mcap"])
def test_existing_output_without_force(catalog: Path, tmp_path: Path, existing: str) -> None:
    (tmp_path / existing).write_bytes(b"keep me")
    requests = tmp_path / "req.jsonl"
    result = run("rig", catalog, "--command", rig("threshold_rig.py", 17, requests), "-o",
                 tmp_path / "lift.parquet", "--log", tmp_path / "lift.mcap")  # fmt: skip
    assert result.exit_code == 1
    assert one_line_error(result) == (
        f"error: {tmp_path / existing}: exists already, not overwriting (use --force)"
    )
    assert (tmp_path / existing).read_bytes() == b"keep me"
    assert listing(tmp_path) == sorted(["objects.csv", existing])  # rig never ran


def test_output_and_log_must_differ(catalog: Path, tmp_path: Path) -> None:
    same = tmp_path / "x.out"
    result = run("rig", catalog, "--command", rig("threshold_rig.py", 1), "-o", same, "--log", same)
    assert result.exit_code == 2
    assert "-o and --log are the same file" in one_line_error(result)


# ------------------------------------------------------- docs and the rig protocol's schemas


def _readme_lift_commands() -> list[str]:
    guide = (REPO / "docs" / "guide" / "gripper.md").read_text(encoding="utf-8")
    section = guide.split("\n## Lifting on the rig", 1)[1].split("\n## ", 1)[0]
    block = section.split("```sh\n", 1)[1].split("```", 1)[0]
    return [line.replace("\\\n", " ") for line in block.replace("\\\n", " ").splitlines()]


def test_readme_lift_example_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    for name in ("examples", "datasets"):
        (tmp_path / name).symlink_to(REPO / name)
    monkeypatch.chdir(tmp_path)
    commands = [c.split("#")[0].strip() for c in _readme_lift_commands()]
    commands = [c for c in commands if c.startswith("deformctl ")]
    assert commands
    assert commands[0].startswith("deformctl lift ")
    for command in commands:
        argv = shlex.split(command)[1:]
        # the interpreter running the tests stands in for python3 (same code, no PATH lookup)
        argv = [a.replace("python3 ", shlex.quote(sys.executable) + " ") for a in argv]
        result = cli.invoke(app, argv)
        assert result.exit_code == 0, (command, result.stderr)
    # examples/threshold_rig.py needs F_w + 0.5 N: F_d is 0.5 N to within the 1 % tolerance.
    table = read_table("lift-rig.parquet", "lift_results")
    assert table["converged"].all()
    assert len(table) == 4
    assert (table["f_d_n"] >= 0.5 - 1e-12).all()
    assert (table["lift_force_n"] <= (table["f_w_n"] + 0.5) / 0.99).all()


def _doc_json_blocks() -> list[Any]:
    doc = (REPO / "docs" / "rig-protocol.md").read_text(encoding="utf-8")
    return [json.loads(b) for b in re.findall(r"```json\n(.*?)```", doc, flags=re.S)]


def test_doc_examples_match_the_rig_schemas() -> None:
    request, *answers = _doc_json_blocks()[:3]  # then the handshake and its answer
    validate_message("rig_request", request)
    assert answers
    for answer in answers:
        validate_message("rig_response", answer)


@pytest.mark.parametrize(
    "answer",
    [
        '{"lifted": true, "slip_m": 0}',
        '{"lifted": false, "slip_m": 0.02, "message": "slipped", "extra": [1]}',
        '{"before_frame": "a.png", "after_frame": "b.png"}',
        '{"lifted": true, "slip_m": 0, "before_frame": "a.png", "after_frame": "b.png"}',
        '{"lifted": true}',
        '{"slip_m": 0.1}',
        '{"lifted": "yes", "slip_m": 0}',
        '{"lifted": true, "slip_m": -0.01}',
        '{"lifted": true, "slip_m": "0"}',
        '{"before_frame": "a.png"}',
        '{"after_frame": "b.png", "lifted": false, "slip_m": 0}',
        '{"before_frame": "", "after_frame": "b.png"}',
        '{"message": "hello"}',
        '{"lifted": true, "slip_m": 0, "message": 3}',
        "{}",
        "[]",
        "true",
    ],
)
def test_rig_response_schema_agrees_with_the_parser(answer: str) -> None:
    try:
        parse_rig_response(answer)
        accepted = True
    except ValueError:
        accepted = False
    decoded = json.loads(answer)
    assert json_validator("rig_response").is_valid(decoded) is accepted
    check = fast_check("rig_response")
    assert check is not None
    assert check(decoded) is accepted
    if not accepted:
        with pytest.raises(SchemaError):
            validate_message("rig_response", decoded)


@pytest.mark.parametrize(
    ("change", "valid"),
    [
        ({}, True),
        ({"size_cm": None}, True),  # size is optional
        ({"grip_force_n": 0.0}, False),
        ({"attempt_index": -1}, False),
        ({"size_cm": [1.0, 2.0]}, False),
        ({"size_cm": [1.0, 2.0, 0.0]}, False),
        ({"object": {"object_id": "x"}}, False),  # the old nested draft is refused
    ],
)
def test_rig_request_schema(change: dict[str, Any], valid: bool) -> None:
    request: dict[str, Any] = {
        "object_id": "a",
        "attempt_index": 0,
        "grip_force_n": 1.5,
        "weight_n": 2.0,
        "friction_mu": 0.4,
        "size_cm": [1.0, 2.0, 3.0],
    }
    request.update(change)
    request = {k: v for k, v in request.items() if v is not None}
    assert json_validator("rig_request").is_valid(request) is valid
    check = fast_check("rig_request")
    assert check is not None
    assert check(request) is valid


def test_lift_help_ends_with_an_example() -> None:
    result = cli.invoke(app, ["lift", "--help"])
    assert result.exit_code == 0
    assert "Example: deformctl lift " in result.stdout


def test_table_to_stdout(catalog: Path, tmp_path: Path) -> None:
    result = run(
        "rig", catalog, "--command", rig("threshold_rig.py", 1.0), "-o", "-", "--objects", "anvil"
    )
    assert result.exit_code == 0, result.stderr
    (tmp_path / "out.parquet").write_bytes(result.stdout_bytes)  # only the Parquet bytes
    table = read_table(tmp_path / "out.parquet", "lift_results")
    assert table["lift_force_n"].tolist() == [40.0]


# ------------------------------------------------------------- the library, without a CLI


def _threshold_runner(threshold_n: float, fail_for: str | None) -> RunnerFactory:
    def make(obj: Mapping[str, Any], max_force_n: float) -> TrialRunner:
        def trial(grip_force_n: float, attempt_index: int, /) -> TrialOutcome:
            if obj["object_id"] == fail_for and attempt_index == 1:
                raise SimulationError("state went non-finite")
            return TrialOutcome(grip_force_n, grip_force_n >= threshold_n, 0.0)

        return trial

    def row_fields(obj: Mapping[str, Any]) -> Mapping[str, object]:
        return {"lift_height_m": obj["size_z_cm"] / 200.0, "slip_criterion": "test"}

    return RunnerFactory("sim", make, row_fields=row_fields, stop_on_failure=False)


def test_lift_catalog_runner_failure_without_stop_continues(catalog: Path) -> None:
    selected = select_objects(read_catalog(catalog), None)
    run_ = lift_catalog(selected, _threshold_runner(THRESHOLD_N, fail_for="sponge"))
    table = run_.table.set_index("object_id")
    assert run_.not_run == ()
    assert [f.object_id for f in run_.failures] == ["sponge"]
    assert run_.failures[0].aborted
    assert table.loc["sponge", "attempts"] == 1  # the attempt before the failure
    assert table.loc["brick", "converged"]  # later objects ran
    assert table.loc["anvil", "lift_force_n"] == 40.0
    assert table.loc["brick", "lift_height_m"] == pytest.approx(0.03)  # runner's own columns
    assert set(table["runner"]) == {"sim"}
    assert [a.object_id for a in run_.attempts].count("sponge") == 1
    message = run_.error_message()
    assert message is not None
    assert message.startswith("search aborted, 1 attempt kept: object 'sponge': attempt 1 at 12")
    assert "state went non-finite" in message
