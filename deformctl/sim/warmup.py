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
"""

from __future__ import annotations

import sys
import time

from deformctl.sim.engine import SimSettings, build_model
from deformctl.sim.objects import ObjectSpec
from deformctl.sim.protocols import SupportRelease, lift_attempt, squeeze

#: a small object: every kernel runs, none for long
_SPEC = ObjectSpec("warmup", (4.0, 4.0, 4.0), 1.0, 0.5, 10.0, 0.5)


def compile_kernels() -> float:
    """Run every simulator kernel once (compiling or loading it); returns the wall time, s."""
    t0 = time.perf_counter()
    for solver in ("direct", "iterative"):
        for integrator in ("euler", "bdf2"):
            settings = SimSettings(
                particles_per_side=4, solver=solver, integrator=integrator, grip_settle_s=0.01
            )
            squeeze(_SPEC, peak_force_n=1.0, ramp_s=0.005, hold_s=0.005, settings=settings)
            for mode in ("table", "support"):
                lift_attempt(_SPEC, 2.0, settings=settings, release=SupportRelease(mode=mode))
    build_model.cache_clear()
    return time.perf_counter() - t0


def main() -> None:
    """``python -m deformctl.sim.warmup``: compile the kernels, print one line."""
    seconds = compile_kernels()
    print(f"deformctl: simulator kernels compiled or loaded in {seconds:.1f} s", file=sys.stderr)


if __name__ == "__main__":
    main()
