"""The layout of the multigrid CG's scratch array (see :func:`deformctl.sim.multigrid.cg.pcg`)."""

from __future__ import annotations

import numpy as np
from numba import njit

from deformctl.arraytypes import FloatArray, IntArray


@njit(cache=True)
def stencil_scratch_offsets(st_shape: IntArray, st_halo: IntArray) -> IntArray:
    """Where each stencil level's two coordinate arrays (the sweep's and its work array, each
    :attr:`deformctl.sim.stencil.Stencil.grid_len` long) start in the stencil scratch, then where
    the grid transfer's two partial arrays start (:func:`_grid_restrict`; none unless level 1 is
    a stencil level too), and the total length at the end, ``[levels + 2]``."""
    levels = st_shape.shape[0]
    off = np.zeros(levels + 2, dtype=np.int64)
    for lvl in range(levels):
        rows = st_shape[lvl, 0] * st_shape[lvl, 1] * st_shape[lvl, 2] + 2 * st_halo[lvl]
        off[lvl + 1] = off[lvl] + 6 * rows
    off[levels + 1] = off[levels]
    if levels >= 2:
        # [cx, ny, nz, 3] after the x pass, [cx, cy, nz, 3] after the y pass
        cx, cy = st_shape[1, 0], st_shape[1, 1]
        ny, nz = st_shape[0, 1], st_shape[0, 2]
        off[levels + 1] += 3 * cx * nz * (ny + cy)
    return off


@njit(cache=True)
def coarse_scratch_size(n: IntArray) -> int:
    """Length of the coarsest level's factor scratch ``cf`` (:func:`fix_levels`) for levels of
    ``n`` DOFs: a flag, the fixed DOFs it was made for, and a dense factor, ``1 + nc + nc^2``."""
    nc = n[n.shape[0] - 1]
    return 1 + nc + nc * nc


@njit(cache=True)
def pcg_work_size(n: IntArray, st_shape: IntArray, st_halo: IntArray) -> int:
    """Length of :func:`pcg`'s scratch for levels of ``n`` DOFs and the stencil levels
    ``st_shape``, ``st_halo`` (:meth:`Hierarchy.stencil_args`): ``5 n[0] + 3 sum(n)``, the
    stencil scratch (:func:`stencil_scratch_offsets`) and, last, the coarsest level's factor
    (:func:`coarse_scratch_size`)."""
    tot = 0
    for lvl in range(n.shape[0]):
        tot += n[lvl]
    grid = stencil_scratch_offsets(st_shape, st_halo)[-1]
    return 5 * n[0] + 3 * tot + grid + coarse_scratch_size(n)


@njit(cache=True)
def pcg_scratch(
    n: IntArray, st_shape: IntArray, st_halo: IntArray, work: FloatArray
) -> tuple[
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
]:
    """:func:`pcg`'s views of its scratch ``work`` (:func:`pcg_work_size`): CG's ``r, z, p, q,
    A z`` (finest level), the V-cycle's ``xs, bs, rs`` (all levels), the stencil levels'
    coordinates (:func:`stencil_scratch_offsets`) and, last, the coarsest level's factor
    (:func:`fix_levels`)."""
    n0 = n[0]
    tot = 0
    for lvl in range(n.shape[0]):
        tot += n[lvl]
    v = 5 * n0 + 3 * tot
    cf_off = v + stencil_scratch_offsets(st_shape, st_halo)[-1]
    return (
        work[0:n0],
        work[n0 : 2 * n0],
        work[2 * n0 : 3 * n0],
        work[3 * n0 : 4 * n0],
        work[4 * n0 : 5 * n0],
        work[5 * n0 : 5 * n0 + tot],
        work[5 * n0 + tot : 5 * n0 + 2 * tot],
        work[5 * n0 + 2 * tot : v],
        work[v:cf_off],
        work[cf_off : cf_off + coarse_scratch_size(n)],
    )
