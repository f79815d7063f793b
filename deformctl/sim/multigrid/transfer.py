"""The grid transfer between the two stencil levels, by the interpolation's axis factors on the
lattice coordinates (see :mod:`deformctl.sim.multigrid`).
"""

from __future__ import annotations

from numba import njit

from deformctl.arraytypes import BoolArray, FloatArray, IntArray


@njit(cache=True, inline="always")
def _coarse_point(i: int, n: int) -> tuple[int, float]:
    """Linear interpolation along one axis of ``n`` points from the coarse points (every second
    one and the last; axes of one or two points are kept): fine point ``i`` is ``(1 - w) c[j] +
    w c[j + 1]``; returns ``(j, w)``, ``w`` 0 or 0.5 (so a constant is interpolated exactly).
    The one home of the rule: :func:`_axis_interpolation` builds ``P``'s axis factors from it."""
    if n <= 2:
        return i, 0.0
    if i == n - 1:
        return (n - 1) // 2 + (n - 1) % 2, 0.0
    return i // 2, 0.5 if i % 2 else 0.0


@njit(cache=True)
def _grid_restrict(
    shape: IntArray,
    cshape: IntArray,
    dof_of: IntArray,
    rep: IntArray,
    cdof_of: IntArray,
    r: FloatArray,
    part: FloatArray,
    out: FloatArray,
) -> None:
    """``out = P^T r`` from the finest level to level 1, by the trilinear interpolation's three
    axis factors on the lattice coordinates instead of :func:`interpolation`'s compressed rows
    (the same sums in another order). ``shape``, ``dof_of``, ``rep``: the finest level's
    particles per axis, coordinate DOFs and DOF representatives; ``cshape``, ``cdof_of``: level
    1's; ``part``: scratch (:func:`stencil_scratch_offsets`).

    A DOF's residual enters at its representative coordinate only; a merged palm DOF's rows of
    ``P`` are equal at every coordinate of its face (the face layer interpolates from the
    coarse face, which is the coarse palm DOF), so that is ``P^T``; the coarse coordinates of a
    palm face add into its DOF."""
    nx, ny, nz = shape[0], shape[1], shape[2]
    cx, cy, cz = cshape[0], cshape[1], cshape[2]
    row = 3 * ny * nz
    zr = 3 * nz
    px = part[: cx * row]
    pxy = part[cx * row : cx * row + cx * cy * zr]
    px[:] = 0.0
    for i in range(nx):
        j, w = _coarse_point(i, nx)
        for k in range(row):
            c = i * row + k
            d = dof_of[c]
            if rep[d] != c:
                continue
            val = r[d]
            if w == 0.0:
                px[j * row + k] += val
            else:
                px[j * row + k] += (1.0 - w) * val
                px[(j + 1) * row + k] += w * val
    pxy[:] = 0.0
    for ix in range(cx):
        for iy in range(ny):
            j, w = _coarse_point(iy, ny)
            src = (ix * ny + iy) * zr
            da = (ix * cy + j) * zr
            if w == 0.0:
                for k in range(zr):
                    pxy[da + k] += px[src + k]
            else:
                db = da + zr
                for k in range(zr):
                    val = px[src + k]
                    pxy[da + k] += (1.0 - w) * val
                    pxy[db + k] += w * val
    out[:] = 0.0
    for ixy in range(cx * cy):
        src = ixy * zr
        dst = ixy * 3 * cz
        for iz in range(nz):
            j, w = _coarse_point(iz, nz)
            for a in range(3):
                val = pxy[src + 3 * iz + a]
                if w == 0.0:
                    out[cdof_of[dst + 3 * j + a]] += val
                else:
                    out[cdof_of[dst + 3 * j + a]] += (1.0 - w) * val
                    out[cdof_of[dst + 3 * (j + 1) + a]] += w * val


@njit(cache=True)
def _grid_prolong_add(
    shape: IntArray,
    cshape: IntArray,
    dof_of: IntArray,
    cdof_of: IntArray,
    fixed: BoolArray,
    xc: FloatArray,
    part: FloatArray,
    halo: int,
    xg: FloatArray,
) -> None:
    """``xg += P xc`` on the free DOFs of the finest level, written to every coordinate of each
    DOF (the sweep's coordinates, ``halo`` particles before the first): :func:`_grid_restrict`'s
    transpose, the three axis factors applied from level 1's DOFs ``xc``. A palm face's
    coordinates all receive its DOF's value (the weights are 0, 1/2 and 1, so the equal coarse
    values interpolate exactly)."""
    nx, ny, nz = shape[0], shape[1], shape[2]
    cx, cy, cz = cshape[0], cshape[1], cshape[2]
    row = 3 * ny * nz
    zr = 3 * nz
    px = part[: cx * row]
    pxy = part[cx * row : cx * row + cx * cy * zr]
    for ixy in range(cx * cy):
        src = ixy * 3 * cz
        dst = ixy * zr
        for iz in range(nz):
            j, w = _coarse_point(iz, nz)
            for a in range(3):
                val = xc[cdof_of[src + 3 * j + a]]
                if w != 0.0:
                    val = (1.0 - w) * val + w * xc[cdof_of[src + 3 * (j + 1) + a]]
                pxy[dst + 3 * iz + a] = val
    for ix in range(cx):
        for iy in range(ny):
            j, w = _coarse_point(iy, ny)
            dst = (ix * ny + iy) * zr
            sa = (ix * cy + j) * zr
            if w == 0.0:
                for k in range(zr):
                    px[dst + k] = pxy[sa + k]
            else:
                sb = sa + zr
                for k in range(zr):
                    px[dst + k] = (1.0 - w) * pxy[sa + k] + w * pxy[sb + k]
    base = 3 * halo
    for i in range(nx):
        j, w = _coarse_point(i, nx)
        for k in range(row):
            c = i * row + k
            if fixed[dof_of[c]]:
                continue
            if w == 0.0:
                xg[base + c] += px[j * row + k]
            else:
                xg[base + c] += (1.0 - w) * px[j * row + k] + w * px[(j + 1) * row + k]
