"""The sweep executor: local processes, partitioned output, failures, resume, bad inputs.

The toy task (``tests/_helpers/sweeps.py``) is a seeded computation per object whose rows are
recomputed independently (``expected_rows``), so every dataset is checked against a direct
answer, not just against another run of the executor.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from deformctl.artifacts.dataset import (
    FAILURES_DIR,
    LOGS_DIR,
    MANIFEST_NAME,
    PartPayloads,
    read_dataset,
    read_failures,
)
from deformctl.artifacts.io import atomic_write_bytes
from deformctl.errors import (
    EXIT_USAGE,
    DeformctlError,
    InputDataError,
    MissingInputError,
    OutputExistsError,
    UsageError,
)
from tests._helpers.sweeps import (
    FAILING_ID,
    FINGERPRINT,
    REPO,
    SCHEMA,
    PidLogWriter,
    bad_rows_task,
    expected_rows,
    make_items,
    snapshot,
    sweep,
    toy_task_with_payload,
)

# --------------------------------------------------------------------------- happy paths


def test_one_and_two_workers_give_the_direct_rows(tmp_path: Path) -> None:
    items = make_items()
    s1 = sweep(items, tmp_path / "w1", workers=1)
    s2 = sweep(items, tmp_path / "w2", workers=2)
    want = expected_rows(items)
    assert len(want) == 18  # sum of i % 3 for i < 20 is 19, minus obj-07's one row
    for out in (tmp_path / "w1", tmp_path / "w2"):
        pd.testing.assert_frame_equal(read_dataset(out), want)
    for s in (s1, s2):
        assert (s.done, s.failed, s.skipped_resumed, s.failed_total, s.parts) == (19, 1, 0, 1, 7)
        assert s.exit_code == 1
        assert "19 done, 1 failed" in s.line()
    assert snapshot(tmp_path / "w1") == snapshot(tmp_path / "w2")  # byte-identical datasets


def test_failed_object_is_recorded_with_cause_and_one_line_message(tmp_path: Path) -> None:
    sweep(make_items(), tmp_path / "o", workers=2)
    fails = read_failures(tmp_path / "o")
    assert fails.to_dict("records") == [
        {
            "object_id": FAILING_ID,
            "cause": "not_converged",
            "error_message": f"lift search for {FAILING_ID} did not converge after 9 steps",
        }
    ]
    assert pq.read_table(tmp_path / "o" / FAILURES_DIR / "part-00002.parquet").num_rows == 1


def test_layout_manifest_and_plain_pyarrow_reading(tmp_path: Path) -> None:
    items = make_items()
    out = tmp_path / "o"
    sweep(items, out, workers=1)
    names = sorted(p.name for p in out.glob("part-*.parquet"))
    assert names == [f"part-{k:05d}.parquet" for k in range(7)]
    manifest = json.loads((out / MANIFEST_NAME).read_text())
    assert manifest["fingerprint"] == FINGERPRINT
    assert manifest["parts"][2] == ["obj-06", "obj-07", "obj-08"]
    assert [c["name"] for c in manifest["schema"]] == SCHEMA.names
    # every part has the same schema, and plain pyarrow reads the directory (ignores _ files)
    for p in out.glob("part-*.parquet"):
        assert pq.read_schema(p).equals(SCHEMA, check_metadata=False)
    plain = pq.read_table(out).to_pandas()
    pd.testing.assert_frame_equal(plain, expected_rows(items), check_dtype=False)
    # a single Parquet file reads the same way
    single = tmp_path / "single.parquet"
    pq.write_table(pa.Table.from_pandas(expected_rows(items), preserve_index=False), single)
    pd.testing.assert_frame_equal(read_dataset(single), read_dataset(out))


def test_rows_outside_the_schema_fail_that_object_only(tmp_path: Path) -> None:
    s = sweep(make_items(), tmp_path / "o", workers=1, task=bad_rows_task)
    assert (s.done, s.failed) == (18, 2)
    fails = read_failures(tmp_path / "o").set_index("object_id")
    assert fails.loc["obj-03", "cause"] == "internal_error"
    assert "extra ['speed_m_per_s']" in fails.loc["obj-03", "error_message"]


def test_part_writer_gets_each_parts_payloads_in_order(tmp_path: Path) -> None:
    seen: list[int] = []

    def write_log(part: PartPayloads) -> None:
        seen.append(part.index)
        atomic_write_bytes(part.path(".log"), b"\n".join(p for _, p in part.payloads))

    out = tmp_path / "o"
    sweep(make_items(), out, workers=2, task=toy_task_with_payload, part_writer=write_log)
    assert sorted(seen) == list(range(7))
    assert (out / LOGS_DIR / "part-00002.log").read_bytes() == b"log of obj-06\nlog of obj-08"
    assert (out / LOGS_DIR / "part-00006.log").read_bytes() == b"log of obj-18\nlog of obj-19"
    pd.testing.assert_frame_equal(read_dataset(out), expected_rows(make_items()))


def _log_lines(out: Path, k: int) -> list[bytes]:
    return (out / LOGS_DIR / f"part-{k:05d}.log").read_bytes().split(b"\n")


def test_in_workers_part_writer_runs_in_the_workers_and_precedes_the_rows(
    tmp_path: Path,
) -> None:
    out = tmp_path / "o"
    violations: list[str] = []
    finished = threading.Event()

    def watch() -> None:  # the invariant, checked while the sweep runs: rows imply the log
        while not finished.is_set():
            for rows in out.glob("part-*.parquet"):
                if not (out / LOGS_DIR / rows.with_suffix(".log").name).exists():
                    violations.append(rows.name)
            time.sleep(0.005)

    watcher = threading.Thread(target=watch)
    watcher.start()
    try:
        items = make_items()
        sweep(items, out, workers=2, task=toy_task_with_payload, part_writer=PidLogWriter())
    finally:
        finished.set()
        watcher.join()
    assert violations == []
    pids = set()
    for k in range(7):
        head, *body = _log_lines(out, k)
        pid, rows_before = head.decode().split()
        assert rows_before == "rows_before=False"
        pids.add(int(pid.removeprefix("pid=")))
        ids = [f"obj-{i:02d}" for i in range(3 * k, min(3 * k + 3, 20)) if i != 7]
        assert body == [f"log of {i}".encode() for i in ids]
    assert os.getpid() not in pids
    assert 1 <= len(pids) <= 2  # the pool's worker processes
    pd.testing.assert_frame_equal(read_dataset(out), expected_rows(make_items()))
    # the same dataset and logs (but for the pid line) as a one-worker run
    one = tmp_path / "one"
    sweep(make_items(), one, workers=1, task=toy_task_with_payload, part_writer=PidLogWriter(0))
    strip = {k: v for k, v in snapshot(out).items() if not k.endswith(".log")}
    assert strip == {k: v for k, v in snapshot(one).items() if not k.endswith(".log")}
    for k in range(7):
        assert _log_lines(out, k)[1:] == _log_lines(one, k)[1:]


def test_failing_in_workers_part_writer_stops_the_sweep_before_that_parts_rows(
    tmp_path: Path,
) -> None:
    out = tmp_path / "o"
    writer = PidLogWriter(sleep_s=0.0, fail_part=2)
    with pytest.raises(RuntimeError, match="disk full while writing part 2"):
        sweep(make_items(), out, workers=2, task=toy_task_with_payload, part_writer=writer)
    assert not (out / "part-00002.parquet").exists()
    assert not (out / LOGS_DIR / "part-00002.log").exists()
    s = sweep(make_items(), out, workers=2, task=toy_task_with_payload,
              part_writer=PidLogWriter(sleep_s=0.0), resume=True)  # fmt: skip
    assert s.done + s.failed + s.skipped_resumed == 20
    assert (out / LOGS_DIR / "part-00002.log").is_file()
    pd.testing.assert_frame_equal(read_dataset(out), expected_rows(make_items()))


# --------------------------------------------------------------------------- resume


def test_resume_recomputes_missing_corrupt_and_partial_parts_only(tmp_path: Path) -> None:
    items = make_items()
    out = tmp_path / "o"
    sweep(items, out, workers=2)
    reference = snapshot(out)
    (out / "part-00001.parquet").unlink()  # missing
    p4 = out / "part-00004.parquet"
    p4.write_bytes(p4.read_bytes()[:50])  # truncated
    (out / FAILURES_DIR / "part-00005.parquet").unlink()  # half-committed part
    (out / ".part-00006.parquet.tmp-1-deadbeef").write_bytes(b"junk")  # leftover temp file
    kept_inode = (out / "part-00000.parquet").stat().st_ino
    with pytest.raises(InputDataError, match="incomplete sweep: 1 of 7 parts missing"):
        read_dataset(out)

    s = sweep(items, out, workers=2, resume=True)
    assert s.skipped_resumed == 20 - 9  # parts 1, 4, 5 (3 objects each) were recomputed
    assert (s.done, s.failed, s.failed_total) == (9, 0, 1)  # obj-07 sits in kept part 2
    assert (out / "part-00000.parquet").stat().st_ino == kept_inode  # kept, not rewritten
    assert snapshot(out) == reference
    pd.testing.assert_frame_equal(read_dataset(out), expected_rows(items))


def test_a_worker_killed_while_sending_its_result_fails_the_sweep_instead_of_hanging(
    tmp_path: Path,
) -> None:
    """The pool's result reader waits for ever for the rest of a half-sent result, so the pool
    itself never learns that the worker died; the sweep's own watch on its workers does."""
    out = tmp_path / "o"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), *sys.path])}
    code = f"from tests._helpers.sweeps import _half_sent_main; _half_sent_main({str(out)!r})"
    proc = subprocess.Popen(
        [sys.executable, "-c", code],
        env=env,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    try:
        _, err = proc.communicate(timeout=60)  # about 2 s idle
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(timeout=10)
    assert proc.returncode == 1, err
    assert "a local worker process died" in err, err


def test_resume_after_the_client_is_killed(tmp_path: Path) -> None:
    out = tmp_path / "o"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), *sys.path])}
    code = f"from tests._helpers.sweeps import _client_main; _client_main({str(out)!r})"
    proc = subprocess.Popen([sys.executable, "-c", code], env=env, start_new_session=True)
    try:
        deadline = time.monotonic() + 40
        while len(list(out.glob("part-*.parquet"))) < 3:
            assert proc.poll() is None, "the sweep ended before it could be killed"
            assert time.monotonic() < deadline, "no parts written within 40 s"
            time.sleep(0.05)
        os.killpg(proc.pid, signal.SIGKILL)  # the client and its pool, mid-sweep
        proc.wait(timeout=10)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(timeout=10)
    written = len(list(out.glob("part-*.parquet")))
    assert 3 <= written < 10
    with pytest.raises(InputDataError, match="incomplete sweep"):
        read_dataset(out)

    items = make_items(20, sleep_s=0.15)
    s = sweep(items, out, workers=2, partition_size=2, resume=True)
    assert s.skipped_resumed == 2 * written
    assert s.done + s.failed == 20 - 2 * written
    got = read_dataset(out)
    pd.testing.assert_frame_equal(got, expected_rows(items))
    assert not got.duplicated(["object_id", "trial"]).any()
    sweep(make_items(20), tmp_path / "ref", workers=2, partition_size=2)  # same ids, no sleep
    assert snapshot(out) == snapshot(tmp_path / "ref")


