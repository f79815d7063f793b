"""The stencils' neighbour sums, inlined into the sweeps (:mod:`deformctl.sim.stencil.sweeps`).

Each stencil kind has its own sums: the finest level's element stencil (``coef`` ``[rows, 21]``)
and level 1's block stencil (``coef`` ``[rows, 26, 9]``). The kind is chosen when a sweep is
compiled, by the dimension of ``coef`` (:func:`_sums_in`, :func:`_sums_out`, :func:`_scatter`,
:func:`_kernel_offsets`), so there is no per-particle branch.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numba.extending import overload

from deformctl.arraytypes import FloatArray, IntArray, UIntArray

#: index constants as unsigned integers: indices computed from them are unsigned, so the
#: compiled sums carry no negative-index wraparound (the same values, fewer instructions)
_U1 = np.uint64(1)
_U2 = np.uint64(2)
_U3 = np.uint64(3)


@njit(cache=True, inline="always")
def _offsets(shape: IntArray) -> UIntArray:
    """:func:`direction_offsets` inside the kernels."""
    ny = shape[1]
    nz = shape[2]
    off = np.empty(9, dtype=np.uint64)
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
    coef: FloatArray, xg: FloatArray, pp: int, off: UIntArray
) -> tuple[float, float, float]:
    """``sum w n n^T x_q`` over the particle's 9 outgoing elements (neighbours ``pp + off``)."""
    u = np.uint64(pp)
    s0 = coef[u, 0] * xg[_U3 * (u + off[0])]
    s1 = coef[u, 1] * xg[_U3 * (u + off[1]) + _U1]
    s2 = coef[u, 2] * xg[_U3 * (u + off[2]) + _U2]
    # xy diagonals
    for d in range(3, 5):
        q = _U3 * (u + off[d])
        k = 3 + 3 * (d - 3)
        c0 = coef[u, k]
        c1 = coef[u, k + 1]
        c2 = coef[u, k + 2]
        s0 += c0 * xg[q] + c1 * xg[q + _U1]
        s1 += c1 * xg[q] + c2 * xg[q + _U1]
    for d in range(5, 7):
        q = _U3 * (u + off[d])
        k = 3 + 3 * (d - 3)
        c0 = coef[u, k]
        c1 = coef[u, k + 1]
        c2 = coef[u, k + 2]
        s0 += c0 * xg[q] + c1 * xg[q + _U2]
        s2 += c1 * xg[q] + c2 * xg[q + _U2]
    for d in range(7, 9):
        q = _U3 * (u + off[d])
        k = 3 + 3 * (d - 3)
        c0 = coef[u, k]
        c1 = coef[u, k + 1]
        c2 = coef[u, k + 2]
        s1 += c0 * xg[q + _U1] + c1 * xg[q + _U2]
        s2 += c1 * xg[q + _U1] + c2 * xg[q + _U2]
    return s0, s1, s2


@njit(cache=True, inline="always")
def _sum_in(
    coef: FloatArray, xg: FloatArray, pp: int, off: UIntArray
) -> tuple[float, float, float]:
    """``sum w n n^T x_q`` over the particle's 9 incoming elements (neighbours ``pp - off``,
    which own them)."""
    u = np.uint64(pp)
    q0 = u - off[0]
    q1 = u - off[1]
    q2 = u - off[2]
    s0 = coef[q0, 0] * xg[_U3 * q0]
    s1 = coef[q1, 1] * xg[_U3 * q1 + _U1]
    s2 = coef[q2, 2] * xg[_U3 * q2 + _U2]
    for d in range(3, 5):
        qq = u - off[d]
        q = _U3 * qq
        k = 3 + 3 * (d - 3)
        c0 = coef[qq, k]
        c1 = coef[qq, k + 1]
        c2 = coef[qq, k + 2]
        s0 += c0 * xg[q] + c1 * xg[q + _U1]
        s1 += c1 * xg[q] + c2 * xg[q + _U1]
    for d in range(5, 7):
        qq = u - off[d]
        q = _U3 * qq
        k = 3 + 3 * (d - 3)
        c0 = coef[qq, k]
        c1 = coef[qq, k + 1]
        c2 = coef[qq, k + 2]
        s0 += c0 * xg[q] + c1 * xg[q + _U2]
        s2 += c1 * xg[q] + c2 * xg[q + _U2]
    for d in range(7, 9):
        qq = u - off[d]
        q = _U3 * qq
        k = 3 + 3 * (d - 3)
        c0 = coef[qq, k]
        c1 = coef[qq, k + 1]
        c2 = coef[qq, k + 2]
        s1 += c0 * xg[q + _U1] + c1 * xg[q + _U2]
        s2 += c1 * xg[q + _U1] + c2 * xg[q + _U2]
    return s0, s1, s2


