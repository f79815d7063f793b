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

from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
import scipy.sparse
from numba import njit
from numpy.typing import NDArray

from deformctl.sim.lattice import shape_dof_map
from deformctl.sim.solver import (
    LDLFactor,
    dof_order,
    ldl_factor,
    ldl_solve,
    nested_dissection_order,
)
from deformctl.sim.stencil import (
    N_COEF,
    Stencil,
    add_dofs,
    backward_sweep,
    build_block_stencil,
    forward_sweep_from_zero,
    grid_matrix,
    residual_after_forward,
    stencil_product,
)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
Int32Array = NDArray[np.int32]
BoolArray = NDArray[np.bool_]


@dataclass(frozen=True, eq=False)
class Hierarchy:
    """The multigrid levels, flattened for numba.

    Attributes:
        n: DOFs per level, ``[L]``; vec_off: offset of each level in the level vectors, ``[L]``.
        a_ptr, a_idx, a_val: every level's matrix in CSR (``a_ptr`` absolute into ``a_idx``/
            ``a_val``; level ``l``'s rows are ``a_ptr[row_off[l] : row_off[l] + n[l] + 1]``).
        row_off: offset of each level's rows in ``a_ptr``, ``[L]``.
        a_diag: position of each row's diagonal entry in ``a_idx``/``a_val``, concatenated like
            the vectors (every row has one; column indices are sorted within a row).
        inv_diag: inverse diagonal of every level, concatenated like the vectors.
        p_ptr, p_idx, p_val, p_row_off: interpolation from level ``l + 1`` to ``l`` (CSR, rows of
            level ``l``), ``[L - 1]`` segments like the matrices.
        coarse: factor of the coarsest matrix.
        stencils: the first levels as lattice stencils (:mod:`deformctl.sim.stencil`: the
            finest level's element stencil, level 1's block stencil), swept particle by particle;
            the other levels (and all of them when empty) are swept by rows.
    """

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
    coarse: LDLFactor
    stencils: tuple[Stencil, ...] = ()

    @property
    def levels(self) -> int:
        """Number of levels."""
        return int(self.n.shape[0])

    @property
    def stencil(self) -> Stencil | None:
        """The finest level's stencil, if any."""
        return self.stencils[0] if self.stencils else None

    @property
    def nbytes(self) -> int:
        """Memory held, bytes."""
        arrays = (
            self.a_ptr, self.a_idx, self.a_val, self.a_diag, self.inv_diag, self.p_ptr, self.p_idx
        )  # fmt: skip
        total = sum(a.nbytes for a in arrays) + self.p_val.nbytes + self.coarse.nbytes
        return total + sum(st.nbytes for st in self.stencils)

    @property
    def work_size(self) -> int:
        """Length of :func:`pcg`'s scratch (:func:`pcg_work_size`)."""
        st_shape, st_halo = self.stencil_args()[:2]
        return int(pcg_work_size(self.n, st_shape, st_halo))

    def fixed_levels(self, fixed: BoolArray) -> tuple[BoolArray, FloatArray]:
        """The fixed DOFs of every level for the finest level's ``fixed``, and the coarsest
        level's factor for them: :func:`v_cycle`'s ``fixed`` and ``cf`` (:func:`fix_levels`)."""
        fixed_all = np.zeros(int(self.n.sum()), dtype=np.bool_)
        cf = np.zeros(int(coarse_scratch_size(self.n)))
        fix_levels(
            self.n, self.vec_off, self.row_off, self.a_ptr, self.a_idx, self.a_val,
            self.p_row_off, self.p_ptr, self.p_idx, self.p_val,
            np.ascontiguousarray(fixed, dtype=np.bool_), fixed_all, cf,
        )  # fmt: skip
        return fixed_all, cf

    def stencil_args(self) -> tuple[Any, ...]:
        """The ``st_*`` arguments of :func:`pcg` and :func:`v_cycle`: the stencils' arrays,
        concatenated level after level (see :func:`v_cycle`); packed once per hierarchy."""
        return self._packed_stencils

    @cached_property
    def _packed_stencils(self) -> tuple[Any, ...]:
        sts = self.stencils
        nodes = np.cumsum([0] + [st.n_particles for st in sts]).astype(np.int64)
        coef_off = np.cumsum([0] + [st.coef.size for st in sts]).astype(np.int64)
        palm = np.full((len(sts), 4), -1, dtype=np.int64)
        for lvl, st in enumerate(sts):
            palm[lvl, : st.palm.size] = st.palm
        if not sts:
            return (np.zeros((0, 3), dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0),
                    coef_off, np.zeros((0, 9)), np.zeros((0, 9)), nodes,
                    np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), palm)  # fmt: skip
        return (
            np.stack([st.shape for st in sts]),
            np.array([st.halo for st in sts], dtype=np.int64),
            np.concatenate([st.coef.ravel() for st in sts]),
            coef_off,
            np.concatenate([st.block for st in sts]),
            np.concatenate([st.block_inv for st in sts]),
            nodes,
            np.concatenate([st.dof_of for st in sts]),
            np.concatenate([st.rep for st in sts]),
            palm,
        )


