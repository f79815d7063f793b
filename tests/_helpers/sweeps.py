"""The sweep tests' toy task: a seeded computation per object whose rows are known in advance.

:func:`toy_task` computes object i's rows from its seed (and fails for :data:`FAILING_ID`);
:func:`expected_rows` recomputes them directly, without the executor, so every dataset is checked
against a direct answer. :func:`sweep` runs the executor on the toy task with small parts.
"""

from __future__ import annotations

import atexit
import os
import shutil
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow as pa

from deformctl.artifacts.dataset import PartPayloads
from deformctl.artifacts.io import atomic_write_bytes
from deformctl.errors import SearchError
from deformctl.parallel import TaskOutput, run_sweep

REPO = Path(__file__).resolve().parents[2]
SCHEMA = pa.schema(
    [
        pa.field("object_id", pa.string(), nullable=False),
        pa.field("trial", pa.int64(), nullable=False),
        pa.field("force_n", pa.float64(), nullable=False),
    ]
)


FINGERPRINT = {"command": "toy", "settings": {"scale": 2.5}, "version": "test"}
FAILING_ID = "obj-07"

# Worker processes (the fork server of Python 3.11 ignores the parent's sys.path, and Dask
# workers are separate programs) import this module by name, so the ``tests`` package goes on
# PYTHONPATH for the rest of the session, through a folder that holds nothing else: the
# checkout itself would also offer its deformctl.egg-info, and pip (test_wheel's fresh venv)
# would then take the wheel's deformctl for installed and skip it.
# The worker processes that import this module inherit the folder and make none of their own.
if "DEFORMCTL_TESTS_IMPORT_ROOT" not in os.environ:
    _import_root = Path(tempfile.mkdtemp(prefix="deformctl-tests-"))
    (_import_root / "tests").symlink_to(REPO / "tests", target_is_directory=True)
    atexit.register(shutil.rmtree, _import_root, True)
    os.environ["DEFORMCTL_TESTS_IMPORT_ROOT"] = str(_import_root)
    os.environ["PYTHONPATH"] = os.pathsep.join(
        p for p in (str(_import_root), os.environ.get("PYTHONPATH", "")) if p
    )


def make_items(n: int = 20, sleep_s: float = 0.0) -> list[dict[str, Any]]:
    """``n`` objects; object i has seed 1000+i and i % 3 rows; ``FAILING_ID`` raises."""
    return [
        {"object_id": f"obj-{i:02d}", "seed": 1000 + i, "n_rows": i % 3, "sleep_s": sleep_s}
        for i in range(n)
    ]


def toy_task(item: dict[str, Any]) -> list[dict[str, Any]]:
    """Seeded per-object computation; raises a DeformctlError for ``FAILING_ID``."""
    if item["sleep_s"]:
        time.sleep(item["sleep_s"])
    if item["object_id"] == FAILING_ID:
        raise SearchError(f"lift search for {item['object_id']} did not converge\nafter 9 steps")
    rng = np.random.default_rng(item["seed"])
    force_n = 2.5 * rng.normal(size=item["n_rows"])
    return [{"trial": t, "force_n": float(f)} for t, f in enumerate(force_n)]


def toy_task_with_payload(item: dict[str, Any]) -> TaskOutput:
    """The toy rows plus a bytes payload naming the object (a stand-in for an MCAP log)."""
    return TaskOutput(toy_task(item), f"log of {item['object_id']}".encode())


@dataclass(frozen=True)
class PidLogWriter:
    """A part writer run by the workers: writes its pid, whether the part's rows file already
    existed when it started, and the payloads; it is slow, so a commit race would show."""

    sleep_s: float = 0.1
    fail_part: int | None = None
    in_workers = True

    def __call__(self, part: PartPayloads) -> None:
        if part.index == self.fail_part:
            raise RuntimeError(f"disk full while writing part {part.index}")
        rows_before = (part.out_dir / f"part-{part.index:05d}.parquet").exists()
        time.sleep(self.sleep_s)
        head = f"pid={os.getpid()} rows_before={rows_before}\n".encode()
        atomic_write_bytes(part.path(".log"), head + b"\n".join(p for _, p in part.payloads))


def bad_rows_task(item: dict[str, Any]) -> list[dict[str, Any]]:
    """Returns a row with an extra column for one object (a schema mismatch)."""
    if item["object_id"] == "obj-03":
        return [{"trial": 0, "force_n": 1.0, "speed_m_per_s": 2.0}]
    return toy_task(item)


def expected_rows(items: list[dict[str, Any]]) -> pd.DataFrame:
    """The rows computed directly, in catalog order, without the executor."""
    recs = []
    for item in items:
        if item["object_id"] == FAILING_ID:
            continue
        rng = np.random.default_rng(item["seed"])
        for t, f in enumerate(2.5 * rng.normal(size=item["n_rows"])):
            recs.append({"object_id": item["object_id"], "trial": t, "force_n": float(f)})
    return pa.Table.from_pylist(recs, schema=SCHEMA).to_pandas()


def sweep(items: list[dict[str, Any]], out: Path, **kw: Any) -> Any:
    kw.setdefault("partition_size", 3)
    kw.setdefault("progress", False)
    kw.setdefault("schema", SCHEMA)
    kw.setdefault("fingerprint", FINGERPRINT)
    task = kw.pop("task", toy_task)
    return run_sweep(task, items, out_dir=out, **kw)


def snapshot(path: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(path)): p.read_bytes() for p in sorted(path.rglob("*")) if p.is_file()
    }


def half_sent_result_task(item: dict[str, Any]) -> list[dict[str, Any]]:
    """The toy task, but the worker that runs ``obj-03`` dies half-way through sending a result:
    it writes a message header and part of the message onto the pool's result pipe, then
    SIGKILLs itself (a worker killed while its result is on the way)."""
    if item["object_id"] == "obj-03":
        import gc
        import multiprocessing.queues
        import signal
        import struct

        (results,) = [o for o in gc.get_objects() if type(o) is multiprocessing.queues.SimpleQueue]
        os.write(results._writer.fileno(), struct.pack("!i", 1 << 20) + b"\x80" * 100)
        os.kill(os.getpid(), signal.SIGKILL)
    return toy_task(item)


def _half_sent_main(out_dir: str) -> None:
    """Entry point of the subprocess whose worker dies half-way through sending a result."""
    sweep(make_items(20), Path(out_dir), workers=2, task=half_sent_result_task)


def _client_main(out_dir: str) -> None:
    """Entry point of the subprocess the client-kill test SIGKILLs part-way."""
    sweep(make_items(20, sleep_s=0.15), Path(out_dir), workers=1, partition_size=2)
