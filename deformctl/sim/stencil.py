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

from dataclasses import dataclass

import numpy as np
import scipy.sparse
from numba import njit
from numba.extending import overload
from numpy.typing import NDArray

from deformctl.sim.lattice import Lattice

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
Int32Array = NDArray[np.int32]
BoolArray = NDArray[np.bool_]

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


@dataclass(frozen=True, eq=False)
class Stencil:
    """The finest level's matrix as a lattice stencil (see the module docs).

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


@njit(cache=True, inline="always")
def _offsets(shape: IntArray) -> IntArray:
    """:func:`direction_offsets` inside the kernels."""
    ny = shape[1]
    nz = shape[2]
    off = np.empty(9, dtype=np.int64)
    off[0] = ny * nz
    off[1] = nz
    off[2] = 1
    off[3] = ny * nz + nz
    off[4] = ny * nz - nz
    off[5] = ny * nz + 1
    off[6] = ny * nz - 1
    off[7] = nz + 1
    off[8] = nz - 1
    return off


@njit(cache=True, inline="always")
def _sum_out(
    coef: FloatArray, xg: FloatArray, pp: int, off: IntArray
) -> tuple[float, float, float]:
    """``sum w n n^T x_q`` over the particle's 9 outgoing elements (neighbours ``pp + off``)."""
    s0 = coef[pp, 0] * xg[3 * (pp + off[0])]
    s1 = coef[pp, 1] * xg[3 * (pp + off[1]) + 1]
    s2 = coef[pp, 2] * xg[3 * (pp + off[2]) + 2]
    # xy diagonals
    for d in range(3, 5):
        q = 3 * (pp + off[d])
        k = 3 + 3 * (d - 3)
        c0 = coef[pp, k]
        c1 = coef[pp, k + 1]
        c2 = coef[pp, k + 2]
        s0 += c0 * xg[q] + c1 * xg[q + 1]
        s1 += c1 * xg[q] + c2 * xg[q + 1]
    for d in range(5, 7):
        q = 3 * (pp + off[d])
        k = 3 + 3 * (d - 3)
        c0 = coef[pp, k]
        c1 = coef[pp, k + 1]
        c2 = coef[pp, k + 2]
        s0 += c0 * xg[q] + c1 * xg[q + 2]
        s2 += c1 * xg[q] + c2 * xg[q + 2]
    for d in range(7, 9):
        q = 3 * (pp + off[d])
        k = 3 + 3 * (d - 3)
        c0 = coef[pp, k]
        c1 = coef[pp, k + 1]
        c2 = coef[pp, k + 2]
        s1 += c0 * xg[q + 1] + c1 * xg[q + 2]
        s2 += c1 * xg[q + 1] + c2 * xg[q + 2]
    return s0, s1, s2


@njit(cache=True, inline="always")
def _sum_in(coef: FloatArray, xg: FloatArray, pp: int, off: IntArray) -> tuple[float, float, float]:
    """``sum w n n^T x_q`` over the particle's 9 incoming elements (neighbours ``pp - off``,
    which own them)."""
    q0 = pp - off[0]
    q1 = pp - off[1]
    q2 = pp - off[2]
    s0 = coef[q0, 0] * xg[3 * q0]
    s1 = coef[q1, 1] * xg[3 * q1 + 1]
    s2 = coef[q2, 2] * xg[3 * q2 + 2]
    for d in range(3, 5):
        qq = pp - off[d]
        q = 3 * qq
        k = 3 + 3 * (d - 3)
        c0 = coef[qq, k]
        c1 = coef[qq, k + 1]
        c2 = coef[qq, k + 2]
        s0 += c0 * xg[q] + c1 * xg[q + 1]
        s1 += c1 * xg[q] + c2 * xg[q + 1]
    for d in range(5, 7):
        qq = pp - off[d]
        q = 3 * qq
        k = 3 + 3 * (d - 3)
        c0 = coef[qq, k]
        c1 = coef[qq, k + 1]
        c2 = coef[qq, k + 2]
        s0 += c0 * xg[q] + c1 * xg[q + 2]
        s2 += c1 * xg[q] + c2 * xg[q + 2]
    for d in range(7, 9):
        qq = pp - off[d]
        q = 3 * qq
        k = 3 + 3 * (d - 3)
        c0 = coef[qq, k]
        c1 = coef[qq, k + 1]
        c2 = coef[qq, k + 2]
        s1 += c0 * xg[q + 1] + c1 * xg[q + 2]
        s2 += c1 * xg[q + 1] + c2 * xg[q + 2]
    return s0, s1, s2


