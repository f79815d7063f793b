"""Sweeps through the CLI: ``lift --sim``, ``measure --sim`` and ``characterize`` into dataset dirs.

Reference answers come from the serial single-file commands (the code path of every earlier
release), so a sweep is checked against an independent run, not against itself. The simulator
runs at a coarse, fast setting (one lattice cell per 10 cm, dt 2 ms, a 1 cm rise, 50 ms hold, the
paper's ramp protocol); the sweeps' correctness does not depend on the physics being fine.
A real Dask scheduler and two workers run as separate processes (the ``dask_cluster`` fixture of
tests/conftest.py).
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import duckdb
import pandas as pd
import pyarrow as pa
import pyarrow.dataset as pads
import pytest
from typer.testing import CliRunner

from deformctl.artifacts import read_lift_log, read_squeeze_log, read_table
from deformctl.artifacts.dataset import read_dataset, read_failures, read_table_any, table_schema
from deformctl.cli import app
from deformctl.measure import MEASURE_SCHEMA
from deformctl.population import make_population
from tests._helpers.dask_cluster import Cluster

FAST_LIFT = [
    "--alpha-cm", "10", "--dt-s", "0.002", "--hold-s", "0.05", "--lift-height-m", "0.01",
    "--protocol", "paper", "--max-attempts", "20",
]  # fmt: skip
FAST_SQUEEZE = [
    "--squeezes", "2", "--ramp-s", "0.05", "--hold-s", "0.1", "--dt-s", "0.002",
    "--alpha-cm", "10", "--noise-force-n", "0.01",
]  # fmt: skip
runner = CliRunner()


def _catalog(tmp_path: Path, n: int = 20) -> Path:
    path = tmp_path / "cat.csv"
    make_population(n, seed=1).to_csv(path, index=False)
    return path


def _cli(*args: object) -> object:
    return runner.invoke(app, [str(a) for a in args])


def _ok(result: object) -> None:
    assert result.exit_code == 0, result.stderr  # type: ignore[attr-defined]


def _parquet_readers_see_the_rows(path: Path, schema: pa.Schema, expected: pd.DataFrame) -> None:
    """pandas, pyarrow.dataset and DuckDB open the dataset folder itself: every row, in part
    order, with the declared schema (the logs, manifest and failures are skipped)."""
    columns = list(schema.names)
    ds = pads.dataset(path, format="parquet")
    assert ds.schema.remove_metadata().equals(schema.remove_metadata()), ds.schema
    by_arrow = ds.to_table().to_pandas()
    by_pandas = pd.read_parquet(path)
    by_duckdb = duckdb.sql(
        f"SELECT * FROM read_parquet('{path}/*.parquet', filename = true) ORDER BY filename"
    ).df()

    def plain(df: pd.DataFrame) -> pd.DataFrame:  # one missing value (None) for every dtype
        df = df[columns].reset_index(drop=True).astype(object)
        return df.where(df.notna(), None)

    for got in (by_arrow, by_pandas, by_duckdb):
        assert list(got["object_id"]) == list(expected["object_id"])
        pd.testing.assert_frame_equal(plain(got), plain(expected))


def _one_line_error(result: object, code: int, text: str) -> None:
    assert result.exit_code == code, result.stderr  # type: ignore[attr-defined]
    err = result.stderr.strip()  # type: ignore[attr-defined]
    assert "\n" not in err, err
    assert err.startswith("error: "), err
    assert text in err, err
    assert "Traceback" not in err


@pytest.fixture(scope="module")
def serial_lift(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, pd.DataFrame]:
    """The 20-object catalog and its lift_results from the serial single-file command."""
    tmp = tmp_path_factory.mktemp("serial")
    cat = _catalog(tmp)
    _ok(_cli("lift", "sim", cat, "-o", tmp / "lift.parquet", *FAST_LIFT))
    return cat, read_table(tmp / "lift.parquet", "lift_results")


@pytest.mark.e2e
def test_dask_cluster_gives_the_local_and_serial_rows(
    dask_cluster: Cluster,
    serial_lift: tuple[Path, pd.DataFrame],
    tmp_path: Path,
) -> None:
    cat, expected = serial_lift
    on_dask = tmp_path / "dask"
    result = _cli("lift", "sim", cat, "-o", f"{on_dask}/", *FAST_LIFT, "--partition-size", 6,
                  "--scheduler", dask_cluster.address, "--connect-timeout", 10)  # fmt: skip
    _ok(result)
    assert "20 done, 0 failed" in result.stderr
    local = tmp_path / "local"
    _ok(_cli("lift", "sim", cat, "-o", f"{local}/", *FAST_LIFT, "--partition-size", 6,
             "--workers", 2))  # fmt: skip
    got_dask, got_local = (
        read_table_any(str(on_dask), "lift_results"),
        read_table_any(str(local), "lift_results"),
    )
    assert len(expected) == 20
    assert expected["converged"].all()
    pd.testing.assert_frame_equal(got_dask, expected)
    pd.testing.assert_frame_equal(got_local, expected)
    _parquet_readers_see_the_rows(local, table_schema("lift_results"), expected)
    # the attempt logs of the parts hold every attempt of every object, once
    objects, attempts = [], []
    for k in range(4):
        o, a = read_lift_log(on_dask / "_logs" / f"part-{k:05d}.mcap")
        objects += [x["object_id"] for x in o]
        attempts += [(x.object_id, x.attempt_index) for x in a]
    assert objects == list(expected["object_id"])
    assert len(attempts) == len(set(attempts)) == int(expected["attempts"].sum())
    # inspect summarises the directory; table reads it
    info = json.loads(_cli("inspect", on_dask, "--json").stdout)  # type: ignore[attr-defined]
    assert (info["kind"], info["parts"], info["rows"], info["failed"]) == ("lift_results", 4, 20, 0)


def _descendants(pid: int) -> dict[int, int]:
    """pid -> parent pid of every live descendant of ``pid`` (from /proc)."""
    parents: dict[int, int] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                stat = Path(f"/proc/{entry}/stat").read_text()
            except OSError:
                continue
            parents[int(entry)] = int(stat.rsplit(")", 1)[1].split()[1])
    out: dict[int, int] = {}
    frontier = [pid]
    while frontier:
        p = frontier.pop()
        for child, parent in parents.items():
            if parent == p and child not in out:
                out[child] = parent
                frontier.append(child)
    return out


def _start_sweep(cat: Path, out: Path) -> subprocess.Popen[bytes]:
    cmd = [sys.executable, "-m", "deformctl", "lift", "sim", str(cat), "-o", f"{out}/",
           *FAST_LIFT, "--partition-size", "2", "--workers", "2"]  # fmt: skip
    # faulthandler on: a client that does not exit is made to print every thread's stack
    env = {**os.environ, "PYTHONFAULTHANDLER": "1"}
    return subprocess.Popen(
        cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True, env=env
    )


def _wait_or_explain(proc: subprocess.Popen[bytes], timeout_s: float) -> None:
    """Wait for ``proc``; if it does not exit in ``timeout_s``, fail with its process tree and
    its threads' stacks (SIGABRT makes faulthandler print them) instead of a bare timeout."""
    try:
        proc.wait(timeout=timeout_s)
        return
    except subprocess.TimeoutExpired:
        tree = _descendants(proc.pid)
    with contextlib.suppress(ProcessLookupError):
        os.kill(proc.pid, signal.SIGABRT)
    with contextlib.suppress(subprocess.TimeoutExpired):
        proc.wait(timeout=10)
    err = proc.stderr.read().decode(errors="replace") if proc.stderr else ""
    pytest.fail(f"the client did not exit within {timeout_s:g} s; its processes {tree}\n{err}")


