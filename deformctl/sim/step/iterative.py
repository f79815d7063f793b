"""The step loop with the iterative solver: multigrid CG with contacts as fixed DOFs (see
:func:`integrate_iterative`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from deformctl.arraytypes import BoolArray, FloatArray, Int32Array, IntArray
from deformctl.sim.multigrid import pcg, pcg_work_size, product
from deformctl.sim.step.bundles import (
    Body,
    Contacts,
    Drive,
    IterativeSolver,
    Palms,
    RowTargets,
    StepState,
    Tally,
)
from deformctl.sim.step.contact import _choose_rows, _moved_less, _row_targets
from deformctl.sim.step.dense import _solve_dense
from deformctl.sim.step.forces import _predict, _step_impulse
from deformctl.sim.step.laws import coulomb_bound
from deformctl.sim.step.maxwell import _arm_predict, _arm_update
from deformctl.sim.step.record import N_REC, _record_step, _slipped_past

#: rounding allowed for each carried product ``A dv`` in :func:`integrate_iterative`, relative to
#: ``max_i sum_j |A_ij| * |dv|_2`` (the scale of a product's rounding: a row of about 80 entries
#: rounds to 80 ulp of ``|A| |dv|``, about 1e-14)
PRODUCT_ROUNDING = 1e-14


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
    gram: FloatArray,
    same_free: bool,
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
    into an array, costs several times more). ``gram`` ``[4]`` carries ``y_1.y_1, y_1.y_2,
    y_2.y_2`` of the last call and whether they are set (its last entry nonzero): when the free
    DOFs are the same as then (``same_free``), the history has moved by one image since, so
    they are this call's ``y_2.y_2, y_2.y_3, y_3.y_3``, the same sums in the same order, and
    the pass forms only the entries of the new image.

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
    carried = same_free and gram[3] != 0.0
    gram[3] = 0.0
    if k >= 2:
        y1 = y_hist[order[0]]
        y2 = y_hist[order[1]]
        y3 = y_hist[order[2]] if k >= 3 else y_hist[order[1]]
        w3 = 1.0 if k >= 3 else 0.0
        g11 = g12 = g13 = g22 = g23 = g33 = 0.0
        t1 = t2 = t3 = 0.0
        if k >= 3 and carried:
            g22 = gram[0]
            g23 = gram[1]
            g33 = gram[2]
            for i in range(n_dof):
                if fixed[i]:
                    continue
                a1 = y1[i]
                a2 = y2[i]
                a3 = y3[i]
                r = rhs[i]
                g11 += a1 * a1
                g12 += a1 * a2
                g13 += a1 * a3
                t1 += a1 * r
                t2 += a2 * r
                t3 += a3 * r
        else:
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
        gram[0] = g11
        gram[1] = g12
        gram[2] = g22
        gram[3] = 1.0
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
def integrate_iterative(
    body: Body,
    palms: Palms,
    contacts: Contacts,
    drive: Drive,
    solver: IterativeSolver,
    q: FloatArray,
    v: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """:func:`deformctl.sim.step.direct.integrate` with a multigrid-preconditioned CG instead of
    the factor.

    The contacts are solved as an active set of *fixed DOFs*: a unit row that is active (table
    contact, sticking palm friction, palm stop, sticking table friction) prescribes its DOF's new
    velocity exactly (``v = target``), the CG solves the free DOFs, and the row's impulse is the
    residual ``(A dv - b)`` at its DOF; a sliding friction row adds its bound as a known impulse.
    Two-DOF rows (palm planes) that are active are added by a Schur complement on CG-solved
    columns. The active set starts from last step's and is updated (release on a wrong-signed
    impulse, fix on a violated row, stick/slide on the friction bound and the sliding direction)
    until it is consistent, so the solution is the same complementarity solution as
    the direct solver's, up to the CG tolerance on the free DOFs; fixed rows hold exactly.

    Args (``solver``'s fields; the others as :func:`deformctl.sim.step.direct.integrate`'s):
        mg: the multigrid hierarchy of ``A`` (:class:`deformctl.sim.multigrid.Hierarchy`;
            level 0 is ``A`` itself, the first levels as lattice stencils).
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
    """
    base_x, particle_mass, dof_of = body.base_x, body.particle_mass, body.dof_of
    palm_x_dof, palm_z_dof = palms.x_dof, palms.z_dof
    row_dof, row_dof2, row_type, row_link = (
        contacts.row_dof, contacts.row_dof2, contacts.row_type, contacts.row_link
    )  # fmt: skip
    bottom_particles, bottom_row = contacts.bottom_particles, contacts.bottom_row
    mu, mu_table = contacts.mu, contacts.mu_table
    force_cmd, palm_vz, gravity_scale, gravity = (
        drive.force_cmd, drive.palm_vz, drive.gravity_scale, drive.gravity
    )  # fmt: skip
    dt, n_steps, bdf2, stop_slip, stop_from = (
        drive.dt, drive.n_steps, drive.bdf2, drive.stop_slip, drive.stop_from
    )  # fmt: skip
    mg = solver.mg
    h_n, h_row_off = mg.levels.n, mg.levels.row_off
    h_a_ptr, h_a_idx, h_a_val = mg.levels.a_ptr, mg.levels.a_idx, mg.levels.a_val
    st_shape, st_halo = mg.stencils.shape, mg.stencils.halo
    cg_tolerance, cg_max_iterations = solver.cg_tolerance, solver.cg_max_iterations
    warm_history, product_carry = solver.warm_history, solver.product_carry
    row_margin, predict_release, stats = solver.row_margin, solver.predict_release, solver.stats
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
    # the history of velocity changes and their images, one row more than kept: the step's dv
    # and adv are the spare row, which becomes the newest (no copy) as the oldest becomes spare
    dv_hist = np.zeros((warm_history + 1, n_dof))
    y_hist = np.zeros((warm_history + 1, n_dof))
    order = np.arange(warm_history)
    spare = warm_history
    n_hist = 0
    residual_in_work = False
    dv = dv_hist[spare]
    adv = y_hist[spare]  # A dv, carried as dv changes (CG's initial product)
    err_hist = np.zeros(warm_history + 1)  # 2-norm error bound of each kept image
    gram = np.zeros(4)  # the warm start's Gram entries carried to the next step
    gram_version = -1  # the free DOFs' version (fixed_version) at the last warm start
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
    motion = StepState(q, v, vnew, v_last, lam, x)
    tally = Tally(rec, slip, palm_z_acc, total_mass, com_z0)
    targets = RowTargets(gap, target, bound)
    for step in range(n_steps):
        f_now = force_cmd[step + 1]
        _predict(q, v, q_last, v_last, q_prev, v_prev, bdf2, palm_x_dof)
        _arm_predict(body.arm, bdf2)
        _step_impulse(
            body, palms, q, v, gravity * gravity_scale[step + 1], f_now, h_step, x, vel, fp, fq
        )
        # targets of the rows (as in the direct solver); only the chosen rows while the lattice has
        # moved less than 0.4 row_margin since they were chosen
        if choose:
            if chosen:
                chosen = _moved_less(x, x_ref, q, palm_x_dof, palm_ref, 0.4 * row_margin)
            if not chosen:
                rows, n_rows, bottoms, n_bottoms = all_rows, nr, all_bottoms, all_bottoms.shape[0]
        friction_bound = coulomb_bound(mu, f_now) * h_step
        _row_targets(
            contacts, palms, rows, n_rows, bottoms, n_bottoms, x, q, palm_vz[step + 1],
            friction_bound, h_step, targets,
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
        same_free = fixed_version == gram_version
        adv_err = _warm_start(
            dv_hist, y_hist, order, n_hist, fixed, fq, dv, adv, err_hist, gram, same_free
        )
        gram_version = fixed_version
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
                    bound[r] = coulomb_bound(mu_table, lam[row_link[r]])
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
            its = pcg(mg, fixed, bt, dv, cg_tolerance, cg_max_iterations, work, adv, adv_known)
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
                    its_y = pcg(mg, fixed, unit, y, 1e-8, cg_max_iterations, work, adv, False)
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
            if not residual_in_work:
                product(mg, work, dv, adv)
                stats[4] += 1
                adv_err = 0.0
            # one pass: A dv without a product when CG's residual is at hand (b - r on the free
            # DOFs, r: CG's final residual, first in its scratch; b + the row impulse on the fixed
            # ones, from _fixed_residual; exact up to the error of CG's initial product and
            # rounding), |dv|^2, the new velocities, the fastest DOF (for the record) and the
            # lattice's fastest x and z DOFs
            dv2 = 0.0
            speed = 0.0
            speed_x = 0.0
            speed_z = 0.0
            for i in range(n_dof):
                if residual_in_work:
                    adv[i] = bt[i] + react[i] if fixed[i] else bt[i] - work[i]
                dv2 += dv[i] * dv[i]
                vnew[i] = v[i] + dv[i]
                if abs(vnew[i]) > speed:
                    speed = abs(vnew[i])
                a = dof_axis[i]
                if a == 0:
                    speed_x = max(speed_x, abs(vnew[i]))
                elif a == 2:
                    speed_z = max(speed_z, abs(vnew[i]))
            adv_err += PRODUCT_ROUNDING * a_abs * np.sqrt(dv2)
            adv_known = True
            if chosen and max(2.0 * speed_x, speed_z) * h_step >= 0.4 * row_margin:
                # fast enough that a left-out row could close its gap: all rows, chosen again
                # next step
                rows, n_rows, bottoms, n_bottoms = all_rows, nr, all_bottoms, all_bottoms.shape[0]
                _row_targets(
                    contacts, palms, rows, n_rows, bottoms, n_bottoms, x, q, palm_vz[step + 1],
                    friction_bound, h_step, targets,
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
        # the history: this step's dv and its image A dv (the spare row) become the newest, the
        # oldest row the next step's spare
        oldest = order[warm_history - 1]
        for a in range(warm_history - 1, 0, -1):
            order[a] = order[a - 1]
        order[0] = spare
        err_hist[spare] = adv_err
        spare = oldest
        dv = dv_hist[spare]
        adv = y_hist[spare]
        n_hist = min(n_hist + 1, warm_history)
        _arm_update(body, x, vnew, h_step)  # before x moves to the new positions
        _record_step(
            step, tally, motion, body, palms, contacts, drive, rows, n_rows, f_now, h_step, speed
        )
        if _slipped_past(rec, step, stop_slip, stop_from):
            return q, v, rec[: step + 1]
    return q, v, rec
