"""Sweeps on a real Dask cluster: a scheduler and two workers as separate processes on 127.0.0.1.

Each test that needs a cluster starts its own (``dask scheduler --port 0`` writes its address to
a scheduler file; the workers run without a nanny so killing one really removes it) and stops it
afterwards. Rows are compared with the direct computation of
``tests._helpers.sweeps.expected_rows`` and with a local run of the same sweep.
"""

from __future__ import annotations

import signal
import socket
import threading
import time
from pathlib import Path
from typing import Any

import pandas as pd
import pytest

from deformctl.artifacts.dataset import read_dataset, read_failures
from deformctl.errors import DeformctlError
from tests._helpers.dask_cluster import Cluster
from tests._helpers.sweeps import expected_rows, make_items, snapshot, sweep


def test_dask_sweep_gives_the_local_rows(dask_cluster: Cluster, tmp_path: Path) -> None:
    items = make_items(20)
    s = sweep(items, tmp_path / "dask", scheduler=dask_cluster.address, connect_timeout_s=10)
    sweep(items, tmp_path / "local", workers=2)
    assert (s.done, s.failed, s.parts) == (19, 1, 7)
    pd.testing.assert_frame_equal(read_dataset(tmp_path / "dask"), expected_rows(items))
    assert snapshot(tmp_path / "dask") == snapshot(tmp_path / "local")
    assert read_failures(tmp_path / "dask")["cause"].tolist() == ["not_converged"]


def test_killing_a_dask_worker_mid_sweep_loses_nothing(
    dask_cluster: Cluster, tmp_path: Path
) -> None:
    items = make_items(20, sleep_s=0.25)
    out = tmp_path / "o"
    result: dict[str, Any] = {}

    def run() -> None:
        try:
            result["summary"] = sweep(
                items, out, scheduler=dask_cluster.address, partition_size=2, max_in_flight=4
            )
        except BaseException as err:
            result["error"] = err

    thread = threading.Thread(target=run)
    thread.start()
    deadline = time.monotonic() + 60
    while not (out / "part-00000.parquet").exists():
        assert thread.is_alive(), f"the sweep ended early: {result}"
        assert time.monotonic() < deadline, "no part written within 60 s"
        time.sleep(0.02)
    victim = dask_cluster.workers[0]
    victim.send_signal(signal.SIGKILL)
    victim.wait(timeout=10)
    parts_at_kill = len(list(out.glob("part-*.parquet")))
    thread.join(timeout=90)
    assert not thread.is_alive(), "the sweep did not finish after the worker was killed"
    assert "error" not in result, result.get("error")
    assert victim.returncode == -signal.SIGKILL
    assert parts_at_kill < 10  # the kill happened part-way
    s = result["summary"]
    assert (s.done, s.failed, s.skipped_resumed) == (19, 1, 0)
    got = read_dataset(out)
    pd.testing.assert_frame_equal(got, expected_rows(items))
    assert not got.duplicated(["object_id", "trial"]).any()


def test_unreachable_scheduler_fails_within_the_connect_timeout(tmp_path: Path) -> None:
    # nothing listens: refused at once
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        closed_port = s.getsockname()[1]
    t0 = time.monotonic()
    with pytest.raises(DeformctlError) as info:
        sweep(make_items(3), tmp_path / "a", scheduler=f"tcp://127.0.0.1:{closed_port}")
    assert time.monotonic() - t0 < 10 + 3
    assert str(info.value).startswith(
        f"cannot connect to the Dask scheduler at tcp://127.0.0.1:{closed_port}: "
    )
    assert "\n" not in str(info.value)
    assert not (tmp_path / "a").exists()

    # something accepts the connection but never speaks Dask: the timeout bounds the wait
    timeout_s = 2.0
    with socket.socket() as silent:
        silent.bind(("127.0.0.1", 0))
        silent.listen(8)
        address = f"tcp://127.0.0.1:{silent.getsockname()[1]}"
        t0 = time.monotonic()
        with pytest.raises(DeformctlError, match="no Dask scheduler answered within 2 s") as info:
            sweep(make_items(3), tmp_path / "b", scheduler=address, connect_timeout_s=timeout_s)
        elapsed_s = time.monotonic() - t0
    assert timeout_s * 0.5 <= elapsed_s < timeout_s + 3.0
    assert "\n" not in str(info.value)
    assert not (tmp_path / "b").exists()
