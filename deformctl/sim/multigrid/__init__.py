"""Geometric multigrid for the lattice's SPD matrices, and a preconditioned CG in numba.

Levels coarsen the box lattice by two along every axis that has more than two particles (keeping
both end layers, so the palm faces and the bottom layer stay on every level); the interpolation
is trilinear in the lattice index per coordinate, written in the generalised DOFs of each level
(a fine face DOF merged into a palm DOF interpolates from the coarse palm DOF). Coarse matrices
are Galerkin products ``P^T A P``; the coarsest is factorised (:mod:`deformctl.sim.solver`).
Between the two stencil levels the V-cycle applies ``P`` and ``P^T`` by the interpolation's three
axis factors on the lattice coordinates (:func:`_grid_restrict`, :func:`_grid_prolong_add`: no
index arrays, the prolonged correction written straight into the sweep's coordinates; ``make
bench``'s V-cycle table at 21^3: 2.78 -> 2.60 compressed-row products per cycle); the coarser
levels use ``P``'s rows.
One V-cycle: a forward Gauss–Seidel sweep, restriction of the residual, the coarse correction,
prolongation, a backward Gauss–Seidel sweep (a symmetric cycle, so it preconditions CG).

Cost (the finest level dominates; one pass = one multiply-add per matrix entry): the forward
sweep starts from zero, so it reads only the lower triangle and the diagonal, and the residual
after it only the strict upper triangle (half a pass each); the backward sweep is a full pass
and also returns ``A z`` for CG by scattering its corrections through the strict upper triangle
(half a pass, by symmetry; see :func:`v_cycle`), which replaces CG's own matrix-vector product.
So a CG iteration reads the finest matrix 2.5 times instead of 3.5.

DOFs can be *fixed* (a prescribed value, e.g. a contact row held at its target velocity): the CG
and the smoothing leave them untouched and the residual ignores them, which solves the principal
subsystem of the free DOFs exactly as the contact problem needs. A coarse DOF whose interpolation
reaches a fixed DOF is fixed too, and the coarsest level solves its free block, so every coarse
correction is the Galerkin correction of the free subsystem (:func:`fix_levels`).
"""

from __future__ import annotations

from deformctl.sim.multigrid.cg import pcg, product
from deformctl.sim.multigrid.cycle import csr_matvec, v_cycle
from deformctl.sim.multigrid.hierarchy import Hierarchy, build_hierarchy, interpolation, solve
from deformctl.sim.multigrid.levels import (
    LevelArrays,
    MultigridArrays,
    StencilArrays,
    fix_levels,
)
from deformctl.sim.multigrid.scratch import (
    coarse_scratch_size,
    pcg_scratch,
    pcg_work_size,
    stencil_scratch_offsets,
)

__all__ = [
    "Hierarchy",
    "LevelArrays",
    "MultigridArrays",
    "StencilArrays",
    "build_hierarchy",
    "coarse_scratch_size",
    "csr_matvec",
    "fix_levels",
    "interpolation",
    "pcg",
    "pcg_scratch",
    "pcg_work_size",
    "product",
    "solve",
    "stencil_scratch_offsets",
    "v_cycle",
]
