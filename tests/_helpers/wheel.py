"""The wheel of the current source tree, and a fresh venv with it installed, once per session.

:func:`wheel_file`, :func:`fresh_venv` and :func:`warm_venv` are fixtures (offered to every test
by ``tests/conftest.py``; tests/test_wheel.py and tests/test_docs.py use them). Each is made once
per ``make test``, not once per xdist worker: the first worker that asks makes it in the
session's shared temporary folder while the other waits (:func:`made_once`). The wheel is built
from a clean copy of the tree (no build isolation, so nothing is downloaded); the venv gets it
with ``pip install --no-deps --no-index`` and reaches the test environment's dependencies
through a ``.pth`` line that adds its site-packages *after* the venv's own, where the installed
deformctl comes first (the ``.pth`` files there, among them the editable install's, are not
read). Building and installing take a few seconds; nothing is fetched from a registry.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
from collections.abc import Callable
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
#: What a clean copy of the tree leaves out: environments, caches, build and run outputs.
SKIP = (".venv", ".git", "build", "dist", "*.egg-info", "__pycache__", ".*_cache", ".examples",
        "reports")  # fmt: skip


def made_once(
    tmp_path_factory: pytest.TempPathFactory, name: str, make: Callable[[Path], None]
) -> Path:
    """The folder ``name`` that ``make(folder)`` filled once for the whole session: the session's
    temporary folder is shared by the xdist workers, so the first worker to ask makes it (under a
    file lock; the other waits for it) and every later ask finds it. A ``make`` that failed
    leaves no folder, and the next ask tries again."""
    import fcntl  # POSIX only, as are the venvs' bin/ and the docs' bash

    root = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        root = root.parent  # .../pytest-N/ above each worker's popen-gwN/
    folder, done = root / name, root / f"{name}.done"
    with (root / f"{name}.lock").open("w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not done.exists():
            shutil.rmtree(folder, ignore_errors=True)
            folder.mkdir()
            make(folder)
            done.touch()
    return folder


@pytest.fixture(scope="session")
def wheel_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The wheel of the current source tree, built from a clean copy (once per session)."""

    def build(tmp: Path) -> None:
        src = tmp / "src"
        shutil.copytree(REPO, src, ignore=shutil.ignore_patterns(*SKIP))
        subprocess.run(
            [sys.executable, "-m", "pip", "wheel", str(src), "--no-deps", "--no-build-isolation",
             "-w", str(tmp / "dist"), "-q"],
            check=True,
            capture_output=True,
        )  # fmt: skip
        shutil.rmtree(src)

    (wheel,) = (made_once(tmp_path_factory, "wheel", build) / "dist").glob("deformctl-*.whl")
    return wheel


@pytest.fixture(scope="session")
def fresh_venv(wheel_file: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A new virtual environment with ``pip install dist/deformctl-*.whl`` done (no download:
    the dependencies are the test environment's, after the venv's own site-packages); once per
    session."""

    def install(venv: Path) -> None:
        subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
        python = venv / "bin" / "python"
        subprocess.run(
            [sys.executable, "-m", "pip", "--python", str(python), "install", "--no-deps",
             "--no-index", "-q", str(wheel_file)],
            check=True,
            capture_output=True,
        )  # fmt: skip
        site = subprocess.run(
            [str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
            check=True,
            capture_output=True,
            text=True,
        ).stdout.strip()
        Path(site, "test_dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")

    return made_once(tmp_path_factory, "venv", install)


@pytest.fixture(scope="session")
def warm_venv(fresh_venv: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """:func:`fresh_venv` as a wheel user leaves it after ``pip install`` and ``deformctl
    warmup`` (once per session, as a user does once per install). The simulator's kernels come
    compiled from the checkout (:func:`seed_kernel_cache`): the warm-up loads them instead of
    compiling for a minute of CPU, and compiles what the checkout lacks (the scene writer's
    kernels, cached under their own file's time stamp)."""

    def warm(folder: Path) -> None:
        seed_kernel_cache(fresh_venv)
        subprocess.run([fresh_venv / "bin" / "deformctl", "warmup"], cwd=folder,
                       env=venv_env(fresh_venv), capture_output=True, check=True)  # fmt: skip

    made_once(tmp_path_factory, "warm", warm)
    return fresh_venv


def venv_env(venv: Path) -> dict[str, str]:
    """The environment of a wheel user who activated ``venv``: its ``bin/`` first on PATH and
    the test interpreter's folder off it, no ``PYTHONPATH``, numba's cache beside the sources
    (no ``NUMBA_CACHE_DIR``)."""
    own = str(Path(sys.executable).parent)
    path = [str(venv / "bin")] + [p for p in os.environ["PATH"].split(os.pathsep) if p != own]
    drop = ("PYTHONPATH", "VIRTUAL_ENV", "NUMBA_CACHE_DIR")
    env = {k: v for k, v in os.environ.items() if k not in drop}
    return {**env, "PATH": os.pathsep.join(path), "VIRTUAL_ENV": str(venv)}


def seed_kernel_cache(venv: Path) -> int:
    """Copy the checkout's compiled simulator kernels (numba's ``__pycache__`` beside the
    sources, written by ``make install``'s warm-up) beside the same sources in ``venv``; the
    number of files copied.

    The simulator's kernels are cached under a hash of their sources' contents
    (deformctl/sim/_kernel_cache.py), not of the files' paths or times, so the installed wheel
    loads them instead of compiling for a minute of CPU; a kernel whose sources differ from
    the checkout's compiled ones is compiled as on any first use. (tests/test_wheel.py compiles
    every kernel in a fresh install.) Nothing is copied when the checkout keeps its cache
    elsewhere (``NUMBA_CACHE_DIR``)."""
    site = next((venv / "lib").glob("python*/site-packages"))
    copied = 0
    if os.environ.get("NUMBA_CACHE_DIR"):
        return copied
    for cached in sorted((REPO / "deformctl" / "sim").rglob("__pycache__/*.nb[ic]")):
        target = site / cached.relative_to(REPO)
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(cached, target)
        copied += 1
    return copied
