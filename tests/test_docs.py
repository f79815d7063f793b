"""Executed docs: every ``sh`` block of README.md runs, in order, in one scratch folder.

The scratch folder links the checkout's ``datasets/``, ``examples/`` and ``tests/`` (the README's
commands name them) and holds the files a user would bring: the ROS 2 bags ``run.mcap`` and
``gripper.mcap`` and the CSV export ``export.csv`` the measure examples read. ``python``,
``python3`` and ``deformctl`` are the test interpreter's. A block preceded by
``<!-- docs-test: skip (why) -->`` is not run (the reason is part of the README); every other
block must exit 0, and the test names the first one that does not.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from test_measure_ingest import JOINTS, write_bag

from deformctl.characterize import synthetic_kelvin_voigt_squeeze

REPO = Path(__file__).resolve().parents[1]
BLOCK = re.compile(
    r"(?:<!-- docs-test: skip \((?P<why>[^)]*)\) -->\n)?```sh\n(?P<code>.*?)```", re.S
)


def readme_blocks() -> list[tuple[int, str, str | None]]:
    """``(line, code, skip reason)`` of every ``sh`` block of README.md, in order."""
    text = (REPO / "README.md").read_text(encoding="utf-8")
    return [
        (text.count("\n", 0, m.start("code")), m["code"], m["why"]) for m in BLOCK.finditer(text)
    ]


def _user_files(folder: Path) -> None:
    """The recordings the README's measure examples read: two bags and a CSV export."""
    write_bag(folder / "run.mcap", 30.02, 0.47, seed=1)
    write_bag(folder / "gripper.mcap", 13.03, 0.33, seed=2, joint_state=True,
              wrench_topics=("/ft",))  # fmt: skip
    assert JOINTS == "/joint_states"
    s = synthetic_kelvin_voigt_squeeze(49.18, 6.47, peak_force_n=2.0, seed=3)
    width_mm = 100.0 - 1000.0 * s.compression_m  # the gripper's opening, mm
    rows = np.column_stack([s.time_s, s.force_n, width_mm])
    np.savetxt(folder / "export.csv", rows, delimiter=",", header="t,load,width", comments="")


def test_every_readme_shell_block_runs(tmp_path: Path) -> None:
    for name in ("datasets", "examples", "tests"):
        (tmp_path / name).symlink_to(REPO / name)
    _user_files(tmp_path)
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    blocks = readme_blocks()
    assert len(blocks) > 10
    for line, code, why in blocks:
        if why is not None:
            assert why.strip(), f"README.md:{line}: a skipped block must say why"
            continue
        proc = subprocess.run(
            ["bash", "-e", "-o", "pipefail", "-c", code],
            cwd=tmp_path,
            env=env,
            capture_output=True,
            text=True,
            check=False,
        )
        if proc.returncode != 0:
            tail = "\n".join((proc.stdout + proc.stderr).strip().splitlines()[-8:])
            pytest.fail(f"README.md:{line}: block exited {proc.returncode}:\n{code}\n{tail}")