@njit(cache=True, inline="always")
def _upper_offsets(shape: IntArray) -> IntArray:
    """Index offsets of :data:`UPPER_OFFSETS` inside the kernels."""
    ny = shape[1]
    nz = shape[2]
    off = np.empty(13, dtype=np.int64)
    i = 0
    for dx in range(-1, 2):
        for dy in range(-1, 2):
            for dz in range(-1, 2):
                if dx > 0 or (dx == 0 and (dy > 0 or (dy == 0 and dz > 0))):
                    off[i] = dx * ny * nz + dy * nz + dz
                    i += 1
    return off


@njit(cache=True, inline="always")
def _block_sum_out(
    coef: FloatArray, xg: FloatArray, pp: int, off: IntArray
) -> tuple[float, float, float]:
    """``-sum A_pq x_q`` over the particle's 13 upper neighbours (blocks stored with it)."""
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    for i in range(13):
        q = 3 * (pp + off[i])
        x0 = xg[q]
        x1 = xg[q + 1]
        x2 = xg[q + 2]
        s0 -= coef[pp, i, 0] * x0 + coef[pp, i, 1] * x1 + coef[pp, i, 2] * x2
        s1 -= coef[pp, i, 3] * x0 + coef[pp, i, 4] * x1 + coef[pp, i, 5] * x2
        s2 -= coef[pp, i, 6] * x0 + coef[pp, i, 7] * x1 + coef[pp, i, 8] * x2
    return s0, s1, s2


@njit(cache=True, inline="always")
def _block_sum_in(
    coef: FloatArray, xg: FloatArray, pp: int, off: IntArray
) -> tuple[float, float, float]:
    """``-sum A_pq x_q`` over the particle's 13 lower neighbours (their blocks, stored with the
    particle after the upper ones)."""
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    for i in range(13):
        qq = pp - off[i]
        q = 3 * qq
        x0 = xg[q]
        x1 = xg[q + 1]
        x2 = xg[q + 2]
        j = 13 + i
        s0 -= coef[pp, j, 0] * x0 + coef[pp, j, 1] * x1 + coef[pp, j, 2] * x2
        s1 -= coef[pp, j, 3] * x0 + coef[pp, j, 4] * x1 + coef[pp, j, 5] * x2
        s2 -= coef[pp, j, 6] * x0 + coef[pp, j, 7] * x1 + coef[pp, j, 8] * x2
    return s0, s1, s2


def _sums_in(coef: FloatArray, xg: FloatArray, pp: int, off: IntArray) -> tuple[float, ...]:
    """The lower neighbours' terms ``-sum A_pq x_q`` of either stencil kind (numba only)."""
    raise NotImplementedError  # pragma: no cover - replaced by the overload in compiled code


def _sums_out(coef: FloatArray, xg: FloatArray, pp: int, off: IntArray) -> tuple[float, ...]:
    """The upper neighbours' terms of either stencil kind (numba only)."""
    raise NotImplementedError  # pragma: no cover


def _scatter(
    coef: FloatArray, axg: FloatArray, pp: int, off: IntArray, d0: float, d1: float, d2: float
) -> None:
    """A particle's change ``delta`` into its upper neighbours' ``A x`` (numba only)."""
    raise NotImplementedError  # pragma: no cover


def _kernel_offsets(coef: FloatArray, shape: IntArray) -> IntArray:
    """The neighbour offsets of the stencil kind of ``coef`` (numba only)."""
    raise NotImplementedError  # pragma: no cover


# the kind is chosen when a kernel is compiled, by the dimension of ``coef``: each kernel is
# compiled once per kind, with no per-particle branch
@overload(_sums_in, inline="always")
def _sums_in_kind(coef, xg, pp, off):  # type: ignore[no-untyped-def]
    if coef.ndim == 3:
        return lambda coef, xg, pp, off: _block_sum_in(coef, xg, pp, off)
    return lambda coef, xg, pp, off: _sum_in(coef, xg, pp, off)


@overload(_sums_out, inline="always")
def _sums_out_kind(coef, xg, pp, off):  # type: ignore[no-untyped-def]
    if coef.ndim == 3:
        return lambda coef, xg, pp, off: _block_sum_out(coef, xg, pp, off)
    return lambda coef, xg, pp, off: _sum_out(coef, xg, pp, off)