@njit(cache=True, inline="always")
def _upper_offsets(shape: IntArray) -> UIntArray:
    """Index offsets of :data:`UPPER_OFFSETS` inside the kernels."""
    ny = shape[1]
    nz = shape[2]
    off = np.empty(13, dtype=np.uint64)
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
    coef: FloatArray, xg: FloatArray, pp: int, off: UIntArray
) -> tuple[float, float, float]:
    """``-sum A_pq x_q`` over the particle's 13 upper neighbours (blocks stored with it)."""
    u = np.uint64(pp)
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    for i in range(13):
        q = _U3 * (u + off[i])
        x0 = xg[q]
        x1 = xg[q + _U1]
        x2 = xg[q + _U2]
        s0 -= coef[u, i, 0] * x0 + coef[u, i, 1] * x1 + coef[u, i, 2] * x2
        s1 -= coef[u, i, 3] * x0 + coef[u, i, 4] * x1 + coef[u, i, 5] * x2
        s2 -= coef[u, i, 6] * x0 + coef[u, i, 7] * x1 + coef[u, i, 8] * x2
    return s0, s1, s2


@njit(cache=True, inline="always")
def _block_sum_in(
    coef: FloatArray, xg: FloatArray, pp: int, off: UIntArray
) -> tuple[float, float, float]:
    """``-sum A_pq x_q`` over the particle's 13 lower neighbours (their blocks, stored with the
    particle after the upper ones)."""
    u = np.uint64(pp)
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    for i in range(13):
        qq = u - off[i]
        q = _U3 * qq
        x0 = xg[q]
        x1 = xg[q + _U1]
        x2 = xg[q + _U2]
        j = 13 + i
        s0 -= coef[u, j, 0] * x0 + coef[u, j, 1] * x1 + coef[u, j, 2] * x2
        s1 -= coef[u, j, 3] * x0 + coef[u, j, 4] * x1 + coef[u, j, 5] * x2
        s2 -= coef[u, j, 6] * x0 + coef[u, j, 7] * x1 + coef[u, j, 8] * x2
    return s0, s1, s2


def _sums_in(coef: FloatArray, xg: FloatArray, pp: int, off: UIntArray) -> tuple[float, ...]:
    """The lower neighbours' terms ``-sum A_pq x_q`` of either stencil kind (numba only)."""
    raise NotImplementedError  # pragma: no cover - replaced by the overload in compiled code


def _sums_out(coef: FloatArray, xg: FloatArray, pp: int, off: UIntArray) -> tuple[float, ...]:
    """The upper neighbours' terms of either stencil kind (numba only)."""
    raise NotImplementedError  # pragma: no cover


def _scatter(
    coef: FloatArray, axg: FloatArray, pp: int, off: UIntArray, d0: float, d1: float, d2: float
) -> None:
    """A particle's change ``delta`` into its upper neighbours' ``A x`` (numba only)."""
    raise NotImplementedError  # pragma: no cover


def _kernel_offsets(coef: FloatArray, shape: IntArray) -> UIntArray:
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
def _block_scatter_out(
    coef: FloatArray, axg: FloatArray, pp: int, off: UIntArray, d0: float, d1: float, d2: float
) -> None:
    """``(A x)_q += A_qp delta`` for the particle's 13 upper neighbours (``A_qp = A_pq^T``)."""
    u = np.uint64(pp)
    for i in range(13):
        q = _U3 * (u + off[i])
        axg[q] += coef[u, i, 0] * d0 + coef[u, i, 3] * d1 + coef[u, i, 6] * d2
        axg[q + _U1] += coef[u, i, 1] * d0 + coef[u, i, 4] * d1 + coef[u, i, 7] * d2
        axg[q + _U2] += coef[u, i, 2] * d0 + coef[u, i, 5] * d1 + coef[u, i, 8] * d2


@njit(cache=True, inline="always")
def _scatter_out(
    coef: FloatArray, axg: FloatArray, pp: int, off: UIntArray, d0: float, d1: float, d2: float
) -> None:
    """``(A x)_q -= w n n^T delta`` for the particle's outgoing neighbours ``q = pp + off``."""
    u = np.uint64(pp)
    q = _U3 * (u + off[0])
    axg[q] -= coef[u, 0] * d0
    q = _U3 * (u + off[1])
    axg[q + _U1] -= coef[u, 1] * d1
    q = _U3 * (u + off[2])
    axg[q + _U2] -= coef[u, 2] * d2
    for d in range(3, 5):
        q = _U3 * (u + off[d])
        k = 3 + 3 * (d - 3)
        axg[q] -= coef[u, k] * d0 + coef[u, k + 1] * d1
        axg[q + _U1] -= coef[u, k + 1] * d0 + coef[u, k + 2] * d1
    for d in range(5, 7):
        q = _U3 * (u + off[d])
        k = 3 + 3 * (d - 3)
        axg[q] -= coef[u, k] * d0 + coef[u, k + 1] * d2
        axg[q + _U2] -= coef[u, k + 1] * d0 + coef[u, k + 2] * d2
    for d in range(7, 9):
        q = _U3 * (u + off[d])
        k = 3 + 3 * (d - 3)
        axg[q + _U1] -= coef[u, k] * d1 + coef[u, k + 1] * d2
        axg[q + _U2] -= coef[u, k + 1] * d1 + coef[u, k + 2] * d2
