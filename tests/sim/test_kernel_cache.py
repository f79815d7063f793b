"""The kernels' numba cache is keyed by every kernel source (deformctl.sim._kernel_cache).

numba alone keys a cached kernel on its own file, so a kernel that calls a kernel of another file
keeps its stale machine code after that file is edited (numba issue 1833). The test copies the
package, caches a kernel of ``step/delassus.py`` that calls ``ldl_solve`` of ``solver.py``, edits
``ldl_solve`` in the copy, and runs the caller again in a fresh process.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numba
from numba.core.caching import NullCache

import deformctl
from deformctl.sim import _kernel_cache
from deformctl.sim._kernel_cache import KernelCacheLocator, kernel_sources

#: runs ``_ensure_column`` (delassus.py) on the factor of the identity: its column is
#: ``ldl_solve``'s (solver.py) ``A^-1 e_0``, 1.0 at DOF 0 (2.0 once ``ldl_solve`` is edited)
CALLER = """
import json
import numpy as np
from deformctl.sim.solver import LDLFactor
from deformctl.sim.step.delassus import _ensure_column
eye = LDLFactor(np.zeros(3, dtype=np.int64), np.zeros(0, dtype=np.int32), np.zeros(0),
                np.ones(2), np.arange(2))
ext, n_ext = _ensure_column(0, np.full(2, -1), np.zeros((0, 2)), np.zeros((0, 2)), 0, eye)
stats = _ensure_column.stats
print(json.dumps({"value": ext[0, 0], "hits": sum(stats.cache_hits.values()),
                  "misses": sum(stats.cache_misses.values())}))
"""
EDIT = ("        out[perm[i]] = work[i]\n", "        out[perm[i]] = 2.0 * work[i]\n")


def _copy_package(tmp: Path) -> Path:
    root = tmp / "copy"
    shutil.copytree(
        Path(deformctl.__file__).parent,
        root / "deformctl",
        ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"),
    )
    return root


def _run(root: Path, guard: bool = True) -> dict[str, float]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_CACHE")}
    env["PYTHONPATH"] = str(root)
    if not guard:  # numba's own in-tree locator only: the guard is not consulted
        env["NUMBA_CACHE_LOCATOR_CLASSES"] = "InTreeCacheLocator"
    done = subprocess.run(
        [sys.executable, "-c", CALLER], cwd=root, env=env, capture_output=True, text=True,
        timeout=300, check=True,
    )  # fmt: skip
    return json.loads(done.stdout.strip().splitlines()[-1])  # type: ignore[no-any-return]


def _edit_ldl_solve(root: Path) -> None:
    path = root / "deformctl" / "sim" / "solver.py"
    text = path.read_text()
    assert text.count(EDIT[0]) == 1
    path.write_text(text.replace(*EDIT))


def test_an_edited_dependency_is_not_served_from_a_stale_cache(tmp_path: Path) -> None:
    guarded = _copy_package(tmp_path / "guarded")
    first = _run(guarded)
    assert first == {"value": 1.0, "hits": 0, "misses": 1}
    again = _run(guarded)
    assert again == {"value": 1.0, "hits": 1, "misses": 0}  # the cache is used while fresh
    _edit_ldl_solve(guarded)
    edited = _run(guarded)
    assert edited == {"value": 2.0, "hits": 0, "misses": 1}  # compiled afresh, not loaded


def test_without_the_guard_numba_serves_the_stale_kernel(tmp_path: Path) -> None:
    """The hazard the guard removes (so the test above can fail): numba's own stamp."""
    plain = _copy_package(tmp_path / "plain")
    assert _run(plain, guard=False)["value"] == 1.0
    _edit_ldl_solve(plain)
    stale = _run(plain, guard=False)
    assert stale == {"value": 1.0, "hits": 1, "misses": 0}


def test_every_cached_kernel_of_the_simulator_is_guarded() -> None:
    """Every numba kernel of deformctl.sim caches through the guard, and its file is one of the
    hashed kernel sources (so are the argument bundles' modules)."""
    import importlib
    import pkgutil

    import deformctl.sim

    sources = set(kernel_sources())
    kernels = 0
    for info in pkgutil.walk_packages(deformctl.sim.__path__, "deformctl.sim."):
        module = importlib.import_module(info.name)
        for value in vars(module).values():
            if isinstance(value, numba.core.registry.CPUDispatcher) and value.__module__ == (
                info.name
            ):
                kernels += 1
                cache = value._cache
                assert not isinstance(cache, NullCache), value
                assert isinstance(cache._impl.locator, KernelCacheLocator), value
                assert Path(value.py_func.__code__.co_filename).resolve() in sources, value
            bundle = (
                isinstance(value, type) and issubclass(value, tuple) and hasattr(value, "_fields")
            )
            if bundle and value.__module__ == info.name:
                assert Path(module.__file__ or "").resolve() in sources, value
    assert kernels >= 50
    assert KernelCacheLocator in numba.core.caching.CacheImpl._locator_classes
    assert Path(deformctl.sim.__file__).resolve().parent == _kernel_cache.SIM_DIR
