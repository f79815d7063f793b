"""The external rig runner, driven by small scripted rig programs in tests/rigs/."""

from __future__ import annotations

import json
import math
import os
import shlex
import sys
import time
from pathlib import Path

import pytest

from deformctl.errors import InputDataError, RigError, SearchError, UsageError
from deformctl.lift import RigSearchAbortedError, find_min_lift_force
from deformctl.lift.ceiling import DEFAULT_ABSOLUTE_MAX_FORCE_N
from deformctl.lift.runners.rig import RigAttemptError, RigRunner, parse_rig_response
from deformctl.series import TrialOutcome

RIGS = Path(__file__).parents[1] / "rigs"
# W = 10 N, mu = 0.5 -> F_w = 10 N; ramp 10, 12, 14.4, 17.28; threshold 17 N.
OBJECT = {"object_id": "sponge", "weight_n": 10.0, "friction_mu": 0.5, "size_cm": [8, 5, 4]}
THRESHOLD_N = 17.0
PALM_RISE_M = 0.05  # what tests/rigs/frames_rig.py lets the palms rise


def rig(name: str, *args: object) -> list[str]:
    return [sys.executable, str(RIGS / name), *map(str, args)]


def reference(protocol: str) -> list[float]:
    """The forces a pure threshold runner sees: what a correct rig search must reproduce."""

    def run(grip_force_n: float, attempt_index: int, /) -> TrialOutcome:
        return TrialOutcome(grip_force_n, grip_force_n >= THRESHOLD_N, 0.0)

    r = find_min_lift_force(run, weight_n=10.0, friction_mu=0.5, protocol=protocol)  # type: ignore[arg-type]
    return [t.grip_force_n for t in r.trials]


@pytest.mark.parametrize("protocol", ["paper", "refine"])
def test_threshold_rig_search_matches_pure_threshold_search(protocol: str, tmp_path: Path) -> None:
    log = tmp_path / "requests.jsonl"
    runner = RigRunner(rig("threshold_rig.py", THRESHOLD_N, log), timeout_s=30, object=OBJECT)
    r = find_min_lift_force(
        runner,
        weight_n=10.0,
        friction_mu=0.5,
        protocol=protocol,  # type: ignore[arg-type]
        object_id="sponge",
    )
    forces = [t.grip_force_n for t in r.trials]
    assert forces == reference(protocol)
    assert r.converged
    assert THRESHOLD_N <= r.lift_force_n <= (17.28 if protocol == "paper" else THRESHOLD_N / 0.99)
    assert [t.slip_m for t in r.trials] == [0.0 if t.lifted else 0.05 for t in r.trials]
    assert r.trials[0].details == {"message": "stand-in rig", "slip_source": "rig"}
    requests = [json.loads(line) for line in log.read_text().splitlines()]
    assert [q["attempt_index"] for q in requests] == list(range(len(forces)))
    assert [q["grip_force_n"] for q in requests] == forces
    assert requests[0] == {
        "object_id": "sponge",
        "attempt_index": 0,
        "grip_force_n": 10.0,
        "weight_n": 10.0,
        "friction_mu": 0.5,
        "size_cm": [8.0, 5.0, 4.0],
        "max_force_n": DEFAULT_ABSOLUTE_MAX_FORCE_N,  # a rig's absolute limit: always sent
    }


def test_command_string_is_shlex_split_and_size_is_optional(tmp_path: Path) -> None:
    log = tmp_path / "requests with space.jsonl"
    command = shlex.join(rig("threshold_rig.py", THRESHOLD_N, log))
    obj = {"object_id": "cube", "weight_n": 1.0, "friction_mu": 0.25, "colour": "red"}
    before_ns = time.time_ns()
    outcome = RigRunner(command, timeout_s=30, object=obj)(20.0, 0)
    started = outcome.start_time_ns  # the wall clock when the attempt began (the lift log's)
    assert started is not None
    assert before_ns <= started <= time.time_ns()
    assert outcome == TrialOutcome(20.0, True, 0.0, None, outcome.details, start_time_ns=started)
    assert json.loads(log.read_text()) == {
        "object_id": "cube",
        "attempt_index": 0,
        "grip_force_n": 20.0,
        "weight_n": 1.0,
        "friction_mu": 0.25,
        "max_force_n": DEFAULT_ABSOLUTE_MAX_FORCE_N,
    }


