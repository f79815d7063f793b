"""The multigrid levels as the kernels take them, and the fixed DOFs of every level (see
:mod:`deformctl.sim.multigrid`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from deformctl.arraytypes import BoolArray, FloatArray, Int32Array, IntArray
from deformctl.sim.solver import LDLFactor


class LevelArrays(NamedTuple):
    """Every level's matrix and interpolation, flattened for the kernels (the fields of the same
    names of :class:`deformctl.sim.multigrid.hierarchy.Hierarchy`)."""

    n: IntArray
    vec_off: IntArray
    row_off: IntArray
    a_ptr: IntArray
    a_idx: Int32Array
    a_val: FloatArray
    a_diag: IntArray
    inv_diag: FloatArray
    p_row_off: IntArray
    p_ptr: IntArray
    p_idx: Int32Array
    p_val: FloatArray


class StencilArrays(NamedTuple):
    """The stencil levels' arrays, concatenated level after level
    (:meth:`deformctl.sim.multigrid.hierarchy.Hierarchy.stencil_args`): particles per axis
    ``[S, 3]``, halos ``[S]``, flat coefficients and their offsets ``[S + 1]``, own blocks and
    their inverses ``[particles, 9]``, particle offsets ``[S + 1]``, coordinate DOFs, DOF
    representatives, and palm DOFs ``[S, 4]`` (``-1``: a free object)."""

    shape: IntArray
    halo: IntArray
    coef: FloatArray
    coef_off: IntArray
    block: FloatArray
    inv: FloatArray
    node_off: IntArray
    dof: IntArray
    rep: IntArray
    palm: IntArray


class MultigridArrays(NamedTuple):
    """What the V-cycle and CG read of a hierarchy: its levels, the coarsest level's factor and
    the stencil levels (:meth:`deformctl.sim.multigrid.hierarchy.Hierarchy.kernel_args`)."""

    levels: LevelArrays
    coarse: LDLFactor
    stencils: StencilArrays


@njit(cache=True)
def fix_levels(lv: LevelArrays, fixed: BoolArray, fixed_all: BoolArray, cf: FloatArray) -> None:
    """The fixed DOFs of every level (``fixed_all``, concatenated like the level vectors) from
    the finest level's ``fixed``, and the coarsest level's solve for them (``cf``, of
    :func:`deformctl.sim.multigrid.scratch.coarse_scratch_size`; zeros before its first use,
    then kept between calls).

    A coarse DOF is fixed when its interpolation reaches a fixed DOF of the finer level. Then
    every free coarse DOF's interpolant is zero on the finer fixed DOFs, so the Galerkin matrix
    ``P^T A P`` restricted to the free coarse DOFs is exactly the Galerkin matrix of the finer
    free subsystem: the V-cycle's coarse corrections are those of the constrained problem. (With
    nothing fixed on the coarse levels, the correction moves coarse DOFs that are held on the
    fine level, and is then cut there: a 12^3 cube held on its bottom face took 13 CG iterations
    to 1e-8 instead of the free cube's 9; now 9. ``tests/sim/test_multigrid.py``.)

    The coarsest level is solved by its sparse factor while none of its DOFs is fixed, else by a
    dense Cholesky factor of its free block, made when its fixed DOFs change: ``cf[0]`` is 1
    when that factor is in use, ``cf[1 : 1 + nc]`` the fixed DOFs it was made for, then the
    factor (row-major, as many rows as free DOFs).
    """
    n, vec_off, row_off, a_ptr, a_idx, a_val = (
        lv.n,
        lv.vec_off,
        lv.row_off,
        lv.a_ptr,
        lv.a_idx,
        lv.a_val,
    )
    p_row_off, p_ptr, p_idx, p_val = lv.p_row_off, lv.p_ptr, lv.p_idx, lv.p_val
    levels = n.shape[0]
    for i in range(n[0]):
        fixed_all[i] = fixed[i]
    for lvl in range(levels - 1):
        off = vec_off[lvl]
        coff = vec_off[lvl + 1]
        p0 = p_row_off[lvl]
        for i in range(n[lvl + 1]):
            fixed_all[coff + i] = False
        for i in range(n[lvl]):
            if fixed_all[off + i]:
                for k in range(p_ptr[p0 + i], p_ptr[p0 + i + 1]):
                    if p_val[k] != 0.0:
                        fixed_all[coff + p_idx[k]] = True
    lc = levels - 1
    off = vec_off[lc]
    nc = n[lc]
    n_fixed = 0
    same = cf[0] == 1.0
    for i in range(nc):
        f = fixed_all[off + i]
        if f:
            n_fixed += 1
        if same and cf[1 + i] != (1.0 if f else 0.0):
            same = False
    if n_fixed == 0:
        cf[0] = 0.0
        return
    if same:
        return
    m = nc - n_fixed
    pos = np.full(nc, -1, dtype=np.int64)
    k = 0
    for i in range(nc):
        cf[1 + i] = 1.0 if fixed_all[off + i] else 0.0
        if not fixed_all[off + i]:
            pos[i] = k
            k += 1
    if m > 0:
        dense = np.zeros((m, m))
        r0 = row_off[lc]
        for i in range(nc):
            pi = pos[i]
            if pi < 0:
                continue
            for kk in range(a_ptr[r0 + i], a_ptr[r0 + i + 1]):
                pj = pos[a_idx[kk]]
                if pj >= 0:
                    dense[pi, pj] = a_val[kk]
        _cholesky_into(dense, cf[1 + nc : 1 + nc + m * m])
    cf[0] = 1.0


@njit(cache=True)
def _cholesky_into(a: FloatArray, out: FloatArray) -> None:
    """The lower Cholesky factor of the SPD matrix ``a`` ``[m, m]`` into ``out`` (row-major
    ``[m * m]``, lower triangle; row by row). Written out rather than ``np.linalg.cholesky``:
    numba's calls LAPACK's ``dpotrf`` of the bundled OpenBLAS, whose threaded version wakes
    its worker threads, and they spin on the other core after every call (py-spy: a default
    lattice's lift; ``make reproduce`` used 145-160 CPU-s, 101 with ``OPENBLAS_NUM_THREADS=1``),
    and its blocking could depend on the thread count."""
    m = a.shape[0]
    for i in range(m):
        row = i * m
        for j in range(i + 1):
            acc = a[i, j]
            col = j * m
            for c in range(j):
                acc -= out[row + c] * out[col + c]
            if i == j:
                if acc <= 0.0:
                    raise ValueError("the coarsest level's free block is not positive definite")
                out[row + i] = np.sqrt(acc)
            else:
                out[row + j] = acc / out[col + j]


@njit(cache=True)
def _coarse_free_solve(
    fixed: BoolArray, cf: FloatArray, b: FloatArray, work: FloatArray, x: FloatArray
) -> None:
    """``x = A_FF^-1 b_F`` on the coarsest level's free DOFs, 0 on the fixed ones, by the dense
    factor in ``cf`` (:func:`fix_levels`; ``work``: scratch ``[nc]``)."""
    nc = fixed.shape[0]
    m = 0
    for i in range(nc):
        if not fixed[i]:
            work[m] = b[i]
            m += 1
    lo = 1 + nc
    for a in range(m):  # L y = b
        acc = work[a]
        row = lo + a * m
        for c in range(a):
            acc -= cf[row + c] * work[c]
        work[a] = acc / cf[row + a]
    for a in range(m - 1, -1, -1):  # L^T x = y
        acc = work[a]
        for c in range(a + 1, m):
            acc -= cf[lo + c * m + a] * work[c]
        work[a] = acc / cf[lo + a * m + a]
    k = 0
    for i in range(nc):
        if fixed[i]:
            x[i] = 0.0
        else:
            x[i] = work[k]
            k += 1
