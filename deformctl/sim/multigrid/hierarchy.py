"""The multigrid levels of a lattice matrix: coarsening, interpolation, Galerkin products, and
a solve by the multigrid CG (see :mod:`deformctl.sim.multigrid`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse

from deformctl.arraytypes import BoolArray, FloatArray, Int32Array, IntArray
from deformctl.sim.lattice import shape_dof_map
from deformctl.sim.multigrid.cg import pcg
from deformctl.sim.multigrid.levels import LevelArrays, MultigridArrays, StencilArrays, fix_levels
from deformctl.sim.multigrid.scratch import coarse_scratch_size, pcg_work_size
from deformctl.sim.multigrid.transfer import _coarse_point
from deformctl.sim.solver import LDLFactor, dof_order, ldl_factor, nested_dissection_order
from deformctl.sim.stencil import Stencil, build_block_stencil, grid_matrix


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
        sts = self.stencil_args()
        return int(pcg_work_size(self.n, sts.shape, sts.halo))

    def kernel_args(self) -> MultigridArrays:
        """The hierarchy as :func:`pcg`, :func:`v_cycle` and the step kernels take it; packed
        once per hierarchy."""
        return self._kernel_args

    @cached_property
    def _kernel_args(self) -> MultigridArrays:
        levels = LevelArrays(
            self.n, self.vec_off, self.row_off, self.a_ptr, self.a_idx, self.a_val, self.a_diag,
            self.inv_diag, self.p_row_off, self.p_ptr, self.p_idx, self.p_val,
        )  # fmt: skip
        return MultigridArrays(levels, self.coarse, self.stencil_args())

    def fixed_levels(self, fixed: BoolArray) -> tuple[BoolArray, FloatArray]:
        """The fixed DOFs of every level for the finest level's ``fixed``, and the coarsest
        level's factor for them: :func:`v_cycle`'s ``fixed`` and ``cf`` (:func:`fix_levels`)."""
        fixed_all = np.zeros(int(self.n.sum()), dtype=np.bool_)
        cf = np.zeros(int(coarse_scratch_size(self.n)))
        fixed_arr = np.ascontiguousarray(fixed, dtype=np.bool_)
        fix_levels(self.kernel_args().levels, fixed_arr, fixed_all, cf)
        return fixed_all, cf

    def stencil_args(self) -> StencilArrays:
        """The stencils' arrays, concatenated level after level (see :func:`v_cycle`); packed
        once per hierarchy."""
        return self._packed_stencils

    @cached_property
    def _packed_stencils(self) -> StencilArrays:
        sts = self.stencils
        nodes = np.cumsum([0] + [st.n_particles for st in sts]).astype(np.int64)
        coef_off = np.cumsum([0] + [st.coef.size for st in sts]).astype(np.int64)
        palm = np.full((len(sts), 4), -1, dtype=np.int64)
        for lvl, st in enumerate(sts):
            palm[lvl, : st.palm.size] = st.palm
        if not sts:
            return StencilArrays(
                np.zeros((0, 3), dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0),
                coef_off, np.zeros((0, 9)), np.zeros((0, 9)), nodes, np.zeros(0, dtype=np.int64),
                np.zeros(0, dtype=np.int64), palm,
            )  # fmt: skip
        return StencilArrays(
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
    bb = np.ascontiguousarray(b, dtype=np.float64)
    tol = rel_tol * float(np.linalg.norm(np.where(fixed, 0.0, bb)))
    fixed_arr = np.ascontiguousarray(fixed, dtype=np.bool_)
    its = pcg(h.kernel_args(), fixed_arr, bb, x, tol, max_iter, work, work[:0], False)
    if its > max_iter:
        raise RuntimeError(f"multigrid CG did not converge in {max_iter} iterations")
    return x
