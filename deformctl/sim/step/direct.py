"""The step loop with the direct solver: sparse ``L D L^T`` solves and the exact contact problem
on the Delassus matrix (see :mod:`deformctl.sim.step`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from deformctl.arraytypes import FloatArray
from deformctl.sim.solver import ldl_solve
from deformctl.sim.step.bundles import (
    Body,
    Contacts,
    DirectSolver,
    Drive,
    Palms,
    RowTargets,
    StepState,
    Tally,
)
from deformctl.sim.step.contact import _row_targets
from deformctl.sim.step.delassus import (
    _delassus_entry,
    _ensure_column,
    _polish,
    _row_state,
    _warm_solve,
)
from deformctl.sim.step.forces import _predict, _step_impulse
from deformctl.sim.step.laws import coulomb_bound
from deformctl.sim.step.maxwell import _arm_predict, _arm_update
from deformctl.sim.step.record import N_REC, _record_step, _slipped_past


@njit(cache=True)
def integrate(
    body: Body,
    palms: Palms,
    contacts: Contacts,
    drive: Drive,
    solver: DirectSolver,
    q: FloatArray,
    v: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Advance the model ``drive.n_steps`` steps of ``drive.dt`` s and record every step.

    Args:
        body, palms, contacts: the model (:mod:`deformctl.sim.step.bundles`).
        drive: the run's commands, step and stop.
        solver: the sparse ``L D L^T`` factor of the implicit system matrix ``A``, the contact
            columns and the projected Gauss–Seidel limits.
        q: DOF displacements, m, ``[n_dof]`` (copied). v: DOF velocities, m/s, ``[n_dof]``
            (copied).

    Returns:
        q, v at the end, and the record matrix ``[n_steps, N_REC]`` (columns ``REC_*``).
    """
    base_x, particle_mass, dof_of = body.base_x, body.particle_mass, body.dof_of
    row_dof, row_dof2, row_type, row_link = (
        contacts.row_dof, contacts.row_dof2, contacts.row_type, contacts.row_link
    )  # fmt: skip
    bottom_particles, mu, mu_table = contacts.bottom_particles, contacts.mu, contacts.mu_table
    force_cmd, palm_vz, gravity_scale, gravity = (
        drive.force_cmd, drive.palm_vz, drive.gravity_scale, drive.gravity
    )  # fmt: skip
    dt, n_steps, bdf2, stop_slip, stop_from = (
        drive.dt, drive.n_steps, drive.bdf2, drive.stop_slip, drive.stop_from
    )  # fmt: skip
    factor, cols, col_of_dof = solver.factor, solver.cols, solver.col_of_dof
    pgs_iterations, pgs_tolerance = solver.pgs_iterations, solver.pgs_tolerance
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
    motion = StepState(q, v, vnew, v_last, lam, x)
    tally = Tally(rec, slip, palm_z_acc, total_mass, com_z0)
    targets = RowTargets(gap, target, friction)
    for step in range(n_steps):
        f_now = force_cmd[step + 1]
        _predict(q, v, q_last, v_last, q_prev, v_prev, bdf2, palms.x_dof)
        _arm_predict(body.arm, bdf2)
        _step_impulse(
            body, palms, q, v, gravity * gravity_scale[step + 1], f_now, h_step, x, vel, fp, fq
        )
        ldl_solve(factor, fq, work, dv)
        for i in range(n_dof):
            vfree[i] = v[i] + dv[i]
            vnew[i] = vfree[i]
        # ---- contacts
        if nr > 0:
            _row_targets(
                contacts, palms, all_rows, nr, all_bottoms, all_bottoms.shape[0], x, q,
                palm_vz[step + 1], coulomb_bound(mu, f_now) * h_step, h_step, targets,
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
                        ext, n_ext = _ensure_column(row_dof[r], col_idx, cols, ext, n_ext, factor)
                        if row_dof2[r] >= 0:
                            ext, n_ext = _ensure_column(
                                row_dof2[r], col_idx, cols, ext, n_ext, factor
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
                                bound = coulomb_bound(mu_table, lam[row_link[r]])
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
                            bound = coulomb_bound(mu_table, lam[row_link[r]])
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
        _arm_update(body, x, vnew, h_step)  # before x moves to the new positions
        _record_step(
            step, tally, motion, body, palms, contacts, drive, all_rows, nr, f_now, h_step, -1.0
        )
        if _slipped_past(rec, step, stop_slip, stop_from):
            return q, v, rec[: step + 1]
    return q, v, rec
