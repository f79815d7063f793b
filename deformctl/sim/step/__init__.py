"""The implicit time step in numba: Kelvin element forces, contacts, the record, and the step loops.

Everything in the step loop runs inside one ``@njit(cache=True)`` function (:func:`integrate`,
or :func:`integrate_iterative` for the iterative solver),
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

Modules, by responsibility: :mod:`.bundles` (the kernels' arguments as named tuples: the model's
body, palms and contact rows, the run's drive, the solver), :mod:`.forces` (element forces and
the step's right-hand side, the BDF2 predictor), :mod:`.contact` (row gaps and targets, the rows
a step visits), :mod:`.delassus` and :mod:`.dense` (the direct solver's contact problem),
:mod:`.record` (the record matrix, columns ``REC_*``), :mod:`.runs` (the Kelvin elements laid out
for vector instructions), :mod:`.direct` (:func:`integrate`) and
:mod:`.iterative` (:func:`integrate_iterative`).
"""

from __future__ import annotations

from deformctl.sim.step.bundles import (
    Body,
    Contacts,
    DirectSolver,
    Drive,
    ElementRuns,
    HuntCrossley,
    IterativeSolver,
    Maxwell,
    Palms,
)
from deformctl.sim.step.direct import integrate
from deformctl.sim.step.forces import spring_forces, spring_forces_numpy
from deformctl.sim.step.iterative import integrate_iterative
from deformctl.sim.step.record import (
    N_REC,
    REC_COM_X,
    REC_COM_Y,
    REC_COM_Z,
    REC_FRICTION_L,
    REC_FRICTION_R,
    REC_MAX_SPEED,
    REC_MIN_Z,
    REC_NORMAL_L,
    REC_NORMAL_R,
    REC_PALM_XL,
    REC_PALM_XR,
    REC_PALM_Z,
    REC_PENETRATION,
    REC_SLIP_L,
    REC_SLIP_R,
    REC_TABLE_N,
    REC_TIME,
)
from deformctl.sim.step.runs import element_runs, with_scratch

__all__ = [
    "N_REC",
    "REC_COM_X",
    "REC_COM_Y",
    "REC_COM_Z",
    "REC_FRICTION_L",
    "REC_FRICTION_R",
    "REC_MAX_SPEED",
    "REC_MIN_Z",
    "REC_NORMAL_L",
    "REC_NORMAL_R",
    "REC_PALM_XL",
    "REC_PALM_XR",
    "REC_PALM_Z",
    "REC_PENETRATION",
    "REC_SLIP_L",
    "REC_SLIP_R",
    "REC_TABLE_N",
    "REC_TIME",
    "Body",
    "Contacts",
    "DirectSolver",
    "Drive",
    "ElementRuns",
    "HuntCrossley",
    "IterativeSolver",
    "Maxwell",
    "Palms",
    "element_runs",
    "integrate",
    "integrate_iterative",
    "spring_forces",
    "spring_forces_numpy",
    "with_scratch",
]
