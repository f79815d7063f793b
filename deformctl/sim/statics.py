"""Static solves on the lattice: the squeeze-stiffness calibration and the rest shape.

Both are linear statics of the lattice's stiffness (:func:`deformctl.sim.lattice.
reduced_stiffness`) with some DOFs held: small lattices by a sparse factor
(:mod:`deformctl.sim.solver`), larger ones by the multigrid CG of the iterative step solver
(:mod:`deformctl.sim.multigrid`). They sit above the lattice, the stencil and the multigrid
levels, which know nothing of them.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse

from deformctl.arraytypes import FloatArray, IntArray
from deformctl.sim.hunt_crossley import weight_prestress_n
from deformctl.sim.lattice import (
    Lattice,
    lattice_factor,
    palm_dof_map,
    reduced_stiffness,
    shape_dof_map,
    table_weight_problem,
)
from deformctl.sim.multigrid import build_hierarchy, solve
from deformctl.sim.stencil import build_stencil
from deformctl.sim.step.bundles import HuntCrossley

#: calibration solves above this many DOFs use multigrid CG instead of a sparse factor
DIRECT_CALIBRATION_MAX_DOFS = 1000


def _regularised_solve(
    lattice: Lattice,
    element_coef: FloatArray,
    load: FloatArray,
    dof_of: IntArray,
    n_dof: int,
    fixed: IntArray,
    gripped: bool,
) -> FloatArray:
    """Solve ``K u = f`` with ``u = 0`` on the DOFs ``fixed``, for a self-equilibrated load; rigid
    modes are removed by ``eps I`` (unit masses). ``K`` is assembled from the elements'
    ``element_coef`` (:func:`reduced_stiffness`). Returns ``u [n_dof]``.

    Sparse ``L D L^T`` of the free DOFs' submatrix (nested dissection) up to
    :data:`DIRECT_CALIBRATION_MAX_DOFS`, multigrid-preconditioned CG to a relative residual of
    ``1e-13`` above (:mod:`deformctl.sim.multigrid`).
    """
    k = reduced_stiffness(lattice, element_coef, dof_of, n_dof)
    keep = np.setdiff1d(np.arange(n_dof), fixed)
    eps = 1e-10 * float(k.diagonal()[keep].sum()) / float(keep.size)
    u = np.zeros(n_dof)
    _, _, px, pz = shape_dof_map(lattice.shape, gripped)
    if n_dof <= DIRECT_CALIBRATION_MAX_DOFS:
        a = k[keep][:, keep] + eps * scipy.sparse.identity(keep.size, format="csr")
        last = np.concatenate([px, pz])
        factor = lattice_factor(lattice, a, dof_of, n_dof, last=last[last >= 0], keep=keep)
        u[keep] = factor.solve(load[keep])
        return u
    a = (k + eps * scipy.sparse.identity(n_dof, format="csr")).tocsr()
    mask = np.zeros(n_dof, dtype=bool)
    mask[fixed] = True
    rhs = np.where(mask, 0.0, load)
    stencil = build_stencil(
        lattice, element_coef, np.full(lattice.n_particles, eps), dof_of, n_dof, px, pz
    )
    hierarchy = build_hierarchy(lattice.shape, gripped, a, stencil=stencil)
    return solve(hierarchy, mask, rhs, rel_tol=1e-13)


def unit_squeeze_stiffness_n_per_m(lattice: Lattice) -> float:
    """Squeeze stiffness of the lattice with unit element scale (``k_e = w_e`` N/m).

    Same boundary conditions as the squeeze protocol: each face layer bonded to its rigid palm in
    x and z (friction sticking, palms fixed in z), free in y; equal and opposite palm forces.
    Returns force / change of the palm gap.
    """
    dof_of, n_dof, px, pz = palm_dof_map(lattice, gripped=True)
    load = np.zeros(n_dof)
    load[px[0]] = 1.0
    load[px[1]] = -1.0
    u = _regularised_solve(lattice, lattice.unit_stiffness, load, dof_of, n_dof, pz, gripped=True)
    closing = u[px[0]] - u[px[1]]
    return 1.0 / closing


def resting_positions_m(
    lattice: Lattice, stiffness: FloatArray, particle_weight_n: FloatArray | float
) -> FloatArray:
    """Linear static equilibrium of the object on a frictionless table under gravity, m, ``[n, 3]``.

    The bottom layer is held at z = 0; the rest of the lattice sags under its weight.
    """
    n = lattice.n_particles
    dof_of, n_dof, fixed, load = table_weight_problem(lattice, particle_weight_n)
    u = _regularised_solve(lattice, stiffness, load, dof_of, n_dof, fixed, gripped=False)
    return np.asarray(lattice.positions_m + u[dof_of].reshape(n, 3))


def resting_state(
    lattice: Lattice, stiffness: FloatArray, particle_weight_n: FloatArray, law: HuntCrossley
) -> tuple[FloatArray, HuntCrossley]:
    """The start of an object resting on the table under gravity: its positions, m, ``[n, 3]``,
    and its law. A Kelvin object sags to :func:`resting_positions_m`; a Hunt–Crossley one keeps
    its unloaded shape and carries its weight as the elements' pre-stress
    (:func:`deformctl.sim.hunt_crossley.weight_prestress_n`), so that its power law acts on the
    compression from the resting state, as a squeeze test measures it.
    """
    if law.exponent == 1.0:
        return resting_positions_m(lattice, stiffness, particle_weight_n), law
    weight = np.broadcast_to(particle_weight_n, (lattice.n_particles,)).astype(np.float64)
    prestress = weight_prestress_n(lattice, weight)
    return lattice.positions_m.copy(), law._replace(rest_force=prestress)