def test_resume_into_an_empty_directory_runs_the_whole_sweep(tmp_path: Path) -> None:
    s = sweep(make_items(6), tmp_path / "new", workers=1, resume=True)
    assert (s.done, s.skipped_resumed) == (6, 0)


# --------------------------------------------------------------------------- bad inputs


def test_workers_zero_is_a_usage_error_and_writes_nothing(tmp_path: Path) -> None:
    with pytest.raises(UsageError) as info:
        sweep(make_items(), tmp_path / "o", workers=0)
    assert info.value.exit_code == EXIT_USAGE
    assert str(info.value) == "--workers must be >= 1, got 0"
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"fingerprint": {**FINGERPRINT, "command": "other"}}, r"different command .*'command'"),
        (
            {"schema": SCHEMA.append(pa.field("extra_n", pa.float64()))},
            "made with a different schema",
        ),
        ({"partition_size": 4}, "different list of objects or partition size"),
    ],
)
def test_resume_of_a_different_sweep_is_refused(
    tmp_path: Path, change: dict[str, Any], match: str
) -> None:
    out = tmp_path / "o"
    sweep(make_items(6), out, workers=1)
    before = snapshot(out)
    with pytest.raises(InputDataError, match=match) as info:
        sweep(make_items(6), out, workers=1, resume=True, **change)
    assert info.value.exit_code == 65
    assert "\n" not in str(info.value)
    assert snapshot(out) == before


