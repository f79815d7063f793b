"""The step's forces: the Kelvin elements (or the Hunt–Crossley ones of a stiffening material;
and a standard linear solid's Maxwell arms, :mod:`.maxwell`), gravity and the palms' drive, as
the implicit step's right-hand side, and the BDF2 predictor.

:func:`_step_impulse` branches once per step, on ``body.law.exponent``, to the linear Kelvin
elements or to the Hunt–Crossley ones (:func:`_element_rhs_hc`). The Kelvin elements run by
index-offset runs (:func:`deformctl.sim.step.runs._element_rhs_runs`, in vector instructions);
:func:`_element_rhs` is the same sums element by element, the reference they are tested against.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from deformctl.arraytypes import FloatArray, IntArray
from deformctl.sim.step.bundles import Body, Palms
from deformctl.sim.step.laws import hunt_crossley_damping, hunt_crossley_spring
from deformctl.sim.step.maxwell import _arm_rhs
from deformctl.sim.step.runs import _element_rhs_runs


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
def _element_rhs(body: Body, x: FloatArray, vel: FloatArray, h: float, out: FloatArray) -> None:
    """Element forces minus ``h K v`` (tangent at rest), accumulated into ``out`` ``[n, 3]``: the
    element-by-element form of what the step computes by runs (:mod:`deformctl.sim.step.runs`).

    The dampers are ``c = retardation k`` (:func:`deformctl.sim.engine.element_constants`), so
    the loop reads one constant per element and forms ``c`` and ``h k`` from it (the same
    products as the arrays would hold, so the same bits; 56 instead of 72 bytes streamed per
    element)."""
    edges, rest, n0, k = body.edges, body.rest, body.n0, body.k
    retardation, nonlinear = body.retardation, body.nonlinear
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
def _element_rhs_hc(body: Body, x: FloatArray, vel: FloatArray, h: float, out: FloatArray) -> None:
    """:func:`_element_rhs` for Hunt–Crossley elements (:mod:`deformctl.sim.hunt_crossley`).

    For a stretch ``s`` (compression negative) from the start shape and stretch rate ``ṡ`` an
    element pulls its ends together with ``f0 + p |s|ⁿ sign(s) + (c_hc + retardation k) ṡ``
    (``f0``: ``law.rest_force``, the weight's pre-stress of a resting object), where
    ``c_hc = law.retardation p min(|s|, cap_strain L0)ⁿ / L0``; minus ``h k v`` along the rest
    direction, ``k`` the tangent the implicit matrix holds.
    """
    edges, rest, n0, k = body.edges, body.rest, body.n0, body.k
    retardation, nonlinear = body.retardation, body.nonlinear
    law = body.law
    n_exp, power, hc_ret, cap = law.exponent, law.power, law.retardation, law.cap_strain
    rest_force = law.rest_force
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
        spring = hunt_crossley_spring(power[e], stretch, n_exp) + rest_force[e]
        damper = hunt_crossley_damping(power[e], stretch, n_exp, hc_ret, cap * rest[e], rest[e])
        damper += k[e] * retardation
        f = spring + damper * (dvx * nx + dvy * ny + dvz * nz)
        g = (k[e] * h) * (dvx * ax + dvy * ay + dvz * az)
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
def _width_scale(body: Body, palm_x_dof: IntArray, q: FloatArray) -> float:
    """The factor on the width damper at the palm compression ``d`` of ``q``: 1 for a Kelvin
    body, ``(min(d, cap) / d_ref)ⁿ`` for a Hunt–Crossley one (0 while the palms are apart)."""
    law = body.law
    if law.exponent == 1.0:
        return 1.0
    d = q[palm_x_dof[0]] - q[palm_x_dof[1]]
    if d <= 0.0:
        return 0.0
    return float((min(d, law.width_cap_m) / law.width_reference_m) ** law.exponent)


@njit(cache=True)
def _step_impulse(
    body: Body,
    palms: Palms,
    q: FloatArray,
    v: FloatArray,
    gravity: float,
    f_now: float,
    dt: float,
    x: FloatArray,
    vel: FloatArray,
    fp: FloatArray,
    fq: FloatArray,
) -> None:
    """The step's right-hand side ``fq = h (f(x, v) + f_ext - h K v)`` in DOFs (also fills the
    particle positions ``x``; ``vel`` and ``fp`` are scratch, the particle velocities and forces
    where the Hunt–Crossley elements or the Maxwell arms need them).

    ``q, v`` are the step's base state (the BDF2 predictor, or the last state for backward Euler)
    and ``dt`` the implicit step ``h`` (``2 dt / 3`` for BDF2); ``particle_mass`` is ``[n]`` and
    ``gravity`` the acceleration acting now. ``width_damping`` (N·s/m) is the damper across the
    gripped width, between the two palm x DOFs.
    """
    base_x, dof_of, particle_mass = body.base_x, body.dof_of, body.particle_mass
    palm_x_dof, width_damping = palms.x_dof, palms.width_damping
    n = base_x.shape[0]
    kelvin = body.law.exponent == 1.0
    arms = body.arm.stiffness.shape[0] > 0  # a standard linear solid's Maxwell arms
    fq[:] = 0.0
    if kelvin:
        # the Kelvin elements by runs (the same sums as _element_rhs, vectorised), into
        # runs.out by coordinate
        runs = body.runs
        xs, vs, out = runs.xs, runs.vs, runs.out
        for p in range(n):
            for a in range(3):
                d = np.uint64(dof_of[3 * p + a])  # unsigned: no wraparound in the gathers
                xv = base_x[p, a] + q[d]
                x[p, a] = xv
                xs[a, p] = xv
                vs[a, p] = v[d]
        _element_rhs_runs(runs, body.retardation, body.nonlinear, dt)
        if not arms:  # straight from runs.out, in the same order as from fp below
            for p in range(n):
                fz = out[2, p] - particle_mass[p] * gravity
                fq[np.uint64(dof_of[3 * p])] += out[0, p]
                fq[np.uint64(dof_of[3 * p + 1])] += out[1, p]
                fq[np.uint64(dof_of[3 * p + 2])] += fz
        else:
            for p in range(n):
                for a in range(3):
                    vel[p, a] = vs[a, p]
                    fp[p, a] = out[a, p]
    else:
        for p in range(n):
            for a in range(3):
                d = dof_of[3 * p + a]
                x[p, a] = base_x[p, a] + q[d]
                vel[p, a] = v[d]
                fp[p, a] = 0.0
        _element_rhs_hc(body, x, vel, dt, fp)
    if arms or not kelvin:
        if arms:
            _arm_rhs(body, x, vel, dt, fp)
        for p in range(n):
            fp[p, 2] -= particle_mass[p] * gravity
            for a in range(3):
                fq[dof_of[3 * p + a]] += fp[p, a]
    if palm_x_dof[0] >= 0:
        fw = width_damping * (v[palm_x_dof[1]] - v[palm_x_dof[0]])
        if not kelvin:
            fw *= _width_scale(body, palm_x_dof, q)
        fq[palm_x_dof[0]] += f_now + fw
        fq[palm_x_dof[1]] -= f_now + fw
    for i in range(fq.shape[0]):
        fq[i] *= dt


@njit(cache=True)
def _predict(
    q: FloatArray,
    v: FloatArray,
    q_last: FloatArray,
    v_last: FloatArray,
    q_prev: FloatArray,
    v_prev: FloatArray,
    bdf2: bool,
    read: IntArray,
) -> None:
    """Shift the history and turn ``q, v`` into the step's base state.

    On entry ``q, v`` are the state at the start of the step and ``q_last, v_last`` the one a step
    earlier; on exit ``q_prev, v_prev`` hold that earlier state, ``q_last, v_last`` the start of
    this step, and ``q, v`` the base of the implicit update: unchanged for backward Euler, the
    BDF2 predictor ``(4 x_n - x_{n-1}) / 3`` otherwise (a run starts from rest, so the first
    step's history is the start state itself). Backward Euler reads no history, so there only
    ``v_last`` at the DOFs ``read`` (the palm x DOFs, whose start velocities the record reads;
    negative entries none) is kept, and nothing else is copied.
    """
    if not bdf2:
        for a in range(read.shape[0]):
            if read[a] >= 0:
                v_last[read[a]] = v[read[a]]
        return
    for i in range(q.shape[0]):  # one pass
        qp = q_last[i]
        vp = v_last[i]
        qn = q[i]
        vn = v[i]
        q_prev[i] = qp
        v_prev[i] = vp
        q_last[i] = qn
        v_last[i] = vn
        q[i] = (4.0 * qn - qp) / 3.0
        v[i] = (4.0 * vn - vp) / 3.0
