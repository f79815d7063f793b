"""One multigrid V-cycle (see :mod:`deformctl.sim.multigrid`)."""

from __future__ import annotations

from numba import njit

from deformctl.arraytypes import BoolArray, FloatArray, Int32Array, IntArray
from deformctl.sim.multigrid.levels import MultigridArrays, StencilArrays, _coarse_free_solve
from deformctl.sim.multigrid.scratch import stencil_scratch_offsets
from deformctl.sim.multigrid.transfer import _grid_prolong_add, _grid_restrict
from deformctl.sim.solver import ldl_solve
from deformctl.sim.stencil import (
    N_COEF,
    Rows,
    Stencil,
    add_dofs,
    backward_sweep,
    forward_sweep_from_zero,
    residual_after_forward,
)


@njit(cache=True)
def csr_matvec(
    ptr: IntArray,
    idx: Int32Array,
    val: FloatArray,
    row0: int,
    n: int,
    x: FloatArray,
    out: FloatArray,
) -> None:
    """``out = A x`` for the CSR matrix whose rows start at ``ptr[row0]``."""
    for i in range(n):
        acc = 0.0
        for k in range(ptr[row0 + i], ptr[row0 + i + 1]):
            acc += val[k] * x[idx[k]]
        out[i] = acc


@njit(cache=True)
def v_cycle(
    mg: MultigridArrays,
    fixed: BoolArray,
    b: FloatArray,
    x: FloatArray,
    ax: FloatArray,
    xs: FloatArray,
    bs: FloatArray,
    rs: FloatArray,
    xg: FloatArray,
    cf: FloatArray,
) -> None:
    """``x = M^-1 b`` by one V-cycle from zero, and ``ax = A x`` (finest level: ``b``, ``x``,
    ``ax`` ``[n0]``; ``xs``, ``bs``, ``rs``: scratch for all levels; ``mg``: the hierarchy,
    :meth:`Hierarchy.kernel_args`). ``fixed``: the fixed DOFs
    of every level, concatenated like the level vectors, and ``cf`` the coarsest level's factor
    for them, both from :func:`fix_levels`. Fixed DOFs of the finest level get ``x = 0`` and
    ``ax = 0``; on every level the sweeps leave the fixed DOFs at zero, so the coarse
    corrections are those of the free subsystem (see :func:`fix_levels`).

    The first levels with a stencil (``st_*``, :meth:`Hierarchy.stencil_args`; ``xg``: their
    coordinates' scratch, two arrays per level, then the grid transfer's partial arrays, laid
    out by :func:`stencil_scratch_offsets`) are swept particle by particle
    (:mod:`deformctl.sim.stencil`), the others by rows. ``A x`` comes from the last sweep:
    right after the backward update of a free row its residual is zero, and only the rows
    updated after it change it afterwards, so each change is scattered to the rows it couples to
    as it is made (``A`` is symmetric) instead of forming the product.
    """
    lv = mg.levels
    n, vec_off, row_off, a_ptr, a_idx, a_val = (
        lv.n,
        lv.vec_off,
        lv.row_off,
        lv.a_ptr,
        lv.a_idx,
        lv.a_val,
    )
    a_diag, inv_diag, p_row_off, p_ptr, p_idx, p_val = (
        lv.a_diag, lv.inv_diag, lv.p_row_off, lv.p_ptr, lv.p_idx, lv.p_val
    )  # fmt: skip
    sts = mg.stencils
    st_shape, st_halo, st_node_off, st_dof, st_rep = (
        sts.shape,
        sts.halo,
        sts.node_off,
        sts.dof,
        sts.rep,
    )
    levels = n.shape[0]
    n0 = n[0]
    # the levels swept as stencils (the coarsest is solved directly)
    n_st = min(st_shape.shape[0], levels - 1)
    grid_off = stencil_scratch_offsets(st_shape, st_halo)
    # between levels 0 and 1, when both are stencils: the transfer on the lattice coordinates
    by_grid = n_st >= 2
    part = xg[grid_off[st_shape.shape[0]] :]
    if n_st == 0:
        for i in range(n0):
            bs[i] = 0.0 if fixed[i] else b[i]
    # down: forward Gauss–Seidel from zero, residual, restriction
    for lvl in range(levels - 1):
        off = vec_off[lvl]
        nl = n[lvl]
        r0 = row_off[lvl]
        if lvl < n_st:
            xg_l, wk_l, coef, block, inv, dof, rep, palm = _stencil_level(
                lvl, off, nl, grid_off, xg, mg.stencils
            )
            rows = xg_l.shape[0] // 3
            level_rows = Rows(a_ptr[r0 : r0 + nl + 1], a_idx, a_val)
            if lvl == 0:  # the finest level: an element stencil
                st0 = Stencil(st_shape[0], st_halo[0], coef.reshape((rows, N_COEF)), block, inv,
                              dof, rep, palm)  # fmt: skip
                _stencil_down(st0, level_rows, fixed[:nl], b, xg_l, wk_l, rs[off : off + nl])
            else:  # level 1: a block stencil
                st1 = Stencil(st_shape[1], st_halo[1], coef.reshape((rows, 26, 9)), block, inv,
                              dof, rep, palm)  # fmt: skip
                _stencil_down(
                    st1, level_rows, fixed[off : off + nl], bs[off : off + nl], xg_l, wk_l,
                    rs[off : off + nl],
                )  # fmt: skip
        else:
            # from zero, the sweep reads only the lower triangle: x_i = (b_i - L_i x) / a_ii
            for i in range(nl):
                if fixed[off + i]:
                    xs[off + i] = 0.0
                    continue
                acc = bs[off + i]
                for k in range(a_ptr[r0 + i], a_diag[off + i]):
                    acc -= a_val[k] * xs[off + a_idx[k]]
                xs[off + i] = acc * inv_diag[off + i]
            # after it, (D + L) x = b, so the residual is -U x: the strict upper triangle
            for i in range(nl):
                if fixed[off + i]:
                    rs[off + i] = 0.0
                    continue
                acc = 0.0
                for k in range(a_diag[off + i] + 1, a_ptr[r0 + i + 1]):
                    acc -= a_val[k] * xs[off + a_idx[k]]
                rs[off + i] = acc
        coff = vec_off[lvl + 1]
        if lvl == 0 and by_grid:
            n1 = st_node_off[1]
            _grid_restrict(
                st_shape[0], st_shape[1], st_dof[: 3 * n1], st_rep[:nl],
                st_dof[3 * n1 : 3 * st_node_off[2]], rs[:nl], part, bs[coff : coff + n[1]],
            )  # fmt: skip
            continue
        for i in range(n[lvl + 1]):
            bs[coff + i] = 0.0
        p0 = p_row_off[lvl]
        for i in range(nl):
            ri = rs[off + i]
            if ri != 0.0:
                for k in range(p_ptr[p0 + i], p_ptr[p0 + i + 1]):
                    bs[coff + p_idx[k]] += p_val[k] * ri
    # coarsest: direct solve (of its free DOFs, when some are fixed)
    lc = levels - 1
    off = vec_off[lc]
    nc = n[lc]
    if cf[0] == 1.0:
        _coarse_free_solve(fixed[off : off + nc], cf, bs[off : off + nc], rs[off : off + nc],
                           xs[off : off + nc])  # fmt: skip
    else:
        ldl_solve(mg.coarse, bs[off : off + nc], rs[off : off + nc], xs[off : off + nc])
    # up: prolongation, backward Gauss–Seidel
    if n_st == 0:
        for i in range(n0):
            ax[i] = 0.0
    for lvl in range(levels - 2, -1, -1):
        off = vec_off[lvl]
        coff = vec_off[lvl + 1]
        nl = n[lvl]
        r0 = row_off[lvl]
        p0 = p_row_off[lvl]
        if lvl < n_st:
            xg_l, wk_l, coef, block, inv, dof, rep, palm = _stencil_level(
                lvl, off, nl, grid_off, xg, mg.stencils
            )
            # the correction, prolonged and added to every coordinate of the free DOFs
            if lvl == 0 and by_grid:
                n1 = st_node_off[1]
                _grid_prolong_add(
                    st_shape[0], st_shape[1], dof, st_dof[3 * n1 : 3 * st_node_off[2]],
                    fixed[:nl], xs[coff : coff + n[1]], part, st_halo[0], xg_l,
                )  # fmt: skip
            else:
                for i in range(nl):
                    acc = 0.0
                    for k in range(p_ptr[p0 + i], p_ptr[p0 + i + 1]):
                        acc += p_val[k] * xs[coff + p_idx[k]]
                    rs[off + i] = acc
            rows = xg_l.shape[0] // 3
            level_rows = Rows(a_ptr[r0 : r0 + nl + 1], a_idx, a_val)
            if lvl == 0:  # returns x and A x
                st0 = Stencil(st_shape[0], st_halo[0], coef.reshape((rows, N_COEF)), block, inv,
                              dof, rep, palm)  # fmt: skip
                _stencil_up(
                    st0, level_rows, fixed[:nl], b, rs[off : off + nl], xg_l, wk_l, x, ax, True,
                    not by_grid,
                )  # fmt: skip
            else:
                st1 = Stencil(st_shape[1], st_halo[1], coef.reshape((rows, 26, 9)), block, inv,
                              dof, rep, palm)  # fmt: skip
                _stencil_up(
                    st1, level_rows, fixed[off : off + nl], bs[off : off + nl],
                    rs[off : off + nl], xg_l, wk_l, xs[off : off + nl], ax[:0], False, True,
                )  # fmt: skip
            continue
        for i in range(nl):
            if fixed[off + i]:
                continue
            acc = 0.0
            for k in range(p_ptr[p0 + i], p_ptr[p0 + i + 1]):
                acc += p_val[k] * xs[coff + p_idx[k]]
            xs[off + i] += acc
        for i in range(nl - 1, -1, -1):
            if fixed[off + i]:
                continue
            acc = bs[off + i]
            for k in range(a_ptr[r0 + i], a_ptr[r0 + i + 1]):
                acc -= a_val[k] * xs[off + a_idx[k]]
            delta = acc * inv_diag[off + i]
            xs[off + i] += delta
            if lvl == 0:
                ax[i] += bs[i]
                for k in range(a_diag[i] + 1, a_ptr[r0 + i + 1]):
                    ax[a_idx[k]] += a_val[k] * delta
    if n_st > 0:
        return
    for i in range(n0):
        x[i] = 0.0 if fixed[i] else xs[i]
    if levels == 1:
        # a single level is solved directly (no sweep to read A x from)
        csr_matvec(a_ptr, a_idx, a_val, row_off[0], n0, x, ax)
    for i in range(n0):
        if fixed[i]:
            ax[i] = 0.0


