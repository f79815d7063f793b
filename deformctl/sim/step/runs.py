"""The linear Kelvin elements as runs of one index offset, so that their forces are computed in
vector instructions (:func:`_element_rhs_runs`; the layout: :func:`element_runs`).

The lattice's elements come family by family (:func:`deformctl.sim.lattice.build_lattice`):
within a family the second particle is the first plus a constant offset and the first increases.
A *run* is such a family laid over every particle index from its first element's to its last's,
so it reads the positions and velocities as contiguous slices; the slots between its elements
(a lattice row's end) are *gaps*, whose force is exactly zero. A family's elements share one
rest direction and one rest length bit for bit (the lattice forms them from the offset, not from
rounded positions), so such a *uniform* run reads them once instead of slot by slot (24 of
the 41 bytes a slot streams; about a fifth of the pass at 16^3).

The forces are the same numbers as the element-by-element loop's, in the same order: each
element's arithmetic is unchanged (no reassociation, no fused multiply-add), and each particle
receives its elements' forces in the element order. Within a run with a positive offset the
element that ends at particle ``p`` comes before the one that starts there, so the run
subtracts from its second particles first and then adds to its first ones (the other way round
for a negative offset); the runs are applied in element order, and a gap adds a zero, which
changes no sum (an accumulator that starts at +0 is never -0).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from deformctl.arraytypes import BoolArray, FloatArray, IntArray
from deformctl.sim.step.bundles import ElementRuns


def element_runs(
    edges: IntArray, rest: FloatArray, direction: FloatArray, stiffness: FloatArray
) -> ElementRuns:
    """The runs of the elements ``edges`` ``[m, 2]`` (rest length m, rest direction ``[m, 3]``,
    stiffness N/m): a new run wherever the offset changes or the first particle does not
    increase, so any element list is laid out exactly (a lattice's has one run per family).
    A run whose elements share one rest direction and one rest length (a lattice's family) is
    marked *uniform*: its loop reads them as scalars instead of streaming them slot by slot.
    Its scratch is empty: :func:`with_scratch` gives a run its own."""
    m = edges.shape[0]
    i = edges[:, 0].astype(np.int64)
    offset = edges[:, 1].astype(np.int64) - i
    new = np.ones(m, dtype=bool)
    if m > 1:
        new[1:] = (offset[1:] != offset[:-1]) | (i[1:] <= i[:-1])
    starts = np.flatnonzero(new)
    ends = np.append(starts[1:], m)
    first = i[starts]
    length = i[ends - 1] - first + 1
    slot0 = np.concatenate([[0], np.cumsum(length)[:-1]]).astype(np.int64)
    uniform = np.zeros(starts.size, dtype=np.int64)
    for r, (a, b) in enumerate(zip(starts, ends, strict=True)):
        same_dir = (direction[a:b] == direction[a]).all()
        uniform[r] = int(same_dir and (rest[a:b] == rest[a]).all())
    seg = np.stack([first, length, offset[starts], slot0, uniform], axis=1).astype(np.int64)
    slots = int(length.sum())
    run_of = np.repeat(np.arange(starts.size), ends - starts)
    slot = slot0[run_of] + (i - first[run_of])
    k = np.zeros(slots)
    rest_s = np.zeros(slots)
    n0 = np.zeros((3, slots))
    real = np.zeros(slots, dtype=bool)
    k[slot] = stiffness
    rest_s[slot] = rest
    n0[:, slot] = direction.T
    real[slot] = True
    return ElementRuns(seg, k, rest_s, n0, real, *_scratch(0, 0))


def _scratch(n: int, longest: int) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    return np.zeros((3, n)), np.zeros((3, n)), np.zeros((3, longest)), np.zeros((3, n))


def with_scratch(runs: ElementRuns, n_particles: int) -> ElementRuns:
    """``runs`` with fresh scratch for ``n_particles`` particles (one run's, like its arms)."""
    longest = int(runs.seg[:, 1].max()) if runs.seg.shape[0] else 0
    xs, vs, f, out = _scratch(n_particles, longest)
    return runs._replace(xs=xs, vs=vs, f=f, out=out)


Rows3 = tuple[FloatArray, FloatArray, FloatArray]


@njit(cache=True, inline="always", error_model="numpy")
def _rows(a: FloatArray, lo: int, hi: int) -> Rows3:
    """The three rows of ``a`` ``[3, n]`` over columns ``lo:hi``, as contiguous 1-d slices (the
    loops over them are vectorised; a 2-d column slice is not contiguous)."""
    return a[0, lo:hi], a[1, lo:hi], a[2, lo:hi]


@njit(cache=True, inline="always", error_model="numpy")
def _run_forces(
    length: int,
    xi: Rows3,
    xj: Rows3,
    vi: Rows3,
    vj: Rows3,
    n0: Rows3,
    rest: FloatArray,
    k: FloatArray,
    real: BoolArray,
    scalars: tuple[float, float, bool],
    f: Rows3,
) -> None:
    """The forces of one run's slots into ``f`` (0 in its gaps), from its first and second
    particles' positions ``xi``, ``xj`` and velocities ``vi``, ``vj``, as
    :func:`deformctl.sim.step.forces._element_rhs` forms them (``scalars``: the retardation,
    the implicit step and whether the springs are exact)."""
    xi0, xi1, xi2 = xi
    xj0, xj1, xj2 = xj
    vi0, vi1, vi2 = vi
    vj0, vj1, vj2 = vj
    a0, a1, a2 = n0
    f0, f1, f2 = f
    retardation, h, nonlinear = scalars
    if nonlinear:
        for t in range(length):
            dx = xj0[t] - xi0[t]
            dy = xj1[t] - xi1[t]
            dz = xj2[t] - xi2[t]
            dvx = vj0[t] - vi0[t]
            dvy = vj1[t] - vi1[t]
            dvz = vj2[t] - vi2[t]
            ax = a0[t]
            ay = a1[t]
            az = a2[t]
            length_e = np.sqrt(dx * dx + dy * dy + dz * dz)
            inv = 1.0 / length_e
            nx = dx * inv
            ny = dy * inv
            nz = dz * inv
            ke = k[t]
            fe = ke * (length_e - rest[t]) + (ke * retardation) * (dvx * nx + dvy * ny + dvz * nz)
            g = (ke * h) * (dvx * ax + dvy * ay + dvz * az)
            keep = real[t]
            f0[t] = fe * nx + g * ax if keep else 0.0
            f1[t] = fe * ny + g * ay if keep else 0.0
            f2[t] = fe * nz + g * az if keep else 0.0
    else:
        for t in range(length):
            dx = xj0[t] - xi0[t]
            dy = xj1[t] - xi1[t]
            dz = xj2[t] - xi2[t]
            dvx = vj0[t] - vi0[t]
            dvy = vj1[t] - vi1[t]
            dvz = vj2[t] - vi2[t]
            ax = a0[t]
            ay = a1[t]
            az = a2[t]
            ke = k[t]
            stretch = dx * ax + dy * ay + dz * az - rest[t]
            fe = ke * stretch + (ke * retardation) * (dvx * ax + dvy * ay + dvz * az)
            g = (ke * h) * (dvx * ax + dvy * ay + dvz * az)
            keep = real[t]
            f0[t] = fe * ax + g * ax if keep else 0.0
            f1[t] = fe * ay + g * ay if keep else 0.0
            f2[t] = fe * az + g * az if keep else 0.0


@njit(cache=True, inline="always", error_model="numpy")
def _uniform_run_forces(
    length: int,
    xi: Rows3,
    xj: Rows3,
    vi: Rows3,
    vj: Rows3,
    n0: tuple[float, float, float],
    rest: float,
    k: FloatArray,
    real: BoolArray,
    scalars: tuple[float, float, bool],
    f: Rows3,
) -> None:
    """:func:`_run_forces` for a uniform run: one rest direction ``n0`` and rest length
    ``rest`` for all its slots (the same arithmetic, so the same bits)."""
    xi0, xi1, xi2 = xi
    xj0, xj1, xj2 = xj
    vi0, vi1, vi2 = vi
    vj0, vj1, vj2 = vj
    ax, ay, az = n0
    f0, f1, f2 = f
    retardation, h, nonlinear = scalars
    if nonlinear:
        for t in range(length):
            dx = xj0[t] - xi0[t]
            dy = xj1[t] - xi1[t]
            dz = xj2[t] - xi2[t]
            dvx = vj0[t] - vi0[t]
            dvy = vj1[t] - vi1[t]
            dvz = vj2[t] - vi2[t]
            length_e = np.sqrt(dx * dx + dy * dy + dz * dz)
            inv = 1.0 / length_e
            nx = dx * inv
            ny = dy * inv
            nz = dz * inv
            ke = k[t]
            fe = ke * (length_e - rest) + (ke * retardation) * (dvx * nx + dvy * ny + dvz * nz)
            g = (ke * h) * (dvx * ax + dvy * ay + dvz * az)
            keep = real[t]
            f0[t] = fe * nx + g * ax if keep else 0.0
            f1[t] = fe * ny + g * ay if keep else 0.0
            f2[t] = fe * nz + g * az if keep else 0.0
    else:
        for t in range(length):
            dx = xj0[t] - xi0[t]
            dy = xj1[t] - xi1[t]
            dz = xj2[t] - xi2[t]
            dvx = vj0[t] - vi0[t]
            dvy = vj1[t] - vi1[t]
            dvz = vj2[t] - vi2[t]
            ke = k[t]
            stretch = dx * ax + dy * ay + dz * az - rest
            fe = ke * stretch + (ke * retardation) * (dvx * ax + dvy * ay + dvz * az)
            g = (ke * h) * (dvx * ax + dvy * ay + dvz * az)
            keep = real[t]
            f0[t] = fe * ax + g * ax if keep else 0.0
            f1[t] = fe * ay + g * ay if keep else 0.0
            f2[t] = fe * az + g * az if keep else 0.0


@njit(cache=True, inline="always", error_model="numpy")
def _add_run(f: Rows3, length: int, sign: float, out: Rows3) -> None:
    """``out += sign f``, row by row."""
    for a in range(3):
        fa = f[a]
        oa = out[a]
        if sign > 0.0:
            for t in range(length):
                oa[t] += fa[t]
        else:
            for t in range(length):
                oa[t] -= fa[t]


@njit(cache=True, error_model="numpy")
def _element_rhs_runs(runs: ElementRuns, retardation: float, nonlinear: bool, h: float) -> None:
    """The linear Kelvin elements' forces minus ``h K v`` into ``runs.out`` ``[3, n]`` (set here)
    from the positions and velocities in ``runs.xs``, ``runs.vs`` ``[3, n]``: the sums of
    :func:`deformctl.sim.step.forces._element_rhs`, bit for bit (see the module docs)."""
    seg, xs, vs, out = runs.seg, runs.xs, runs.vs, runs.out
    out[:, :] = 0.0
    scalars = (retardation, h, nonlinear)
    for s in range(seg.shape[0]):
        i0 = seg[s, 0]
        length = seg[s, 1]
        j0 = i0 + seg[s, 2]
        s0 = seg[s, 3]
        i1 = i0 + length
        j1 = j0 + length
        s1 = s0 + length
        fs = _rows(runs.f, 0, length)
        if seg[s, 4] == 1:  # one rest direction and length: read once, not slot by slot
            _uniform_run_forces(
                length,
                _rows(xs, i0, i1),
                _rows(xs, j0, j1),
                _rows(vs, i0, i1),
                _rows(vs, j0, j1),
                (runs.n0[0, s0], runs.n0[1, s0], runs.n0[2, s0]),
                runs.rest[s0],
                runs.k[s0:s1],
                runs.real[s0:s1],
                scalars,
                fs,
            )
        else:
            _run_forces(
                length,
                _rows(xs, i0, i1),
                _rows(xs, j0, j1),
                _rows(vs, i0, i1),
                _rows(vs, j0, j1),
                _rows(runs.n0, s0, s1),
                runs.rest[s0:s1],
                runs.k[s0:s1],
                runs.real[s0:s1],
                scalars,
                fs,
            )
        if j0 > i0:  # an element ending at p comes before the one starting there
            _add_run(fs, length, -1.0, _rows(out, j0, j1))
            _add_run(fs, length, 1.0, _rows(out, i0, i1))
        else:
            _add_run(fs, length, 1.0, _rows(out, i0, i1))
            _add_run(fs, length, -1.0, _rows(out, j0, j1))
