"""The step kernels' arguments, bundled by what they describe (numba takes named tuples of arrays
and scalars as arguments, so no kernel needs more than a dozen).

:class:`Body`, :class:`Palms` and :class:`Contacts` describe a model (built once by
:func:`deformctl.sim.engine.build_model`), :class:`Drive` one run of it, :class:`DirectSolver` and
:class:`IterativeSolver` the solver of its implicit step. :class:`StepState`, :class:`Tally` and
:class:`RowTargets` are made inside the kernels, from their scratch arrays.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from deformctl.arraytypes import FloatArray, IntArray
from deformctl.sim.multigrid import MultigridArrays
from deformctl.sim.solver import LDLFactor


class HuntCrossley(NamedTuple):
    """The Hunt–Crossley law of a stiffening lattice (``exponent == 1``: none, the elements are
    the linear Kelvin elements of :class:`Body`; see :mod:`deformctl.sim.hunt_crossley`).

    Attributes:
        exponent: n; an element's spring force is ``rest_force + power |s|ⁿ sign(s)`` for a
            stretch ``s`` from the start shape.
        power: each element's ``p_e``, N/mⁿ, ``[m]`` (``[0]`` when linear).
        rest_force: each element's tension in the start shape, N, ``[m]``: the weight's
            pre-stress of an object resting on the table, zeros otherwise (``[0]`` when linear).
        retardation: s; each element's Hunt–Crossley damper is ``retardation p_e |s|ⁿ / L0``
            N·s/m, with ``|s|`` capped at ``cap_strain L0``.
        cap_strain: the strain above which the dampers stop growing (the implicit step's
            damping matrix is built at the reference strain; above twice it the step would be
            unstable).
        width_reference_m, width_cap_m: the width damper of :class:`Palms` is scaled by
            ``(min(d, width_cap_m) / width_reference_m)ⁿ`` for a palm compression ``d``.
    """

    exponent: float
    power: FloatArray
    retardation: float
    cap_strain: float
    width_reference_m: float
    width_cap_m: float
    rest_force: FloatArray


class Maxwell(NamedTuple):
    """The Maxwell arms of a standard linear solid (Zener): a spring in series with a dashpot
    beside each element's spring and damper (``stiffness`` of length 0: none, the Kelvin or
    Hunt–Crossley elements alone; see :mod:`deformctl.sim.sls`).

    Each arm's force ``σ`` (a tension, N) follows ``σ̇ = k_a ṡ − σ/τ`` for the element's stretch
    rate ``ṡ``; the step integrates it with the positions' own scheme
    (:mod:`deformctl.sim.step.maxwell`).

    Attributes:
        stiffness: each arm's spring ``k_a``, N/m, ``[m]`` (``[0]``: no arms).
        relaxation: τ, s, the arms' relaxation time (``inf``: the arm is a spring).
        force: each arm's force at the start of the step, N, ``[m]`` (updated in place; zero:
            the relaxed object a run starts from).
        previous: the arms' force a step earlier, N, ``[m]`` (BDF2's history).
        base: the arms' force at the step's base state, N, ``[m]`` (the BDF2 predictor).
    """

    stiffness: FloatArray
    relaxation: float
    force: FloatArray
    previous: FloatArray
    base: FloatArray


class ElementRuns(NamedTuple):
    """The linear Kelvin elements as runs of one index offset, and the scratch of their forces
    (:mod:`deformctl.sim.step.runs`).

    Attributes:
        seg: per run its first particle, its length (slots), its particle index offset, its
            first slot and whether it is uniform (1: its elements share one rest direction and
            length, read from its first slot), ``[runs, 5]``.
        k, rest, n0: per slot the element's stiffness N/m, rest length m, and rest direction
            ``[3, slots]``; zero in the gaps.
        real: whether a slot holds an element (false in the gaps), ``[slots]``.
        xs, vs, out: scratch, the positions, velocities and forces by coordinate, ``[3, n]``.
        f: scratch, one run's forces, ``[3, longest run]``.
    """

    seg: IntArray
    k: FloatArray
    rest: FloatArray
    n0: FloatArray
    real: NDArray[np.bool_]
    xs: FloatArray
    vs: FloatArray
    f: FloatArray
    out: FloatArray


class Body(NamedTuple):
    """The lattice and its Kelvin elements.

    Attributes:
        base_x: reference positions, m, ``[n, 3]``; positions are ``base_x + q[dof_of]``.
        dof_of: DOF of each particle coordinate, ``[3 n]``.
        particle_mass: mass of each particle, kg, ``[n]``.
        edges, rest, n0, k: elements ``[m, 2]``, rest length m, rest direction ``[m, 3]``,
            stiffness N/m, ``[m]``.
        retardation: s; each element's damping is ``retardation k`` N·s/m.
        nonlinear: exact spring geometry (else linear small-strain forces).
        law: the Hunt–Crossley springs and dampers (``law.exponent == 1``: the Kelvin elements
            above); with them ``k`` is the tangent the implicit step was built with and
            ``retardation k`` a linear damper added to each element.
        arm: the Maxwell arms of a standard linear solid (none: ``arm.stiffness`` is empty).
        runs: the same elements laid out for the linear Kelvin loop (:class:`ElementRuns`).
    """

    base_x: FloatArray
    dof_of: IntArray
    particle_mass: FloatArray
    edges: IntArray
    rest: FloatArray
    n0: FloatArray
    k: FloatArray
    retardation: float
    nonlinear: bool
    law: HuntCrossley
    arm: Maxwell
    runs: ElementRuns


class Palms(NamedTuple):
    """The two palms (``-1`` DOFs: no palms, a free object).

    Attributes:
        x_dof, z_dof: DOFs of the two palms / face patches, ``[2]``.
        x0: palm x positions when the palm DOFs are zero, m, ``[2]``.
        stop: innermost x of the left and right palm, m, ``[2]``.
        mass: mass of each palm, kg (moves with its x DOF; the felt force excludes it).
        width_damping: the damper across the gripped width, between the palm x DOFs, N·s/m.
    """

    x_dof: IntArray
    z_dof: IntArray
    x0: FloatArray
    stop: FloatArray
    mass: float
    width_damping: float


class Contacts(NamedTuple):
    """The constraint rows (see :mod:`deformctl.sim.step`).

    Attributes:
        row_dof, row_dof2, row_type, row_link, row_particle: ``J_r = e[row_dof] - e[row_dof2]``
            (no second term when ``row_dof2 < 0``); ``row_link`` is the normal row of a
            table-friction row, ``row_particle`` the particle of a palm-plane row.
        bottom_particles, bottom_row: particles in table contact and their table normal row.
        mu, mu_table: palm and table friction coefficients.
    """

    row_dof: IntArray
    row_dof2: IntArray
    row_type: IntArray
    row_link: IntArray
    row_particle: IntArray
    bottom_particles: IntArray
    bottom_row: IntArray
    mu: float
    mu_table: float


class Drive(NamedTuple):
    """One run: the commands at each step end, the step and when to stop.

    Attributes:
        force_cmd: commanded normal force per palm, N, ``[n_steps + 1]``.
        palm_vz: palm vertical velocity, m/s, ``[n_steps + 1]``.
        gravity_scale: the fraction of ``gravity`` acting, ``[n_steps + 1]``.
        gravity: gravitational acceleration along -z, m/s².
        dt: time step, s. n_steps: steps to run. bdf2: BDF2 (else backward Euler).
        stop_slip, stop_from: stop once the mean palm slip since step ``stop_from - 1`` exceeds
            ``stop_slip`` m (never when negative).
        frame_every: copy the particle positions into ``frames`` after every ``frame_every``-th
            step (steps 0, k, 2k, ...; 0: never, the default, which costs one comparison per
            step and changes no simulated number).
        frames: the copies, m, ``[n_frames, n, 3]`` (``[0, n, 3]`` when ``frame_every`` is 0).
    """

    force_cmd: FloatArray
    palm_vz: FloatArray
    gravity_scale: FloatArray
    gravity: float
    dt: float
    n_steps: int
    bdf2: bool
    stop_slip: float
    stop_from: int
    frame_every: int
    frames: NDArray[np.float64]


class DirectSolver(NamedTuple):
    """The direct solver: the sparse factor of ``A`` and the contact columns.

    Attributes:
        factor: ``L D L^T`` of the implicit system matrix ``A``.
        cols: precomputed contact columns ``A^-1 e_d``, ``[n_cols, n_dof]``.
        col_of_dof: the column of each DOF (``-1``: solved for when its row first becomes live).
        pgs_iterations, pgs_tolerance: projected Gauss–Seidel limits (tolerance in m/s).
    """

    factor: LDLFactor
    cols: FloatArray
    col_of_dof: IntArray
    pgs_iterations: int
    pgs_tolerance: float


class IterativeSolver(NamedTuple):
    """The iterative solver (see :func:`deformctl.sim.step.iterative.integrate_iterative`).

    Attributes:
        mg: the multigrid hierarchy of ``A`` (:meth:`deformctl.sim.multigrid.Hierarchy.
            kernel_args`).
        cg_tolerance: CG stops when the free DOFs' residual 2-norm is at most this, N·s.
        cg_max_iterations: CG iteration limit per solve.
        warm_history: velocity changes kept for the warm start.
        product_carry: the largest error bound (2-norm, N·s) of a carried product ``A dv``.
        row_margin: gap, m, beyond which an inactive table or palm-plane row is left out.
        predict_release: release a table row whose extrapolated impulse is not positive.
        stats: counters, ``[6]`` (updated in place).
    """

    mg: MultigridArrays
    cg_tolerance: float
    cg_max_iterations: int
    warm_history: int
    product_carry: float
    row_margin: float
    predict_release: bool
    stats: IntArray


class StepState(NamedTuple):
    """The state a step updates in place: DOF displacements ``q`` and velocities ``v`` (the step's
    base state until recorded), the new velocities ``vnew``, the velocities at the start of the
    step ``v_last`` (with backward Euler only at the palm x DOFs, the record's only reader), the
    row impulses ``lam`` and the particle positions ``x`` ``[n, 3]``."""

    q: FloatArray
    v: FloatArray
    vnew: FloatArray
    v_last: FloatArray
    lam: FloatArray
    x: FloatArray


class Tally(NamedTuple):
    """What the record accumulates: the record matrix ``[n_steps, N_REC]``, the two palms' slip
    (m, ``[2]``), the palm height (m, ``[1]``), the total mass (kg) and the start height of the
    centre of mass (m)."""

    rec: FloatArray
    slip: FloatArray
    palm_z_acc: FloatArray
    total_mass: float
    com_z0: float


class RowTargets(NamedTuple):
    """Per row: the gap (m), the target velocity (m/s) and the palm friction bound (N·s)."""

    gap: FloatArray
    target: FloatArray
    bound: FloatArray