def test_existing_output_needs_force_or_resume(tmp_path: Path) -> None:
    out = tmp_path / "o"
    sweep(make_items(6), out, workers=1)
    (out / "notes.txt").write_text("mine")
    before = snapshot(out)
    with pytest.raises(OutputExistsError):
        sweep(make_items(6), out, workers=1)
    assert snapshot(out) == before
    s = sweep(make_items(4), out, workers=1, force=True)
    assert s.parts == 2
    assert (out / "notes.txt").read_text() == "mine"  # only sweep files are replaced
    assert sorted(p.name for p in out.glob("part-*")) == [
        "part-00000.parquet",
        "part-00001.parquet",
    ]


def test_resume_of_a_directory_without_manifest_is_refused(tmp_path: Path) -> None:
    (tmp_path / "o").mkdir()
    (tmp_path / "o" / "x.csv").write_text("a\n")
    with pytest.raises(InputDataError, match=r"no _sweep\.json"):
        sweep(make_items(3), tmp_path / "o", resume=True, workers=1)


@pytest.mark.parametrize(
    ("items", "match"),
    [
        ([{"object_id": "a"}, {"object_id": "a"}], "duplicate object_id 'a'"),
        ([{"name": "a"}], "object at position 0 has no 'object_id'"),
        ([{"object_id": 1.5}], "is not a string or int"),
    ],
)
def test_bad_catalog_ids(tmp_path: Path, items: list[dict[str, Any]], match: str) -> None:
    with pytest.raises(InputDataError, match=match):
        sweep(items, tmp_path / "o", workers=1)
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("address", ["127.0.0.1:8786", "http://127.0.0.1:8786", "tcp://host"])
def test_malformed_scheduler_address_is_a_usage_error(tmp_path: Path, address: str) -> None:
    with pytest.raises(UsageError, match="not of the form tcp://HOST:PORT"):
        sweep(make_items(3), tmp_path / "o", scheduler=address)
    assert not (tmp_path / "o").exists()


