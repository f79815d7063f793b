"""numba's on-disk cache of the simulator's kernels, keyed by every kernel source.

numba keys a cached kernel on its own source file only: a kernel that calls a kernel of another
file (the step loops call the multigrid CG, the CG the stencil sweeps, the sweeps the neighbour
sums) keeps loading its cached machine code after that other file is edited (numba issue 1833),
and once golden files were regenerated on such stale kernels. Here every kernel of
:mod:`deformctl.sim` is cached under one stamp instead: a hash of every *kernel source*, that is
every module of the package that imports numba (its kernels and the constants they read) or
defines a ``NamedTuple`` (the argument bundles the kernels are compiled for). Editing any of them
makes every cached kernel stale, and the next process compiles afresh (``make install``'s
warm-up, ``python -m deformctl.sim.warmup``, does it once for everyone).

The cache stays where numba puts it (``__pycache__`` beside the sources, or ``NUMBA_CACHE_DIR``):
:class:`KernelCacheLocator` wraps numba's own locators and only replaces the stamp. It is
registered when :mod:`deformctl.sim` is imported, before any kernel is decorated (a kernel's
cache locator is chosen at decoration). Setting ``NUMBA_CACHE_LOCATOR_CLASSES`` replaces numba's
list of locators and so turns the guard off.
"""

from __future__ import annotations

import functools
import hashlib
import re
from pathlib import Path
from typing import Any

from numba.core.caching import CacheImpl, _CacheLocator

#: the package whose kernels are guarded
SIM_DIR = Path(__file__).resolve().parent
_SELF = Path(__file__).resolve()
_KERNEL_SOURCE = re.compile(r"^(?:from numba\b|import numba\b|class \w+\(NamedTuple\))", re.M)


def kernel_sources() -> list[Path]:
    """The kernel sources of :mod:`deformctl.sim` (see the module docs; this module, which
    compiles nothing, is not one), sorted."""
    return [
        path
        for path in sorted(SIM_DIR.rglob("*.py"))
        if path != _SELF and _KERNEL_SOURCE.search(path.read_text(encoding="utf-8"))
    ]


@functools.cache
def sources_digest() -> str:
    """SHA-256 of the kernel sources' paths (relative to the package) and contents; made once
    per process (numba reads a kernel's stamp once, when it is decorated)."""
    h = hashlib.sha256()
    for path in kernel_sources():
        h.update(path.relative_to(SIM_DIR).as_posix().encode())
        h.update(b"\0")
        h.update(path.read_bytes())
        h.update(b"\0")
    return h.hexdigest()


class KernelCacheLocator(_CacheLocator):
    """numba's cache locator for a kernel of :mod:`deformctl.sim`: where numba's own locator
    puts the cache, stamped with :func:`sources_digest` instead of the kernel's own file."""

    def __init__(self, inner: _CacheLocator) -> None:
        self._inner = inner

    def ensure_cache_path(self) -> None:
        self._inner.ensure_cache_path()

    def get_cache_path(self) -> str:
        return str(self._inner.get_cache_path())

    def get_source_stamp(self) -> Any:
        return ("deformctl.sim kernel sources", sources_digest())

    def get_disambiguator(self) -> str:
        return str(self._inner.get_disambiguator())

    @classmethod
    def from_function(cls, py_func: Any, py_file: str) -> KernelCacheLocator | None:
        """The guard for a function of :mod:`deformctl.sim`; None for any other function (numba's
        own locators handle it)."""
        try:
            Path(py_file).resolve().relative_to(SIM_DIR)
        except ValueError:
            return None
        locators: list[Any] = CacheImpl._locator_classes
        for other in locators:
            if other is cls:
                continue
            inner = other.from_function(py_func, py_file)
            if inner is not None:
                return cls(inner)
        return None


def install() -> None:
    """Put :class:`KernelCacheLocator` first in numba's locators (once)."""
    locators: list[Any] = CacheImpl._locator_classes
    if KernelCacheLocator not in locators:
        locators.insert(0, KernelCacheLocator)


install()