def _axis_interpolation(n_fine: int) -> scipy.sparse.csr_matrix:
    """1-D linear interpolation from the coarse points (every second, both ends) to all points,
    as a matrix: the rule of :func:`_coarse_point`, which the V-cycle's grid transfer applies
    without one."""
    rows: list[int] = []
    cols: list[int] = []
    vals: list[float] = []
    for i in range(n_fine):
        j, w = _coarse_point.py_func(i, n_fine)
        rows.append(i)
        cols.append(j)
        vals.append(1.0 - w)
        if w > 0:
            rows.append(i)
            cols.append(j + 1)
            vals.append(w)
    n_coarse = _coarse_point.py_func(n_fine - 1, n_fine)[0] + 1
    return scipy.sparse.csr_matrix((vals, (rows, cols)), shape=(n_fine, n_coarse))


def _scalar_interpolation(shape: tuple[int, int, int]) -> scipy.sparse.csr_matrix:
    """Trilinear interpolation of one value per particle from the coarse lattice of ``shape``."""
    px, py, pz = (_axis_interpolation(n) for n in shape)
    return scipy.sparse.csr_matrix(scipy.sparse.kron(scipy.sparse.kron(px, py), pz))


def _coarsen(shape: tuple[int, int, int]) -> tuple[int, int, int]:
    out = [n if n <= 2 else (n + 1) // 2 + (1 if (n - 1) % 2 else 0) for n in shape]
    return (out[0], out[1], out[2])


def interpolation(
    shape: tuple[int, int, int], gripped: bool
) -> tuple[scipy.sparse.csr_matrix, tuple[int, int, int], IntArray]:
    """Interpolation from the coarse lattice to ``shape`` in generalised DOFs.

    Returns:
        ``P [n_dof_fine, n_dof_coarse]``, the coarse shape and the coarse ``dof_of``.
    """
    coarse_shape = _coarsen(shape)
    scalar = _scalar_interpolation(shape).tocoo()
    dof_f, n_f, _, _ = shape_dof_map(shape, gripped)
    dof_c, n_c, _, _ = shape_dof_map(coarse_shape, gripped)
    # one representative coordinate per fine DOF (merged palm DOFs appear many times)
    first = np.full(n_f, -1, dtype=np.int64)
    coords = np.arange(dof_f.size)
    order = np.argsort(dof_f, kind="stable")
    sorted_dofs = dof_f[order]
    starts = np.concatenate([[0], np.flatnonzero(np.diff(sorted_dofs)) + 1])
    first[sorted_dofs[starts]] = coords[order[starts]]
    representative = np.zeros(dof_f.size, dtype=bool)
    representative[first] = True
    rows: list[IntArray] = []
    cols: list[IntArray] = []
    vals: list[FloatArray] = []
    for a in range(3):
        keep = representative[3 * scalar.row + a]
        rows.append(dof_f[3 * scalar.row[keep] + a])
        cols.append(dof_c[3 * scalar.col[keep] + a])
        vals.append(scalar.data[keep])
    p = scipy.sparse.coo_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n_f, n_c)
    ).tocsr()
    p.sum_duplicates()
    return p, coarse_shape, dof_c


