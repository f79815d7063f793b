"""Compile the simulator's numba kernels once, ahead of the first real run.

The kernels are ``@njit(cache=True)``: the first call in a fresh install compiles them (about
20 s of CPU for the two step loops) and writes numba's cache beside the sources, and every later
process loads them from there in well under a second. Without a warm-up, the first command that
simulates pays the compiler in each of its worker processes at once (a fresh clone's first
``measure --sim`` of the 73-object population took 72 s instead of 29 s). ``make install`` runs
``python -m deformctl.sim.warmup`` after installing, so ``make reproduce`` and ``make test`` start
with compiled kernels.

Every kernel is reached through the public protocols with the argument types of a real run: a
squeeze and a lift attempt with the direct solver (the ``table`` preset's lattice) and with the
iterative one (multigrid CG), backward Euler and BDF2.

Every kernel's cache is keyed by a hash of all the simulator's kernel sources
(:mod:`deformctl.sim._kernel_cache`), not by its own file only as numba's is: after an edit of
any kernel module (the multigrid, the stencil sweeps, the step loops...) every kernel compiles
afresh, so a stale kernel is never loaded; run the warm-up again after such an edit.

A process's first simulated run compiles the kernels when they were never compiled, on one stderr
line (:mod:`deformctl.sim.first_use`); ``deformctl warmup`` (and ``make install``) does it ahead.
"""

from __future__ import annotations

import sys

from deformctl.sim.first_use import ensure_compiled
from deformctl.sim.protocols import compile_kernels

__all__ = ["compile_kernels", "ensure_compiled", "main"]


def main() -> None:
    """``python -m deformctl.sim.warmup``: compile the kernels, print one line."""
    seconds = compile_kernels()
    print(f"deformctl: simulator kernels compiled or loaded in {seconds:.1f} s", file=sys.stderr)


if __name__ == "__main__":
    main()