@overload(_scatter, inline="always")
def _scatter_kind(coef, axg, pp, off, d0, d1, d2):  # type: ignore[no-untyped-def]
    if coef.ndim == 3:
        return lambda coef, axg, pp, off, d0, d1, d2: _block_scatter_out(
            coef, axg, pp, off, d0, d1, d2
        )
    return lambda coef, axg, pp, off, d0, d1, d2: _scatter_out(coef, axg, pp, off, d0, d1, d2)


@overload(_kernel_offsets, inline="always")
def _kernel_offsets_kind(coef, shape):  # type: ignore[no-untyped-def]
    if coef.ndim == 3:
        return lambda coef, shape: _upper_offsets(shape)
    return lambda coef, shape: _offsets(shape)


@njit(cache=True, inline="always")
def _solve_free(
    p: int, pp: int, r0: float, r1: float, r2: float, block_inv: FloatArray, xg: FloatArray
) -> None:
    """``x_p = block_p^-1 r`` for a particle whose three coordinates are free."""
    base = 3 * pp
    xg[base] = block_inv[p, 0] * r0 + block_inv[p, 1] * r1 + block_inv[p, 2] * r2
    xg[base + 1] = block_inv[p, 3] * r0 + block_inv[p, 4] * r1 + block_inv[p, 5] * r2
    xg[base + 2] = block_inv[p, 6] * r0 + block_inv[p, 7] * r1 + block_inv[p, 8] * r2


@njit(cache=True)
def _solve_particle(
    p: int,
    pp: int,
    free0: bool,
    free1: bool,
    free2: bool,
    r0: float,
    r1: float,
    r2: float,
    block: FloatArray,
    xg: FloatArray,
) -> None:
    """Solve particle ``p``'s free coordinates (one or two) of ``block x = r`` (``r``: the
    right-hand side with the neighbours' terms), the others held at their values in ``xg`` (row
    ``pp``)."""
    base = 3 * pp
    # the held coordinates' terms of the block
    x0 = xg[base]
    x1 = xg[base + 1]
    x2 = xg[base + 2]
    if not free0:
        r1 -= block[p, 3] * x0
        r2 -= block[p, 6] * x0
    if not free1:
        r0 -= block[p, 1] * x1
        r2 -= block[p, 7] * x1
    if not free2:
        r0 -= block[p, 2] * x2
        r1 -= block[p, 5] * x2
    nfree = int(free0) + int(free1) + int(free2)
    if nfree == 1:
        if free0:
            xg[base] = r0 / block[p, 0]
        elif free1:
            xg[base + 1] = r1 / block[p, 4]
        else:
            xg[base + 2] = r2 / block[p, 8]
        return
    if nfree == 2:
        # the 2x2 block of the free pair (i, j)
        if not free2:
            i, j, ri, rj = 0, 1, r0, r1
        elif not free1:
            i, j, ri, rj = 0, 2, r0, r2
        else:
            i, j, ri, rj = 1, 2, r1, r2
        aii = block[p, 4 * i]
        aij = block[p, 3 * i + j]
        ajj = block[p, 4 * j]
        det = aii * ajj - aij * aij
        xg[base + i] = (ajj * ri - aij * rj) / det
        xg[base + j] = (aii * rj - aij * ri) / det


@njit(cache=True, inline="always")
def _palm_row(
    g: int,
    b: FloatArray,
    a_ptr: IntArray,
    a_idx: Int32Array,
    a_val: FloatArray,
    rep: IntArray,
    halo: int,
    xg: FloatArray,
) -> tuple[float, float]:
    """``(b - A x)_g`` without the diagonal term, and ``A_gg``, for a palm DOF (compressed row;
    every other DOF's value read at its representative coordinate)."""
    acc = b[g] if b.shape[0] > 0 else 0.0
    diag = 0.0
    for k in range(a_ptr[g], a_ptr[g + 1]):
        j = a_idx[k]
        if j == g:
            diag = a_val[k]
        else:
            acc -= a_val[k] * xg[3 * halo + rep[j]]
    return acc, diag


@njit(cache=True)
def _set_palm(k: int, value: float, shape: IntArray, halo: int, xg: FloatArray) -> None:
    """Write palm DOF ``k`` (0 left x, 1 left z, 2 right x, 3 right z) to its face's coordinates."""
    face = shape[1] * shape[2]
    n = shape[0] * face
    first = 0 if k < 2 else n - face
    axis = 0 if k % 2 == 0 else 2
    for p in range(first + halo, first + halo + face):
        xg[3 * p + axis] = value