def build_hierarchy(
    shape: tuple[int, int, int],
    gripped: bool,
    a: scipy.sparse.spmatrix,
    max_coarse: int = 200,
    stencil: Stencil | None = None,
) -> Hierarchy:
    """Multigrid levels of the lattice matrix ``a`` (generalised DOFs of ``shape``, ``gripped``).

    Args:
        stencil: the same matrix as a lattice stencil (:func:`deformctl.sim.stencil.
            build_stencil`), which the V-cycle then sweeps on the finest level; level 1 (when it
            is not the coarsest) is then swept as a block stencil too, its Galerkin matrix
            formed on the particles' coordinates (:func:`deformctl.sim.stencil.grid_matrix`).
    """
    mats = [scipy.sparse.csr_matrix(a)]
    interps: list[scipy.sparse.csr_matrix] = []
    shapes = [shape]
    dof_maps = [shape_dof_map(shape, gripped)]
    cur = shape
    while mats[-1].shape[0] > max_coarse and _coarsen(cur) != cur:
        p, cur, _ = interpolation(cur, gripped)
        interps.append(p)
        mats.append(scipy.sparse.csr_matrix(p.T @ mats[-1] @ p))
        shapes.append(cur)
        dof_maps.append(shape_dof_map(cur, gripped))
    stencils: tuple[Stencil, ...] = () if stencil is None else (stencil,)
    if stencil is not None and len(mats) >= 3:
        # level 1 in coordinates: R_1 P_grid = P R_0, so its Galerkin matrix is
        # R_1^T (P_grid^T A_grid P_grid) R_1 plus the palm DOFs' own terms (in its rows)
        p_grid = scipy.sparse.kron(_scalar_interpolation(shape), scipy.sparse.identity(3))
        a1 = scipy.sparse.csr_matrix(p_grid.T @ grid_matrix(stencil) @ p_grid)
        dof1, n1, px1, pz1 = dof_maps[1]
        stencils += (build_block_stencil(a1, shapes[1], dof1, n1, px1, pz1),)
    dof_c, n_c, px_c, pz_c = dof_maps[-1]
    last = np.concatenate([px_c, pz_c])
    last = last[last >= 0]
    perm = dof_order(nested_dissection_order(cur), dof_c, n_c, last)
    coarse = ldl_factor(mats[-1], perm)
    n = np.array([m.shape[0] for m in mats], dtype=np.int64)
    vec_off = np.concatenate([[0], np.cumsum(n)[:-1]]).astype(np.int64)
    a_ptr, a_idx, a_val, row_off = _concat_csr(mats)
    p_ptr, p_idx, p_val, p_row_off = _concat_csr(interps)
    inv_diag = np.concatenate([1.0 / m.diagonal() for m in mats])
    a_diag = _diagonal_positions(a_ptr, a_idx, row_off, n)
    return Hierarchy(
        n=n,
        vec_off=vec_off,
        row_off=row_off,
        a_ptr=a_ptr,
        a_idx=a_idx,
        a_val=a_val,
        a_diag=a_diag,
        inv_diag=inv_diag,
        p_row_off=p_row_off,
        p_ptr=p_ptr,
        p_idx=p_idx,
        p_val=p_val,
        coarse=coarse,
        stencils=stencils,
    )


