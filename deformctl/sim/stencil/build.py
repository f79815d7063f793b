"""The stencil levels' arrays and their builders (see :mod:`deformctl.sim.stencil`)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.sparse

from deformctl.arraytypes import FloatArray, Int32Array, IntArray
from deformctl.sim.lattice import Lattice

#: the 9 element directions (grid offsets), each element stored with its lower-index particle:
#: axial x, y, z, then the face diagonals (as :mod:`deformctl.sim.lattice` builds them)
DIRECTIONS = (
    (1, 0, 0),
    (0, 1, 0),
    (0, 0, 1),
    (1, 1, 0),
    (1, -1, 0),
    (1, 0, 1),
    (1, 0, -1),
    (0, 1, 1),
    (0, 1, -1),
)
#: the two coordinates an element direction couples (equal for the axial ones)
DIRECTION_AXES = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 1), (0, 2), (0, 2), (1, 2), (1, 2))
#: coefficients per particle: one per axial direction (``w``), three per diagonal
#: (``w n_a^2, w n_a n_b, w n_b^2``) at ``3 + 3 (d - 3)``
N_COEF = 21
#: the 13 neighbour offsets of a 27-point stencil with a higher index (a coarse level's
#: Galerkin matrix couples every particle to its 26 neighbours by full 3x3 blocks; each pair's
#: block is stored once, with the lower-index particle)
UPPER_OFFSETS = tuple(
    (dx, dy, dz)
    for dx in (-1, 0, 1)
    for dy in (-1, 0, 1)
    for dz in (-1, 0, 1)
    if (dx, dy, dz) > (0, 0, 0)
)


class Stencil(NamedTuple):
    """The finest level's matrix as a lattice stencil (see :mod:`deformctl.sim.stencil`).

    A named tuple of arrays: the sweeps (:mod:`deformctl.sim.stencil.sweeps`) take it as one
    argument, and the V-cycle builds one per stencil level from the packed arrays.

    Two kinds share this layout: the finest level's *element* stencil (``coef`` holds the
    element coefficients, :data:`N_COEF` per particle) and a coarse level's *block* stencil
    (``coef`` holds the matrix's 3x3 blocks to the 13 upper neighbours, row-major, then those
    to the 13 lower ones;
    :func:`build_block_stencil`). The kernels are compiled for each kind (the ``coef`` array's
    dimension selects the neighbour sums at compile time).

    Attributes:
        shape: particles per axis ``[3]`` (C-order particle numbering).
        halo: zero rows before and after the particles in ``coef`` and in the sweeps' coordinate
            array, so that every neighbour offset stays in bounds.
        coef: element coefficients of each particle's 9 outgoing directions, ``[n + 2 halo, 21]``
            (``n`` particles; a missing element has zeros), or its upper and lower blocks
            ``[n + 2 halo, 26, 9]``.
        block: each particle's own 3x3 block (row-major), ``[n, 9]``.
        block_inv: its inverse, ``[n, 9]`` (used when all three coordinates are free).
        dof_of: generalised DOF of every coordinate ``3 p + a``, ``[3 n]``.
        rep: one coordinate ``3 p + a`` of every generalised DOF, ``[n_dof]``.
        palm: the palm DOFs (left x, left z, right x, right z; increasing, all numbered after the
            particles' own DOFs), ``[4]``, or ``[0]`` for a free object.
    """

    shape: IntArray
    halo: int
    coef: FloatArray
    block: FloatArray
    block_inv: FloatArray
    dof_of: IntArray
    rep: IntArray
    palm: IntArray

    @property
    def n_particles(self) -> int:
        """Number of particles."""
        return int(self.block.shape[0])

    @property
    def grid_len(self) -> int:
        """Length of the sweeps' coordinate scratch (halo included)."""
        return 3 * (self.n_particles + 2 * self.halo)

    @property
    def nbytes(self) -> int:
        """Memory held, bytes."""
        arrays = (self.coef, self.block, self.block_inv, self.dof_of, self.rep, self.palm)
        return sum(a.nbytes for a in arrays)


def halo_of(shape: tuple[int, int, int]) -> int:
    """The largest neighbour offset plus one, particles."""
    _, ny, nz = shape
    return ny * nz + nz + 1


def direction_offsets(shape: tuple[int, int, int]) -> IntArray:
    """Index offset of each of :data:`DIRECTIONS` in a lattice of ``shape``, ``[9]``."""
    _, ny, nz = shape
    return np.array([dx * ny * nz + dy * nz + dz for dx, dy, dz in DIRECTIONS], dtype=np.int64)


def build_stencil(
    lattice: Lattice,
    element_coef: FloatArray,
    particle_diag: FloatArray,
    dof_of: IntArray,
    n_dof: int,
    palm_x: IntArray,
    palm_z: IntArray,
) -> Stencil:
    """The stencil of ``R^T (diag(particle_diag) (x) I_3 + sum_e w_e ...) R`` (see module docs).

    Args:
        element_coef: ``w_e`` of every element of ``lattice`` (``h^2 k_e + h c_e`` for the
            implicit matrix), ``[m]``.
        particle_diag: the diagonal term of every particle's three coordinates (its mass), ``[n]``.
        dof_of, n_dof: the generalised DOFs (:func:`deformctl.sim.lattice.palm_dof_map`).
        palm_x, palm_z: the palm DOFs (left, right; ``-1`` for a free object), ``[2]`` each.
    """
    shape = lattice.shape
    n = lattice.n_particles
    halo = halo_of(shape)
    edges = lattice.edges
    step = lattice.grid_index[edges[:, 1]] - lattice.grid_index[edges[:, 0]]
    coef = np.zeros((n + 2 * halo, N_COEF))
    block = np.zeros((n, 3, 3))
    for a in range(3):
        block[:, a, a] = particle_diag
    for d, (off, (a, b)) in enumerate(zip(DIRECTIONS, DIRECTION_AXES, strict=True)):
        sel = np.flatnonzero(np.all(step == np.asarray(off), axis=1))
        if sel.size == 0:
            continue
        w = element_coef[sel]
        nv = lattice.direction[sel]
        src = edges[sel, 0]
        dst = edges[sel, 1]
        if a == b:
            vals = [w * nv[:, a] * nv[:, a]]
            coef[src + halo, d] = vals[0]
        else:
            vals = [w * nv[:, a] * nv[:, a], w * nv[:, a] * nv[:, b], w * nv[:, b] * nv[:, b]]
            for k in range(3):
                coef[src + halo, 3 + 3 * (d - 3) + k] = vals[k]
        full = w[:, None, None] * nv[:, :, None] * nv[:, None, :]
        np.add.at(block, src, full)
        np.add.at(block, dst, full)
    return _finish(shape, halo, coef, block, dof_of, n_dof, palm_x, palm_z)


def _finish(
    shape: tuple[int, int, int],
    halo: int,
    coef: FloatArray,
    block: FloatArray,
    dof_of: IntArray,
    n_dof: int,
    palm_x: IntArray,
    palm_z: IntArray,
) -> Stencil:
    """A :class:`Stencil` from its coefficients and own blocks ``[n, 3, 3]``: the blocks'
    inverses, each DOF's first coordinate, the palm DOFs (checked to be the last four)."""
    n = block.shape[0]
    det = np.linalg.det(block)
    block_inv = np.zeros_like(block)
    ok = det > 0.0
    block_inv[ok] = np.linalg.inv(block[ok])
    rep = np.zeros(n_dof, dtype=np.int64)
    rep[dof_of[::-1]] = np.arange(3 * n - 1, -1, -1)  # the first coordinate of each DOF
    palm = np.array([palm_x[0], palm_z[0], palm_x[1], palm_z[1]], dtype=np.int64)
    if palm[0] < 0:
        palm = palm[:0]
    elif not (np.all(np.diff(palm) > 0) and palm[0] == n_dof - 4):
        raise ValueError("the palm DOFs must be the last four, left x, left z, right x, right z")
    return Stencil(
        shape=np.asarray(shape, dtype=np.int64),
        halo=halo,
        coef=coef,
        block=np.ascontiguousarray(block.reshape(n, 9)),
        block_inv=np.ascontiguousarray(block_inv.reshape(n, 9)),
        dof_of=np.asarray(dof_of, dtype=np.int64),
        rep=rep,
        palm=palm,
    )


def build_block_stencil(
    a_grid: scipy.sparse.spmatrix,
    shape: tuple[int, int, int],
    dof_of: IntArray,
    n_dof: int,
    palm_x: IntArray,
    palm_z: IntArray,
) -> Stencil:
    """The block stencil of ``R^T A_grid R`` (see :class:`Stencil`).

    Args:
        a_grid: a symmetric matrix on the particles' own coordinates (``3 p + a``), coupling
            each particle to its 26 neighbours at most (a coarse level's Galerkin matrix in
            coordinates), ``[3 n, 3 n]``.
        shape, dof_of, n_dof, palm_x, palm_z: the lattice and its generalised DOFs.

    Raises:
        ValueError: ``a_grid`` couples particles that are not neighbours.
    """
    n = shape[0] * shape[1] * shape[2]
    halo = halo_of(shape)
    coo = scipy.sparse.coo_matrix(a_grid)
    rp, ra = coo.row // 3, coo.row % 3
    cp, ca = coo.col // 3, coo.col % 3
    grid = np.stack(np.unravel_index(np.arange(n), shape), axis=1)
    step = grid[cp] - grid[rp]
    if np.any(np.abs(step) > 1):
        raise ValueError("the matrix couples particles that are not lattice neighbours")
    block = np.zeros((n, 3, 3))
    own = np.all(step == 0, axis=1)
    np.add.at(block, (rp[own], ra[own], ca[own]), coo.data[own])
    # the 13 upper blocks A_pq, then (a copy, so that a sweep reads one particle's row) the 13
    # lower ones A_qp = A_pq^T of the neighbours q = p - offset
    m = len(UPPER_OFFSETS)
    coef = np.zeros((n + 2 * halo, 2 * m, 9))
    for i, off in enumerate(UPPER_OFFSETS):
        sel = np.all(step == np.asarray(off), axis=1)
        np.add.at(coef, (rp[sel] + halo, i, 3 * ra[sel] + ca[sel]), coo.data[sel])
        sel = np.all(step == -np.asarray(off), axis=1)
        np.add.at(coef, (rp[sel] + halo, m + i, 3 * ra[sel] + ca[sel]), coo.data[sel])
    return _finish(shape, halo, coef, block, dof_of, n_dof, palm_x, palm_z)


def grid_matrix(st: Stencil) -> scipy.sparse.csr_matrix:
    """The matrix a stencil stands for, on the particles' own coordinates (``3 p + a``, no palm
    DOFs merged), ``[3 n, 3 n]`` (for building coarse levels and for tests)."""
    n = st.n_particles
    shape = (int(st.shape[0]), int(st.shape[1]), int(st.shape[2]))
    h = st.halo
    rows: list[IntArray] = [np.repeat(3 * np.arange(n)[:, None] + np.arange(3), 3, axis=1).ravel()]
    cols: list[IntArray] = [np.tile(3 * np.arange(n)[:, None] + np.arange(3), (1, 3)).ravel()]
    vals: list[FloatArray] = [st.block.ravel()]
    p = np.arange(n)
    grid = np.stack(np.unravel_index(p, shape), axis=1)
    if st.coef.ndim == 2:
        for d, (off, (a, b)) in enumerate(zip(DIRECTIONS, DIRECTION_AXES, strict=True)):
            q = grid + np.asarray(off)
            ok = np.all((q >= 0) & (q < np.asarray(shape)), axis=1)
            src = p[ok]
            dst = np.ravel_multi_index(q[ok].T, shape)
            if a == b:
                entries = [(a, a, -st.coef[src + h, d])]
            else:
                k = 3 + 3 * (d - 3)
                c0, c1, c2 = (-st.coef[src + h, k + i] for i in range(3))
                entries = [(a, a, c0), (a, b, c1), (b, a, c1), (b, b, c2)]
            for ra, rb, v in entries:
                rows += [3 * src + ra, 3 * dst + rb]
                cols += [3 * dst + rb, 3 * src + ra]
                vals += [v, v]
    else:
        for i, off in enumerate(UPPER_OFFSETS):  # the upper blocks (the lower ones are copies)
            q = grid + np.asarray(off)
            ok = np.all((q >= 0) & (q < np.asarray(shape)), axis=1)
            src = p[ok]
            dst = np.ravel_multi_index(q[ok].T, shape)
            for ra in range(3):
                for rb in range(3):
                    v = st.coef[src + h, i, 3 * ra + rb]
                    rows += [3 * src + ra, 3 * dst + rb]
                    cols += [3 * dst + rb, 3 * src + ra]
                    vals += [v, v]
    m = scipy.sparse.coo_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(3 * n, 3 * n)
    ).tocsr()
    m.eliminate_zeros()
    return m


class Rows(NamedTuple):
    """A level's matrix in compressed rows, as the sweeps read it (only the palm DOFs' rows):
    row ``g`` is ``val[ptr[g] : ptr[g + 1]]`` at columns ``idx[...]``."""

    ptr: IntArray
    idx: Int32Array
    val: FloatArray
