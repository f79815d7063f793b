"""The bundled sample recordings and guide inputs, copied into a folder a wheel user works in.

The guides name their inputs as a checkout has them: ``datasets/examples/gripper.mcap``,
``datasets/paper/objects.csv``, ``examples/threshold_rig.py``. A wheel installs them as the
package data ``deformctl.datasets`` and ``deformctl.examples``; :func:`copy_examples` writes
them under ``DIR/datasets/`` and ``DIR/examples/`` (``deformctl examples DIR``), so every guide
command runs unchanged from ``DIR``. Package files (``__init__.py``, caches) are left out.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from importlib.resources import files
from importlib.resources.abc import Traversable
from os import PathLike
from pathlib import Path, PurePosixPath

from deformctl.errors import OutputExistsError, UsageError

#: The package data copied, and the folder of DIR each goes to.
SOURCES: tuple[tuple[str, str], ...] = (
    ("deformctl.datasets", "datasets"),
    ("deformctl.examples", "examples"),
)
#: Names never copied: the files that make a folder a Python package, and caches.
SKIPPED: frozenset[str] = frozenset({"__init__.py", "__pycache__", ".DS_Store"})


def _walk(node: Traversable, at: PurePosixPath) -> list[tuple[Traversable, PurePosixPath]]:
    out: list[tuple[Traversable, PurePosixPath]] = []
    for child in sorted(node.iterdir(), key=lambda c: c.name):
        if child.name in SKIPPED or child.name.endswith((".pyc", ".tmp")):
            continue
        if child.is_dir():
            out.extend(_walk(child, at / child.name))
        elif child.is_file():
            out.append((child, at / child.name))
    return out


def example_files() -> list[tuple[Traversable, PurePosixPath]]:
    """Every bundled file :func:`copy_examples` copies, with its path under DIR, sorted."""
    found = [
        pair for package, folder in SOURCES for pair in _walk(files(package), PurePosixPath(folder))
    ]
    return sorted(found, key=lambda pair: str(pair[1]))


def copy_examples(dest: str | PathLike[str], *, force: bool = False) -> list[PurePosixPath]:
    """Copy the bundled samples and guide inputs into ``dest`` (created with its parents).

    An existing ``dest`` that holds anything is refused unless ``force``; with ``force`` the
    bundled files are written over their copies and other files in ``dest`` are kept. Nothing
    half-written is left: a new folder is filled next to ``dest`` and renamed into place, and
    each file overwritten with ``force`` is replaced whole.

    Returns:
        The paths written, relative to ``dest``.

    Raises:
        UsageError: ``dest`` is a file, or names stdout (exit 2).
        OutputExistsError: ``dest`` holds files and ``force`` is false (exit 1).
    """
    target = Path(dest)
    if str(dest) in ("", "-"):
        raise UsageError("examples: give a folder to copy the samples into, not stdout")
    if target.exists() and not target.is_dir():
        raise UsageError(f"{target}: is a file; give a folder to copy the samples into")
    pairs = example_files()
    if target.is_dir() and any(target.iterdir()):
        if not force:
            raise OutputExistsError(target)
        for source, rel in pairs:
            path = target.joinpath(*rel.parts)
            path.parent.mkdir(parents=True, exist_ok=True)
            _write_whole(source, path)
        return [rel for _, rel in pairs]
    target.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{target.name}.deformctl-", dir=target.parent))
    try:
        for source, rel in pairs:
            path = staging.joinpath(*rel.parts)
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(source.read_bytes())
        umask = os.umask(0)
        os.umask(umask)
        staging.chmod(0o777 & ~umask)  # as a folder made by mkdir (mkdtemp's is private)
        if target.is_dir():
            target.rmdir()  # empty: replaced by the filled folder
        os.replace(staging, target)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    return [rel for _, rel in pairs]


def _write_whole(source: Traversable, path: Path) -> None:
    """Write ``source``'s bytes to ``path`` through a temporary file in its folder."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.deformctl-", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(source.read_bytes())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


__all__ = ["SOURCES", "copy_examples", "example_files"]