@njit(cache=True)
def forward_sweep_from_zero(
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
) -> None:
    """One forward block Gauss–Seidel sweep of ``A x = b`` from ``x = 0`` (``xg``: coordinates,
    halo included, set here): the palm DOFs first, then the particles in index order. Starting
    from zero, a particle's later neighbours are still zero, so only its incoming elements are
    read (and, on the left palm's face and next to the right palm, the outgoing ones for the
    palm-bound coordinates)."""
    nx, ny, nz = shape[0], shape[1], shape[2]
    n = nx * ny * nz
    face = ny * nz
    gripped = palm.shape[0] > 0
    off = _kernel_offsets(coef, shape)
    for i in range(xg.shape[0]):
        xg[i] = 0.0
    for k in range(palm.shape[0]):
        g = palm[k]
        if fixed[g]:
            continue
        acc, diag = _palm_row(g, b, a_ptr, a_idx, a_val, rep, halo, xg)
        _set_palm(k, acc / diag, shape, halo, xg)
    for p in range(n):
        pp = p + halo
        on_face = gripped and (p < face or p >= n - face)
        g0 = dof_of[3 * p]
        g1 = dof_of[3 * p + 1]
        g2 = dof_of[3 * p + 2]
        f0 = (not on_face) and not fixed[g0]
        f1 = not fixed[g1]
        f2 = (not on_face) and not fixed[g2]
        s0, s1, s2 = _sums_in(coef, xg, pp, off)
        if gripped and (p < face or p >= n - 2 * face):
            # on the left palm or next to the right one: later neighbours' palm-bound
            # coordinates are already set
            t0, t1, t2 = _sums_out(coef, xg, pp, off)
            s0 += t0
            s1 += t1
            s2 += t2
        if f0 and f1 and f2:
            _solve_free(p, pp, b[g0] + s0, b[g1] + s1, b[g2] + s2, block_inv, xg)
        elif f0 or f1 or f2:
            _solve_particle(
                p, pp, f0, f1, f2, (b[g0] if f0 else 0.0) + s0, (b[g1] if f1 else 0.0) + s1,
                (b[g2] if f2 else 0.0) + s2, block, xg,
            )  # fmt: skip


@njit(cache=True)
def residual_after_forward(
    shape: IntArray,
    halo: int,
    coef: FloatArray,
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
    out: FloatArray,
) -> None:
    """``out = b - A x`` (0 on the fixed DOFs) right after :func:`forward_sweep_from_zero`.

    Each particle's free rows held exactly when it was solved, with the palm DOFs already at
    their final values and its later neighbours still at zero, so its residual is the outgoing
    elements' terms of what changed afterwards: the later particles' own coordinates (the
    palm-bound ones, copied to ``work`` as zero, did not change). Half a pass; the palm rows (all
    of the particles changed after them) in full. ``work``: scratch like ``xg``."""
    nx, ny, nz = shape[0], shape[1], shape[2]
    n = nx * ny * nz
    face = ny * nz
    off = _kernel_offsets(coef, shape)
    for i in range(xg.shape[0]):
        work[i] = xg[i]
    if palm.shape[0] > 0:
        for first in (0, n - face):
            for p in range(first + halo, first + halo + face):
                work[3 * p] = 0.0
                work[3 * p + 2] = 0.0
    for p in range(n):
        t0, t1, t2 = _sums_out(coef, work, p + halo, off)
        g0 = dof_of[3 * p]
        g1 = dof_of[3 * p + 1]
        g2 = dof_of[3 * p + 2]
        out[g0] = 0.0 if fixed[g0] else t0
        out[g1] = 0.0 if fixed[g1] else t1
        out[g2] = 0.0 if fixed[g2] else t2
    for k in range(palm.shape[0]):
        g = palm[k]
        if fixed[g]:
            out[g] = 0.0
            continue
        acc, diag = _palm_row(g, b, a_ptr, a_idx, a_val, rep, halo, xg)
        out[g] = acc - diag * xg[3 * halo + rep[g]]