def _wait_for_parts(proc: subprocess.Popen[bytes], out: Path, n: int) -> None:
    deadline = time.monotonic() + 60
    while len(list(out.glob("part-*.parquet"))) < n:
        assert proc.poll() is None, proc.stderr.read() if proc.stderr else ""
        assert time.monotonic() < deadline, "no parts written within 60 s"
        time.sleep(0.02)


def _kill_group(proc: subprocess.Popen[bytes]) -> None:
    with contextlib.suppress(ProcessLookupError):
        os.killpg(proc.pid, signal.SIGKILL)
    proc.wait(timeout=10)


@pytest.mark.e2e
@pytest.mark.parametrize("victim", ["client", "worker"])
def test_killed_sweep_resumes_with_nothing_lost_or_duplicated(
    victim: str, serial_lift: tuple[Path, pd.DataFrame], tmp_path: Path
) -> None:
    cat, expected = serial_lift
    out = tmp_path / "out"
    proc = _start_sweep(cat, out)
    try:
        _wait_for_parts(proc, out, 2)
        if victim == "client":
            proc.send_signal(signal.SIGKILL)
            proc.wait(timeout=10)
            assert proc.returncode == -signal.SIGKILL
        else:  # a pool worker: a grandchild (the forkserver's child), not the resource tracker
            tree = _descendants(proc.pid)
            workers = [p for p, parent in tree.items() if parent != proc.pid]
            assert workers, tree
            os.kill(workers[0], signal.SIGKILL)
            _wait_or_explain(proc, 60.0)  # about 3 s idle; a loaded 2-core machine is slower
            err = proc.stderr.read().decode() if proc.stderr else ""
            assert proc.returncode == 1, err
            assert "a local worker process died" in err
            assert "--resume" in err
    finally:
        _kill_group(proc)
    kept = len(list(out.glob("part-*.parquet")))
    assert 2 <= kept < 10  # killed part-way
    result = _cli("lift", "sim", cat, "-o", f"{out}/", *FAST_LIFT, "--partition-size", 2,
                  "--workers", 2, "--resume")  # fmt: skip
    _ok(result)
    assert f"{2 * kept} kept from an earlier run" in result.stderr
    got = read_table_any(str(out), "lift_results")
    assert not got["object_id"].duplicated().any()
    pd.testing.assert_frame_equal(got, expected)
    assert not [p for p in out.rglob(".*") if p.is_file()]  # no temporary files left