def test_rig_crash_mid_search_is_one_line_and_keeps_attempts() -> None:
    runner = RigRunner(rig("crash_rig.py", THRESHOLD_N), timeout_s=30, object=OBJECT)
    with pytest.raises(RigSearchAbortedError) as info:
        find_min_lift_force(runner, weight_n=10.0, friction_mu=0.5, object_id="sponge")
    err = info.value
    message = str(err)
    assert "\n" not in message
    assert "attempt_index 2 at 14.4 N" in message
    assert "exited with status 3" in message
    assert "MotorFault: left palm encoder lost" in message  # last stderr line, not the traceback
    assert "Traceback" not in message
    assert isinstance(err, RigError)
    assert isinstance(err, SearchError)
    assert [t.grip_force_n for t in err.partial.trials] == pytest.approx([10.0, 12.0])
    assert not err.partial.converged
    assert message.startswith("search aborted, 2 attempts kept: rig: object 'sponge' ")
    assert err.partial.message == message
    assert isinstance(err.__cause__, RigAttemptError)
    assert err.__cause__.attempt_index == 2


def test_garbage_answer_is_a_one_line_rig_error() -> None:
    runner = RigRunner(rig("garbage_rig.py"), timeout_s=30, object=OBJECT)
    with pytest.raises(RigError, match="not valid JSON") as info:
        runner(12.0, 1)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith("rig: object 'sponge' attempt_index 1 at 12 N: ")
    assert "Connecting to robot" in message


def test_garbage_mid_search_keeps_attempts_so_far() -> None:
    runner = RigRunner(rig("garbage_rig.py"), timeout_s=30, object=OBJECT)
    with pytest.raises(RigSearchAbortedError) as info:
        find_min_lift_force(runner, weight_n=10.0, friction_mu=0.5, object_id="sponge")
    message = str(info.value)
    assert message.startswith(
        "search aborted, 0 attempts kept: rig: object 'sponge' attempt_index 0 at 10 N: "
        "answer is not valid JSON"
    )
    assert message.count("sponge") == 1
    assert info.value.partial.attempts == 0
    assert info.value.partial.message == message


def test_timeout_kills_the_rig() -> None:
    runner = RigRunner(rig("sleepy_rig.py", 30), timeout_s=0.5, object=OBJECT)
    start = time.monotonic()
    with pytest.raises(RigError, match=r"no answer within 0\.5 s \(killed\)") as info:
        runner(10.0, 0)
    assert time.monotonic() - start < 10
    assert "\n" not in str(info.value)


