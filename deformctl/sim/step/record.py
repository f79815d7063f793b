"""The record of every step: palm and object motion, slip, contact forces (columns ``REC_*``)."""

from __future__ import annotations

import numpy as np
from numba import njit

from deformctl.arraytypes import FloatArray, IntArray
from deformctl.sim.step.bundles import Body, Contacts, Drive, Palms, StepState, Tally

# columns of the record matrix returned by the step loops
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
def _record_step(
    step: int,
    tally: Tally,
    state: StepState,
    body: Body,
    palms: Palms,
    contacts: Contacts,
    drive: Drive,
    rows: IntArray,
    n_rows: int,
    f_now: float,
    h: float,
    max_speed: float,
) -> None:
    """Record step ``step`` and advance ``v <- vnew``, ``q <- q + h v`` (palm quantities before
    the position update use the new velocities); copy the positions into ``drive.frames`` on
    every ``drive.frame_every``-th step (a scene frame; nothing simulated reads them).

    ``q, v`` hold the step's base state (for BDF2 the predictor, see
    :func:`deformctl.sim.step.direct.integrate`), ``h`` is
    the implicit step (impulses are ``h`` times the force) and ``v_last`` the velocity at the
    start of the step (for the palm's acceleration). The centre of mass is mass-weighted. The
    contact forces sum the impulses of rows ``rows[:n_rows]`` (every row with an impulse).
    ``max_speed`` is the largest ``|vnew|`` (m/s) when the caller has it at hand, else negative
    (then it is found here).
    """
    rec, slip, palm_z_acc, total_mass, com_z0 = tally
    q, v, vnew, v_last, lam, x = state
    base_x, dof_of, particle_mass = body.base_x, body.dof_of, body.particle_mass
    palm_x_dof, palm_z_dof, palm_x0, palm_mass = palms.x_dof, palms.z_dof, palms.x0, palms.mass
    row_type, row_dof = contacts.row_type, contacts.row_dof
    palm_vz, dt = drive.palm_vz, drive.dt
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
    if max_speed >= 0.0:
        for i in range(n_dof):
            v[i] = vnew[i]
            q[i] += h * v[i]
    else:
        max_speed = 0.0
        for i in range(n_dof):
            v[i] = vnew[i]
            q[i] += h * v[i]
            if abs(v[i]) > max_speed:
                max_speed = abs(v[i])
    # the centre of mass in scalars (an array's entries would be stored and reloaded each time)
    com_x = 0.0
    com_y = 0.0
    com_z = 0.0
    min_z = 1e300
    penetration = 0.0
    xl = palm_x0[0] + q[palm_x_dof[0]] if gripped else -np.inf
    xr = palm_x0[1] + q[palm_x_dof[1]] if gripped else np.inf
    for p in range(n):
        m = particle_mass[p]
        px = base_x[p, 0] + q[np.uint64(dof_of[3 * p])]  # unsigned: no wraparound
        py = base_x[p, 1] + q[np.uint64(dof_of[3 * p + 1])]
        pz = base_x[p, 2] + q[np.uint64(dof_of[3 * p + 2])]
        x[p, 0] = px
        x[p, 1] = py
        x[p, 2] = pz
        com_x += m * px
        com_y += m * py
        com_z += m * pz
        if pz < min_z:
            min_z = pz
        pen = max(xl - px, px - xr)
        if pen > penetration:
            penetration = pen
    if gripped:
        rec[step, REC_PALM_XL] = xl
        rec[step, REC_PALM_XR] = xr
    rec[step, REC_TIME] = (step + 1) * dt
    rec[step, REC_PALM_Z] = palm_z_acc[0]
    rec[step, REC_COM_Z] = com_z / total_mass - com_z0
    rec[step, REC_COM_X] = com_x / total_mass
    rec[step, REC_COM_Y] = com_y / total_mass
    rec[step, REC_SLIP_L] = slip[0]
    rec[step, REC_SLIP_R] = slip[1]
    rec[step, REC_FRICTION_L] = fric_l
    rec[step, REC_FRICTION_R] = fric_r
    rec[step, REC_TABLE_N] = table_n
    rec[step, REC_MIN_Z] = min_z
    rec[step, REC_PENETRATION] = penetration
    rec[step, REC_MAX_SPEED] = max_speed
    every = drive.frame_every
    if every > 0 and step % every == 0:  # a scene frame: copy the positions, nothing else
        frames = drive.frames
        k = step // every
        for p in range(n):
            for a in range(3):
                frames[k, p, a] = x[p, a]