@njit(cache=True)
def backward_sweep(
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
    axg: FloatArray,
    x: FloatArray,
    ax: FloatArray,
    with_product: bool,
) -> None:
    """One backward block Gauss–Seidel sweep of ``A x = b`` from the ``x`` in ``xg``: the
    particles in decreasing index order, then the palm DOFs in decreasing order (the reverse of
    :func:`forward_sweep_from_zero`). Returns the DOFs ``x`` and ``ax = A x`` (0 on the fixed
    DOFs; ``axg``: scratch like ``xg``).

    ``A x`` comes from the sweep itself: right after a particle or palm DOF is solved its free
    rows hold exactly (``A x = b``), and only what is solved after it changes them afterwards, so
    each change is added to the rows it couples to as it is made: a particle's through its
    outgoing elements (the particles solved after it have lower indices), a palm DOF's through
    its compressed row."""
    nx, ny, nz = shape[0], shape[1], shape[2]
    n = nx * ny * nz
    face = ny * nz
    gripped = palm.shape[0] > 0
    off = _kernel_offsets(coef, shape)
    for p in range(n - 1, -1, -1):
        pp = p + halo
        base = 3 * pp
        on_face = gripped and (p < face or p >= n - face)
        g0 = dof_of[3 * p]
        g1 = dof_of[3 * p + 1]
        g2 = dof_of[3 * p + 2]
        f0 = (not on_face) and not fixed[g0]
        f1 = not fixed[g1]
        f2 = (not on_face) and not fixed[g2]
        if not (f0 or f1 or f2):
            continue
        old0 = xg[base]
        old1 = xg[base + 1]
        old2 = xg[base + 2]
        s0, s1, s2 = _sums_in(coef, xg, pp, off)
        t0, t1, t2 = _sums_out(coef, xg, pp, off)
        if f0 and f1 and f2:
            _solve_free(p, pp, b[g0] + s0 + t0, b[g1] + s1 + t1, b[g2] + s2 + t2, block_inv, xg)
        else:
            _solve_particle(
                p, pp, f0, f1, f2, (b[g0] if f0 else 0.0) + s0 + t0,
                (b[g1] if f1 else 0.0) + s1 + t1, (b[g2] if f2 else 0.0) + s2 + t2, block, xg,
            )  # fmt: skip
        if with_product:
            axg[base] = b[g0] if f0 else 0.0
            axg[base + 1] = b[g1] if f1 else 0.0
            axg[base + 2] = b[g2] if f2 else 0.0
            d0 = xg[base] - old0
            d1 = xg[base + 1] - old1
            d2 = xg[base + 2] - old2
            _scatter(coef, axg, pp, off, d0, d1, d2)
    np_ = palm.shape[0]
    axp = np.zeros(4)
    for k in range(np_ - 1, -1, -1):
        g = palm[k]
        if fixed[g]:
            continue
        acc, diag = _palm_row(g, b, a_ptr, a_idx, a_val, rep, halo, xg)
        new = acc / diag
        delta = new - xg[3 * halo + rep[g]]
        _set_palm(k, new, shape, halo, xg)
        if not with_product:
            continue
        axp[k] = b[g]
        # the change reaches every row of the palm's column (its row: A is symmetric)
        for kk in range(a_ptr[g], a_ptr[g + 1]):
            j = a_idx[kk]
            if j == g:
                continue
            if j >= palm[0]:
                axp[j - palm[0]] += a_val[kk] * delta
            else:
                axg[3 * halo + rep[j]] += a_val[kk] * delta
    base = 3 * halo
    for g in range(rep.shape[0]):
        if fixed[g]:
            x[g] = 0.0
            if with_product:
                ax[g] = 0.0
        else:
            x[g] = xg[base + rep[g]]
            if with_product:
                ax[g] = axg[base + rep[g]]
    if with_product:
        for k in range(np_):
            if not fixed[palm[k]]:
                ax[palm[k]] = axp[k]


@njit(cache=True, inline="always")
def _block_scatter_out(
    coef: FloatArray, axg: FloatArray, pp: int, off: IntArray, d0: float, d1: float, d2: float
) -> None:
    """``(A x)_q += A_qp delta`` for the particle's 13 upper neighbours (``A_qp = A_pq^T``)."""
    for i in range(13):
        q = 3 * (pp + off[i])
        axg[q] += coef[pp, i, 0] * d0 + coef[pp, i, 3] * d1 + coef[pp, i, 6] * d2
        axg[q + 1] += coef[pp, i, 1] * d0 + coef[pp, i, 4] * d1 + coef[pp, i, 7] * d2
        axg[q + 2] += coef[pp, i, 2] * d0 + coef[pp, i, 5] * d1 + coef[pp, i, 8] * d2


