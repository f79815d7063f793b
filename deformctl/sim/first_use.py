"""The first simulated run of an install compiles the kernels, and says so on one line.

The kernels are ``@njit(cache=True)``: a fresh install compiles them on first use (about a minute
on 2 cores) and later processes load them from numba's cache in well under a second. A silent
minute looks like a hang, so the first run of a process checks :func:`marker_path`, a file
beside numba's cache named by the digest of the kernel sources
(:func:`deformctl.sim._kernel_cache.sources_digest`): when it is missing, :func:`ensure_compiled`
prints one stderr line that it is compiling once, compiles every kernel (the warm-up,
:func:`deformctl.sim.protocols.compile_kernels`), ends the line with the time it took and writes
the marker. ``deformctl warmup`` (which ``make install`` runs) does it ahead of time.
"""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TextIO

#: set once this process has compiled or checked the kernels
_CHECKED = False


def marker_path() -> Path | None:
    """The file that says the kernels of these sources are compiled: beside numba's cache of
    the kernels, named by the sources' digest (None where numba keeps no cache)."""
    from deformctl.sim._kernel_cache import sources_digest
    from deformctl.sim.step.iterative import integrate_iterative

    cache_path = getattr(getattr(integrate_iterative, "_cache", None), "_cache_path", None)
    if not cache_path:
        return None
    return Path(cache_path) / f"deformctl-kernels-{sources_digest()[:16]}.compiled"


def mark_compiled() -> None:
    """Write the marker (this process compiled or loaded every kernel); a read-only install
    keeps none, and its runs say they compile each time numba compiles."""
    global _CHECKED
    _CHECKED = True
    marker = marker_path()
    if marker is not None:
        with contextlib.suppress(OSError):
            marker.parent.mkdir(parents=True, exist_ok=True)
            marker.touch()


def ensure_compiled(compile_all: Callable[[], float], stream: TextIO | None = None) -> bool:
    """Run ``compile_all`` (which returns its wall time, s) once if these sources' kernels were
    never compiled, on one line of ``stream`` (stderr) that ends with the time it took; otherwise
    nothing. True when it compiled them."""
    global _CHECKED
    if _CHECKED:
        return False
    _CHECKED = True
    marker = marker_path()
    if marker is None or marker.exists():
        return False
    out = sys.stderr if stream is None else stream
    print(
        "deformctl: compiling the simulator's kernels once (about a minute on 2 cores; "
        "'deformctl warmup' does it ahead) ...",
        end="",
        file=out,
        flush=True,
    )
    seconds = compile_all()
    print(f" done in {seconds:.1f} s", file=out, flush=True)
    return True