def test_workers_and_scheduler_together_are_refused(tmp_path: Path) -> None:
    with pytest.raises(UsageError, match="not both"):
        sweep(make_items(3), tmp_path / "o", workers=2, scheduler="tcp://127.0.0.1:8786")


def test_reading_missing_or_non_parquet_inputs(tmp_path: Path) -> None:
    with pytest.raises(MissingInputError):
        read_dataset(tmp_path / "nope")
    bad = tmp_path / "bad.parquet"
    bad.write_text("not parquet")
    with pytest.raises(InputDataError, match="not a readable Parquet file"):
        read_dataset(bad)
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputDataError, match="no part-"):
        read_dataset(tmp_path / "empty")
    assert issubclass(InputDataError, DeformctlError)


def test_progress_bar_only_on_a_terminal(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    sweep(make_items(6), tmp_path / "quiet", workers=1, progress=True)
    assert capsys.readouterr().err == ""  # stderr is not a TTY under pytest
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    sweep(make_items(8), tmp_path / "tty", workers=1, progress=True)  # obj-07 fails
    err = capsys.readouterr().err
    assert "8/8" in err
    assert "1 failed" in err
    assert "obj/s" in err


def test_stage_task_modules_do_not_load_the_simulator() -> None:
    # A local sweep's fork server preloads the task's module: it must not load the simulator
    # (numba, OpenBLAS threads) before the workers are forked and limit their BLAS threads.
    code = (
        "import sys, deformctl.lift.runners.sim, deformctl.measure.stage, "
        "deformctl.characterize.stage; "
        "print(sorted(m for m in ('deformctl.sim', 'numba', 'scipy', 'sklearn', 'cv2') "
        "if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