@njit(cache=True, inline="always")
def _scatter_out(
    coef: FloatArray, axg: FloatArray, pp: int, off: IntArray, d0: float, d1: float, d2: float
) -> None:
    """``(A x)_q -= w n n^T delta`` for the particle's outgoing neighbours ``q = pp + off``."""
    q = 3 * (pp + off[0])
    axg[q] -= coef[pp, 0] * d0
    q = 3 * (pp + off[1])
    axg[q + 1] -= coef[pp, 1] * d1
    q = 3 * (pp + off[2])
    axg[q + 2] -= coef[pp, 2] * d2
    for d in range(3, 5):
        q = 3 * (pp + off[d])
        k = 3 + 3 * (d - 3)
        axg[q] -= coef[pp, k] * d0 + coef[pp, k + 1] * d1
        axg[q + 1] -= coef[pp, k + 1] * d0 + coef[pp, k + 2] * d1
    for d in range(5, 7):
        q = 3 * (pp + off[d])
        k = 3 + 3 * (d - 3)
        axg[q] -= coef[pp, k] * d0 + coef[pp, k + 1] * d2
        axg[q + 2] -= coef[pp, k + 1] * d0 + coef[pp, k + 2] * d2
    for d in range(7, 9):
        q = 3 * (pp + off[d])
        k = 3 + 3 * (d - 3)
        axg[q + 1] -= coef[pp, k] * d1 + coef[pp, k + 1] * d2
        axg[q + 2] -= coef[pp, k + 1] * d1 + coef[pp, k + 2] * d2


@njit(cache=True)
def add_dofs(dof_of: IntArray, halo: int, fixed: BoolArray, t: FloatArray, xg: FloatArray) -> None:
    """``x += t`` on the free DOFs, written to every coordinate of each DOF."""
    base = 3 * halo
    for c in range(dof_of.shape[0]):
        g = dof_of[c]
        if not fixed[g]:
            xg[base + c] += t[g]


@njit(cache=True)
def stencil_product(
    shape: IntArray,
    halo: int,
    coef: FloatArray,
    block: FloatArray,
    dof_of: IntArray,
    palm: IntArray,
    a_ptr: IntArray,
    a_idx: Int32Array,
    a_val: FloatArray,
    x: FloatArray,
    xg: FloatArray,
    out: FloatArray,
) -> None:
    """``out = A x`` over every DOF from the stencil (``xg``: coordinate scratch like a sweep's).

    Each particle's rows are its own block times its coordinates plus its outgoing and incoming
    elements' terms, read without column indices; the palm DOFs' rows (which also hold the
    palms' own terms) come from their compressed rows. A particle row of a palm-bound
    coordinate is written and then overwritten by its palm's row. Cheaper than the compressed
    rows, and it reads only the stencil's arrays (about 3x fewer bytes per particle), so it
    evicts less of what the V-cycle reads next."""
    nx, ny, nz = shape[0], shape[1], shape[2]
    n = nx * ny * nz
    off = _kernel_offsets(coef, shape)
    base = 3 * halo
    for i in range(base):
        xg[i] = 0.0
        xg[base + 3 * n + i] = 0.0
    for c in range(3 * n):
        xg[base + c] = x[dof_of[c]]
    for p in range(n):
        pp = p + halo
        s0, s1, s2 = _sums_in(coef, xg, pp, off)
        t0, t1, t2 = _sums_out(coef, xg, pp, off)
        q = 3 * pp
        x0 = xg[q]
        x1 = xg[q + 1]
        x2 = xg[q + 2]
        out[dof_of[3 * p]] = block[p, 0] * x0 + block[p, 1] * x1 + block[p, 2] * x2 - s0 - t0
        out[dof_of[3 * p + 1]] = block[p, 3] * x0 + block[p, 4] * x1 + block[p, 5] * x2 - s1 - t1
        out[dof_of[3 * p + 2]] = block[p, 6] * x0 + block[p, 7] * x1 + block[p, 8] * x2 - s2 - t2
    for k in range(palm.shape[0]):
        g = palm[k]
        acc = 0.0
        for kk in range(a_ptr[g], a_ptr[g + 1]):
            acc += a_val[kk] * x[a_idx[kk]]
        out[g] = acc
