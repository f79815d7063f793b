"""Which BLAS computes this process's matrix products, and with how many threads.

Floating-point results that go through BLAS (the network's fit, least-squares fits, dense
solves) can differ in the last bits between BLAS kernels (OpenBLAS picks one per CPU: Haswell,
SkylakeX, ...) and thread counts, and an iterative fit can amplify those bits. Artifacts whose
numbers depend on it (the model file) record :func:`blas_info`, so a user can tell why two
machines disagree.

Example:
    >>> info = blas_info()
    >>> all({"library", "internal_api", "version", "architecture", "num_threads"} <= set(i)
    ...     for i in info)
    True
"""

from __future__ import annotations

import os
from typing import Any

#: The keys of each :func:`blas_info` entry.
BLAS_INFO_KEYS = (
    "library",
    "internal_api",
    "version",
    "architecture",
    "threading_layer",
    "num_threads",
)


def blas_info() -> list[dict[str, Any]]:
    """Every BLAS library loaded in this process, as threadpoolctl reports it now.

    Call it inside a ``threadpool_limits`` block to record the thread count that block uses.

    Returns:
        One dict per library, sorted by file name: ``library`` (the shared library's file name,
        e.g. ``libscipy_openblas64_-....so``), ``internal_api`` (``openblas``, ``mkl``,
        ``blis``, ...), ``version``, ``architecture`` (the kernel the library chose for this CPU,
        e.g. ``SkylakeX``, or that ``OPENBLAS_CORETYPE`` forced; None when the library does not
        say), ``threading_layer`` and ``num_threads``.
    """
    from threadpoolctl import threadpool_info

    out = [
        {
            "library": os.path.basename(str(lib.get("filepath", ""))),
            "internal_api": lib.get("internal_api"),
            "version": lib.get("version"),
            "architecture": lib.get("architecture"),
            "threading_layer": lib.get("threading_layer"),
            "num_threads": lib.get("num_threads"),
        }
        for lib in threadpool_info()
        if lib.get("user_api") == "blas"
    ]
    return sorted(out, key=lambda lib: str(lib["library"]))


def blas_summary(info: list[dict[str, Any]] | None = None) -> str:
    """One line, ``openblas 0.3.31 SkylakeX x1, ...``: API, version, kernel, threads per library."""
    libs = blas_info() if info is None else info
    if not libs:
        return "no BLAS library loaded"
    return ", ".join(
        f"{lib['internal_api']} {lib['version']} {lib['architecture'] or '?'} x{lib['num_threads']}"
        for lib in libs
    )


def blas_record(value: object) -> list[dict[str, Any]] | None:
    """A :func:`blas_info` list read back from a file, or None when it is not one.

    Each entry keeps only :data:`BLAS_INFO_KEYS` whose values are strings, integers or None, so
    a damaged or hostile record can be shown but never trusted beyond that.
    """
    if not isinstance(value, list) or not all(isinstance(lib, dict) for lib in value):
        return None
    return [
        {
            key: lib.get(key)
            if isinstance(lib.get(key), str | int) and not isinstance(lib.get(key), bool)
            else None
            for key in BLAS_INFO_KEYS
        }
        for lib in value
    ]
