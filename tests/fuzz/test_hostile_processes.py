"""No process outlives its client, and a rig timeout holds."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from deformctl.errors import RigError
from deformctl.lift.runners.rig import RigRunner

pytestmark = pytest.mark.e2e

OBJECT = {"object_id": "sponge", "weight_n": 10.0, "friction_mu": 0.5, "size_cm": [8, 5, 4]}

#: A rig whose grandchild starts its own session (out of the rig's process group) and keeps the
#: rig's stdout open; the rig itself then hangs.
ESCAPING_RIG = """
import os, sys, time
sys.stdin.read()
if os.fork() == 0:
    os.setsid()
    with open(sys.argv[1], "w") as f:
        f.write(str(os.getpid()))
    time.sleep(60)
    os._exit(0)
time.sleep(60)
"""


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    stat = Path(f"/proc/{pid}/stat")
    return not (stat.exists() and stat.read_text().split()[2] == "Z")


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="needs /proc")
def test_the_rig_timeout_holds_whatever_the_rig_spawns(tmp_path: Path) -> None:
    pid_file = tmp_path / "grandchild.pid"
    runner = RigRunner(
        [sys.executable, "-c", ESCAPING_RIG, str(pid_file)], timeout_s=1.0, object=OBJECT
    )
    start = time.monotonic()
    with pytest.raises(RigError, match="no answer within 1 s"):
        runner(10.0, 0)
    assert time.monotonic() - start < 8  # 1 s timeout + 2 s drain, not the grandchild's 60 s
    os.kill(int(pid_file.read_text()), signal.SIGKILL)  # it left the group: ours to clean up


def _group(pgid: int) -> list[int]:
    """Live (non-zombie) processes of process group ``pgid``, from /proc."""
    out = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[2]) == pgid and fields[0] != "Z":
            out.append(int(entry.name))
    return out


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="needs /proc")
@pytest.mark.parametrize("output", ["d/", "lift.parquet"])
def test_a_killed_sweep_client_leaves_no_process_behind(tmp_path: Path, output: str) -> None:
    """A dataset sweep and a single-file lift on two workers: kill -9 the client."""
    rows = [f"o{i},20,20,20,1.0,0.5,5,1" for i in range(40)]
    cat = tmp_path / "cat.csv"
    header = "object_id,size_x_cm,size_y_cm,size_z_cm,weight_n,friction_mu"
    cat.write_text(header + ",material_stiffness_n_per_cm,material_damping_ns_per_cm\n")
    with cat.open("a") as fh:
        fh.write("\n".join(rows) + "\n")
    argv = [sys.executable, "-m", "deformctl", "lift", "sim", str(cat), "--workers", "2"]
    client = subprocess.Popen(
        [*argv, "-o", str(tmp_path / output)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,  # its pid is the group of everything it starts
    )
    deadline = time.monotonic() + 120
    while len(_group(client.pid)) < 4 and time.monotonic() < deadline:  # client, server, 2 workers
        time.sleep(0.2)
    assert len(_group(client.pid)) >= 4, "the sweep did not start its workers"
    os.kill(client.pid, signal.SIGKILL)
    client.wait()
    deadline = time.monotonic() + 5
    while _group(client.pid) and time.monotonic() < deadline:
        time.sleep(0.1)
    left = _group(client.pid)
    for pid in left:  # do not leave them to the next test either
        os.kill(pid, signal.SIGKILL)
    assert left == [], f"{len(left)} processes outlived their client by 5 s"
    if not output.endswith("/"):  # a single file is written at the end: nothing yet
        assert not (tmp_path / output).exists()
