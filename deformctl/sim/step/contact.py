"""The contact rows' gaps and targets, and the rows a step visits (shared by both solvers)."""

from __future__ import annotations

import numpy as np
from numba import njit

from deformctl.arraytypes import BoolArray, FloatArray, IntArray
from deformctl.sim.step.bundles import Contacts, Palms, RowTargets


@njit(cache=True)
def _row_targets(
    contacts: Contacts,
    palms: Palms,
    rows: IntArray,
    n_rows: int,
    bottoms: IntArray,
    n_bottoms: int,
    x: FloatArray,
    q: FloatArray,
    palm_vz_now: float,
    friction_bound: float,
    h_step: float,
    out: RowTargets,
) -> None:
    """Gap (m) and target velocity (m/s) of rows ``rows[:n_rows]``, and the palm friction rows'
    bound ``friction_bound`` (N·s), into ``out``. A table row's gap is the lowest height of its
    particles ``bottom_particles[bottoms[:n_bottoms]]`` (``bottom_row``: the row of each)."""
    bottom_particles, bottom_row = contacts.bottom_particles, contacts.bottom_row
    row_type, row_particle = contacts.row_type, contacts.row_particle
    palm_x_dof, palm_x0, palm_stop = palms.x_dof, palms.x0, palms.stop
    gap, target, bound = out
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
    """The rows :func:`deformctl.sim.step.iterative.integrate_iterative`'s loops visit until the
    lattice moves: all but the ``cullable`` ones (table rows off the palm patches, palm-plane rows)
    that are inactive with a gap of at least ``row_margin`` (m). Also returns the bottom particles
    of the kept table rows, and records the positions ``x`` and palm x displacements they were
    chosen at (``x_ref``, ``palm_ref``, for :func:`_moved_less`).

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
