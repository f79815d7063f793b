"""The first multigrid levels as lattice stencils: block Gauss–Seidel without column indices.

The implicit matrix of the lattice is ``A = R^T (M + h C + h^2 K) R + E`` (:mod:`.engine`): the
particle masses and the Kelvin elements assembled on the particles' own coordinates, ``R`` the
map from the generalised DOFs to the coordinates (a palm face's x and z coordinates all take the
palm's DOF, :func:`deformctl.sim.lattice.palm_dof_map`), and ``E`` the few terms on the palm DOFs
alone (the palms' mass, the damper across the gripped width). On the box lattice every particle
has the same neighbours at the same index offsets (missing ones at the boundary carry zero
coefficients), so a row of ``A`` needs no column indices:

* the finest level is an *element* stencil (:func:`build_stencil`): the particle's own 3x3
  block plus, per element, ``w_e n_e n_e^T`` times the neighbour's coordinates (one number for
  an axial element, three for a face diagonal: 21 numbers per particle, against about 57 entries
  and their indices per particle in compressed rows);
* level 1 is a *block* stencil (:func:`build_block_stencil`): its Galerkin matrix, formed on the
  particles' coordinates, as 3x3 blocks to the 26 neighbours.

A sweep solves each particle's free coordinates together (block Gauss–Seidel: the 3x3 block's
inverse is precomputed; a particle with fixed or palm-bound coordinates solves the free part of
its block). The palm DOFs, which couple a whole face, are swept by their compressed rows, first
on the way down (:func:`forward_sweep_from_zero`, then the particles in index order) and last on
the way up (:func:`backward_sweep`, the exact reverse), and each new value is written to every
coordinate of its face. In that order the residual after the forward sweep is half a pass
(:func:`residual_after_forward`) and ``A x`` comes out of the backward sweep; the smoother is
symmetric, so the V-cycle stays a valid CG preconditioner (:mod:`deformctl.sim.multigrid`).

``bench/bench_sim.py`` measures one V-cycle with and without the stencils, in units of one
compressed-row product ``A x`` of the same run.
"""

from __future__ import annotations

from deformctl.sim.stencil.build import (
    DIRECTION_AXES,
    DIRECTIONS,
    N_COEF,
    UPPER_OFFSETS,
    Rows,
    Stencil,
    build_block_stencil,
    build_stencil,
    direction_offsets,
    grid_matrix,
    halo_of,
)
from deformctl.sim.stencil.sweeps import (
    add_dofs,
    backward_sweep,
    forward_sweep_from_zero,
    residual_after_forward,
    stencil_product,
)

__all__ = [
    "DIRECTIONS",
    "DIRECTION_AXES",
    "N_COEF",
    "UPPER_OFFSETS",
    "Rows",
    "Stencil",
    "add_dofs",
    "backward_sweep",
    "build_block_stencil",
    "build_stencil",
    "direction_offsets",
    "forward_sweep_from_zero",
    "grid_matrix",
    "halo_of",
    "residual_after_forward",
    "stencil_product",
]
