"""Executed docs: every ``sh`` block of README.md runs, in order, in one scratch folder.

The scratch folder links the checkout's ``datasets/``, ``examples/`` and ``tests/`` (the README's
commands name them) and nothing else: the rig recordings the measure examples read are the
bundled ``datasets/examples/``. ``python``, ``python3`` and ``deformctl`` are the test
interpreter's (an activated ``.venv``). A block preceded by
``<!-- docs-test: skip (why) -->`` is not run (the reason is part of the README); every other
block must exit 0, and the test names the first one that does not.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

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


def test_every_readme_shell_block_runs(tmp_path: Path) -> None:
    for name in ("datasets", "examples", "tests"):
        (tmp_path / name).symlink_to(REPO / name)
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