@njit(cache=True, inline="always")
def _stencil_level(
    lvl: int, off: int, nl: int, grid_off: IntArray, xg: FloatArray, sts: StencilArrays
) -> tuple[
    FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, IntArray, IntArray, IntArray
]:
    """Stencil level ``lvl``'s views of the packed arrays (:meth:`Hierarchy.stencil_args`;
    ``off``, ``nl``: the level's DOF offset and count): its sweep's and work coordinates in the
    scratch ``xg``, its flat coefficients, own blocks and their inverses, coordinate DOFs, DOF
    representatives and palm DOFs (none for a free object)."""
    st_coef, st_coef_off, st_block, st_inv = sts.coef, sts.coef_off, sts.block, sts.inv
    st_node_off, st_dof, st_rep, st_palm = sts.node_off, sts.dof, sts.rep, sts.palm
    half = (grid_off[lvl + 1] - grid_off[lvl]) // 2
    nb = st_node_off[lvl]
    ne = st_node_off[lvl + 1]
    return (
        xg[grid_off[lvl] : grid_off[lvl] + half],
        xg[grid_off[lvl] + half : grid_off[lvl + 1]],
        st_coef[st_coef_off[lvl] : st_coef_off[lvl + 1]],
        st_block[nb:ne],
        st_inv[nb:ne],
        st_dof[3 * nb : 3 * ne],
        st_rep[off : off + nl],
        st_palm[lvl, : (4 if st_palm[lvl, 0] >= 0 else 0)],
    )


@njit(cache=True)
def _stencil_down(
    st: Stencil,
    rows: Rows,
    fixed: BoolArray,
    b: FloatArray,
    xg: FloatArray,
    work: FloatArray,
    r: FloatArray,
) -> None:
    """A stencil level on the way down: the forward sweep from zero and its residual ``r``."""
    forward_sweep_from_zero(st, rows, fixed, b, xg)
    residual_after_forward(st, rows, fixed, b, xg, work, r)


@njit(cache=True)
def _stencil_up(
    st: Stencil,
    rows: Rows,
    fixed: BoolArray,
    b: FloatArray,
    t: FloatArray,
    xg: FloatArray,
    work: FloatArray,
    x: FloatArray,
    ax: FloatArray,
    with_product: bool,
    add_t: bool,
) -> None:
    """A stencil level on the way up: add the prolonged correction ``t`` (unless ``add_t`` is
    false: already in ``xg``), sweep backward, return the DOFs ``x`` (and ``ax = A x``)."""
    if add_t:
        add_dofs(st.dof_of, st.halo, fixed, t, xg)
    backward_sweep(st, rows, fixed, b, xg, work, x, ax, with_product)
