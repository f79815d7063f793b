"""numba kernels: Kelvin element forces and the implicit time-stepping loop.

Everything in the step loop runs inside one ``@njit(cache=True)`` function (:func:`integrate`),
so a lift attempt is a single call with no Python work per step. The loop is serial and its
floating-point operation order is fixed, so results are bit-identical run to run.

Step (linearised backward Euler, tangent frozen at the rest configuration; see
:mod:`deformctl.sim.engine` for why)::

    A dv = dt (f(x, v) + f_ext - dt K v) + J^T Lambda,    A = M + (dt beta + dt^2) K
    v <- v + dv,  x <- x + dt v

``f`` is the exact (geometrically nonlinear) Kelvin element force, ``A = M + dt C + dt^2 K`` is
factorised once per model (sparse ``L D L^T``, :mod:`deformctl.sim.solver`; the solves run here),
and ``Lambda`` are the contact impulses. Every constraint row ``J_r`` is a unit vector on one DOF
(or the difference of two), so the Delassus matrix ``W = J A^-1 J^T`` of the *live* rows is a
gather from the contact columns ``A^-1 e_d``: precomputed for the palm and bottom-layer DOFs,
solved for inside the kernel when another row first becomes live. A unilateral row without
impulse that the free velocity already satisfies is not live; after the solve every such row is
checked against the final velocity and the solve is repeated with the violated ones, so skipping
never changes the solution. The contact problem is solved exactly: first with last step's active
set (an LU of the active rows' ``W`` block, cached while the active set stays the same, and a
check of the complementarity conditions); when that fails, projected Gauss–Seidel on ``W``
followed by an exact active-set solve (so sticking contacts stick to round-off).

:func:`integrate_iterative` is the same step for the iterative solver (multigrid CG,
:mod:`deformctl.sim.multigrid`): there the contact rows are an active set of fixed DOFs solved
together with the free DOFs (see its docstring), since columns of ``A^-1`` would cost a solve each.

Row types: 0 table normal (``v >= -gap/dt``, ``Lambda >= 0``); 1 palm friction on a face-patch z
DOF (``v = v_palm`` or ``|Lambda| = mu N dt``); 2 table friction on a bottom x/y DOF
(``|Lambda| <= mu_table Lambda_normal``, a four-sided friction pyramid); 3 and 4 the left and
right palm stops (the palm x may not pass the densification limit, see ``SimSettings``); 5 and 6
non-penetration of a particle next to the left / right palm plane (two-DOF rows).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from deformctl.sim.multigrid import pcg, pcg_work_size, product
from deformctl.sim.solver import ldl_solve

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
Int32Array = NDArray[np.int32]
BoolArray = NDArray[np.bool_]

# columns of the record matrix returned by integrate()
REC_TIME = 0
REC_PALM_Z = 1
REC_COM_Z = 2
REC_SLIP_L = 3
REC_SLIP_R = 4
REC_FRICTION_L = 5
REC_FRICTION_R = 6
REC_NORMAL_L = 7
REC_NORMAL_R = 8
REC_PALM_XL = 9
REC_PALM_XR = 10
REC_TABLE_N = 11
REC_MIN_Z = 12
REC_PENETRATION = 13
REC_MAX_SPEED = 14
REC_COM_X = 15
REC_COM_Y = 16
N_REC = 17

#: rounding allowed for each carried product ``A dv`` in :func:`integrate_iterative`, relative to
#: ``max_i sum_j |A_ij| * |dv|_2`` (the scale of a product's rounding: a row of about 80 entries
#: rounds to 80 ulp of ``|A| |dv|``, about 1e-14)
PRODUCT_ROUNDING = 1e-14


@njit(cache=True)
def spring_forces(
    x: FloatArray,
    v: FloatArray,
    edges: IntArray,
    rest_length: FloatArray,
    k: FloatArray,
    c: FloatArray,
    out: FloatArray,
) -> None:
    """Add the Kelvin element forces to ``out`` (geometrically exact springs, axial dampers).

    ``f_i += k (L - L0) n + c ((v_j - v_i) . n) n`` and ``f_j -= ...`` with ``n = (x_j - x_i)/L``.

    Args:
        x: positions, m, ``[n, 3]``.
        v: velocities, m/s, ``[n, 3]``.
        edges: ``[m, 2]``; rest_length: m, ``[m]``; k: N/m, ``[m]``; c: N·s/m, ``[m]``.
        out: forces, N, ``[n, 3]`` (accumulated into).
    """
    for e in range(edges.shape[0]):
        i = edges[e, 0]
        j = edges[e, 1]
        dx = x[j, 0] - x[i, 0]
        dy = x[j, 1] - x[i, 1]
        dz = x[j, 2] - x[i, 2]
        length = np.sqrt(dx * dx + dy * dy + dz * dz)
        inv = 1.0 / length
        nx = dx * inv
        ny = dy * inv
        nz = dz * inv
        rate = (v[j, 0] - v[i, 0]) * nx + (v[j, 1] - v[i, 1]) * ny + (v[j, 2] - v[i, 2]) * nz
        f = k[e] * (length - rest_length[e]) + c[e] * rate
        out[i, 0] += f * nx
        out[i, 1] += f * ny
        out[i, 2] += f * nz
        out[j, 0] -= f * nx
        out[j, 1] -= f * ny
        out[j, 2] -= f * nz


def spring_forces_numpy(
    x: FloatArray,
    v: FloatArray,
    edges: IntArray,
    rest_length: FloatArray,
    k: FloatArray,
    c: FloatArray,
) -> FloatArray:
    """Plain NumPy reference of :func:`spring_forces` (vectorised gather, ``np.add.at`` scatter).

    Returns:
        forces, N, ``[n, 3]``.
    """
    i = edges[:, 0]
    j = edges[:, 1]
    d = x[j] - x[i]
    length = np.linalg.norm(d, axis=1)
    n = d / length[:, None]
    rate = np.einsum("ij,ij->i", v[j] - v[i], n)
    f = (k * (length - rest_length) + c * rate)[:, None] * n
    out = np.zeros_like(x)
    np.add.at(out, i, f)
    np.add.at(out, j, -f)
    return out


@njit(cache=True)
def _element_rhs(
    x: FloatArray,
    vel: FloatArray,
    edges: IntArray,
    rest: FloatArray,
    n0: FloatArray,
    k: FloatArray,
    retardation: float,
    h: float,
    nonlinear: bool,
    out: FloatArray,
) -> None:
    """Element forces minus ``h K v`` (tangent at rest), accumulated into ``out`` ``[n, 3]``.

    The dampers are ``c = retardation k`` (:func:`deformctl.sim.engine.element_constants`), so
    the loop reads one constant per element and forms ``c`` and ``h k`` from it (the same
    products as the arrays would hold, so the same bits; 56 instead of 72 bytes streamed per
    element)."""
    for e in range(edges.shape[0]):
        i = edges[e, 0]
        j = edges[e, 1]
        dx = x[j, 0] - x[i, 0]
        dy = x[j, 1] - x[i, 1]
        dz = x[j, 2] - x[i, 2]
        dvx = vel[j, 0] - vel[i, 0]
        dvy = vel[j, 1] - vel[i, 1]
        dvz = vel[j, 2] - vel[i, 2]
        ax = n0[e, 0]
        ay = n0[e, 1]
        az = n0[e, 2]
        if nonlinear:
            length = np.sqrt(dx * dx + dy * dy + dz * dz)
            inv = 1.0 / length
            nx = dx * inv
            ny = dy * inv
            nz = dz * inv
            stretch = length - rest[e]
        else:
            nx = ax
            ny = ay
            nz = az
            stretch = dx * ax + dy * ay + dz * az - rest[e]
        ke = k[e]
        f = ke * stretch + (ke * retardation) * (dvx * nx + dvy * ny + dvz * nz)
        g = (ke * h) * (dvx * ax + dvy * ay + dvz * az)
        fx = f * nx + g * ax
        fy = f * ny + g * ay
        fz = f * nz + g * az
        out[i, 0] += fx
        out[i, 1] += fy
        out[i, 2] += fz
        out[j, 0] -= fx
        out[j, 1] -= fy
        out[j, 2] -= fz


@njit(cache=True)
def _solve_dense(a: FloatArray, b: FloatArray, out: FloatArray) -> bool:
    """Gaussian elimination with partial pivoting (in place); False when singular."""
    n = b.shape[0]
    scale = 0.0
    for i in range(n):
        scale = max(scale, abs(a[i, i]))
    for col in range(n):
        piv = col
        for r in range(col + 1, n):
            if abs(a[r, col]) > abs(a[piv, col]):
                piv = r
        if abs(a[piv, col]) <= 1e-12 * scale:
            return False
        if piv != col:
            for c in range(n):
                a[col, c], a[piv, c] = a[piv, c], a[col, c]
            b[col], b[piv] = b[piv], b[col]
        for r in range(col + 1, n):
            f = a[r, col] / a[col, col]
            if f != 0.0:
                for c in range(col, n):
                    a[r, c] -= f * a[col, c]
                b[r] -= f * b[col]
    for i in range(n - 1, -1, -1):
        acc = b[i]
        for c in range(i + 1, n):
            acc -= a[i, c] * out[c]
        out[i] = acc / a[i, i]
    return True


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
def _lu_factor(a: FloatArray, n: int) -> bool:
    """In-place LU without pivoting of ``a[:n, :n]`` (Delassus matrices: nearly symmetric, SPD)."""
    for k in range(n):
        piv = a[k, k]
        if not piv > 0.0:
            return False
        for i in range(k + 1, n):
            f = a[i, k] / piv
            a[i, k] = f
            if f != 0.0:
                for j in range(k + 1, n):
                    a[i, j] -= f * a[k, j]
    return True


@njit(cache=True)
def _lu_solve(a: FloatArray, n: int, b: FloatArray) -> None:
    """Solve with the factor of :func:`_lu_factor`, in place on ``b[:n]``."""
    for i in range(n):
        acc = b[i]
        for j in range(i):
            acc -= a[i, j] * b[j]
        b[i] = acc
    for i in range(n - 1, -1, -1):
        acc = b[i]
        for j in range(i + 1, n):
            acc -= a[i, j] * b[j]
        b[i] = acc / a[i, i]


@njit(cache=True)
def _col_value(ci: int, i: int, pre: FloatArray, ext: FloatArray) -> float:
    """Entry ``i`` of contact column ``ci`` (precomputed columns first, then the lazy ones)."""
    n_pre = pre.shape[0]
    if ci < n_pre:
        return pre[ci, i]
    return ext[ci - n_pre, i]


@njit(cache=True)
def _ensure_column(
    d: int,
    col_idx: IntArray,
    pre: FloatArray,
    ext: FloatArray,
    n_ext: int,
    colptr: IntArray,
    rowidx: Int32Array,
    values: FloatArray,
    diag: FloatArray,
    perm: IntArray,
) -> tuple[FloatArray, int]:
    """Make sure column ``A^-1 e_d`` exists (solved for when missing); returns ``ext, n_ext``."""
    if col_idx[d] >= 0:
        return ext, n_ext
    n_dof = diag.shape[0]
    if n_ext == ext.shape[0]:
        grown = np.empty((max(8, 2 * ext.shape[0]), n_dof))
        grown[:n_ext] = ext[:n_ext]
        ext = grown
    unit = np.zeros(n_dof)
    unit[d] = 1.0
    ldl_solve(colptr, rowidx, values, diag, perm, unit, np.empty(n_dof), ext[n_ext])
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


@njit(cache=True)
def _step_impulse(
    base_x: FloatArray,
    q: FloatArray,
    v: FloatArray,
    dof_of: IntArray,
    particle_mass: FloatArray,
    edges: IntArray,
    rest: FloatArray,
    n0: FloatArray,
    k: FloatArray,
    retardation: float,
    nonlinear: bool,
    gravity: float,
    palm_x_dof: IntArray,
    f_now: float,
    width_damping: float,
    dt: float,
    x: FloatArray,
    vel: FloatArray,
    fp: FloatArray,
    fq: FloatArray,
) -> None:
    """The step's right-hand side ``fq = h (f(x, v) + f_ext - h K v)`` in DOFs (also fills the
    particle positions ``x`` and velocities ``vel``).

    ``q, v`` are the step's base state (the BDF2 predictor, or the last state for backward Euler)
    and ``dt`` the implicit step ``h`` (``2 dt / 3`` for BDF2); ``particle_mass`` is ``[n]`` and
    ``gravity`` the acceleration acting now. ``width_damping`` (N·s/m) is the damper across the
    gripped width, between the two palm x DOFs.
    """
    n = base_x.shape[0]
    for p in range(n):
        for a in range(3):
            d = dof_of[3 * p + a]
            x[p, a] = base_x[p, a] + q[d]
            vel[p, a] = v[d]
            fp[p, a] = 0.0
    _element_rhs(x, vel, edges, rest, n0, k, retardation, dt, nonlinear, fp)
    fq[:] = 0.0
    for p in range(n):
        fp[p, 2] -= particle_mass[p] * gravity
        for a in range(3):
            fq[dof_of[3 * p + a]] += fp[p, a]
    if palm_x_dof[0] >= 0:
        fw = width_damping * (v[palm_x_dof[1]] - v[palm_x_dof[0]])
        fq[palm_x_dof[0]] += f_now + fw
        fq[palm_x_dof[1]] -= f_now + fw
    for i in range(fq.shape[0]):
        fq[i] *= dt


@njit(cache=True)
def _slipped_past(rec: FloatArray, step: int, stop_slip: float, stop_from: int) -> bool:
    """Whether the mean palm slip since step ``stop_from - 1`` exceeds ``stop_slip`` (m) at
    ``step`` (never when ``stop_slip < 0``): the attempt's verdict can no longer change, since
    the accumulated slip only grows."""
    if stop_slip < 0.0 or step < stop_from:
        return False
    base_l = rec[stop_from - 1, REC_SLIP_L] if stop_from >= 1 else 0.0
    base_r = rec[stop_from - 1, REC_SLIP_R] if stop_from >= 1 else 0.0
    return 0.5 * (rec[step, REC_SLIP_L] - base_l + rec[step, REC_SLIP_R] - base_r) > stop_slip


@njit(cache=True)
def _predict(
    q: FloatArray,
    v: FloatArray,
    q_last: FloatArray,
    v_last: FloatArray,
    q_prev: FloatArray,
    v_prev: FloatArray,
    bdf2: bool,
) -> None:
    """Shift the history and turn ``q, v`` into the step's base state.

    On entry ``q, v`` are the state at the start of the step and ``q_last, v_last`` the one a step
    earlier; on exit ``q_prev, v_prev`` hold that earlier state, ``q_last, v_last`` the start of
    this step, and ``q, v`` the base of the implicit update: unchanged for backward Euler, the
    BDF2 predictor ``(4 x_n - x_{n-1}) / 3`` otherwise (a run starts from rest, so the first
    step's history is the start state itself).
    """
    for i in range(q.shape[0]):  # one pass
        qp = q_last[i]
        vp = v_last[i]
        qn = q[i]
        vn = v[i]
        q_prev[i] = qp
        v_prev[i] = vp
        q_last[i] = qn
        v_last[i] = vn
        if bdf2:
            q[i] = (4.0 * qn - qp) / 3.0
            v[i] = (4.0 * vn - vp) / 3.0


@njit(cache=True)
def _record_step(
    step: int,
    rec: FloatArray,
    q: FloatArray,
    v: FloatArray,
    vnew: FloatArray,
    lam: FloatArray,
    rows: IntArray,
    n_rows: int,
    row_type: IntArray,
    row_dof: IntArray,
    base_x: FloatArray,
    dof_of: IntArray,
    x: FloatArray,
    palm_x_dof: IntArray,
    palm_z_dof: IntArray,
    palm_x0: FloatArray,
    palm_vz: FloatArray,
    palm_mass: float,
    f_now: float,
    dt: float,
    h: float,
    v_last: FloatArray,
    particle_mass: FloatArray,
    total_mass: float,
    slip: FloatArray,
    palm_z_acc: FloatArray,
    com_z0: float,
) -> None:
    """Record step ``step`` and advance ``v <- vnew``, ``q <- q + h v`` (palm quantities before
    the position update use the new velocities).

    ``q, v`` hold the step's base state (for BDF2 the predictor, see :func:`integrate`), ``h`` is
    the implicit step (impulses are ``h`` times the force) and ``v_last`` the velocity at the
    start of the step (for the palm's acceleration). The centre of mass is mass-weighted. The
    contact forces sum the impulses of rows ``rows[:n_rows]`` (every row with an impulse).
    """
    n = base_x.shape[0]
    n_dof = q.shape[0]
    gripped = palm_x_dof[0] >= 0
    table_n = 0.0
    fric_l = 0.0
    fric_r = 0.0
    for j in range(n_rows):
        r = rows[j]
        if row_type[r] == 0:
            table_n += lam[r] / h
        elif row_type[r] == 1:
            if row_dof[r] == palm_z_dof[0]:
                fric_l += lam[r] / h
            else:
                fric_r += lam[r] / h
    if gripped:
        vz_palm = palm_vz[step + 1]
        slip[0] += abs(vnew[palm_z_dof[0]] - vz_palm) * dt
        slip[1] += abs(vnew[palm_z_dof[1]] - vz_palm) * dt
        palm_z_acc[0] += vz_palm * dt
        acc_l = (vnew[palm_x_dof[0]] - v_last[palm_x_dof[0]]) / dt
        acc_r = (vnew[palm_x_dof[1]] - v_last[palm_x_dof[1]]) / dt
        rec[step, REC_NORMAL_L] = f_now - palm_mass * acc_l
        rec[step, REC_NORMAL_R] = f_now + palm_mass * acc_r
    max_speed = 0.0
    for i in range(n_dof):
        v[i] = vnew[i]
        q[i] += h * v[i]
        if abs(v[i]) > max_speed:
            max_speed = abs(v[i])
    com = np.zeros(3)
    min_z = 1e300
    penetration = 0.0
    xl = palm_x0[0] + q[palm_x_dof[0]] if gripped else -np.inf
    xr = palm_x0[1] + q[palm_x_dof[1]] if gripped else np.inf
    for p in range(n):
        for a in range(3):
            x[p, a] = base_x[p, a] + q[dof_of[3 * p + a]]
            com[a] += particle_mass[p] * x[p, a]
        if x[p, 2] < min_z:
            min_z = x[p, 2]
        pen = max(xl - x[p, 0], x[p, 0] - xr)
        if pen > penetration:
            penetration = pen
    if gripped:
        rec[step, REC_PALM_XL] = xl
        rec[step, REC_PALM_XR] = xr
    rec[step, REC_TIME] = (step + 1) * dt
    rec[step, REC_PALM_Z] = palm_z_acc[0]
    rec[step, REC_COM_Z] = com[2] / total_mass - com_z0
    rec[step, REC_COM_X] = com[0] / total_mass
    rec[step, REC_COM_Y] = com[1] / total_mass
    rec[step, REC_SLIP_L] = slip[0]
    rec[step, REC_SLIP_R] = slip[1]
    rec[step, REC_FRICTION_L] = fric_l
    rec[step, REC_FRICTION_R] = fric_r
    rec[step, REC_TABLE_N] = table_n
    rec[step, REC_MIN_Z] = min_z
    rec[step, REC_PENETRATION] = penetration
    rec[step, REC_MAX_SPEED] = max_speed


@njit(cache=True)
def integrate(
    base_x: FloatArray,
    q: FloatArray,
    v: FloatArray,
    dof_of: IntArray,
    particle_mass: FloatArray,
    edges: IntArray,
    rest: FloatArray,
    n0: FloatArray,
    k: FloatArray,
    retardation: float,
    l_colptr: IntArray,
    l_rowidx: Int32Array,
    l_values: FloatArray,
    l_diag: FloatArray,
    l_perm: IntArray,
    cols: FloatArray,
    col_of_dof: IntArray,
    gravity: float,
    palm_x_dof: IntArray,
    palm_z_dof: IntArray,
    palm_x0: FloatArray,
    palm_stop: FloatArray,
    palm_mass: float,
    width_damping: float,
    force_cmd: FloatArray,
    palm_vz: FloatArray,
    gravity_scale: FloatArray,
    mu: float,
    mu_table: float,
    row_dof: IntArray,
    row_dof2: IntArray,
    row_type: IntArray,
    row_link: IntArray,
    row_particle: IntArray,
    bottom_particles: IntArray,
    bottom_row: IntArray,
    dt: float,
    n_steps: int,
    nonlinear: bool,
    bdf2: bool,
    stop_slip: float,
    stop_from: int,
    pgs_iterations: int,
    pgs_tolerance: float,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Advance the model ``n_steps`` steps of ``dt`` s and record every step.

    Args:
        base_x: reference positions, m, ``[n, 3]``; positions are ``base_x + q[dof_of]``.
        q: DOF displacements, m, ``[n_dof]`` (copied). v: DOF velocities, m/s, ``[n_dof]``.
        dof_of: DOF of each particle coordinate, ``[3 n]``.
        particle_mass: mass of each particle, kg.
        edges, rest, n0, k: elements ``[m, 2]``, rest length m, rest direction ``[m, 3]``,
            stiffness N/m; retardation: s, each element's damping is ``retardation k`` N·s/m.
        l_colptr, l_rowidx, l_values, l_diag, l_perm: sparse ``L D L^T`` factor of the implicit
            system matrix ``A`` (:class:`deformctl.sim.solver.LDLFactor`).
        cols: precomputed contact columns ``A^-1 e_d``, ``[n_cols, n_dof]``; col_of_dof: the
            column of each DOF (``-1``: solved for when its row first becomes live), ``[n_dof]``.
        gravity: gravitational acceleration along -z, m/s².
        palm_x_dof, palm_z_dof: DOFs of the two palms / face patches (``-1`` = no palms), ``[2]``.
        palm_x0: palm x positions when the palm DOFs are zero, m, ``[2]``.
        palm_stop: innermost x of the left and right palm, m, ``[2]``.
        palm_mass: mass of each palm, kg (moves with its x DOF; the felt force excludes it).
        force_cmd: commanded normal force per palm at each step end, N, ``[n_steps + 1]``.
        palm_vz: palm vertical velocity at each step end, m/s, ``[n_steps + 1]``.
        mu, mu_table: palm and table friction coefficients.
        row_dof, row_dof2, row_type, row_link, row_particle: constraint rows (see module docs):
            ``J_r = e[row_dof] - e[row_dof2]`` (no second term when ``row_dof2 < 0``);
            ``row_link`` is the normal row of a table-friction row, ``row_particle`` the particle
            of a palm-plane row.
        bottom_particles, bottom_row: particles in table contact and their table normal row.
        dt: time step, s. nonlinear: exact spring geometry (else linear small-strain forces).
        pgs_iterations, pgs_tolerance: PGS limits (tolerance in m/s).

    Returns:
        q, v at the end, and the record matrix ``[n_steps, N_REC]`` (columns ``REC_*``).
    """
    n = base_x.shape[0]
    n_dof = q.shape[0]
    nr = row_dof.shape[0]
    q = q.copy()
    v = v.copy()
    x = np.empty((n, 3))
    vel = np.empty((n, 3))
    fp = np.empty((n, 3))
    fq = np.empty(n_dof)
    dv = np.empty(n_dof)
    work = np.empty(n_dof)
    vfree = np.empty(n_dof)
    vnew = np.empty(n_dof)
    h_step = 2.0 * dt / 3.0 if bdf2 else dt
    q_prev = q.copy()
    v_prev = v.copy()
    q_last = q.copy()
    v_last = v.copy()
    rec = np.zeros((n_steps, N_REC))
    # contact columns: precomputed ones, then lazily solved ones
    col_idx = col_of_dof.copy()
    ext = np.empty((0, n_dof))
    n_ext = 0
    skip = np.zeros(nr, dtype=np.bool_)
    forced = np.zeros(nr, dtype=np.bool_)
    live = np.zeros(nr, dtype=np.int64)
    prev_live = np.zeros(nr, dtype=np.int64)
    n_prev = -1
    w = np.empty((0, 0))
    u = np.zeros(nr)
    lam = np.zeros(nr)
    state = np.zeros(nr, dtype=np.int64)
    lo = np.zeros(nr)
    hi = np.zeros(nr)
    target = np.zeros(nr)
    vrow = np.zeros(nr)
    gap = np.zeros(nr)
    friction = np.zeros(nr)  # the palm friction rows' bound, N·s
    all_rows = np.arange(nr)
    all_bottoms = np.arange(bottom_particles.shape[0])
    fact = np.empty((0, 0))
    fact_rows = np.zeros(nr, dtype=np.int64)
    fact_n = np.zeros(1, dtype=np.int64)
    fact_n[0] = -1
    # table rows on a face-patch DOF and the friction row of that DOF
    friction_row_of_dof = np.full(n_dof, -1, dtype=np.int64)
    for r in range(nr):
        if row_type[r] == 1:
            friction_row_of_dof[row_dof[r]] = r
    friction_of = np.full(nr, -1, dtype=np.int64)
    for r in range(nr):
        if row_type[r] == 0:
            friction_of[r] = friction_row_of_dof[row_dof[r]]
    has_table_friction = False
    for r in range(nr):
        if row_type[r] == 2:
            has_table_friction = True
    slip = np.zeros(2)
    palm_z_acc = np.zeros(1)
    total_mass = 0.0
    com_z0 = 0.0
    for p in range(n):
        total_mass += particle_mass[p]
        com_z0 += particle_mass[p] * (base_x[p, 2] + q[dof_of[3 * p + 2]])
    com_z0 /= total_mass
    for step in range(n_steps):
        f_now = force_cmd[step + 1]
        _predict(q, v, q_last, v_last, q_prev, v_prev, bdf2)
        _step_impulse(
            base_x, q, v, dof_of, particle_mass, edges, rest, n0, k, retardation, nonlinear,
            gravity * gravity_scale[step + 1], palm_x_dof, f_now, width_damping, h_step, x, vel, fp,
            fq,
        )  # fmt: skip
        ldl_solve(l_colptr, l_rowidx, l_values, l_diag, l_perm, fq, work, dv)
        for i in range(n_dof):
            vfree[i] = v[i] + dv[i]
            vnew[i] = vfree[i]
        # ---- contacts
        if nr > 0:
            _row_targets(
                all_rows, nr, all_bottoms, all_bottoms.shape[0], bottom_particles, bottom_row, x,
                q, row_type, row_particle, palm_x_dof, palm_x0, palm_stop, palm_vz[step + 1],
                mu * max(f_now, 0.0) * h_step, h_step, gap, target, friction,
            )  # fmt: skip
            for r in range(nr):
                forced[r] = False
                vrow[r] = vfree[row_dof[r]]
                if row_dof2[r] >= 0:
                    vrow[r] -= vfree[row_dof2[r]]
                t = row_type[r]
                if t == 0 or t >= 5:
                    lo[r] = 0.0
                    hi[r] = 1e300
                elif t == 1:
                    lo[r] = -friction[r]
                    hi[r] = friction[r]
                elif t == 3:
                    lo[r] = -1e300
                    hi[r] = 0.0
                elif t == 4:
                    lo[r] = 0.0
                    hi[r] = 1e300
            # unilateral rows without impulse that the free velocity satisfies are skipped; after
            # the solve every skipped row is checked and the solve repeated if one is violated,
            # so skipping never changes the solution
            for _round in range(nr + 1):
                for r in range(nr):
                    t = row_type[r]
                    skip[r] = (
                        (t == 0 or t >= 5)
                        and lam[r] == 0.0
                        and vrow[r] >= target[r]
                        and not forced[r]
                    )
                n_live = 0
                for r in range(nr):
                    if not skip[r]:
                        live[n_live] = r
                        n_live += 1
                lv = live[:n_live]
                changed = n_live != n_prev
                if not changed:
                    for i in range(n_live):
                        if prev_live[i] != lv[i]:
                            changed = True
                            break
                if changed:
                    # the live rows' Delassus matrix, gathered from the contact columns
                    for i in range(n_live):
                        r = lv[i]
                        ext, n_ext = _ensure_column(
                            row_dof[r],
                            col_idx,
                            cols,
                            ext,
                            n_ext,
                            l_colptr,
                            l_rowidx,
                            l_values,
                            l_diag,
                            l_perm,
                        )
                        if row_dof2[r] >= 0:
                            ext, n_ext = _ensure_column(
                                row_dof2[r],
                                col_idx,
                                cols,
                                ext,
                                n_ext,
                                l_colptr,
                                l_rowidx,
                                l_values,
                                l_diag,
                                l_perm,
                            )
                    if w.shape[0] < n_live:
                        w = np.empty((max(n_live, 2 * w.shape[0]), max(n_live, 2 * w.shape[0])))
                        fact = np.empty((w.shape[0], w.shape[0]))
                        fact_n[0] = -1
                    for i in range(n_live):
                        for j in range(n_live):
                            w[i, j] = _delassus_entry(
                                lv[i], lv[j], row_dof, row_dof2, col_idx, cols, ext
                            )
                    for i in range(n_live):
                        prev_live[i] = lv[i]
                    n_prev = n_live
                for r in range(nr):
                    if skip[r]:
                        lam[r] = 0.0
                solved = False
                if not has_table_friction and n_live > 0:
                    solved = _warm_solve(
                        w,
                        lv,
                        vrow,
                        target,
                        lo,
                        hi,
                        lam,
                        state,
                        row_type,
                        fact,
                        fact_rows,
                        fact_n,
                    )
                if not solved and n_live > 0:
                    for i in range(n_live):
                        r = lv[i]
                        if lam[r] < lo[r]:
                            lam[r] = lo[r]
                        elif lam[r] > hi[r]:
                            lam[r] = hi[r]
                    # u = current row velocities J v for the warm-started impulses
                    for i in range(n_live):
                        r = lv[i]
                        acc = vrow[r]
                        for j in range(n_live):
                            s = lv[j]
                            if lam[s] != 0.0:
                                acc += w[i, j] * lam[s]
                        u[r] = acc
                    for _it in range(pgs_iterations):
                        change = 0.0
                        for i in range(n_live):
                            r = lv[i]
                            t = row_type[r]
                            if t == 2:
                                bound = mu_table * lam[row_link[r]]
                                lo[r] = -bound
                                hi[r] = bound
                            new = lam[r] - (u[r] - target[r]) / w[i, i]
                            if new < lo[r]:
                                new = lo[r]
                            elif new > hi[r]:
                                new = hi[r]
                            delta = new - lam[r]
                            if delta != 0.0:
                                lam[r] = new
                                for j in range(n_live):
                                    s = lv[j]
                                    u[s] += w[j, i] * delta
                                if abs(delta) * w[i, i] > change:
                                    change = abs(delta) * w[i, i]
                        if change < pgs_tolerance:
                            break
                    for r in range(nr):
                        if row_type[r] == 2:
                            bound = mu_table * lam[row_link[r]]
                            lo[r] = -bound
                            hi[r] = bound
                    _polish(w[:n_live, :n_live], vrow, target, lo, hi, lam, row_type, row_dof, lv)
                for i in range(n_dof):
                    vnew[i] = vfree[i]
                for i in range(n_live):
                    r = lv[i]
                    lr = lam[r]
                    if lr != 0.0:
                        ca = col_idx[row_dof[r]]
                        if ca < cols.shape[0]:
                            for j in range(n_dof):
                                vnew[j] += cols[ca, j] * lr
                        else:
                            for j in range(n_dof):
                                vnew[j] += ext[ca - cols.shape[0], j] * lr
                        if row_dof2[r] >= 0:
                            cb = col_idx[row_dof2[r]]
                            if cb < cols.shape[0]:
                                for j in range(n_dof):
                                    vnew[j] -= cols[cb, j] * lr
                            else:
                                for j in range(n_dof):
                                    vnew[j] -= ext[cb - cols.shape[0], j] * lr
                violated = False
                for r in range(nr):
                    if skip[r]:
                        vr = vnew[row_dof[r]]
                        if row_dof2[r] >= 0:
                            vr -= vnew[row_dof2[r]]
                        if vr < target[r] - 1e-9:
                            forced[r] = True
                            violated = True
                if not violated:
                    break
            for r in range(nr):
                state[r] = _row_state(lam, lo, hi, row_type, r)
            for r in range(nr):
                f = friction_of[r]
                if f >= 0 and state[r] == 1 and state[f] == 1:
                    state[r] = 3
        _record_step(
            step, rec, q, v, vnew, lam, all_rows, nr, row_type, row_dof, base_x, dof_of, x,
            palm_x_dof, palm_z_dof, palm_x0, palm_vz, palm_mass, f_now, dt, h_step, v_last,
            particle_mass, total_mass, slip, palm_z_acc, com_z0,
        )  # fmt: skip
        if _slipped_past(rec, step, stop_slip, stop_from):
            return q, v, rec[: step + 1]
    return q, v, rec


@njit(cache=True)
def _warm_start(
    dv_hist: FloatArray,
    y_hist: FloatArray,
    order: IntArray,
    n_hist: int,
    fixed: BoolArray,
    rhs: FloatArray,
    dv: FloatArray,
    adv: FloatArray,
    err_hist: FloatArray,
) -> float:
    """CG's initial guess from the last ``n_hist`` (at most 3) velocity changes ``dv_k`` (rows
    ``order[0], order[1], ...`` of ``dv_hist``, newest first) and their images ``y_k = A dv_k``
    (same rows of ``y_hist``), and its image ``adv = A dv`` from the same combination of the
    ``y_k`` (so CG needs no product for its initial residual): ``dv = sum_k c_k dv_k`` with the
    least-squares ``c`` of
    ``min |rhs - sum_k c_k y_k|`` over the DOFs not in ``fixed`` (last step's active set), by
    the normal equations with a 1e-12 relative ridge. The span contains the linear extrapolation
    ``2 dv_1 - dv_2``, the guess while fewer than two are known or the small system is singular.
    The Gram entries are accumulated in one pass, in scalars (a pass per entry, or accumulating
    into an array, costs several times more).

    Returns:
        a bound on the 2-norm error of ``adv`` on the free DOFs: ``sum_k |c_k| (err_k + rho
        |y_k|)`` with ``err_hist[order[k]]`` the bound of image ``k`` (the images are carried,
        not recomputed, so their errors add up through the coefficients) and ``rho`` the
        rounding of the combination (:data:`PRODUCT_ROUNDING`, relative to the terms it sums).
        Checked step by step against the product itself on an 8^3 lift: the error stayed
        below the bound in every step, and below 5e-8 of the largest error carried.
    """
    n_dof = dv.shape[0]
    k = min(n_hist, 3)  # a longer history keeps its newest three
    if k >= 2:
        y1 = y_hist[order[0]]
        y2 = y_hist[order[1]]
        y3 = y_hist[order[2]] if k >= 3 else y_hist[order[1]]
        w3 = 1.0 if k >= 3 else 0.0
        g11 = g12 = g13 = g22 = g23 = g33 = 0.0
        t1 = t2 = t3 = 0.0
        for i in range(n_dof):
            if fixed[i]:
                continue
            a1 = y1[i]
            a2 = y2[i]
            a3 = w3 * y3[i]
            r = rhs[i]
            g11 += a1 * a1
            g12 += a1 * a2
            g13 += a1 * a3
            g22 += a2 * a2
            g23 += a2 * a3
            g33 += a3 * a3
            t1 += a1 * r
            t2 += a2 * r
            t3 += a3 * r
        trace = g11 + g22 + g33
        if trace > 0.0:
            g = np.empty((k, k))
            t = np.empty(k)
            g[0, 0] = g11
            g[0, 1] = g[1, 0] = g12
            g[1, 1] = g22
            t[0] = t1
            t[1] = t2
            if k >= 3:
                g[0, 2] = g[2, 0] = g13
                g[1, 2] = g[2, 1] = g23
                g[2, 2] = g33
                t[2] = t3
            for a in range(k):
                g[a, a] += 1e-12 * trace
            c = np.zeros(k)
            if _solve_dense(g, t, c):
                d1 = dv_hist[order[0]]
                d2 = dv_hist[order[1]]
                d3 = dv_hist[order[2]] if k >= 3 else d2
                c3 = c[2] if k >= 3 else 0.0
                for i in range(n_dof):
                    dv[i] = c[0] * d1[i] + c[1] * d2[i] + c3 * d3[i]
                    adv[i] = c[0] * y1[i] + c[1] * y2[i] + c3 * y3[i]
                # the images' errors through the coefficients, and the combination's rounding
                # (relative to the terms it sums; the Gram diagonal holds their free norms)
                bound = abs(c[0]) * (err_hist[order[0]] + PRODUCT_ROUNDING * np.sqrt(g11))
                bound += abs(c[1]) * (err_hist[order[1]] + PRODUCT_ROUNDING * np.sqrt(g22))
                if k >= 3:
                    bound += abs(c3) * (err_hist[order[2]] + PRODUCT_ROUNDING * np.sqrt(g33))
                return bound
    if k == 0:
        for i in range(n_dof):
            dv[i] = 0.0
            adv[i] = 0.0
        return 0.0
    if k == 1:
        for i in range(n_dof):
            dv[i] = 2.0 * dv_hist[order[0], i]
            adv[i] = 2.0 * y_hist[order[0], i]
        return 2.0 * err_hist[order[0]]
    for i in range(n_dof):
        dv[i] = 2.0 * dv_hist[order[0], i] - dv_hist[order[1], i]
        adv[i] = 2.0 * y_hist[order[0], i] - y_hist[order[1], i]
    return 2.0 * err_hist[order[0]] + err_hist[order[1]]


@njit(cache=True)
def _fixed_residual(
    a_ptr: IntArray,
    a_idx: Int32Array,
    a_val: FloatArray,
    fixed_list: IntArray,
    n_fixed: int,
    dv: FloatArray,
    b: FloatArray,
    out: FloatArray,
) -> None:
    """``out[d] = (A dv - b)[d]`` for the fixed DOFs ``d`` (the impulse their rows apply)."""
    for f in range(n_fixed):
        d = fixed_list[f]
        acc = -b[d]
        for kk in range(a_ptr[d], a_ptr[d + 1]):
            acc += a_val[kk] * dv[a_idx[kk]]
        out[d] = acc


@njit(cache=True)
def _row_targets(
    rows: IntArray,
    n_rows: int,
    bottoms: IntArray,
    n_bottoms: int,
    bottom_particles: IntArray,
    bottom_row: IntArray,
    x: FloatArray,
    q: FloatArray,
    row_type: IntArray,
    row_particle: IntArray,
    palm_x_dof: IntArray,
    palm_x0: FloatArray,
    palm_stop: FloatArray,
    palm_vz_now: float,
    friction_bound: float,
    h_step: float,
    gap: FloatArray,
    target: FloatArray,
    bound: FloatArray,
) -> None:
    """Gap (m) and target velocity (m/s) of rows ``rows[:n_rows]``, and the palm friction rows'
    bound ``friction_bound`` (N·s), as in :func:`integrate`. A table row's gap is the lowest
    height of its particles ``bottom_particles[bottoms[:n_bottoms]]`` (``bottom_row``: the row
    of each)."""
    for j in range(n_rows):
        gap[rows[j]] = 1e300
    for j in range(n_bottoms):
        b = bottoms[j]
        r = bottom_row[b]
        z = x[bottom_particles[b], 2]
        if z < gap[r]:
            gap[r] = z
    for j in range(n_rows):
        r = rows[j]
        t = row_type[r]
        if t == 5:
            gap[r] = x[row_particle[r], 0] - palm_x0[0] - q[palm_x_dof[0]]
        elif t == 6:
            gap[r] = palm_x0[1] + q[palm_x_dof[1]] - x[row_particle[r], 0]
        if t == 0 or t >= 5:
            target[r] = -gap[r] / h_step
        elif t == 1:
            target[r] = palm_vz_now
            bound[r] = friction_bound
        elif t == 3:
            target[r] = (palm_stop[0] - palm_x0[0] - q[palm_x_dof[0]]) / h_step
        elif t == 4:
            target[r] = (palm_stop[1] - palm_x0[1] - q[palm_x_dof[1]]) / h_step
        else:
            target[r] = 0.0


@njit(cache=True)
def _choose_rows(
    cullable: BoolArray,
    state: IntArray,
    gap: FloatArray,
    row_margin: float,
    bottom_row: IntArray,
    x: FloatArray,
    q: FloatArray,
    palm_x_dof: IntArray,
    x_ref: FloatArray,
    palm_ref: FloatArray,
) -> tuple[IntArray, int, IntArray, int]:
    """The rows :func:`integrate_iterative`'s loops visit until the lattice moves: all but the
    ``cullable`` ones (table rows off the palm patches, palm-plane rows) that are inactive with a
    gap of at least ``row_margin`` (m). Also returns the bottom particles of the kept table rows,
    and records the positions ``x`` and palm x displacements they were chosen at (``x_ref``,
    ``palm_ref``, for :func:`_moved_less`).

    Such a row stays inactive, with no impulse, while the lattice has moved less than
    ``0.4 row_margin`` (its gap then exceeds ``0.6 row_margin``) and no velocity could close more
    than ``0.4 row_margin`` in the step (the caller checks both), so leaving it out changes no
    result."""
    nr = cullable.shape[0]
    keep = np.empty(nr, dtype=np.bool_)
    rows = np.empty(nr, dtype=np.int64)
    n_rows = 0
    for r in range(nr):
        keep[r] = (not cullable[r]) or state[r] != 0 or gap[r] < row_margin
        if keep[r]:
            rows[n_rows] = r
            n_rows += 1
    bottoms = np.empty(bottom_row.shape[0], dtype=np.int64)
    n_bottoms = 0
    for b in range(bottom_row.shape[0]):
        if keep[bottom_row[b]]:
            bottoms[n_bottoms] = b
            n_bottoms += 1
    x_ref[:, :] = x
    for a in range(2):
        palm_ref[a] = q[palm_x_dof[a]] if palm_x_dof[a] >= 0 else 0.0
    return rows, n_rows, bottoms, n_bottoms


@njit(cache=True)
def _moved_less(
    x: FloatArray,
    x_ref: FloatArray,
    q: FloatArray,
    palm_x_dof: IntArray,
    palm_ref: FloatArray,
    limit: float,
) -> bool:
    """Whether every gap a table or palm-plane row measures has changed by less than ``limit``
    (m) since :func:`_choose_rows`: the particles' largest height change, and their largest x
    change plus the palms' largest x change."""
    moved_x = 0.0
    moved_z = 0.0
    for p in range(x.shape[0]):
        moved_x = max(moved_x, abs(x[p, 0] - x_ref[p, 0]))
        moved_z = max(moved_z, abs(x[p, 2] - x_ref[p, 2]))
    palm = 0.0
    for a in range(2):
        if palm_x_dof[a] >= 0:
            palm = max(palm, abs(q[palm_x_dof[a]] - palm_ref[a]))
    return moved_x + palm < limit and moved_z < limit


@njit(cache=True)
def integrate_iterative(
    base_x: FloatArray,
    q: FloatArray,
    v: FloatArray,
    dof_of: IntArray,
    particle_mass: FloatArray,
    edges: IntArray,
    rest: FloatArray,
    n0: FloatArray,
    k: FloatArray,
    retardation: float,
    h_n: IntArray,
    h_vec_off: IntArray,
    h_row_off: IntArray,
    h_a_ptr: IntArray,
    h_a_idx: Int32Array,
    h_a_val: FloatArray,
    h_a_diag: IntArray,
    h_inv_diag: FloatArray,
    h_p_row_off: IntArray,
    h_p_ptr: IntArray,
    h_p_idx: Int32Array,
    h_p_val: FloatArray,
    hc_colptr: IntArray,
    hc_rowidx: Int32Array,
    hc_values: FloatArray,
    hc_diag: FloatArray,
    hc_perm: IntArray,
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
    cg_tolerance: float,
    cg_max_iterations: int,
    warm_history: int,
    product_carry: float,
    row_margin: float,
    predict_release: bool,
    gravity: float,
    palm_x_dof: IntArray,
    palm_z_dof: IntArray,
    palm_x0: FloatArray,
    palm_stop: FloatArray,
    palm_mass: float,
    width_damping: float,
    force_cmd: FloatArray,
    palm_vz: FloatArray,
    gravity_scale: FloatArray,
    mu: float,
    mu_table: float,
    row_dof: IntArray,
    row_dof2: IntArray,
    row_type: IntArray,
    row_link: IntArray,
    row_particle: IntArray,
    bottom_particles: IntArray,
    bottom_row: IntArray,
    dt: float,
    n_steps: int,
    nonlinear: bool,
    bdf2: bool,
    stop_slip: float,
    stop_from: int,
    stats: IntArray,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """:func:`integrate` with a multigrid-preconditioned CG instead of the factor.

    The contacts are solved as an active set of *fixed DOFs*: a unit row that is active (table
    contact, sticking palm friction, palm stop, sticking table friction) prescribes its DOF's new
    velocity exactly (``v = target``), the CG solves the free DOFs, and the row's impulse is the
    residual ``(A dv - b)`` at its DOF; a sliding friction row adds its bound as a known impulse.
    Two-DOF rows (palm planes) that are active are added by a Schur complement on CG-solved
    columns. The active set starts from last step's and is updated (release on a wrong-signed
    impulse, fix on a violated row, stick/slide on the friction bound and the sliding direction)
    until it is consistent, so the solution is the same complementarity solution as
    :func:`integrate`'s, up to the CG tolerance on the free DOFs; fixed rows hold exactly.

    Args:
        h_*: the multigrid hierarchy of ``A`` (:class:`deformctl.sim.multigrid.Hierarchy`;
            level 0 is ``A`` itself); st_*: its first levels as lattice stencils
            (:meth:`deformctl.sim.multigrid.Hierarchy.stencil_args`).
        cg_tolerance: CG stops when the free DOFs' residual 2-norm is at most this, N·s.
        cg_max_iterations: CG iteration limit per solve.
        warm_history: velocity changes kept for the warm start (:func:`_warm_start`).
        product_carry: the largest error bound (2-norm, N·s) of a carried product ``A dv`` that
            CG may start from instead of forming the product (a small fraction of
            ``cg_tolerance``; 0 forms it every step).
        row_margin: gap, m, beyond which an inactive table or palm-plane row is left out of the
            step's row loops (:func:`_choose_rows`); ``inf`` keeps every row in them. The
            result does not depend on it: a left-out row cannot become active before the
            rows are chosen again.
        predict_release: release, before the step's first round, a table row whose impulse
            extrapolated linearly from the last two steps is not positive (as the checks would
            after a solve); a wrong guess is undone by the checks, so the solution is the same up
            to the CG tolerance, in fewer rounds while the support peels off the table.
        stats: counters, ``[6]``: solves, CG iterations, active-set rounds, unconverged solves,
            explicit products ``A dv``, rows checked after the solves.
        Other arguments: as :func:`integrate`.
    """
    n = base_x.shape[0]
    n_dof = q.shape[0]
    nr = row_dof.shape[0]
    q = q.copy()
    v = v.copy()
    x = np.empty((n, 3))
    vel = np.empty((n, 3))
    fp = np.empty((n, 3))
    fq = np.empty(n_dof)
    bt = np.empty(n_dof)
    dv = np.zeros(n_dof)
    dv_hist = np.zeros((warm_history, n_dof))
    y_hist = np.zeros((warm_history, n_dof))
    order = np.arange(warm_history)
    n_hist = 0
    residual_in_work = False
    adv = np.zeros(n_dof)  # A dv, carried as dv changes (CG's initial product)
    err_hist = np.zeros(warm_history)  # 2-norm error bound of each kept image
    a_abs = 0.0  # max_i sum_j |A_ij|, the scale of a product's rounding
    for i in range(n_dof):
        row_abs = 0.0
        for kk in range(h_a_ptr[h_row_off[0] + i], h_a_ptr[h_row_off[0] + i + 1]):
            row_abs += abs(h_a_val[kk])
        a_abs = max(a_abs, row_abs)
    vnew = np.empty(n_dof)
    react = np.zeros(n_dof)
    h_step = 2.0 * dt / 3.0 if bdf2 else dt
    q_prev = q.copy()
    v_prev = v.copy()
    q_last = q.copy()
    v_last = v.copy()
    rec = np.zeros((n_steps, N_REC))
    work = np.zeros(pcg_work_size(h_n, st_shape, st_halo))
    fixed = np.zeros(n_dof, dtype=np.bool_)
    fixed_list = np.zeros(n_dof, dtype=np.int64)
    fixer = np.full(n_dof, -1, dtype=np.int64)
    n_fixed = 0
    cand = np.zeros(nr, dtype=np.int64)  # the DOFs the round's rows fix (repeats possible)
    lam = np.zeros(nr)
    lam_last = np.zeros(nr)  # each row's impulse one step earlier
    state = np.zeros(nr, dtype=np.int64)
    for r in range(nr):
        if row_type[r] == 1:
            state[r] = 1  # palm friction starts sticking
    target = np.zeros(nr)
    gap = np.zeros(nr)
    bound = np.zeros(nr)
    table_of_dof = np.full(n_dof, -1, dtype=np.int64)
    for r in range(nr):
        if row_type[r] == 0:
            table_of_dof[row_dof[r]] = r
    general = np.zeros(nr, dtype=np.int64)
    general_slot = np.zeros(nr, dtype=np.int64)
    yslot = np.full(nr, -1, dtype=np.int64)
    ystore = np.zeros((0, n_dof))
    slot_version = np.zeros(0, dtype=np.int64)
    n_slots = 0
    fixed_prev = np.zeros(n_dof, dtype=np.int64)
    n_fixed_prev = -1
    fixed_version = 0
    unit = np.zeros(n_dof)
    slip = np.zeros(2)
    palm_z_acc = np.zeros(1)
    total_mass = 0.0
    com_z0 = 0.0
    for p in range(n):
        total_mass += particle_mass[p]
        com_z0 += particle_mass[p] * (base_x[p, 2] + q[dof_of[3 * p + 2]])
    com_z0 /= total_mass
    a_ptr0 = h_a_ptr[h_row_off[0] : h_row_off[0] + n_dof + 1]
    # the rows the step's loops visit (see _choose_rows): every row at first
    all_rows = np.arange(nr)
    all_bottoms = np.arange(bottom_particles.shape[0])
    rows, n_rows, bottoms, n_bottoms = all_rows, nr, all_bottoms, all_bottoms.shape[0]
    cullable = np.zeros(nr, dtype=np.bool_)
    for r in range(nr):
        t = row_type[r]
        cullable[r] = t >= 5 or (
            t == 0 and row_dof[r] != palm_z_dof[0] and row_dof[r] != palm_z_dof[1]
        )
    dof_axis = np.full(n_dof, 1, dtype=np.int64)
    for p in range(n):
        dof_axis[dof_of[3 * p]] = 0
        dof_axis[dof_of[3 * p + 2]] = 2
    for a in range(2):
        if palm_x_dof[a] >= 0:
            dof_axis[palm_x_dof[a]] = 0
    x_ref = np.empty((n, 3))
    palm_ref = np.zeros(2)
    choose = np.isfinite(row_margin)
    chosen = False
    for step in range(n_steps):
        f_now = force_cmd[step + 1]
        _predict(q, v, q_last, v_last, q_prev, v_prev, bdf2)
        _step_impulse(
            base_x, q, v, dof_of, particle_mass, edges, rest, n0, k, retardation, nonlinear,
            gravity * gravity_scale[step + 1], palm_x_dof, f_now, width_damping, h_step, x, vel, fp,
            fq,
        )  # fmt: skip
        # targets of the rows (as in integrate); only the chosen rows while the lattice has
        # moved less than 0.4 row_margin since they were chosen
        if choose:
            if chosen:
                chosen = _moved_less(x, x_ref, q, palm_x_dof, palm_ref, 0.4 * row_margin)
            if not chosen:
                rows, n_rows, bottoms, n_bottoms = all_rows, nr, all_bottoms, all_bottoms.shape[0]
        friction_bound = mu * max(f_now, 0.0) * h_step
        _row_targets(
            rows, n_rows, bottoms, n_bottoms, bottom_particles, bottom_row, x, q, row_type,
            row_particle, palm_x_dof, palm_x0, palm_stop, palm_vz[step + 1], friction_bound,
            h_step, gap, target, bound,
        )  # fmt: skip
        if choose and not chosen:
            rows, n_rows, bottoms, n_bottoms = _choose_rows(
                cullable, state, gap, row_margin, bottom_row, x, q, palm_x_dof, x_ref, palm_ref
            )
            chosen = True
        for j in range(n_rows):
            r = rows[j]
            lam_before = lam[r]
            # the extrapolated impulse 2 lam - lam_last is not positive
            falling = lam[r] > 0.0 and 2.0 * lam[r] - lam_last[r] <= 0.0
            if predict_release and falling and row_type[r] == 0 and cullable[r] and state[r] == 1:
                state[r] = 0
                lam[r] = 0.0
            lam_last[r] = lam_before
        adv_err = _warm_start(dv_hist, y_hist, order, n_hist, fixed, fq, dv, adv, err_hist)
        # A dv is carried through the images while its error bound stays far below CG's
        # tolerance (then CG's stopping test still holds for the true residual); else CG forms
        # the product (the image is then exact, and the bounds start again from rounding)
        adv_known = adv_err <= product_carry
        if not adv_known:
            stats[4] += 1
        for _round in range(64):
            stats[2] += 1
            # fixed DOFs and known impulses of the current active set (the last round's fixed
            # DOFs are the only ones to clear; the rows that fix one are collected as they are
            # met and visited in DOF order, so no pass over every DOF)
            bt[:] = fq
            for f in range(n_fixed):
                fixed[fixed_list[f]] = False
                fixer[fixed_list[f]] = -1
            n_general = 0
            n_cand = 0
            for j in range(n_rows):
                r = rows[j]
                t = row_type[r]
                st = state[r]
                d = row_dof[r]
                if t == 1:
                    if st == 1:
                        fixer[d] = r
                        cand[n_cand] = d
                        n_cand += 1
                    elif st != 0:
                        bt[d] += (1.0 if st > 0 else -1.0) * bound[r]
                elif t == 2:
                    bound[r] = mu_table * max(lam[row_link[r]], 0.0)
                    if st == 1 and bound[r] > 0.0:
                        fixer[d] = r
                        cand[n_cand] = d
                        n_cand += 1
                    elif st == 2 or st == -2:
                        bt[d] += (1.0 if st > 0 else -1.0) * bound[r]
                elif t >= 5:
                    if st == 1:
                        general[n_general] = r
                        n_general += 1
                        # last impulse as a known one: the Schur step solves for the change
                        bt[d] += lam[r]
                        bt[row_dof2[r]] -= lam[r]
                elif st == 1 and (fixer[d] < 0 or t != 0):
                    fixer[d] = r  # a sticking friction row, not the table row, fixes a patch
                    cand[n_cand] = d
                    n_cand += 1
            n_fixed = 0
            change2 = 0.0
            cand[:n_cand].sort()
            for ci in range(n_cand):
                i = cand[ci]
                if ci > 0 and i == cand[ci - 1]:
                    continue
                r = fixer[i]
                if r >= 0:
                    fixed[i] = True
                    fixed_list[n_fixed] = i
                    n_fixed += 1
                    change = target[r] - v[i] - dv[i]
                    if change != 0.0:
                        dv[i] += change
                        if adv_known:  # A is symmetric: column i is row i
                            for kk in range(a_ptr0[i], a_ptr0[i + 1]):
                                adv[h_a_idx[kk]] += h_a_val[kk] * change
                            change2 += change * change
            adv_err += PRODUCT_ROUNDING * a_abs * np.sqrt(change2)
            same_fixed = n_fixed == n_fixed_prev
            if same_fixed:
                for f in range(n_fixed):
                    if fixed_list[f] != fixed_prev[f]:
                        same_fixed = False
                        break
            if not same_fixed:
                fixed_version += 1
                for f in range(n_fixed):
                    fixed_prev[f] = fixed_list[f]
                n_fixed_prev = n_fixed
            # free solve (the fixed DOFs keep their prescribed change)
            its = pcg(
                h_n, h_vec_off, h_row_off, h_a_ptr, h_a_idx, h_a_val, h_a_diag, h_inv_diag,
                h_p_row_off, h_p_ptr, h_p_idx, h_p_val, hc_colptr, hc_rowidx, hc_values, hc_diag,
                hc_perm, st_shape, st_halo, st_coef, st_coef_off, st_block, st_inv, st_node_off,
                st_dof, st_rep, st_palm, fixed, bt, dv, cg_tolerance, cg_max_iterations, work, adv,
                adv_known,
            )  # fmt: skip
            if not adv_known:
                adv_err = 0.0
            stats[0] += 1
            stats[1] += min(its, cg_max_iterations)
            if its > cg_max_iterations:
                stats[3] += 1
            residual_in_work = n_general == 0  # the Schur columns' solves reuse the scratch
            if n_general > 0:
                # Schur complement on the two-DOF rows: columns y_r = A_FF^-1 J_r^T by CG, each
                # warm-started from its last solve. W = J Y is formed from the same columns that
                # apply the impulses, so the rows hold exactly whatever the columns' accuracy.
                for g in range(n_general):
                    r = general[g]
                    if yslot[r] < 0:
                        if n_slots == ystore.shape[0]:
                            grown = np.zeros((max(8, 2 * n_slots), n_dof))
                            grown[:n_slots] = ystore[:n_slots]
                            ystore = grown
                            grown_v = np.full(grown.shape[0], -1, dtype=np.int64)
                            grown_v[:n_slots] = slot_version[:n_slots]
                            slot_version = grown_v
                        yslot[r] = n_slots
                        n_slots += 1
                    general_slot[g] = yslot[r]
                    if slot_version[yslot[r]] == fixed_version:
                        continue  # same free DOFs as when it was solved for
                    slot_version[yslot[r]] = fixed_version
                    y = ystore[yslot[r]]
                    for i in range(n_dof):
                        unit[i] = 0.0
                        if fixed[i]:
                            y[i] = 0.0
                    unit[row_dof[r]] = 1.0
                    if row_dof2[r] >= 0:
                        unit[row_dof2[r]] -= 1.0
                    its_y = pcg(
                        h_n, h_vec_off, h_row_off, h_a_ptr, h_a_idx, h_a_val, h_a_diag, h_inv_diag,
                        h_p_row_off, h_p_ptr, h_p_idx, h_p_val, hc_colptr, hc_rowidx,
                        hc_values, hc_diag, hc_perm, st_shape, st_halo, st_coef, st_coef_off,
                        st_block, st_inv, st_node_off, st_dof, st_rep, st_palm, fixed, unit, y,
                        1e-8, cg_max_iterations, work, adv, False,
                    )  # fmt: skip
                    stats[0] += 1
                    stats[1] += min(its_y, cg_max_iterations)
                    if its_y > cg_max_iterations:
                        stats[3] += 1
                wg = np.empty((n_general, n_general))
                rhs = np.empty(n_general)
                for g in range(n_general):
                    r = general[g]
                    a_r = row_dof[r]
                    b_r = row_dof2[r]
                    vr = v[a_r] + dv[a_r]
                    if b_r >= 0:
                        vr -= v[b_r] + dv[b_r]
                    rhs[g] = target[r] - vr
                    for h in range(n_general):
                        val = ystore[general_slot[h], a_r]
                        if b_r >= 0:
                            val -= ystore[general_slot[h], b_r]
                        wg[g, h] = val
                lg = np.empty(n_general)
                if _solve_dense(wg, rhs, lg):
                    for g in range(n_general):
                        lam[general[g]] += lg[g]
                        for i in range(n_dof):
                            dv[i] += ystore[general_slot[g], i] * lg[g]
                        # the row's impulse acts on its DOFs: fold it into the right-hand side
                        bt[row_dof[general[g]]] += lg[g]
                        if row_dof2[general[g]] >= 0:
                            bt[row_dof2[general[g]]] -= lg[g]
            _fixed_residual(a_ptr0, h_a_idx, h_a_val, fixed_list, n_fixed, dv, bt, react)
            dv2 = 0.0
            if residual_in_work:
                # A dv without a product: b - r on the free DOFs (r: CG's final residual, first
                # in its scratch), b + the row impulse on the fixed ones (from _fixed_residual);
                # exact up to the error of CG's initial product and rounding
                for i in range(n_dof):
                    adv[i] = bt[i] + react[i] if fixed[i] else bt[i] - work[i]
                    dv2 += dv[i] * dv[i]
            else:
                product(
                    h_n, h_vec_off, h_row_off, h_a_ptr, h_a_idx, h_a_val, st_shape, st_halo,
                    st_coef, st_coef_off, st_block, st_inv, st_node_off, st_dof, st_rep, st_palm,
                    work, dv, adv,
                )  # fmt: skip
                stats[4] += 1
                adv_err = 0.0
                for i in range(n_dof):
                    dv2 += dv[i] * dv[i]
            adv_err += PRODUCT_ROUNDING * a_abs * np.sqrt(dv2)
            adv_known = True
            speed_x = 0.0
            speed_z = 0.0
            for i in range(n_dof):
                vnew[i] = v[i] + dv[i]
                a = dof_axis[i]
                if a == 0:
                    speed_x = max(speed_x, abs(vnew[i]))
                elif a == 2:
                    speed_z = max(speed_z, abs(vnew[i]))
            if chosen and max(2.0 * speed_x, speed_z) * h_step >= 0.4 * row_margin:
                # fast enough that a left-out row could close its gap: all rows, chosen again
                # next step
                rows, n_rows, bottoms, n_bottoms = all_rows, nr, all_bottoms, all_bottoms.shape[0]
                _row_targets(
                    rows, n_rows, bottoms, n_bottoms, bottom_particles, bottom_row, x, q,
                    row_type, row_particle, palm_x_dof, palm_x0, palm_stop, palm_vz[step + 1],
                    friction_bound, h_step, gap, target, bound,
                )  # fmt: skip
                chosen = False
            # impulses of the rows, then the complementarity checks
            changed = False
            stats[5] += n_rows
            for j in range(n_rows):
                r = rows[j]
                t = row_type[r]
                st = state[r]
                d = row_dof[r]
                vr = vnew[d]
                if row_dof2[r] >= 0:
                    vr -= vnew[row_dof2[r]]
                slack = vr - target[r]
                if t == 2:
                    if bound[r] == 0.0:
                        if st != 0:
                            state[r] = 0
                            changed = True
                        lam[r] = 0.0
                        continue
                    if st == 0:
                        state[r] = 1
                        changed = True
                        continue
                if t == 1 or t == 2:
                    if st == 1 and fixer[d] == r:
                        total = react[d]
                        tr = table_of_dof[d]
                        if t == 1 and tr >= 0:
                            # a face patch on the table: the table carries the push, friction
                            # the pull (as projected Gauss–Seidel's row order resolves it)
                            if target[r] < target[tr] + 1e-9 and total > 0.0:
                                lam[tr] = total
                                state[tr] = 1
                                total = 0.0
                            else:
                                lam[tr] = 0.0
                                state[tr] = 0
                        lam[r] = total
                        if abs(total) > bound[r]:
                            state[r] = 2 if total > 0.0 else -2
                            changed = True
                    elif st == 2 or st == -2:
                        lam[r] = (1.0 if st > 0 else -1.0) * bound[r]
                        if (st == 2 and slack > 1e-9) or (st == -2 and slack < -1e-9):
                            state[r] = 1
                            changed = True
                    continue
                if t >= 5:
                    if st == 1:
                        if lam[r] < 0.0:
                            state[r] = 0
                            lam[r] = 0.0
                            changed = True
                    else:
                        lam[r] = 0.0
                        if slack < -1e-9:
                            state[r] = 1
                            changed = True
                    continue
                if t == 0 and fixer[d] >= 0 and row_type[fixer[d]] == 1:
                    continue  # under a sticking face patch: set with the friction row
                sign = -1.0 if t == 3 else 1.0
                if st == 1:
                    lam[r] = react[d]
                    if sign * lam[r] < 0.0:
                        state[r] = 0
                        lam[r] = 0.0
                        changed = True
                else:
                    lam[r] = 0.0
                    if sign * slack < -1e-9:
                        state[r] = 1
                        changed = True
            if not changed:
                break
        # the history: the oldest slot takes this step's dv and its image A dv
        slot = order[warm_history - 1]
        for a in range(warm_history - 1, 0, -1):
            order[a] = order[a - 1]
        order[0] = slot
        n_hist = min(n_hist + 1, warm_history)
        for i in range(n_dof):
            dv_hist[slot, i] = dv[i]
            y_hist[slot, i] = adv[i]
        err_hist[slot] = adv_err
        _record_step(
            step, rec, q, v, vnew, lam, rows, n_rows, row_type, row_dof, base_x, dof_of, x,
            palm_x_dof, palm_z_dof, palm_x0, palm_vz, palm_mass, f_now, dt, h_step, v_last,
            particle_mass, total_mass, slip, palm_z_acc, com_z0,
        )  # fmt: skip
        if _slipped_past(rec, step, stop_slip, stop_from):
            return q, v, rec[: step + 1]
    return q, v, rec
