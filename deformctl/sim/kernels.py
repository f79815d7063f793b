"""numba kernels: Kelvin element forces and the implicit time-stepping loop.

Everything in the step loop runs inside one ``@njit(cache=True)`` function (:func:`integrate`),
so a lift attempt is a single call with no Python work per step. The loop is serial and its
floating-point operation order is fixed, so results are bit-identical run to run.

Step (linearised backward Euler, tangent frozen at the rest configuration; see
:mod:`deformctl.sim.engine` for why)::

    A dv = dt (f(x, v) + f_ext - dt K v) + J^T Lambda,    A = M + (dt beta + dt^2) K
    v <- v + dv,  x <- x + dt v

``f`` is the exact (geometrically nonlinear) Kelvin element force, ``A^-1`` is precomputed once
per model, and ``Lambda`` are the contact impulses found by projected Gauss–Seidel on the
Delassus matrix ``W = J A^-1 J^T`` followed by an exact active-set solve (so sticking contacts
stick to round-off). Every constraint row ``J_r`` is a unit vector on one DOF, so ``W`` is a
gather from ``A^-1``.

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

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

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
    c: FloatArray,
    k_dt: FloatArray,
    nonlinear: bool,
    out: FloatArray,
) -> None:
    """Element forces minus ``dt K v`` (tangent at rest), accumulated into ``out`` ``[n, 3]``."""
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
        f = k[e] * stretch + c[e] * (dvx * nx + dvy * ny + dvz * nz)
        g = k_dt[e] * (dvx * ax + dvy * ay + dvz * az)
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
    """Exact solve on the PGS active set (among ``live`` rows); keeps PGS when inconsistent."""
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
            idx[na] = live[i]
            na += 1
    a = np.empty((na, na))
    b = np.empty(na)
    for p in range(na):
        r = idx[p]
        rhs = target[r] - vrow[r]
        for j in range(nl):
            if not active[j]:
                rhs -= w[r, live[j]] * lam[live[j]]
        b[p] = rhs
        for q in range(na):
            a[p, q] = w[r, idx[q]]
    sol = np.empty(na)
    if not _solve_dense(a, b, sol):
        return
    trial = lam.copy()
    for p in range(na):
        trial[idx[p]] = sol[p]
    # feasibility: bounds, and non-active unilateral rows must not penetrate
    for i in range(nl):
        r = live[i]
        t = row_type[r]
        if t == 0 or t >= 3:
            sign = -1.0 if t == 3 else 1.0
            if sign * trial[r] < 0.0:
                return
            if not active[i]:
                vr = vrow[r]
                for j in range(nl):
                    vr += w[r, live[j]] * trial[live[j]]
                if sign * (vr - target[r]) < -1e-9:
                    return
        elif trial[r] > hi[r] or trial[r] < lo[r]:
            return
    for p in range(na):
        lam[idx[p]] = trial[idx[p]]


@njit(cache=True)
def integrate(
    base_x: FloatArray,
    q: FloatArray,
    v: FloatArray,
    dof_of: IntArray,
    particle_mass: float,
    edges: IntArray,
    rest: FloatArray,
    n0: FloatArray,
    k: FloatArray,
    c: FloatArray,
    a_inv: FloatArray,
    dof_mass: FloatArray,
    gravity: float,
    palm_x_dof: IntArray,
    palm_z_dof: IntArray,
    palm_x0: FloatArray,
    palm_stop: FloatArray,
    palm_mass: float,
    force_cmd: FloatArray,
    palm_vz: FloatArray,
    mu: float,
    mu_table: float,
    row_dof: IntArray,
    row_dof2: IntArray,
    row_type: IntArray,
    row_link: IntArray,
    row_particle: IntArray,
    bottom_particles: IntArray,
    bottom_row: IntArray,
    contact_margin: float,
    dt: float,
    n_steps: int,
    nonlinear: bool,
    pgs_iterations: int,
    pgs_tolerance: float,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Advance the model ``n_steps`` steps of ``dt`` s and record every step.

    Args:
        base_x: reference positions, m, ``[n, 3]``; positions are ``base_x + q[dof_of]``.
        q: DOF displacements, m, ``[n_dof]`` (copied). v: DOF velocities, m/s, ``[n_dof]``.
        dof_of: DOF of each particle coordinate, ``[3 n]``.
        particle_mass: mass of each particle, kg.
        edges, rest, n0, k, c: elements ``[m, 2]``, rest length m, rest direction ``[m, 3]``,
            stiffness N/m, damping N·s/m.
        a_inv: inverse of the implicit system matrix, 1/kg, ``[n_dof, n_dof]``.
        dof_mass: mass of each DOF including palm mass, kg, ``[n_dof]``.
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
        contact_margin: unilateral rows farther than this (m) and without impulse are skipped.
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
    k_dt = k * dt
    rec = np.zeros((n_steps, N_REC))
    # Delassus matrix and contact columns of A^-1, gathered once
    w = np.empty((nr, nr))
    for r in range(nr):
        for s in range(nr):
            a_r = row_dof[r]
            b_r = row_dof2[r]
            a_s = row_dof[s]
            b_s = row_dof2[s]
            val = a_inv[a_r, a_s]
            if b_s >= 0:
                val -= a_inv[a_r, b_s]
            if b_r >= 0:
                val -= a_inv[b_r, a_s]
                if b_s >= 0:
                    val += a_inv[b_r, b_s]
            w[r, s] = val
    skip = np.zeros(nr, dtype=np.bool_)
    live = np.zeros(nr, dtype=np.int64)
    u = np.zeros(nr)
    lam = np.zeros(nr)
    lo = np.zeros(nr)
    hi = np.zeros(nr)
    target = np.zeros(nr)
    vrow = np.zeros(nr)
    gap = np.zeros(nr)
    gripped = palm_x_dof[0] >= 0
    slip = np.zeros(2)
    palm_z = 0.0
    com_z0 = 0.0
    for p in range(n):
        com_z0 += base_x[p, 2] + q[dof_of[3 * p + 2]]
    com_z0 /= n
    for step in range(n_steps):
        for p in range(n):
            for a in range(3):
                d = dof_of[3 * p + a]
                x[p, a] = base_x[p, a] + q[d]
                vel[p, a] = v[d]
                fp[p, a] = 0.0
        _element_rhs(x, vel, edges, rest, n0, k, c, k_dt, nonlinear, fp)
        fq[:] = 0.0
        for p in range(n):
            fp[p, 2] -= particle_mass * gravity
            for a in range(3):
                fq[dof_of[3 * p + a]] += fp[p, a]
        f_now = force_cmd[step + 1]
        if gripped:
            fq[palm_x_dof[0]] += f_now
            fq[palm_x_dof[1]] -= f_now
        for i in range(n_dof):
            fq[i] *= dt
        for i in range(n_dof):
            acc = 0.0
            for j in range(n_dof):
                acc += a_inv[i, j] * fq[j]
            dv[i] = acc
        vfree = v + dv
        # ---- contacts
        if nr > 0:
            for r in range(nr):
                gap[r] = 1e300
            for b in range(bottom_particles.shape[0]):
                r = bottom_row[b]
                z = x[bottom_particles[b], 2]
                if z < gap[r]:
                    gap[r] = z
            for r in range(nr):
                t = row_type[r]
                if t == 5:
                    gap[r] = x[row_particle[r], 0] - palm_x0[0] - q[palm_x_dof[0]]
                elif t == 6:
                    gap[r] = palm_x0[1] + q[palm_x_dof[1]] - x[row_particle[r], 0]
            for r in range(nr):
                vrow[r] = vfree[row_dof[r]]
                if row_dof2[r] >= 0:
                    vrow[r] -= vfree[row_dof2[r]]
                t = row_type[r]
                skip[r] = False
                if t == 0 or t >= 5:
                    target[r] = -gap[r] / dt
                    lo[r] = 0.0
                    hi[r] = 1e300
                    skip[r] = lam[r] == 0.0 and gap[r] > contact_margin and vrow[r] >= target[r]
                elif t == 1:
                    target[r] = palm_vz[step + 1]
                    bound = mu * max(f_now, 0.0) * dt
                    lo[r] = -bound
                    hi[r] = bound
                elif t == 3:
                    target[r] = (palm_stop[0] - palm_x0[0] - q[palm_x_dof[0]]) / dt
                    lo[r] = -1e300
                    hi[r] = 0.0
                elif t == 4:
                    target[r] = (palm_stop[1] - palm_x0[1] - q[palm_x_dof[1]]) / dt
                    lo[r] = 0.0
                    hi[r] = 1e300
                else:
                    target[r] = 0.0
            n_live = 0
            for r in range(nr):
                if not skip[r]:
                    live[n_live] = r
                    n_live += 1
            lv = live[:n_live]
            # u = current row velocities J v for the warm-started impulses
            for i in range(n_live):
                r = lv[i]
                acc = vrow[r]
                for j in range(n_live):
                    s = lv[j]
                    if lam[s] != 0.0:
                        acc += w[r, s] * lam[s]
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
                    new = lam[r] - (u[r] - target[r]) / w[r, r]
                    if new < lo[r]:
                        new = lo[r]
                    elif new > hi[r]:
                        new = hi[r]
                    delta = new - lam[r]
                    if delta != 0.0:
                        lam[r] = new
                        for j in range(n_live):
                            s = lv[j]
                            u[s] += w[s, r] * delta
                        if abs(delta) * w[r, r] > change:
                            change = abs(delta) * w[r, r]
                if change < pgs_tolerance:
                    break
            for r in range(nr):
                if row_type[r] == 2:
                    bound = mu_table * lam[row_link[r]]
                    lo[r] = -bound
                    hi[r] = bound
            _polish(w, vrow, target, lo, hi, lam, row_type, row_dof, lv)
            for r in range(nr):
                if lam[r] != 0.0:
                    d = row_dof[r]
                    d2 = row_dof2[r]
                    for i in range(n_dof):
                        vfree[i] += a_inv[i, d] * lam[r]
                    if d2 >= 0:
                        for i in range(n_dof):
                            vfree[i] -= a_inv[i, d2] * lam[r]
        # ---- records (palm quantities before the position update use the new velocities)
        table_n = 0.0
        fric_l = 0.0
        fric_r = 0.0
        for r in range(nr):
            if row_type[r] == 0:
                table_n += lam[r] / dt
            elif row_type[r] == 1:
                if row_dof[r] == palm_z_dof[0]:
                    fric_l += lam[r] / dt
                else:
                    fric_r += lam[r] / dt
        if gripped:
            vz_palm = palm_vz[step + 1]
            slip[0] += abs(vfree[palm_z_dof[0]] - vz_palm) * dt
            slip[1] += abs(vfree[palm_z_dof[1]] - vz_palm) * dt
            palm_z += vz_palm * dt
            acc_l = (vfree[palm_x_dof[0]] - v[palm_x_dof[0]]) / dt
            acc_r = (vfree[palm_x_dof[1]] - v[palm_x_dof[1]]) / dt
            rec[step, REC_NORMAL_L] = f_now - palm_mass * acc_l
            rec[step, REC_NORMAL_R] = f_now + palm_mass * acc_r
        max_speed = 0.0
        for i in range(n_dof):
            v[i] = vfree[i]
            q[i] += dt * v[i]
            if abs(v[i]) > max_speed:
                max_speed = abs(v[i])
        com = np.zeros(3)
        min_z = 1e300
        for p in range(n):
            for a in range(3):
                x[p, a] = base_x[p, a] + q[dof_of[3 * p + a]]
                com[a] += x[p, a]
            if x[p, 2] < min_z:
                min_z = x[p, 2]
        penetration = 0.0
        if gripped:
            xl = palm_x0[0] + q[palm_x_dof[0]]
            xr = palm_x0[1] + q[palm_x_dof[1]]
            for p in range(n):
                pen = max(xl - x[p, 0], x[p, 0] - xr)
                if pen > penetration:
                    penetration = pen
            rec[step, REC_PALM_XL] = xl
            rec[step, REC_PALM_XR] = xr
        rec[step, REC_TIME] = (step + 1) * dt
        rec[step, REC_PALM_Z] = palm_z
        rec[step, REC_COM_Z] = com[2] / n - com_z0
        rec[step, REC_COM_X] = com[0] / n
        rec[step, REC_COM_Y] = com[1] / n
        rec[step, REC_SLIP_L] = slip[0]
        rec[step, REC_SLIP_R] = slip[1]
        rec[step, REC_FRICTION_L] = fric_l
        rec[step, REC_FRICTION_R] = fric_r
        rec[step, REC_TABLE_N] = table_n
        rec[step, REC_MIN_Z] = min_z
        rec[step, REC_PENETRATION] = penetration
        rec[step, REC_MAX_SPEED] = max_speed
    return q, v, rec
