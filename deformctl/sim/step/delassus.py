"""The direct solver's contact problem on the Delassus matrix ``W = J A^-1 J^T`` of the live rows:
its entries from the contact columns, the warm solve with last step's active set, and the
exact polish after projected Gauss–Seidel (see :mod:`deformctl.sim.step`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from deformctl.arraytypes import FloatArray, IntArray
from deformctl.sim.solver import LDLFactor, ldl_solve
from deformctl.sim.step.dense import _lu_factor, _lu_solve, _solve_dense


@njit(cache=True)
def _polish(
    w: FloatArray,
    vrow: FloatArray,
    target: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    lam: FloatArray,
    row_type: IntArray,
    row_dof: IntArray,
    live: IntArray,
) -> None:
    """Exact solve on the PGS active set; keeps PGS when inconsistent.

    ``w`` is the live rows' Delassus matrix (local indices ``0..len(live)``); the other arrays are
    indexed by global row.
    """
    nl = live.shape[0]
    active = np.zeros(nl, dtype=np.bool_)
    for i in range(nl):
        r = live[i]
        t = row_type[r]
        if t == 0 or t >= 4:
            active[i] = lam[r] > 0.0
        elif t == 3:
            active[i] = lam[r] < 0.0
        else:
            active[i] = lo[r] < lam[r] < hi[r]
    # a table row on a face-patch DOF duplicates that patch's friction row: keep one
    for i in range(nl):
        r = live[i]
        if active[i] and row_type[r] == 0:
            for j in range(nl):
                s = live[j]
                if row_type[s] == 1 and row_dof[s] == row_dof[r] and active[j]:
                    active[i] = False
    na = 0
    for i in range(nl):
        if active[i]:
            na += 1
    if na == 0:
        return
    idx = np.empty(na, dtype=np.int64)
    na = 0
    for i in range(nl):
        if active[i]:
            idx[na] = i
            na += 1
    a = np.empty((na, na))
    b = np.empty(na)
    for p in range(na):
        i = idx[p]
        r = live[i]
        rhs = target[r] - vrow[r]
        for j in range(nl):
            if not active[j]:
                rhs -= w[i, j] * lam[live[j]]
        b[p] = rhs
        for q in range(na):
            a[p, q] = w[i, idx[q]]
    sol = np.empty(na)
    if not _solve_dense(a, b, sol):
        return
    trial = np.empty(nl)
    for i in range(nl):
        trial[i] = lam[live[i]]
    for p in range(na):
        trial[idx[p]] = sol[p]
    # feasibility: bounds, and non-active unilateral rows must not penetrate
    for i in range(nl):
        r = live[i]
        t = row_type[r]
        if t == 0 or t >= 3:
            sign = -1.0 if t == 3 else 1.0
            if sign * trial[i] < 0.0:
                return
            if not active[i]:
                vr = vrow[r]
                for j in range(nl):
                    vr += w[i, j] * trial[j]
                if sign * (vr - target[r]) < -1e-9:
                    return
        elif trial[i] > hi[r] or trial[i] < lo[r]:
            return
    for p in range(na):
        lam[live[idx[p]]] = trial[idx[p]]


@njit(cache=True)
def _col_value(ci: int, i: int, pre: FloatArray, ext: FloatArray) -> float:
    """Entry ``i`` of contact column ``ci`` (precomputed columns first, then the lazy ones)."""
    n_pre = pre.shape[0]
    if ci < n_pre:
        return pre[ci, i]
    return ext[ci - n_pre, i]


@njit(cache=True)
def _ensure_column(
    d: int, col_idx: IntArray, pre: FloatArray, ext: FloatArray, n_ext: int, factor: LDLFactor
) -> tuple[FloatArray, int]:
    """Make sure column ``A^-1 e_d`` exists (solved for when missing); returns ``ext, n_ext``."""
    if col_idx[d] >= 0:
        return ext, n_ext
    n_dof = factor.diag.shape[0]
    if n_ext == ext.shape[0]:
        grown = np.empty((max(8, 2 * ext.shape[0]), n_dof))
        grown[:n_ext] = ext[:n_ext]
        ext = grown
    unit = np.zeros(n_dof)
    unit[d] = 1.0
    ldl_solve(factor, unit, np.empty(n_dof), ext[n_ext])
    col_idx[d] = pre.shape[0] + n_ext
    return ext, n_ext + 1


@njit(cache=True)
def _delassus_entry(
    r: int,
    s: int,
    row_dof: IntArray,
    row_dof2: IntArray,
    col_idx: IntArray,
    pre: FloatArray,
    ext: FloatArray,
) -> float:
    """``W[r, s] = J_r A^-1 J_s^T`` (the velocity change of row r per unit impulse on row s)."""
    a_r = row_dof[r]
    b_r = row_dof2[r]
    ca = col_idx[row_dof[s]]
    val = _col_value(ca, a_r, pre, ext)
    if b_r >= 0:
        val -= _col_value(ca, b_r, pre, ext)
    if row_dof2[s] >= 0:
        cb = col_idx[row_dof2[s]]
        val -= _col_value(cb, a_r, pre, ext)
        if b_r >= 0:
            val += _col_value(cb, b_r, pre, ext)
    return val


@njit(cache=True)
def _warm_solve(
    w: FloatArray,
    lv: IntArray,
    vrow: FloatArray,
    target: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    lam: FloatArray,
    state: IntArray,
    row_type: IntArray,
    fact: FloatArray,
    fact_rows: IntArray,
    fact_n: IntArray,
) -> bool:
    """Exact solve with last step's active set; True (and ``lam`` set) when it satisfies the KKT
    conditions, so PGS is not needed.

    ``state[r]``: 0 inactive at zero, 1 active (equality), 2 / -2 friction sliding at ``hi`` /
    ``lo``, 3 a table row on a face-patch DOF whose friction row is active (its impulse is kept,
    as :func:`_polish` keeps one of two duplicate rows). The LU factor of the active rows'
    Delassus block is cached in ``fact`` and reused while the active rows stay the same (the
    system matrix is constant).
    """
    nl = lv.shape[0]
    na = 0
    for i in range(nl):
        if state[lv[i]] == 1:
            na += 1
    idx = np.empty(na, dtype=np.int64)
    na = 0
    for i in range(nl):
        if state[lv[i]] == 1:
            idx[na] = i
            na += 1
    trial = np.zeros(nl)
    for i in range(nl):
        st = state[lv[i]]
        if st == 2:
            trial[i] = hi[lv[i]]
        elif st == -2:
            trial[i] = lo[lv[i]]
        elif st == 3:
            trial[i] = lam[lv[i]]
    if na > 0:
        same = fact_n[0] == na
        if same:
            for p in range(na):
                if fact_rows[p] != lv[idx[p]]:
                    same = False
                    break
        if not same:
            if na > fact.shape[0]:
                return False
            for p in range(na):
                fact_rows[p] = lv[idx[p]]
                for q in range(na):
                    fact[p, q] = w[idx[p], idx[q]]
            fact_n[0] = -1
            if not _lu_factor(fact, na):
                return False
            fact_n[0] = na
        b = np.empty(na)
        for p in range(na):
            i = idx[p]
            r = lv[i]
            rhs = target[r] - vrow[r]
            for j in range(nl):
                if trial[j] != 0.0:
                    rhs -= w[i, j] * trial[j]
            b[p] = rhs
        _lu_solve(fact, na, b)
        for p in range(na):
            trial[idx[p]] = b[p]
    # KKT: bounds of the active rows, velocities of the others
    for i in range(nl):
        r = lv[i]
        t = row_type[r]
        st = state[r]
        if st == 1:
            if trial[i] < lo[r] or trial[i] > hi[r]:
                return False
            if t == 1 and (trial[i] <= lo[r] or trial[i] >= hi[r]):
                return False
            continue
        vr = vrow[r]
        for j in range(nl):
            if trial[j] != 0.0:
                vr += w[i, j] * trial[j]
        gap = vr - target[r]
        if t == 3:
            gap = -gap
        if st == 3:
            # a table row duplicating an active friction row: impulse kept, must stay consistent
            if gap < -1e-9 or (trial[i] > 0.0 and gap > 1e-9):
                return False
            continue
        if st == 0 and t != 1 and gap < -1e-9:
            return False
        if st == 0 and t == 1:
            return False
        if st == 2 and gap > 1e-9:
            return False
        if st == -2 and gap < -1e-9:
            return False
    for i in range(nl):
        lam[lv[i]] = trial[i]
    return True


@njit(cache=True)
def _row_state(lam: FloatArray, lo: FloatArray, hi: FloatArray, row_type: IntArray, r: int) -> int:
    """Active-set state of row ``r`` for the next step's warm solve (see :func:`_warm_solve`)."""
    t = row_type[r]
    if t == 1 or t == 2:
        if lam[r] >= hi[r]:
            return 2
        if lam[r] <= lo[r]:
            return -2
        return 1
    return 1 if lam[r] != 0.0 else 0
