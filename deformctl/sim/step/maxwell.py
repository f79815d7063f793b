"""The Maxwell arms of a standard linear solid in the implicit step (the law once, for both step
loops; the calibration is :mod:`deformctl.sim.sls`).

Each element ``e`` carries, beside its spring and damper, an arm force ``σ`` (a tension, N) with
``σ̇ = k_a ṡ − σ/τ`` (a spring ``k_a`` in series with a dashpot ``k_a τ``; ``ṡ``: the element's
stretch rate). The step integrates it with the positions' own scheme: from the base state
``σ_b`` (``σ_n`` for backward Euler, the BDF2 predictor ``(4 σ_n − σ_{n−1}) / 3`` otherwise, as
:func:`deformctl.sim.step.forces._predict` forms ``q`` and ``v``) and the implicit step ``h``::

    σ_{n+1} = (σ_b + h k_a ṡ_{n+1}) / (1 + h/τ)

that is, the arm acts in the step as the constant force ``σ_b / (1 + h/τ)`` plus a damper
``c_a = h k_a / (1 + h/τ)`` on the new stretch rate. The implicit matrix holds that damper
(:func:`deformctl.sim.sls.implicit_damping`, assembled with the elements' dampers), the
right-hand side its force at the base velocities (:func:`_arm_rhs`), so with the small-strain
springs the arms are integrated exactly implicitly, stable for any ``k_a``, τ and step (the
recurrence's factor ``1/(1 + h/τ)`` is below 1; ``τ = inf`` makes the arm a spring). After the
step :func:`_arm_update` forms ``σ_{n+1}`` from the step's final velocities (contacts included).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from deformctl.arraytypes import FloatArray
from deformctl.sim.step.bundles import Body, Maxwell


@njit(cache=True)
def _arm_predict(arm: Maxwell, bdf2: bool) -> None:
    """Shift the arms' history (as ``_predict`` shifts ``q, v``) and form the step's base force."""
    force, previous, base = arm.force, arm.previous, arm.base
    for e in range(arm.stiffness.shape[0]):
        now = force[e]
        before = previous[e]
        previous[e] = now
        base[e] = (4.0 * now - before) / 3.0 if bdf2 else now


@njit(cache=True)
def _direction(body: Body, x: FloatArray, e: int) -> tuple[float, float, float]:
    """The element's unit direction: its rest direction (small-strain springs) or along its
    current length (exact springs), as the element forces use it."""
    if not body.nonlinear:
        return body.n0[e, 0], body.n0[e, 1], body.n0[e, 2]
    i = body.edges[e, 0]
    j = body.edges[e, 1]
    dx = x[j, 0] - x[i, 0]
    dy = x[j, 1] - x[i, 1]
    dz = x[j, 2] - x[i, 2]
    inv = 1.0 / np.sqrt(dx * dx + dy * dy + dz * dz)
    return dx * inv, dy * inv, dz * inv


@njit(cache=True)
def _arm_rhs(body: Body, x: FloatArray, vel: FloatArray, h: float, out: FloatArray) -> None:
    """Add the arms' forces in the step, ``σ_b / (1 + h/τ) + c_a ṡ`` at the base positions
    ``x`` and velocities ``vel`` (``[n, 3]``), to ``out`` ``[n, 3]`` (the implicit matrix holds
    ``c_a``)."""
    arm = body.arm
    edges, stiffness, base = body.edges, arm.stiffness, arm.base
    keep = 1.0 / (1.0 + h / arm.relaxation)
    for e in range(stiffness.shape[0]):
        i = edges[e, 0]
        j = edges[e, 1]
        nx, ny, nz = _direction(body, x, e)
        rate = (vel[j, 0] - vel[i, 0]) * nx + (vel[j, 1] - vel[i, 1]) * ny
        rate += (vel[j, 2] - vel[i, 2]) * nz
        f = keep * (base[e] + h * stiffness[e] * rate)
        out[i, 0] += f * nx
        out[i, 1] += f * ny
        out[i, 2] += f * nz
        out[j, 0] -= f * nx
        out[j, 1] -= f * ny
        out[j, 2] -= f * nz


@njit(cache=True)
def _arm_update(body: Body, x: FloatArray, vnew: FloatArray, h: float) -> None:
    """The arms' force at the end of the step, from the step's base positions ``x`` ``[n, 3]``
    and its final DOF velocities ``vnew`` ``[n_dof]``: ``σ_{n+1} = (σ_b + h k_a ṡ_{n+1}) /
    (1 + h/τ)`` into ``arm.force``."""
    arm = body.arm
    edges, dof_of, stiffness, base = body.edges, body.dof_of, arm.stiffness, arm.base
    keep = 1.0 / (1.0 + h / arm.relaxation)
    for e in range(stiffness.shape[0]):
        i = edges[e, 0]
        j = edges[e, 1]
        nx, ny, nz = _direction(body, x, e)
        rate = (vnew[dof_of[3 * j]] - vnew[dof_of[3 * i]]) * nx
        rate += (vnew[dof_of[3 * j + 1]] - vnew[dof_of[3 * i + 1]]) * ny
        rate += (vnew[dof_of[3 * j + 2]] - vnew[dof_of[3 * i + 2]]) * nz
        arm.force[e] = keep * (base[e] + h * stiffness[e] * rate)
