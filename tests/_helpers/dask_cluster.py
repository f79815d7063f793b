"""A real Dask cluster for sweep tests: a scheduler and two workers as separate processes.

:func:`dask_cluster` (a fixture, offered to every test by ``tests/conftest.py``) starts
``dask scheduler --port 0`` on 127.0.0.1, which writes its address to a scheduler file, and two
single-thread workers without a nanny (so killing one really removes it), and stops them after
the test.
"""

from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

START_TIMEOUT_S = 45.0


@dataclass
class Cluster:
    address: str
    scheduler: subprocess.Popen[bytes]
    workers: list[subprocess.Popen[bytes]]


def _stop(proc: subprocess.Popen[bytes]) -> None:
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=5)


@pytest.fixture
def dask_cluster(tmp_path: Path) -> Iterator[Cluster]:
    """A scheduler and two single-thread workers, each its own process; stopped afterwards."""
    import distributed

    sched_file = tmp_path / "scheduler.json"
    log = open(tmp_path / "cluster.log", "wb")  # noqa: SIM115 - closed in the finally below
    common = {"env": os.environ.copy(), "stdout": log, "stderr": subprocess.STDOUT}
    procs: list[subprocess.Popen[bytes]] = []
    try:
        scheduler = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "distributed.cli.dask_scheduler",
                "--host",
                "127.0.0.1",
                "--port",
                "0",
                "--no-dashboard",
                "--scheduler-file",
                str(sched_file),
            ],
            **common,  # type: ignore[call-overload]
        )
        procs.append(scheduler)
        deadline = time.monotonic() + START_TIMEOUT_S
        address = None
        while address is None:
            assert scheduler.poll() is None, "the scheduler exited"
            assert time.monotonic() < deadline, "the scheduler did not start"
            with contextlib.suppress(OSError, ValueError, KeyError):
                address = json.loads(sched_file.read_text())["address"]
            time.sleep(0.1)
        workers = [
            subprocess.Popen(
                [
                    sys.executable,
                    "-m",
                    "distributed.cli.dask_worker",
                    address,
                    "--name",
                    f"w{n}",
                    "--nthreads",
                    "1",
                    "--no-nanny",
                    "--no-dashboard",
                    "--host",
                    "127.0.0.1",
                    "--memory-limit",
                    "0",
                    "--death-timeout",
                    "30",
                ],
                **common,  # type: ignore[call-overload]
            )
            for n in range(2)
        ]
        procs.extend(workers)
        with distributed.Client(address, timeout=10, set_as_default=False) as client:
            client.wait_for_workers(2, timeout=START_TIMEOUT_S)
        yield Cluster(address, scheduler, workers)
    finally:
        for proc in reversed(procs):
            _stop(proc)
        log.close()
