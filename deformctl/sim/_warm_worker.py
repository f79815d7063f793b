"""Imported by the fork server of local worker processes: load the simulator's kernels once.

A task that simulates names this module in its ``worker_preload``
(:func:`deformctl.parallel.backends._worker_context`); the fork server imports it before it
forks any worker, so every worker starts with numba, the simulator and its compiled kernels
already in memory instead of loading them itself on its first object (measured: about 2 s of
a worker's start on this project's 2-core machine). Importing it anywhere else runs the
warm-up (:func:`deformctl.sim.warmup.compile_kernels`, well under a second once compiled).
"""

from __future__ import annotations

import contextlib

with contextlib.suppress(Exception):  # a fork server that failed here would break every pool
    from deformctl.sim.first_use import ensure_compiled
    from deformctl.sim.protocols import compile_kernels

    if not ensure_compiled(compile_kernels):  # compiled here (on one stderr line), or loaded now
        compile_kernels()
