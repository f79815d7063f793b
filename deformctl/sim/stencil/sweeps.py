"""Block Gauss–Seidel sweeps and the product on a stencil level (see :mod:`deformctl.sim.stencil`).

Every sweep takes the level as a :class:`~deformctl.sim.stencil.build.Stencil` and its
compressed rows as :class:`~deformctl.sim.stencil.build.Rows` (read for the palm DOFs only).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from deformctl.arraytypes import BoolArray, FloatArray, Int32Array, IntArray
from deformctl.sim.stencil.build import Rows, Stencil
from deformctl.sim.stencil.sums import _U1, _U2, _U3, _kernel_offsets, _scatter, _sums_in, _sums_out


@njit(cache=True, inline="always")
def _solve_free(
    p: int, pp: int, r0: float, r1: float, r2: float, block_inv: FloatArray, xg: FloatArray
) -> None:
    """``x_p = block_p^-1 r`` for a particle whose three coordinates are free."""
    base = _U3 * np.uint64(pp)
    u = np.uint64(p)
    xg[base] = block_inv[u, 0] * r0 + block_inv[u, 1] * r1 + block_inv[u, 2] * r2
    xg[base + _U1] = block_inv[u, 3] * r0 + block_inv[u, 4] * r1 + block_inv[u, 5] * r2
    xg[base + _U2] = block_inv[u, 6] * r0 + block_inv[u, 7] * r1 + block_inv[u, 8] * r2


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
    st: Stencil, rows: Rows, fixed: BoolArray, b: FloatArray, xg: FloatArray
) -> None:
    """One forward block Gauss–Seidel sweep of ``A x = b`` from ``x = 0`` (``xg``: coordinates,
    halo included, set here): the palm DOFs first, then the particles in index order. Starting
    from zero, a particle's later neighbours are still zero, so only its incoming elements are
    read (and, on the left palm's face and next to the right palm, the outgoing ones for the
    palm-bound coordinates)."""
    shape, halo, coef, block, block_inv, dof_of, rep, palm = st
    a_ptr, a_idx, a_val = rows
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
        g0 = np.uint64(dof_of[3 * p])
        g1 = np.uint64(dof_of[3 * p + 1])
        g2 = np.uint64(dof_of[3 * p + 2])
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
    st: Stencil,
    rows: Rows,
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
    shape, halo, coef, dof_of, rep, palm = st.shape, st.halo, st.coef, st.dof_of, st.rep, st.palm
    a_ptr, a_idx, a_val = rows
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
        g0 = np.uint64(dof_of[3 * p])
        g1 = np.uint64(dof_of[3 * p + 1])
        g2 = np.uint64(dof_of[3 * p + 2])
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
    st: Stencil,
    rows: Rows,
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
    shape, halo, coef, block, block_inv, dof_of, rep, palm = st
    a_ptr, a_idx, a_val = rows
    nx, ny, nz = shape[0], shape[1], shape[2]
    n = nx * ny * nz
    face = ny * nz
    gripped = palm.shape[0] > 0
    off = _kernel_offsets(coef, shape)
    for p in range(n - 1, -1, -1):
        pp = p + halo
        base = _U3 * np.uint64(pp)
        on_face = gripped and (p < face or p >= n - face)
        g0 = np.uint64(dof_of[3 * p])
        g1 = np.uint64(dof_of[3 * p + 1])
        g2 = np.uint64(dof_of[3 * p + 2])
        f0 = (not on_face) and not fixed[g0]
        f1 = not fixed[g1]
        f2 = (not on_face) and not fixed[g2]
        if not (f0 or f1 or f2):
            continue
        old0 = xg[base]
        old1 = xg[base + _U1]
        old2 = xg[base + _U2]
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
            axg[base + _U1] = b[g1] if f1 else 0.0
            axg[base + _U2] = b[g2] if f2 else 0.0
            d0 = xg[base] - old0
            d1 = xg[base + _U1] - old1
            d2 = xg[base + _U2] - old2
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
    first = 3 * halo
    for g in range(rep.shape[0]):
        if fixed[g]:
            x[g] = 0.0
            if with_product:
                ax[g] = 0.0
        else:
            x[g] = xg[first + rep[g]]
            if with_product:
                ax[g] = axg[first + rep[g]]
    if with_product:
        for k in range(np_):
            if not fixed[palm[k]]:
                ax[palm[k]] = axp[k]


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
    st: Stencil, rows: Rows, x: FloatArray, xg: FloatArray, out: FloatArray
) -> None:
    """``out = A x`` over every DOF from the stencil (``xg``: coordinate scratch like a sweep's).

    Each particle's rows are its own block times its coordinates plus its outgoing and incoming
    elements' terms, read without column indices; the palm DOFs' rows (which also hold the
    palms' own terms) come from their compressed rows. A particle row of a palm-bound
    coordinate is written and then overwritten by its palm's row. Cheaper than the compressed
    rows, and it reads only the stencil's arrays (about 3x fewer bytes per particle), so it
    evicts less of what the V-cycle reads next."""
    shape, halo, coef, block, dof_of, palm = (
        st.shape,
        st.halo,
        st.coef,
        st.block,
        st.dof_of,
        st.palm,
    )
    a_ptr, a_idx, a_val = rows
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
        qu = _U3 * np.uint64(pp)
        u = np.uint64(p)
        cu = _U3 * u
        x0 = xg[qu]
        x1 = xg[qu + _U1]
        x2 = xg[qu + _U2]
        out[dof_of[cu]] = block[u, 0] * x0 + block[u, 1] * x1 + block[u, 2] * x2 - s0 - t0
        out[dof_of[cu + _U1]] = block[u, 3] * x0 + block[u, 4] * x1 + block[u, 5] * x2 - s1 - t1
        out[dof_of[cu + _U2]] = block[u, 6] * x0 + block[u, 7] * x1 + block[u, 8] * x2 - s2 - t2
    for k in range(palm.shape[0]):
        g = palm[k]
        acc = 0.0
        for kk in range(a_ptr[g], a_ptr[g + 1]):
            acc += a_val[kk] * x[a_idx[kk]]
        out[g] = acc
