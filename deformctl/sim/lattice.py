"""Particle lattice of a box, its Kelvin elements and generalised DOFs, and its stiffness matrix.

The box ``[-sx/2, sx/2] x [-sy/2, sy/2] x [0, sz]`` (m) is sampled by ``n_x x n_y x n_z`` particles
with ``n_a = max(2, round(s_a / alpha) + 1)``. The spacing along each axis is ``s_a / (n_a - 1)``
so the lattice spans the box exactly; it equals alpha when alpha divides the size (a deliberate,
documented deviation from a strictly cubic lattice: the box keeps its catalog size for any alpha).

Kelvin elements join axial neighbours (spacing 1 along one axis) and face-diagonal neighbours. Each
element gets the *cell-shared* unit stiffness ``w_e``: an axial element inside the body is shared
by four lattice cells, one on an edge of the box by one; a face diagonal by two cells or one.
Assembling cell by cell this way gives a uniform material, so boundary layers are not stiffer
than the interior. The per-element stiffness is ``k_e = kappa * w_e`` with one scale ``kappa``
(N/m) calibrated so that the lattice's squeeze stiffness between two rigid palms equals the
object's D exactly, whatever alpha: see
:func:`deformctl.sim.statics.unit_squeeze_stiffness_n_per_m`. Dampers are
``c_e = k_e * lambda / D`` (damping matrix proportional to the stiffness matrix), which makes the
lattice an exact Kelvin–Voigt body in the quasi-static limit (the engine can move part of the
squeeze damping onto a damper across the gripped width, see
:attr:`deformctl.sim.engine.SimSettings.shear_damping_ratio`).

Palm surface layers (``palm_surface=True``)
    By default the two x faces are ordinary particle layers at the lattice spacing. With
    ``palm_surface`` the x faces are the palm contact *surfaces*: the engine gives them no mass,
    and the interior layers sit at the centres of ``n_x - 2`` equal slabs, so the first one is
    half a slab from each palm. Each interior layer then carries exactly its slab's mass (the
    midpoint rule), no mass rides rigidly with the palms, and the weight reaches the grip only
    through the material, as in a continuum. The half slabs at the palms get element weights
    scaled with their geometry, ``w_e`` times the cell volume over the element length squared
    (relative to a full cell): an x element of a half slab is twice as stiff, a y or z element
    half as stiff. Measured (10 cm-class cubes, hanging-mode frequency with the faces held):
    within 1.5 % from 5 to 13 particles per side, where equal masses on every layer drift by
    12 % (the face layers' extra mass rides with the palms).

Shapes: ``positions_m [n, 3]``, ``edges [m, 2]`` (int64), ``rest_length_m [m]``,
``direction [m, 3]`` (unit rest directions i->j), ``unit_stiffness [m]``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse
from numpy.typing import NDArray

from deformctl.arraytypes import FloatArray, IntArray
from deformctl.reprs import short_repr
from deformctl.sim.solver import LDLFactor, dof_order, ldl_factor, nested_dissection_order

_AXIAL_OFFSETS = ((1, 0, 0), (0, 1, 0), (0, 0, 1))
_DIAGONAL_OFFSETS = ((1, 1, 0), (1, -1, 0), (1, 0, 1), (1, 0, -1), (0, 1, 1), (0, 1, -1))


@dataclass(frozen=True)
class Lattice:
    """Rest geometry and unit element pattern of a box lattice.

    Attributes:
        shape: particles per axis (n_x, n_y, n_z).
        spacing_m: lattice spacing per axis, m, ``[3]``.
        positions_m: rest positions, m, ``[n, 3]``; bottom layer at z = 0.
        grid_index: integer lattice index of each particle, ``[n, 3]``.
        edges: particle pairs of the Kelvin elements, ``[m, 2]``.
        rest_length_m: rest length of each element, m, ``[m]``.
        direction: unit rest direction from ``edges[:, 0]`` to ``edges[:, 1]``, ``[m, 3]``.
        unit_stiffness: cell-shared stiffness weight of each element, ``[m]`` (dimensionless).
    """

    __repr__ = short_repr

    shape: tuple[int, int, int]
    spacing_m: FloatArray
    positions_m: FloatArray
    grid_index: IntArray
    edges: IntArray
    rest_length_m: FloatArray
    direction: FloatArray
    unit_stiffness: FloatArray

    @property
    def n_particles(self) -> int:
        """Number of particles n."""
        return int(self.positions_m.shape[0])

    def face_mask(self, side: int) -> NDArray[np.bool_]:
        """Particles on the palm face at x-min (``side=0``) or x-max (``side=1``), ``[n]``."""
        target = 0 if side == 0 else self.shape[0] - 1
        return np.asarray(self.grid_index[:, 0] == target)

    def bottom_mask(self) -> NDArray[np.bool_]:
        """Particles of the bottom layer (z = 0 at rest), ``[n]``."""
        return np.asarray(self.grid_index[:, 2] == 0)


def particles_per_axis(size_m: tuple[float, float, float], alpha_m: float) -> tuple[int, int, int]:
    """Particles along each axis for spacing ``alpha_m``: ``max(2, round(s / alpha) + 1)`` (at
    most 10¹⁸ + 1: an absurd spacing's lattice is refused by the memory budget, not an overflow)."""
    n = [max(2, round(min(s / alpha_m, 1e18)) + 1) for s in size_m]
    return (n[0], n[1], n[2])


def build_lattice(
    size_m: tuple[float, float, float], alpha_m: float, *, palm_surface: bool = False
) -> Lattice:
    """Sample the box of ``size_m`` (x, y, z) with spacing about ``alpha_m`` (see module docs).

    Args:
        palm_surface: the x faces are palm surfaces with the interior layers at slab centres
            (needs at least 3 particles along x; with 2 it has no effect).
    """
    shape = particles_per_axis(size_m, alpha_m)
    nx, ny, nz = shape
    spacing = np.array([size_m[a] / (shape[a] - 1) for a in range(3)])
    ix, iy, iz = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    grid = np.stack([ix.ravel(), iy.ravel(), iz.ravel()], axis=1).astype(np.int64)
    origin = np.array([-size_m[0] / 2.0, -size_m[1] / 2.0, 0.0])
    positions = origin + grid * spacing
    half = palm_surface and nx >= 3
    slab = size_m[0] / (nx - 2) if half else spacing[0]
    if half:
        layer_x = np.clip((np.arange(nx) - 0.5) * slab, 0.0, size_m[0])
        positions[:, 0] = origin[0] + layer_x[grid[:, 0]]
    index = np.arange(nx * ny * nz).reshape(shape)

    def cell_factor(cell_x: IntArray, off: tuple[int, int, int]) -> FloatArray:
        """Weight factor of an element in the x slab ``cell_x`` (1 in a full slab)."""
        f = np.where((cell_x == 0) | (cell_x == nx - 2), 0.5, 1.0) if half else np.ones(cell_x.size)
        if off[0] != 0 and (off[1] != 0 or off[2] != 0):
            other = spacing[1] if off[1] != 0 else spacing[2]
            return np.asarray(f * (slab**2 + other**2) / (f * f * slab**2 + other**2))
        if off[0] != 0:
            return np.asarray(1.0 / f)
        return np.asarray(f)

    edge_list: list[IntArray] = []
    weight_list: list[FloatArray] = []
    for offsets, share in ((_AXIAL_OFFSETS, 4.0), (_DIAGONAL_OFFSETS, 2.0)):
        for off in offsets:
            lo = [max(0, -o) for o in off]
            hi = [shape[a] - max(0, off[a]) for a in range(3)]
            if any(hi[a] <= lo[a] for a in range(3)):
                continue
            src = index[lo[0] : hi[0], lo[1] : hi[1], lo[2] : hi[2]]
            dst = index[
                lo[0] + off[0] : hi[0] + off[0],
                lo[1] + off[1] : hi[1] + off[1],
                lo[2] + off[2] : hi[2] + off[2],
            ]
            a_src = grid[src.ravel()]
            # number of lattice cells containing the element: along every axis the element does
            # not span, the cell may lie on either side when that side exists.
            cells = np.ones(src.size)
            for a in (1, 2):
                if off[a] == 0:
                    below = a_src[:, a] >= 1
                    above = a_src[:, a] <= shape[a] - 2
                    cells *= below.astype(float) + above.astype(float)
            # along x the two candidate slabs may differ (half slabs at palm surfaces)
            i = a_src[:, 0]
            if off[0] != 0:
                cells *= cell_factor(i, off)
            else:
                below_x = np.where(i >= 1, cell_factor(np.maximum(i - 1, 0), off), 0.0)
                above_x = np.where(i <= shape[0] - 2, cell_factor(i, off), 0.0)
                cells *= below_x + above_x
            edge_list.append(np.stack([src.ravel(), dst.ravel()], axis=1))
            weight_list.append(cells / share)
    edges = np.concatenate(edge_list).astype(np.int64)
    weights = np.concatenate(weight_list)
    # each element's rest vector is its lattice offset times the spacing (x: between its layers),
    # not the difference of two rounded positions: one family's elements share it bit for bit
    # (the step reads a family's rest direction and length once: deformctl.sim.step.runs)
    offset = grid[edges[:, 1]] - grid[edges[:, 0]]
    delta = offset * spacing
    if half:
        delta[:, 0] = layer_x[grid[edges[:, 1], 0]] - layer_x[grid[edges[:, 0], 0]]
    rest = np.linalg.norm(delta, axis=1)
    return Lattice(
        shape=shape,
        spacing_m=spacing,
        positions_m=positions,
        grid_index=grid,
        edges=edges,
        rest_length_m=rest,
        direction=delta / rest[:, None],
        unit_stiffness=weights,
    )


def palm_dof_map(lattice: Lattice, gripped: bool) -> tuple[IntArray, int, IntArray, IntArray]:
    """Map every particle coordinate to a generalised degree of freedom.

    Free object: one DOF per coordinate. Gripped object: the face layer touching each palm shares
    one x DOF (the palm's position; the palm face is rigid and flat) and one z DOF (the face patch
    height, which moves with the palm while friction sticks and slides when it slips); the face
    particles keep their own y.

    Returns:
        dof_of: DOF index of each coordinate, ``[3 n]`` (coordinate ``3 p + axis``).
        n_dof: number of DOFs.
        palm_x_dof: x DOF of the left and right palm, ``[2]`` (``-1`` when free).
        palm_z_dof: z DOF of the left and right face patch, ``[2]`` (``-1`` when free).
    """
    return shape_dof_map(lattice.shape, gripped)


def bottom_z_dofs(lattice: Lattice, dof_of: IntArray) -> IntArray:
    """The z DOFs of the bottom layer (the particles the table holds), ``[k]``."""
    return np.asarray(dof_of[3 * np.flatnonzero(lattice.bottom_mask()) + 2])


def table_weight_problem(
    lattice: Lattice, particle_weight_n: FloatArray | float
) -> tuple[IntArray, int, IntArray, FloatArray]:
    """The free object resting on a frictionless table under gravity, as a static problem:
    ``(dof_of, n_dof, fixed, load)`` with the bottom layer's z DOFs ``fixed`` and each
    particle's weight, N, as the load on its z DOF (:func:`deformctl.sim.statics.
    resting_positions_m`, :func:`deformctl.sim.hunt_crossley.weight_prestress_n`)."""
    n = lattice.n_particles
    dof_of, n_dof, _, _ = palm_dof_map(lattice, gripped=False)
    load = np.zeros(n_dof)
    load[dof_of[3 * np.arange(n) + 2]] = -np.broadcast_to(particle_weight_n, (n,))
    return dof_of, n_dof, bottom_z_dofs(lattice, dof_of), load


def shape_dof_map(
    shape: tuple[int, int, int], gripped: bool
) -> tuple[IntArray, int, IntArray, IntArray]:
    """:func:`palm_dof_map` of a lattice of ``shape`` particles (C-order particle numbering)."""
    n = shape[0] * shape[1] * shape[2]
    ix = np.arange(n) // (shape[1] * shape[2])
    dof_of = np.full(3 * n, -1, dtype=np.int64)
    faces = [ix == 0, ix == shape[0] - 1] if gripped else []
    on_face = np.zeros(n, dtype=bool)
    for mask in faces:
        on_face |= mask
    counter = 0
    for p in range(n):
        for a in range(3):
            if on_face[p] and a != 1:
                continue
            dof_of[3 * p + a] = counter
            counter += 1
    palm_x = np.array([-1, -1], dtype=np.int64)
    palm_z = np.array([-1, -1], dtype=np.int64)
    for side, mask in enumerate(faces):
        idx = np.flatnonzero(mask)
        palm_x[side] = counter
        dof_of[3 * idx + 0] = counter
        palm_z[side] = counter + 1
        dof_of[3 * idx + 2] = counter + 1
        counter += 2
    return dof_of, counter, palm_x, palm_z


def reduced_stiffness(
    lattice: Lattice, stiffness: FloatArray, dof_of: IntArray, n_dof: int
) -> scipy.sparse.csr_matrix:
    """Tangent matrix at rest ``P^T K P`` in generalised coordinates, sparse ``[n_dof, n_dof]``.

    ``K = sum_e k_e (e_i - e_j)(e_i - e_j)^T (x) n_e n_e^T`` (assembled COO -> CSR). With element
    stiffness (N/m) it is the stiffness matrix; with element dampers (N·s/m), the damping matrix.

    Args:
        stiffness: element coefficient, ``[m]``.
    """
    e = lattice.edges
    d = lattice.direction
    block = stiffness[:, None, None] * d[:, :, None] * d[:, None, :]  # [m, 3, 3]
    rows: list[IntArray] = []
    cols: list[IntArray] = []
    vals: list[FloatArray] = []
    nonzero = block.ravel() != 0.0  # axis-aligned directions give exact zeros
    flat = block.ravel()[nonzero]
    for a_end, a_sign in ((0, 1.0), (1, -1.0)):
        r = dof_of[3 * e[:, a_end, None] + np.arange(3)]  # [m, 3]
        for b_end, b_sign in ((0, 1.0), (1, -1.0)):
            c = dof_of[3 * e[:, b_end, None] + np.arange(3)]
            rows.append(np.broadcast_to(r[:, :, None], block.shape).ravel()[nonzero])
            cols.append(np.broadcast_to(c[:, None, :], block.shape).ravel()[nonzero])
            vals.append(a_sign * b_sign * flat)
    k = scipy.sparse.coo_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n_dof, n_dof)
    ).tocsr()
    k.sum_duplicates()
    return k


def lattice_factor(
    lattice: Lattice,
    a: scipy.sparse.spmatrix,
    dof_of: IntArray,
    n_dof: int,
    last: IntArray | None = None,
    keep: IntArray | None = None,
) -> LDLFactor:
    """Sparse ``L D L^T`` of an SPD lattice matrix in nested-dissection order (:mod:`.solver`).

    Args:
        a: the matrix on the DOFs ``keep`` (default: all ``n_dof``).
        last: DOFs numbered last (the palm DOFs).
        keep: the DOFs of ``a`` (a principal submatrix of the lattice's DOFs), increasing.
    """
    last_dofs = np.zeros(0, dtype=np.int64) if last is None else np.asarray(last, dtype=np.int64)
    last_dofs = last_dofs[last_dofs >= 0]
    perm = dof_order(nested_dissection_order(lattice.shape), dof_of, n_dof, last_dofs)
    if keep is not None:
        local = np.full(n_dof, -1, dtype=np.int64)
        local[keep] = np.arange(keep.size)
        perm = local[perm]
        perm = perm[perm >= 0]
    return ldl_factor(a, perm)