def _diagonal_positions(
    a_ptr: IntArray, a_idx: Int32Array, row_off: IntArray, n: IntArray
) -> IntArray:
    """Position of every row's diagonal entry (see :class:`Hierarchy`), levels concatenated."""
    out: list[IntArray] = []
    for lvl in range(n.shape[0]):
        ptr = a_ptr[row_off[lvl] : row_off[lvl] + n[lvl] + 1]
        rows = np.repeat(np.arange(n[lvl]), np.diff(ptr))
        cols = a_idx[ptr[0] : ptr[-1]]
        pos = np.flatnonzero(rows == cols) + ptr[0]
        if pos.size != n[lvl]:
            raise ValueError(f"multigrid level {lvl} has a row without a diagonal entry")
        out.append(pos.astype(np.int64))
    return np.concatenate(out)


def _concat_csr(
    mats: list[scipy.sparse.csr_matrix],
) -> tuple[IntArray, Int32Array, FloatArray, IntArray]:
    ptrs: list[IntArray] = []
    idx: list[Int32Array] = []
    val: list[FloatArray] = []
    row_off: list[int] = []
    base = 0
    rows = 0
    for m in mats:
        m = scipy.sparse.csr_matrix(m)
        m.sort_indices()
        row_off.append(rows)
        ptrs.append(m.indptr.astype(np.int64) + base)
        idx.append(m.indices.astype(np.int32))
        val.append(m.data.astype(np.float64))
        base += m.nnz
        rows += m.shape[0] + 1
    if not mats:
        return (
            np.zeros(1, dtype=np.int64),
            np.zeros(0, dtype=np.int32),
            np.zeros(0),
            np.zeros(0, dtype=np.int64),
        )
    return (
        np.concatenate(ptrs),
        np.concatenate(idx),
        np.concatenate(val),
        np.asarray(row_off, dtype=np.int64),
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
def product(
    n: IntArray,
    vec_off: IntArray,
    row_off: IntArray,
    a_ptr: IntArray,
    a_idx: Int32Array,
    a_val: FloatArray,
    st_shape: IntArray,
    st_halo: IntArray,
    st_coef: FloatArray,
    st_coef_off: IntArray,
    st_block: FloatArray,
    st_inv: FloatArray,
    st_node_off: IntArray,
    st_dof: IntArray,
    st_rep: IntArray,
    st_palm: IntArray,
    work: FloatArray,
    x: FloatArray,
    out: FloatArray,
) -> None:
    """``out = A x`` on the finest level: by its stencil when it has one
    (:func:`deformctl.sim.stencil.stencil_product`, using the stencil scratch of :func:`pcg`'s
    ``work``, :func:`pcg_scratch`), else by its compressed rows."""
    n0 = n[0]
    if st_shape.shape[0] == 0 or n.shape[0] < 2:
        csr_matvec(a_ptr, a_idx, a_val, row_off[0], n0, x, out)
        return
    xg = pcg_scratch(n, st_shape, st_halo, work)[8]
    grid_off = stencil_scratch_offsets(st_shape, st_halo)
    xg_l, _, coef, block, _, dof, _, palm = _stencil_level(
        0, 0, n0, grid_off, xg, st_coef, st_coef_off, st_block, st_inv, st_node_off, st_dof,
        st_rep, st_palm,
    )  # fmt: skip
    rows = xg_l.shape[0] // 3
    stencil_product(
        st_shape[0], st_halo[0], coef.reshape((rows, N_COEF)), block, dof, palm,
        a_ptr[row_off[0] : row_off[0] + n0 + 1], a_idx, a_val, x, xg_l, out,
    )  # fmt: skip


@njit(cache=True)
def v_cycle(
    n: IntArray,
    vec_off: IntArray,
    row_off: IntArray,
    a_ptr: IntArray,
    a_idx: Int32Array,
    a_val: FloatArray,
    a_diag: IntArray,
    inv_diag: FloatArray,
    p_row_off: IntArray,
    p_ptr: IntArray,
    p_idx: Int32Array,
    p_val: FloatArray,
    c_colptr: IntArray,
    c_rowidx: Int32Array,
    c_values: FloatArray,
    c_diag: FloatArray,
    c_perm: IntArray,
    st_shape: IntArray,
    st_halo: IntArray,
    st_coef: FloatArray,
    st_coef_off: IntArray,
    st_block: FloatArray,
    st_inv: FloatArray,
    st_node_off: IntArray,
    st_dof: IntArray,
    st_rep: IntArray,
    st_palm: IntArray,
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
    ``ax`` ``[n0]``; ``xs``, ``bs``, ``rs``: scratch for all levels). ``fixed``: the fixed DOFs
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
                lvl, off, nl, grid_off, xg, st_coef, st_coef_off, st_block, st_inv, st_node_off,
                st_dof, st_rep, st_palm,
            )  # fmt: skip
            rows = xg_l.shape[0] // 3
            ptr = a_ptr[r0 : r0 + nl + 1]
            if lvl == 0:  # the finest level: an element stencil
                _stencil_down(
                    st_shape[0], st_halo[0], coef.reshape((rows, N_COEF)), block, inv, dof,
                    rep, palm, ptr, a_idx, a_val, fixed[:nl], b, xg_l, wk_l, rs[off : off + nl],
                )  # fmt: skip
            else:  # level 1: a block stencil
                _stencil_down(
                    st_shape[1], st_halo[1], coef.reshape((rows, 26, 9)), block, inv, dof,
                    rep, palm, ptr, a_idx, a_val, fixed[off : off + nl], bs[off : off + nl],
                    xg_l, wk_l, rs[off : off + nl],
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
        ldl_solve(
            c_colptr,
            c_rowidx,
            c_values,
            c_diag,
            c_perm,
            bs[off : off + nc],
            rs[off : off + nc],
            xs[off : off + nc],
        )
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
                lvl, off, nl, grid_off, xg, st_coef, st_coef_off, st_block, st_inv, st_node_off,
                st_dof, st_rep, st_palm,
            )  # fmt: skip
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
            ptr = a_ptr[r0 : r0 + nl + 1]
            if lvl == 0:  # returns x and A x
                _stencil_up(
                    st_shape[0], st_halo[0], coef.reshape((rows, N_COEF)), block, inv, dof,
                    rep, palm, ptr, a_idx, a_val, fixed[:nl], b, rs[off : off + nl], xg_l, wk_l, x,
                    ax, True, not by_grid,
                )  # fmt: skip
            else:
                _stencil_up(
                    st_shape[1], st_halo[1], coef.reshape((rows, 26, 9)), block, inv, dof,
                    rep, palm, ptr, a_idx, a_val, fixed[off : off + nl], bs[off : off + nl],
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
    lvl: int,
    off: int,
    nl: int,
    grid_off: IntArray,
    xg: FloatArray,
    st_coef: FloatArray,
    st_coef_off: IntArray,
    st_block: FloatArray,
    st_inv: FloatArray,
    st_node_off: IntArray,
    st_dof: IntArray,
    st_rep: IntArray,
    st_palm: IntArray,
) -> tuple[
    FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, IntArray, IntArray, IntArray
]:
    """Stencil level ``lvl``'s views of the packed arrays (:meth:`Hierarchy.stencil_args`;
    ``off``, ``nl``: the level's DOF offset and count): its sweep's and work coordinates in the
    scratch ``xg``, its flat coefficients, own blocks and their inverses, coordinate DOFs, DOF
    representatives and palm DOFs (none for a free object)."""
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
    shape: IntArray,
    halo: int,
    coef: FloatArray,
    block: FloatArray,
    block_inv: FloatArray,
    dof_of: IntArray,
    rep: IntArray,
    palm: IntArray,
    a_ptr: IntArray,
    a_idx: Int32Array,
    a_val: FloatArray,
    fixed: BoolArray,
    b: FloatArray,
    xg: FloatArray,
    work: FloatArray,
    r: FloatArray,
) -> None:
    """A stencil level on the way down: the forward sweep from zero and its residual ``r``."""
    forward_sweep_from_zero(
        shape, halo, coef, block, block_inv, dof_of, rep, palm, a_ptr, a_idx, a_val, fixed, b, xg
    )
    residual_after_forward(
        shape, halo, coef, dof_of, rep, palm, a_ptr, a_idx, a_val, fixed, b, xg, work, r
    )


