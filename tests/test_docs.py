"""Executed docs: every ``sh`` block of README.md and of each page under docs/ runs.

Each file's blocks run in order in one scratch folder of their own, which links the checkout's
``datasets/``, ``examples/`` and ``tests/`` (the docs' commands name them) and nothing else.
``python``, ``python3`` and ``deformctl`` are the test interpreter's (an activated ``.venv``). A
block preceded by ``<!-- docs-test: skip (why) -->`` is not run (the reason is part of the page);
every other block must exit 0, and the test names the file, line and block that did not. The CLI
reference (docs/reference/cli.md) must be what ``python -m deformctl.cli.reference`` prints now,
and every relative link of the docs must name a file that exists.
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
LINK = re.compile(r"\]\((?!https?://|#|mailto:)(?P<target>[^)#\s]+)(?:#[^)]*)?\)")
#: The README stays short: what, for whom, install, a first example and links (issue 31).
README_MAX_LINES = 150


def doc_files() -> list[Path]:
    """README.md and every Markdown page under docs/, in a fixed order."""
    return [REPO / "README.md", *sorted((REPO / "docs").rglob("*.md"))]


def shell_blocks(path: Path) -> list[tuple[int, str, str | None]]:
    """``(line, code, skip reason)`` of every ``sh`` block of ``path``, in order."""
    text = path.read_text(encoding="utf-8")
    return [
        (text.count("\n", 0, m.start("code")), m["code"], m["why"]) for m in BLOCK.finditer(text)
    ]


def _id(path: Path) -> str:
    return str(path.relative_to(REPO))


RUNNABLE = [p for p in doc_files() if shell_blocks(p)]


@pytest.mark.slow
@pytest.mark.parametrize("path", RUNNABLE, ids=_id)
def test_every_shell_block_runs(path: Path, tmp_path: Path) -> None:
    for name in ("datasets", "examples", "tests"):
        (tmp_path / name).symlink_to(REPO / name)
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    for line, code, why in shell_blocks(path):
        if why is not None:
            assert why.strip(), f"{_id(path)}:{line}: a skipped block must say why"
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
            pytest.fail(f"{_id(path)}:{line}: block exited {proc.returncode}:\n{code}\n{tail}")


def test_cli_reference_is_current() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "deformctl.cli.reference", "--check", "docs/reference/cli.md"],
        cwd=REPO,
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr


def test_readme_is_short_and_links_the_docs() -> None:
    text = (REPO / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) <= README_MAX_LINES
    for page in ("docs/guide/", "docs/explanation/", "docs/reference/cli.md"):
        assert page in text, page


@pytest.mark.parametrize("path", doc_files(), ids=_id)
def test_relative_links_name_existing_files(path: Path) -> None:
    text = path.read_text(encoding="utf-8")
    text = re.sub(r"```.*?```", "", text, flags=re.S)
    missing = [m["target"] for m in LINK.finditer(text) if not (path.parent / m["target"]).exists()]
    assert not missing, f"{_id(path)}: links to missing files: {missing}"