def _alive(pid: int) -> bool:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except FileNotFoundError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"  # a zombie is dead


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="needs /proc")
def test_timeout_kills_the_rigs_children_too(tmp_path: Path) -> None:
    pid_file = tmp_path / "child.pid"
    runner = RigRunner(rig("sleepy_rig.py", 30, pid_file), timeout_s=1.5, object=OBJECT)
    start = time.monotonic()
    with pytest.raises(RigError, match="no answer within"):
        runner(10.0, 0)
    # The child holds the stdout pipe; without killing the group, reading would wait 30 s.
    assert time.monotonic() - start < 10
    child_pid = int(pid_file.read_text())
    deadline = time.monotonic() + 5
    while _alive(child_pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not _alive(child_pid)


def read_frame_slip(before: Path, after: Path) -> tuple[bool, float]:
    """Test stand-in for the vision helper: a 'frame' holds the object's height, m."""
    rise_m = float(after.read_text()) - float(before.read_text())
    slip_m = PALM_RISE_M - rise_m
    return slip_m < 0.005, slip_m


def test_frames_only_rig_with_slip_from_frames(tmp_path: Path) -> None:
    runner = RigRunner(
        rig("frames_rig.py", THRESHOLD_N),
        timeout_s=30,
        object=OBJECT,
        cwd=tmp_path,
        slip_from_frames=read_frame_slip,
    )
    r = find_min_lift_force(runner, weight_n=10.0, friction_mu=0.5, protocol="paper")
    assert [t.grip_force_n for t in r.trials] == reference("paper")
    assert r.lift_force_n == pytest.approx(17.28)
    assert [t.slip_m for t in r.trials] == pytest.approx([0.05, 0.05, 0.05, 0.0])
    details = r.trials[-1].details
    assert details["slip_source"] == "frames"
    assert details["after_frame"] == str(tmp_path / "frames" / "a3_after.txt")
    assert Path(str(details["before_frame"])).is_file()


def test_frames_only_rig_without_slip_from_frames_fails(tmp_path: Path) -> None:
    runner = RigRunner(rig("frames_rig.py", THRESHOLD_N), timeout_s=30, object=OBJECT, cwd=tmp_path)
    with pytest.raises(RigError, match="no slip-from-frames function") as info:
        runner(10.0, 0)
    assert "\n" not in str(info.value)


def test_slip_from_frames_failure_becomes_rig_error(tmp_path: Path) -> None:
    def broken(before: Path, after: Path) -> tuple[bool, float]:
        raise InputDataError("cannot decode image", path=after)

    runner = RigRunner(
        rig("frames_rig.py", THRESHOLD_N),
        timeout_s=30,
        object=OBJECT,
        cwd=tmp_path,
        slip_from_frames=broken,
    )
    with pytest.raises(RigError, match=r"slip from frames failed: .*a0_after.txt: cannot decode"):
        runner(10.0, 0)


@pytest.mark.parametrize(
    ("answer", "fragment"),
    [
        ("", "empty answer"),
        ("[1, 2]", "must be a JSON object, got list"),
        ('{"lifted": "yes", "slip_m": 0}', "'lifted' must be true or false"),
        ('{"lifted": 1, "slip_m": 0}', "'lifted' must be true or false"),
        ('{"lifted": true}', "'slip_m' is required"),
        ('{"lifted": true, "slip_m": -0.1}', "'slip_m' must be a number >= 0"),
        ('{"lifted": true, "slip_m": "0"}', "'slip_m' must be a number >= 0"),
        ('{"lifted": true, "slip_m": NaN}', "not valid JSON"),
        ('{"slip_m": 0.1}', "'slip_m' given without 'lifted'"),
        ("{}", "neither 'lifted' nor"),
        ('{"before_frame": "a.png"}', "must be given together"),
        ('{"before_frame": 3, "after_frame": "b.png"}', "must be a non-empty path string"),
        ('{"lifted": true, "slip_m": 0, "message": 5}', "'message' must be a string"),
        ('{"lifted": true, "slip_m": 0}{"lifted": true, "slip_m": 0}', "not valid JSON"),
        (
            '{"lifted": true, "slip_m": 0, "before_frame": "no.png", "after_frame": "no.png"}',
            "frame 'no.png' does not exist",
        ),
    ],
)
def test_answer_breaking_the_contract_is_one_line_rig_error(
    answer: str, fragment: str, tmp_path: Path
) -> None:
    runner = RigRunner(rig("echo_rig.py", answer), timeout_s=30, object=OBJECT, cwd=tmp_path)
    with pytest.raises(RigError, match=fragment) as info:
        runner(12.0, 4)
    assert "\n" not in str(info.value)
    assert "attempt_index 4 at 12 N" in str(info.value)


def test_valid_answer_with_extra_keys_and_frames_is_accepted(tmp_path: Path) -> None:
    (tmp_path / "b.png").write_bytes(b"")
    (tmp_path / "a.png").write_bytes(b"")
    answer = (
        '{"lifted": false, "slip_m": 0.02, "before_frame": "b.png", '
        '"after_frame": "a.png", "message": "dropped", "torque_nm": 1.5}\n'
    )
    outcome = RigRunner(rig("echo_rig.py", answer), timeout_s=30, object=OBJECT, cwd=tmp_path)(
        12.0, 0
    )
    assert outcome.lifted is False
    assert outcome.slip_m == 0.02
    assert outcome.details == {
        "message": "dropped",
        "before_frame": str(tmp_path / "b.png"),
        "after_frame": str(tmp_path / "a.png"),
        "slip_source": "rig",
    }


@pytest.mark.parametrize(
    ("stderr", "expected"),
    [("", "exited with status 7: (no stderr)"), ("warn\n\nfatal: e-stop\n\n", "fatal: e-stop")],
)
def test_nonzero_exit_names_status_and_last_stderr_line(stderr: str, expected: str) -> None:
    answer = '{"lifted": true, "slip_m": 0}'
    runner = RigRunner(rig("echo_rig.py", answer, 7, stderr), timeout_s=30, object=OBJECT)
    with pytest.raises(RigError) as info:
        runner(10.0, 0)
    assert expected in str(info.value)
    assert "\n" not in str(info.value)


def test_command_that_cannot_start_is_a_rig_error(tmp_path: Path) -> None:
    runner = RigRunner([str(tmp_path / "no-such-rig")], timeout_s=30, object=OBJECT)
    with pytest.raises(RigError, match=r"cannot run .*no-such-rig") as info:
        runner(10.0, 0)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(
    ("command", "timeout_s", "obj", "fragment"),
    [
        ("", 30, OBJECT, "rig command is empty"),
        ("   ", 30, OBJECT, "rig command is empty"),
        ("rig", 0, OBJECT, "timeout must be"),
        ("rig", math.nan, OBJECT, "timeout must be"),
        ("rig", 30, {"weight_n": 1.0, "friction_mu": 0.5}, "non-empty string 'object_id'"),
        ("rig", 30, {"object_id": "A", "weight_n": 1.0}, r"friction_mu must be .*, got None"),
        ("rig", 30, {"object_id": "A", "weight_n": 1.0, "friction_mu": 0}, "friction_mu must"),
        ("rig", 30, {"object_id": "A", "weight_n": -1, "friction_mu": 1}, "weight_n must"),
        ("rig", 30, {**OBJECT, "size_cm": [1, 2]}, "size_cm must be three numbers"),
    ],
)
def test_bad_rig_setup_is_usage_error(
    command: str, timeout_s: float, obj: dict[str, object], fragment: str
) -> None:
    with pytest.raises(UsageError, match=fragment):
        RigRunner(command, timeout_s=timeout_s, object=obj)


def test_parse_rig_response_accepts_integer_slip() -> None:
    assert parse_rig_response('{"lifted": true, "slip_m": 0}') == {"lifted": True, "slip_m": 0}


def test_rig_runs_in_cwd(tmp_path: Path) -> None:
    # frames_rig writes relative to its working directory; nothing lands in ours.
    before = set(os.listdir("."))
    RigRunner(
        rig("frames_rig.py", 1.0),
        timeout_s=30,
        object=OBJECT,
        cwd=tmp_path,
        slip_from_frames=read_frame_slip,
    )(10.0, 0)
    assert (tmp_path / "frames" / "a0_after.txt").is_file()
    assert set(os.listdir(".")) == before


def _json_blocks(markdown: str) -> list[str]:
    blocks, inside, current = [], False, []
    for line in markdown.splitlines():
        if line.startswith("```json"):
            inside, current = True, []
        elif line.startswith("```") and inside:
            inside = False
            blocks.append("\n".join(current))
        elif inside:
            current.append(line)
    return blocks


def test_protocol_doc_examples_match_the_code(tmp_path: Path) -> None:
    doc = (Path(__file__).parents[2] / "docs" / "rig-protocol.md").read_text(encoding="utf-8")
    request_text, decided_text, frames_text, *_handshake = _json_blocks(doc)
    request = json.loads(request_text)
    keys = ("object_id", "weight_n", "friction_mu", "size_cm", "max_force_n")
    obj = {k: request[k] for k in keys}
    runner = RigRunner("rig", timeout_s=1, object=obj)
    assert runner.request(request["grip_force_n"], request["attempt_index"]) == request
    assert parse_rig_response(decided_text)["lifted"] is True
    assert set(parse_rig_response(frames_text)) == {"before_frame", "after_frame"}