@njit(cache=True)
def _stencil_up(
    shape: IntArray,
    halo: int,
    coef: FloatArray,
    block: FloatArray,
    block_inv: FloatArray,
    dof_of: IntArray,
    rep: IntArray,
    palm: IntArray,
    a_ptr: IntArray,
    a_idx: Int32Array,
    a_val: FloatArray,
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
        add_dofs(dof_of, halo, fixed, t, xg)
    backward_sweep(
        shape, halo, coef, block, block_inv, dof_of, rep, palm, a_ptr, a_idx, a_val, fixed, b,
        xg, work, x, ax, with_product,
    )  # fmt: skip


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


@njit(cache=True, inline="always")
def _coarse_point(i: int, n: int) -> tuple[int, float]:
    """Linear interpolation along one axis of ``n`` points from the coarse points (every second
    one and the last; axes of one or two points are kept): fine point ``i`` is ``(1 - w) c[j] +
    w c[j + 1]``; returns ``(j, w)``, ``w`` 0 or 0.5 (so a constant is interpolated exactly).
    The one home of the rule: :func:`_axis_interpolation` builds ``P``'s axis factors from it."""
    if n <= 2:
        return i, 0.0
    if i == n - 1:
        return (n - 1) // 2 + (n - 1) % 2, 0.0
    return i // 2, 0.5 if i % 2 else 0.0


@njit(cache=True)
def _grid_restrict(
    shape: IntArray,
    cshape: IntArray,
    dof_of: IntArray,
    rep: IntArray,
    cdof_of: IntArray,
    r: FloatArray,
    part: FloatArray,
    out: FloatArray,
) -> None:
    """``out = P^T r`` from the finest level to level 1, by the trilinear interpolation's three
    axis factors on the lattice coordinates instead of :func:`interpolation`'s compressed rows
    (the same sums in another order). ``shape``, ``dof_of``, ``rep``: the finest level's
    particles per axis, coordinate DOFs and DOF representatives; ``cshape``, ``cdof_of``: level
    1's; ``part``: scratch (:func:`stencil_scratch_offsets`).

    A DOF's residual enters at its representative coordinate only; a merged palm DOF's rows of
    ``P`` are equal at every coordinate of its face (the face layer interpolates from the
    coarse face, which is the coarse palm DOF), so that is ``P^T``; the coarse coordinates of a
    palm face add into its DOF."""
    nx, ny, nz = shape[0], shape[1], shape[2]
    cx, cy, cz = cshape[0], cshape[1], cshape[2]
    row = 3 * ny * nz
    zr = 3 * nz
    px = part[: cx * row]
    pxy = part[cx * row : cx * row + cx * cy * zr]
    px[:] = 0.0
    for i in range(nx):
        j, w = _coarse_point(i, nx)
        for k in range(row):
            c = i * row + k
            d = dof_of[c]
            if rep[d] != c:
                continue
            val = r[d]
            if w == 0.0:
                px[j * row + k] += val
            else:
                px[j * row + k] += (1.0 - w) * val
                px[(j + 1) * row + k] += w * val
    pxy[:] = 0.0
    for ix in range(cx):
        for iy in range(ny):
            j, w = _coarse_point(iy, ny)
            src = (ix * ny + iy) * zr
            da = (ix * cy + j) * zr
            if w == 0.0:
                for k in range(zr):
                    pxy[da + k] += px[src + k]
            else:
                db = da + zr
                for k in range(zr):
                    val = px[src + k]
                    pxy[da + k] += (1.0 - w) * val
                    pxy[db + k] += w * val
    out[:] = 0.0
    for ixy in range(cx * cy):
        src = ixy * zr
        dst = ixy * 3 * cz
        for iz in range(nz):
            j, w = _coarse_point(iz, nz)
            for a in range(3):
                val = pxy[src + 3 * iz + a]
                if w == 0.0:
                    out[cdof_of[dst + 3 * j + a]] += val
                else:
                    out[cdof_of[dst + 3 * j + a]] += (1.0 - w) * val
                    out[cdof_of[dst + 3 * (j + 1) + a]] += w * val


@njit(cache=True)
def _grid_prolong_add(
    shape: IntArray,
    cshape: IntArray,
    dof_of: IntArray,
    cdof_of: IntArray,
    fixed: BoolArray,
    xc: FloatArray,
    part: FloatArray,
    halo: int,
    xg: FloatArray,
) -> None:
    """``xg += P xc`` on the free DOFs of the finest level, written to every coordinate of each
    DOF (the sweep's coordinates, ``halo`` particles before the first): :func:`_grid_restrict`'s
    transpose, the three axis factors applied from level 1's DOFs ``xc``. A palm face's
    coordinates all receive its DOF's value (the weights are 0, 1/2 and 1, so the equal coarse
    values interpolate exactly)."""
    nx, ny, nz = shape[0], shape[1], shape[2]
    cx, cy, cz = cshape[0], cshape[1], cshape[2]
    row = 3 * ny * nz
    zr = 3 * nz
    px = part[: cx * row]
    pxy = part[cx * row : cx * row + cx * cy * zr]
    for ixy in range(cx * cy):
        src = ixy * 3 * cz
        dst = ixy * zr
        for iz in range(nz):
            j, w = _coarse_point(iz, nz)
            for a in range(3):
                val = xc[cdof_of[src + 3 * j + a]]
                if w != 0.0:
                    val = (1.0 - w) * val + w * xc[cdof_of[src + 3 * (j + 1) + a]]
                pxy[dst + 3 * iz + a] = val
    for ix in range(cx):
        for iy in range(ny):
            j, w = _coarse_point(iy, ny)
            dst = (ix * ny + iy) * zr
            sa = (ix * cy + j) * zr
            if w == 0.0:
                for k in range(zr):
                    px[dst + k] = pxy[sa + k]
            else:
                sb = sa + zr
                for k in range(zr):
                    px[dst + k] = (1.0 - w) * pxy[sa + k] + w * pxy[sb + k]
    base = 3 * halo
    for i in range(nx):
        j, w = _coarse_point(i, nx)
        for k in range(row):
            c = i * row + k
            if fixed[dof_of[c]]:
                continue
            if w == 0.0:
                xg[base + c] += px[j * row + k]
            else:
                xg[base + c] += (1.0 - w) * px[j * row + k] + w * px[(j + 1) * row + k]


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


@njit(cache=True)
def fix_levels(
    n: IntArray,
    vec_off: IntArray,
    row_off: IntArray,
    a_ptr: IntArray,
    a_idx: Int32Array,
    a_val: FloatArray,
    p_row_off: IntArray,
    p_ptr: IntArray,
    p_idx: Int32Array,
    p_val: FloatArray,
    fixed: BoolArray,
    fixed_all: BoolArray,
    cf: FloatArray,
) -> None:
    """The fixed DOFs of every level (``fixed_all``, concatenated like the level vectors) from
    the finest level's ``fixed``, and the coarsest level's solve for them (``cf``, of
    :func:`coarse_scratch_size`; zeros before its first use, then kept between calls).

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


@njit(cache=True)
def pcg(
    n: IntArray,
    vec_off: IntArray,
    row_off: IntArray,
    a_ptr: IntArray,
    a_idx: Int32Array,
    a_val: FloatArray,
    a_diag: IntArray,
    inv_diag: FloatArray,
    p_row_off: IntArray,
    p_ptr: IntArray,
    p_idx: Int32Array,
    p_val: FloatArray,
    c_colptr: IntArray,
    c_rowidx: Int32Array,
    c_values: FloatArray,
    c_diag: FloatArray,
    c_perm: IntArray,
    st_shape: IntArray,
    st_halo: IntArray,
    st_coef: FloatArray,
    st_coef_off: IntArray,
    st_block: FloatArray,
    st_inv: FloatArray,
    st_node_off: IntArray,
    st_dof: IntArray,
    st_rep: IntArray,
    st_palm: IntArray,
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
    ``st_*``: the stencil levels (:meth:`Hierarchy.stencil_args`; none: every level is swept by
    rows).

    At most one matrix-vector product per solve (the initial residual, skipped when the caller
    knows ``A x``: ``ax_known`` with ``ax = A x`` on entry, read only); each iteration's ``A p``
    is ``A z + beta A p_prev``, with ``A z`` from the V-cycle (:func:`v_cycle`). On return
    ``work[:n[0]]`` holds the final residual ``b - A x`` (the recursive one; 0 on fixed DOFs).

    Returns:
        the number of iterations (``max_iter + 1`` when it did not converge).
    """
    n0 = n[0]
    tot = 0
    for lvl in range(n.shape[0]):
        tot += n[lvl]
    r, z, p, q, az, xs, bs, rs, xg, cf = pcg_scratch(n, st_shape, st_halo, work)
    if not ax_known:
        product(
            n, vec_off, row_off, a_ptr, a_idx, a_val, st_shape, st_halo, st_coef, st_coef_off,
            st_block, st_inv, st_node_off, st_dof, st_rep, st_palm, work, x, q,
        )  # fmt: skip
        ax = q
    rr = 0.0
    for i in range(n0):
        r[i] = 0.0 if fixed[i] else b[i] - ax[i]
        rr += r[i] * r[i]
    if np.sqrt(rr) <= tol:
        return 0
    # the coarse levels' fixed DOFs (only when a V-cycle runs)
    fixed_all = np.empty(tot, dtype=np.bool_)
    fix_levels(
        n, vec_off, row_off, a_ptr, a_idx, a_val, p_row_off, p_ptr, p_idx, p_val, fixed, fixed_all,
        cf,
    )  # fmt: skip
    rz = 0.0
    for it in range(1, max_iter + 1):
        v_cycle(
            n, vec_off, row_off, a_ptr, a_idx, a_val, a_diag, inv_diag, p_row_off, p_ptr, p_idx,
            p_val, c_colptr, c_rowidx, c_values, c_diag, c_perm, st_shape, st_halo, st_coef,
            st_coef_off, st_block, st_inv, st_node_off, st_dof, st_rep, st_palm, fixed_all, r, z,
            az, xs, bs, rs, xg, cf,
        )  # fmt: skip
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


def solve(
    hierarchy: Hierarchy,
    fixed: BoolArray,
    b: FloatArray,
    *,
    rel_tol: float,
    max_iter: int = 1000,
    x0: FloatArray | None = None,
) -> FloatArray:
    """Solve ``A x = b`` on the free DOFs (``x = x0`` on the fixed ones, default 0) by :func:`pcg`
    to a residual of ``rel_tol * |b|``.

    Raises:
        RuntimeError: CG did not converge within ``max_iter`` iterations.
    """
    h = hierarchy
    n0 = int(h.n[0])
    x = np.zeros(n0) if x0 is None else np.array(x0, dtype=np.float64)
    work = np.zeros(h.work_size)
    c = h.coarse
    bb = np.ascontiguousarray(b, dtype=np.float64)
    tol = rel_tol * float(np.linalg.norm(np.where(fixed, 0.0, bb)))
    args = (
        h.n, h.vec_off, h.row_off, h.a_ptr, h.a_idx, h.a_val, h.a_diag, h.inv_diag, h.p_row_off,
        h.p_ptr, h.p_idx, h.p_val, c.colptr, c.rowidx, c.values, c.diag, c.perm,
        *h.stencil_args(), np.ascontiguousarray(fixed, dtype=np.bool_), bb, x, tol, max_iter,
        work, work[:0], False,
    )  # fmt: skip
    its = pcg(*args)
    if its > max_iter:
        raise RuntimeError(f"multigrid CG did not converge in {max_iter} iterations")
    return x
