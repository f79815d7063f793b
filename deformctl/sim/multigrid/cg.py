"""The multigrid-preconditioned CG and the finest level's product (see
:mod:`deformctl.sim.multigrid`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from deformctl.arraytypes import BoolArray, FloatArray
from deformctl.sim.multigrid.cycle import _stencil_level, csr_matvec, v_cycle
from deformctl.sim.multigrid.levels import MultigridArrays, fix_levels
from deformctl.sim.multigrid.scratch import pcg_scratch, stencil_scratch_offsets
from deformctl.sim.stencil import N_COEF, Rows, Stencil, stencil_product


@njit(cache=True)
def product(mg: MultigridArrays, work: FloatArray, x: FloatArray, out: FloatArray) -> None:
    """``out = A x`` on the finest level: by its stencil when it has one
    (:func:`deformctl.sim.stencil.stencil_product`, using the stencil scratch of :func:`pcg`'s
    ``work``, :func:`pcg_scratch`), else by its compressed rows."""
    n, row_off, a_ptr, a_idx, a_val = (
        mg.levels.n, mg.levels.row_off, mg.levels.a_ptr, mg.levels.a_idx, mg.levels.a_val
    )  # fmt: skip
    st_shape, st_halo = mg.stencils.shape, mg.stencils.halo
    n0 = n[0]
    if st_shape.shape[0] == 0 or n.shape[0] < 2:
        csr_matvec(a_ptr, a_idx, a_val, row_off[0], n0, x, out)
        return
    xg = pcg_scratch(n, st_shape, st_halo, work)[8]
    grid_off = stencil_scratch_offsets(st_shape, st_halo)
    xg_l, _, coef, block, inv, dof, rep, palm = _stencil_level(0, 0, n0, grid_off, xg, mg.stencils)
    rows = xg_l.shape[0] // 3
    st0 = Stencil(st_shape[0], st_halo[0], coef.reshape((rows, N_COEF)), block, inv, dof, rep, palm)
    stencil_product(st0, Rows(a_ptr[row_off[0] : row_off[0] + n0 + 1], a_idx, a_val), x, xg_l, out)


@njit(cache=True)
def pcg(
    mg: MultigridArrays,
    fixed: BoolArray,
    b: FloatArray,
    x: FloatArray,
    tol: float,
    max_iter: int,
    work: FloatArray,
    ax: FloatArray,
    ax_known: bool,
) -> int:
    """Multigrid-preconditioned CG on the free DOFs: ``(A x)_i = b_i`` for every free ``i``, the
    fixed ``x_i`` kept. ``x`` holds the initial guess and receives the solution. Stops when the
    free residual's 2-norm is at most ``tol``. ``work``: scratch of :func:`pcg_work_size`,
    zeros before its first use; it keeps the coarsest level's factor for the fixed DOFs between
    calls (:func:`fix_levels`, redone only when they change there), so reuse it for the same
    hierarchy only.
    ``mg``: the hierarchy (:meth:`Hierarchy.kernel_args`; with no stencil levels every level is
    swept by rows).

    At most one matrix-vector product per solve (the initial residual, skipped when the caller
    knows ``A x``: ``ax_known`` with ``ax = A x`` on entry, read only); each iteration's ``A p``
    is ``A z + beta A p_prev``, with ``A z`` from the V-cycle (:func:`v_cycle`). On return
    ``work[:n[0]]`` holds the final residual ``b - A x`` (the recursive one; 0 on fixed DOFs).

    Returns:
        the number of iterations (``max_iter + 1`` when it did not converge).
    """
    n = mg.levels.n
    n0 = n[0]
    tot = 0
    for lvl in range(n.shape[0]):
        tot += n[lvl]
    r, z, p, q, az, xs, bs, rs, xg, cf = pcg_scratch(n, mg.stencils.shape, mg.stencils.halo, work)
    if not ax_known:
        product(mg, work, x, q)
        ax = q
    rr = 0.0
    for i in range(n0):
        r[i] = 0.0 if fixed[i] else b[i] - ax[i]
        rr += r[i] * r[i]
    if np.sqrt(rr) <= tol:
        return 0
    # the coarse levels' fixed DOFs (only when a V-cycle runs)
    fixed_all = np.empty(tot, dtype=np.bool_)
    fix_levels(mg.levels, fixed, fixed_all, cf)
    rz = 0.0
    for it in range(1, max_iter + 1):
        v_cycle(mg, fixed_all, r, z, az, xs, bs, rs, xg, cf)
        rz_new = 0.0
        for i in range(n0):
            rz_new += r[i] * z[i]
        pq = 0.0
        if it == 1:
            for i in range(n0):
                p[i] = z[i]
                q[i] = az[i]
                pq += p[i] * q[i]
        else:
            beta = rz_new / rz
            for i in range(n0):
                p[i] = z[i] + beta * p[i]
                q[i] = az[i] + beta * q[i]
                pq += p[i] * q[i]
        rz = rz_new
        alpha = rz / pq
        rr = 0.0
        for i in range(n0):
            x[i] += alpha * p[i]
            r[i] -= alpha * q[i]
            rr += r[i] * r[i]
        if np.sqrt(rr) <= tol:
            return it
    return max_iter + 1