def test_failed_objects_are_recorded_and_the_sweep_goes_on(tmp_path: Path) -> None:
    catalog = make_population(6, seed=2)
    catalog.loc[2, "material_stiffness_n_per_cm"] = float("nan")  # the simulator refuses it
    refused = str(catalog.loc[2, "object_id"])
    cat = tmp_path / "cat.csv"
    catalog.to_csv(cat, index=False)
    out = tmp_path / "out"
    args = [a if a != "20" else "1" for a in FAST_LIFT]  # one attempt: F_w itself must lift
    result = _cli("lift", "sim", cat, "-o", f"{out}/", *args, "--workers", 1)
    assert result.exit_code == 1, result.stderr
    rows = read_table_any(str(out), "lift_results")
    failures = read_failures(out)
    unconverged = rows.loc[~rows["converged"], "object_id"].tolist()
    assert refused not in set(rows["object_id"])  # refused: no row
    assert len(rows) == 5
    assert len(unconverged) >= 1  # F_w itself rarely lifts
    assert sorted(failures["object_id"]) == sorted([refused, *unconverged])
    by_id = failures.set_index("object_id")
    assert by_id.loc[refused, "cause"] == "bad_input"
    assert "material" in by_id.loc[refused, "error_message"]
    assert set(by_id.drop(refused)["cause"]) == {"not_converged"}
    n_failed = len(failures)
    summary = result.stderr.strip().splitlines()[-1]
    assert f"{6 - n_failed} done, {n_failed} failed" in summary


def test_measure_and_characterize_sweeps_equal_the_serial_files(tmp_path: Path) -> None:
    cat = _catalog(tmp_path, 6)
    _ok(_cli("measure", "sim", cat, "-o", tmp_path / "sq.mcap", *FAST_SQUEEZE, "--seed", 5))
    sq = tmp_path / "sq"
    _ok(_cli("measure", "sim", cat, "-o", f"{sq}/", *FAST_SQUEEZE, "--seed", 5,
             "--partition-size", 4, "--workers", 2))  # fmt: skip
    objs, serial = read_squeeze_log(tmp_path / "sq.mcap")
    swept = [s for k in range(2) for s in read_squeeze_log(sq / "_logs" / f"part-{k:05d}.mcap")[1]]
    assert len(serial) == len(swept) == 12
    for a, b in zip(serial, swept, strict=True):  # same noise streams: seed and catalog position
        assert (a.object_id, a.squeeze_index) == (b.object_id, b.squeeze_index)
        assert (a.force_n == b.force_n).all()
        assert (a.compression_m == b.compression_m).all()
    _ok(_cli("characterize", tmp_path / "sq.mcap", "-o", tmp_path / "c.parquet",
             "--window-s", 0.03))  # fmt: skip
    _ok(_cli("characterize", sq, "-o", f"{tmp_path / 'cd'}/", "--window-s", 0.03,
             "--workers", 2, "--partition-size", 4))  # fmt: skip
    _ok(_cli("characterize", sq, "-o", tmp_path / "c2.parquet", "--window-s", 0.03))
    expected = read_table(tmp_path / "c.parquet", "coefficients")
    pd.testing.assert_frame_equal(read_table_any(str(tmp_path / "cd"), "coefficients"), expected)
    pd.testing.assert_frame_equal(read_table(tmp_path / "c2.parquet", "coefficients"), expected)
    assert len(expected) == 6
    assert len(objs) == 6
    _parquet_readers_see_the_rows(tmp_path / "cd", table_schema("coefficients"), expected)
    _parquet_readers_see_the_rows(sq, MEASURE_SCHEMA, read_dataset(sq))


def test_dataset_folders_of_the_first_layout_are_read_and_resumed(tmp_path: Path) -> None:
    cat = _catalog(tmp_path, 3)
    sq = tmp_path / "sq"
    args = ["measure", "sim", cat, "-o", f"{sq}/", *FAST_SQUEEZE, "--partition-size", 2]
    _ok(_cli(*args, "--workers", 1))
    _ok(_cli("characterize", sq, "-o", tmp_path / "c.parquet", "--window-s", 0.03))
    logs = sorted((sq / "_logs").iterdir())
    for log in logs:  # the first layout: logs beside the rows
        log.rename(sq / log.name)
    (sq / "_logs").rmdir()
    _ok(_cli("characterize", sq, "-o", tmp_path / "old.parquet", "--window-s", 0.03))
    pd.testing.assert_frame_equal(read_table(tmp_path / "old.parquet", "coefficients"),
                                  read_table(tmp_path / "c.parquet", "coefficients"))  # fmt: skip
    result = _cli(*args, "--workers", 1, "--resume")  # keeps every part, moves the logs
    _ok(result)
    assert sorted(p.name for p in (sq / "_logs").iterdir()) == [p.name for p in logs]
    assert not list(sq.glob("part-*.mcap"))


def _snapshot(path: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(path)): p.read_bytes() for p in sorted(path.rglob("*")) if p.is_file()
    }


def test_bad_sweep_inputs(serial_lift: tuple[Path, pd.DataFrame], tmp_path: Path) -> None:
    cat, _ = serial_lift
    base = ["lift", "sim", cat, *FAST_LIFT]
    # --workers 0, or a sweep flag with a single-file output: usage errors, nothing written
    _one_line_error(_cli(*base, "-o", f"{tmp_path / 'a'}/", "--workers", 0), 2,
                    "--workers must be >= 1, got 0")  # fmt: skip
    _one_line_error(_cli(*base, "-o", tmp_path / "a.parquet", "--partition-size", 2), 2,
                    "--partition-size needs a dataset directory output")  # fmt: skip
    assert not (tmp_path / "a").exists()
    assert not (tmp_path / "a.parquet").exists()

    # an unreachable scheduler: nothing listens, then a peer that never answers
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    t0 = time.monotonic()
    result = _cli(*base, "-o", f"{tmp_path / 'b'}/", "--scheduler", f"tcp://127.0.0.1:{port}",
                  "--connect-timeout", 2)  # fmt: skip
    _one_line_error(result, 1, f"cannot connect to the Dask scheduler at tcp://127.0.0.1:{port}")
    assert time.monotonic() - t0 < 2 + 2
    with socket.socket() as silent:
        silent.bind(("127.0.0.1", 0))
        silent.listen(4)
        address = f"tcp://127.0.0.1:{silent.getsockname()[1]}"
        t0 = time.monotonic()
        result = _cli(*base, "-o", f"{tmp_path / 'b'}/", "--scheduler", address,
                      "--connect-timeout", 1.5)  # fmt: skip
        elapsed_s = time.monotonic() - t0
    _one_line_error(result, 1, "no Dask scheduler answered within 1.5 s")
    assert 0.7 <= elapsed_s < 1.5 + 2.5
    assert not (tmp_path / "b").exists()

    # resume into a directory another command wrote, or one with another schema: exit 65
    sq = tmp_path / "sq"
    _ok(_cli("measure", "sim", cat, "-o", f"{sq}/", *FAST_SQUEEZE, "--objects", "P00,P01",
             "--workers", 1))  # fmt: skip
    before = _snapshot(sq)
    _one_line_error(_cli(*base, "-o", f"{sq}/", "--resume", "--objects", "P00,P01"), 65,
                    "cannot resume: made by a different command or settings")  # fmt: skip
    assert _snapshot(sq) == before
    lf = tmp_path / "lf"
    _ok(_cli(*base, "-o", f"{lf}/", "--objects", "P00,P01", "--workers", 1))
    manifest = json.loads((lf / "_sweep.json").read_text())
    manifest["schema"] = [f for f in manifest["schema"] if f["name"] != "error"]  # an older one
    (lf / "_sweep.json").write_text(json.dumps(manifest))
    before = _snapshot(lf)
    _one_line_error(_cli(*base, "-o", f"{lf}/", "--resume", "--objects", "P00,P01"), 65,
                    "cannot resume: made with a different schema")  # fmt: skip
    assert _snapshot(lf) == before
