"""The finest multigrid level as a lattice stencil (deformctl.sim.stencil).

Each kernel is checked against the compressed-row matrix it stands for and against a dense
block Gauss–Seidel in the documented order (the palm DOFs, then every particle's free
coordinates as one block), on gripped lattices (particle and surface palm layers, palm DOFs fixed
or free) and on a free one, with random fixed DOFs.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.sparse

from deformctl.sim.lattice import build_lattice, palm_dof_map, reduced_stiffness, shape_dof_map
from deformctl.sim.multigrid import build_hierarchy, interpolation, product, v_cycle
from deformctl.sim.multigrid.hierarchy import _scalar_interpolation
from deformctl.sim.stencil import (
    DIRECTIONS,
    UPPER_OFFSETS,
    Rows,
    Stencil,
    add_dofs,
    backward_sweep,
    build_block_stencil,
    build_stencil,
    direction_offsets,
    forward_sweep_from_zero,
    grid_matrix,
    residual_after_forward,
    stencil_product,
)
from deformctl.sim.stencil.sums import _offsets, _upper_offsets

CASES = [
    # (particles along x, gripped, palm surface layers, palm z DOFs fixed)
    (5, True, False, False),
    (6, True, True, True),
    (5, False, False, False),
    (7, True, False, True),
]


def _system(
    nx: int, gripped: bool, surface: bool, seed: int = 0
) -> tuple[scipy.sparse.csr_matrix, Stencil, np.ndarray]:
    """``A = R^T (M + K) R + E`` of a small box lattice, as compressed rows and as a stencil."""
    lat = build_lattice((0.1, 0.07, 0.05), 0.1 / (nx - 1), palm_surface=surface)
    dof_of, n_dof, px, pz = palm_dof_map(lat, gripped)
    rng = np.random.default_rng(seed)
    w = lat.unit_stiffness * rng.uniform(500.0, 1500.0, lat.edges.shape[0])
    masses = rng.uniform(0.005, 0.02, lat.n_particles)
    if surface:
        masses[lat.face_mask(0) | lat.face_mask(1)] = 0.0
    dof_mass = np.bincount(dof_of, weights=np.repeat(masses, 3), minlength=n_dof)
    a = reduced_stiffness(lat, w, dof_of, n_dof) + scipy.sparse.diags(dof_mass)
    if gripped:  # the palms' own terms: their mass and the damper across the width
        e = scipy.sparse.coo_matrix(
            ([0.3, -0.2, -0.2, 0.5], ([px[0], px[0], px[1], px[1]], [px[0], px[1], px[0], px[1]])),
            shape=(n_dof, n_dof),
        )
        a = a + e
    a = scipy.sparse.csr_matrix(a)
    a.sort_indices()
    return a, build_stencil(lat, w, masses, dof_of, n_dof, px, pz), pz


def _fixed(n_dof: int, pz: np.ndarray, fix_palm_z: bool, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    fixed = np.zeros(n_dof, dtype=bool)
    fixed[rng.choice(n_dof, n_dof // 8, replace=False)] = True
    if pz[0] >= 0:
        fixed[pz] = fix_palm_z
    return fixed


def _csr(a: scipy.sparse.csr_matrix) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return a.indptr.astype(np.int64), a.indices.astype(np.int32), a.data


def _dense_block_gs(
    a: np.ndarray, st: Stencil, fixed: np.ndarray, b: np.ndarray, x: np.ndarray, reverse: bool
) -> None:
    """Block Gauss–Seidel in the stencil's order (palm DOFs, then each particle's own free
    coordinates), or its exact reverse."""
    blocks = [[int(g)] for g in st.palm if not fixed[g]]
    for p in range(st.n_particles):
        own = [int(g) for g in st.dof_of[3 * p : 3 * p + 3] if g not in st.palm and not fixed[g]]
        if own:
            blocks.append(own)
    for blk in reversed(blocks) if reverse else blocks:
        rhs = b[blk] - a[blk] @ x + a[np.ix_(blk, blk)] @ x[blk]
        x[blk] = np.linalg.solve(a[np.ix_(blk, blk)], rhs)


def test_offsets_follow_the_directions() -> None:
    shape = (6, 5, 4)
    assert np.array_equal(_offsets(np.asarray(shape)), direction_offsets(shape))
    assert len(DIRECTIONS) == 9
    want = [dx * 5 * 4 + dy * 4 + dz for dx, dy, dz in UPPER_OFFSETS]
    assert np.array_equal(_upper_offsets(np.asarray(shape)), want)
    assert len(UPPER_OFFSETS) == 13
    assert min(want) > 0


def _level_one(
    a: scipy.sparse.csr_matrix, st: Stencil, gripped: bool
) -> tuple[scipy.sparse.csr_matrix, Stencil]:
    """The Galerkin matrix of level 1 (generalised DOFs) and its block stencil."""
    shape = (int(st.shape[0]), int(st.shape[1]), int(st.shape[2]))
    p, coarse, _ = interpolation(shape, gripped)
    a1 = scipy.sparse.csr_matrix(p.T @ a @ p)
    a1.sort_indices()
    p_grid = scipy.sparse.kron(_scalar_interpolation(shape), scipy.sparse.identity(3))
    g1 = p_grid.T @ grid_matrix(st) @ p_grid
    dof1, n1, px1, pz1 = shape_dof_map(coarse, gripped)
    return a1, build_block_stencil(g1, coarse, dof1, n1, px1, pz1)


@pytest.mark.parametrize(("nx", "gripped", "surface", "fix_palm_z"), CASES)
def test_stencils_stand_for_the_compressed_rows(
    nx: int, gripped: bool, surface: bool, fix_palm_z: bool
) -> None:
    """``R^T A_grid R`` is ``A`` but for the palm DOFs' own terms, on the finest level and on
    level 1 (its Galerkin matrix formed on coordinates); a block stencil gives back its matrix."""
    a, st, _ = _system(nx, gripped, surface)
    for level in range(2):
        if level == 1:
            a, st = _level_one(a, st, gripped)
        g = grid_matrix(st)
        assert abs(g - g.T).max() <= 1e-12 * abs(g).max()
        r = scipy.sparse.csr_matrix(
            (np.ones(st.dof_of.size), (np.arange(st.dof_of.size), st.dof_of)),
            shape=(st.dof_of.size, a.shape[0]),
        )
        diff = (r.T @ g @ r - a).tocoo()
        big = np.abs(diff.data) > 1e-12 * abs(a).max()
        on_palms = np.isin(diff.row[big], st.palm) & np.isin(diff.col[big], st.palm)
        assert np.all(on_palms)
        if level == 1:
            dof1, n1, px1, pz1 = shape_dof_map(tuple(int(v) for v in st.shape), gripped)
            again = build_block_stencil(g, tuple(int(v) for v in st.shape), dof1, n1, px1, pz1)
            assert abs(grid_matrix(again) - g).max() <= 1e-14 * abs(g).max()


@pytest.mark.parametrize(("nx", "gripped", "surface", "fix_palm_z"), CASES[:3])
def test_block_stencil_sweeps_are_exact_block_gauss_seidel(
    nx: int, gripped: bool, surface: bool, fix_palm_z: bool
) -> None:
    """Level 1's sweeps (no fixed DOFs there)."""
    a0, st0, _ = _system(nx + 4, gripped, surface)
    a, st = _level_one(a0, st0, gripped)
    n_dof = a.shape[0]
    none = np.zeros(n_dof, dtype=bool)
    b = np.random.default_rng(2).normal(size=n_dof)
    ptr, idx, val = _csr(a)
    dense = a.toarray()
    xg = np.zeros(st.grid_len)
    wk = np.zeros(st.grid_len)
    forward_sweep_from_zero(st, Rows(ptr, idx, val), none, b, xg)
    want = np.zeros(n_dof)
    _dense_block_gs(dense, st, none, b, want, reverse=False)
    np.testing.assert_allclose(xg[3 * st.halo + st.rep], want, rtol=0, atol=1e-12 * abs(want).max())
    r = np.empty(n_dof)
    residual_after_forward(st, Rows(ptr, idx, val), none, b, xg, wk, r)
    np.testing.assert_allclose(r, b - a @ want, rtol=0, atol=1e-12 * abs(b).max())
    out_x, out_ax = np.empty(n_dof), np.empty(n_dof)
    backward_sweep(st, Rows(ptr, idx, val), none, b, xg, wk, out_x, out_ax, True)
    _dense_block_gs(dense, st, none, b, want, reverse=True)
    np.testing.assert_allclose(out_x, want, rtol=0, atol=1e-12 * abs(want).max())
    np.testing.assert_allclose(out_ax, a @ out_x, rtol=0, atol=1e-12 * abs(out_ax).max())


@pytest.mark.parametrize(("nx", "gripped", "surface", "fix_palm_z"), CASES)
def test_sweeps_are_exact_block_gauss_seidel(
    nx: int, gripped: bool, surface: bool, fix_palm_z: bool
) -> None:
    a, st, pz = _system(nx, gripped, surface)
    n_dof = a.shape[0]
    fixed = _fixed(n_dof, pz, fix_palm_z, seed=nx)
    b = np.random.default_rng(1).normal(size=n_dof)
    ptr, idx, val = _csr(a)
    dense = a.toarray()
    xg = np.zeros(st.grid_len)
    axg = np.empty(st.grid_len)
    forward_sweep_from_zero(st, Rows(ptr, idx, val), fixed, b, xg)
    want = np.zeros(n_dof)
    _dense_block_gs(dense, st, fixed, b, want, reverse=False)
    x = xg[3 * st.halo + st.rep]
    np.testing.assert_allclose(np.where(fixed, 0.0, x), want, rtol=0, atol=1e-12 * abs(want).max())
    # every coordinate of a DOF (the palm-bound face coordinates) holds the DOF's value
    coords = xg[3 * st.halo : 3 * st.halo + 3 * st.n_particles]
    np.testing.assert_array_equal(coords, x[st.dof_of])
    # the residual right after the sweep (half a pass) is b - A x
    r = np.empty(n_dof)
    residual_after_forward(st, Rows(ptr, idx, val), fixed, b, xg, axg, r)
    np.testing.assert_allclose(
        r, np.where(fixed, 0.0, b - a @ want), rtol=0, atol=1e-12 * abs(b).max()
    )
    # the backward sweep is the exact reverse, and returns A x without a product
    out_x, out_ax = np.empty(n_dof), np.empty(n_dof)
    backward_sweep(st, Rows(ptr, idx, val), fixed, b, xg, axg, out_x, out_ax, True)
    _dense_block_gs(dense, st, fixed, b, want, reverse=True)
    np.testing.assert_allclose(out_x, want, rtol=0, atol=1e-12 * abs(want).max())
    ax = np.where(fixed, 0.0, a @ out_x)
    np.testing.assert_allclose(out_ax, ax, rtol=0, atol=1e-12 * abs(ax).max())
    assert np.all(out_x[fixed] == 0.0)


@pytest.mark.parametrize("levels", [2, 3])
@pytest.mark.parametrize(("nx", "gripped", "surface", "fix_palm_z"), CASES[:3])
def test_v_cycle_with_stencils_is_the_multigrid_cycle_and_symmetric(
    nx: int, gripped: bool, surface: bool, fix_palm_z: bool, levels: int
) -> None:
    """Block sweeps on the stencil levels (the finest, and level 1 when it is not the coarsest),
    Galerkin coarse corrections, exact coarsest solve: the V-cycle equals a dense emulation, and
    ``u . M^-1 v == v . M^-1 u`` (a valid CG preconditioner)."""
    a, st, pz = _system(nx + 4 * (levels - 2), gripped, surface)
    n_dof = a.shape[0]
    fixed = _fixed(n_dof, pz, fix_palm_z, seed=3)
    shape = (int(st.shape[0]), int(st.shape[1]), int(st.shape[2]))
    h = build_hierarchy(
        shape, gripped, a, max_coarse=n_dof // (3 if levels == 2 else 9), stencil=st
    )
    assert h.levels == levels
    assert len(h.stencils) == levels - 1
    tot = int(h.n.sum())

    fixed_all, cf = h.fixed_levels(fixed)

    def cycle(b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        z, az = np.empty(n_dof), np.empty(n_dof)
        v_cycle(
            h.kernel_args(), fixed_all, b, z, az, np.empty(tot), np.empty(tot), np.empty(tot),
            np.empty(h.work_size), cf,
        )  # fmt: skip
        return z, az

    mats = [a.toarray()]
    interps = []
    for lvl in range(levels - 1):
        ptr = h.p_ptr[h.p_row_off[lvl] : h.p_row_off[lvl] + h.n[lvl] + 1]
        interps.append(
            scipy.sparse.csr_matrix(
                (h.p_val[ptr[0] : ptr[-1]], h.p_idx[ptr[0] : ptr[-1]], ptr - ptr[0]),
                shape=(int(h.n[lvl]), int(h.n[lvl + 1])),
            ).toarray()
        )
        mats.append(interps[-1].T @ mats[-1] @ interps[-1])

    # a coarse DOF is fixed when its interpolation reaches a fixed finer DOF
    fixes = [fixed]
    for lvl in range(levels - 1):
        fixes.append(np.abs(interps[lvl][fixes[-1]]).sum(axis=0) > 0)
    np.testing.assert_array_equal(fixed_all, np.concatenate(fixes))

    def dense_cycle(lvl: int, b: np.ndarray) -> np.ndarray:
        fx = fixes[lvl]
        if lvl == levels - 1:
            x = np.zeros(b.size)
            free = ~fx
            x[free] = np.linalg.solve(mats[lvl][np.ix_(free, free)], b[free])
            return x
        x = np.zeros(b.size)
        _dense_block_gs(mats[lvl], h.stencils[lvl], fx, b, x, reverse=False)
        r = np.where(fx, 0.0, b - mats[lvl] @ x)
        x += np.where(fx, 0.0, interps[lvl] @ dense_cycle(lvl + 1, interps[lvl].T @ r))
        _dense_block_gs(mats[lvl], h.stencils[lvl], fx, b, x, reverse=True)
        return x

    rng = np.random.default_rng(5)
    b = rng.normal(size=n_dof)
    z, az = cycle(b)
    want = dense_cycle(0, b)
    np.testing.assert_allclose(z, want, rtol=0, atol=1e-10 * abs(want).max())
    np.testing.assert_allclose(az, np.where(fixed, 0.0, a @ z), rtol=0, atol=1e-10 * abs(az).max())
    b2 = rng.normal(size=n_dof)
    z2, _ = cycle(b2)
    free = ~fixed
    assert abs(b2[free] @ z[free] - b[free] @ z2[free]) <= 1e-12 * abs(b[free] @ z[free])


def test_add_dofs_writes_every_coordinate_of_a_free_dof() -> None:
    a, st, pz = _system(5, True, False)
    n_dof = a.shape[0]
    fixed = np.zeros(n_dof, dtype=bool)
    fixed[pz[0]] = True
    t = np.arange(n_dof, dtype=float) + 1.0
    xg = np.zeros(st.grid_len)
    add_dofs(st.dof_of, st.halo, fixed, t, xg)
    coords = xg[3 * st.halo : 3 * st.halo + 3 * st.n_particles]
    np.testing.assert_array_equal(coords, np.where(fixed[st.dof_of], 0.0, t[st.dof_of]))
    assert np.all(xg[: 3 * st.halo] == 0.0)
    assert np.all(xg[3 * (st.halo + st.n_particles) :] == 0.0)


def test_build_stencil_refuses_palm_dofs_out_of_order() -> None:
    lat = build_lattice((0.1, 0.07, 0.05), 0.025)
    dof_of, n_dof, px, pz = palm_dof_map(lat, True)
    w = lat.unit_stiffness
    with pytest.raises(ValueError, match="palm DOFs"):
        build_stencil(lat, w, np.ones(lat.n_particles), dof_of, n_dof, pz, px)


@pytest.mark.parametrize(("nx", "gripped", "surface", "fix_palm_z"), CASES)
def test_stencil_product_is_the_matrix_product(
    nx: int, gripped: bool, surface: bool, fix_palm_z: bool
) -> None:
    """Every DOF's row, the palm DOFs' included, from the stencil equals the compressed rows';
    garbage in the scratch (the halo included) does not leak into it."""
    a, st, _ = _system(nx, gripped, surface)
    ptr, idx, val = _csr(a)
    x = np.random.default_rng(nx).normal(size=a.shape[0])
    out = np.full(a.shape[0], np.nan)
    xg = np.full(st.grid_len, np.nan)
    stencil_product(st, Rows(ptr, idx, val), x, xg, out)
    want = a @ x
    np.testing.assert_allclose(out, want, rtol=0, atol=1e-12 * np.abs(want).max())


@pytest.mark.parametrize("stencils", [2, 0])
def test_hierarchy_product_is_the_finest_matrix_product(stencils: int) -> None:
    """The product CG and the step use: by the stencil when there is one, else by rows."""
    a, st, _ = _system(7, True, False)
    shape = (int(st.shape[0]), int(st.shape[1]), int(st.shape[2]))
    h = build_hierarchy(shape, True, a, max_coarse=a.shape[0] // 9, stencil=st)
    h = dataclasses.replace(h, stencils=h.stencils[:stencils])
    x = np.random.default_rng(2).normal(size=a.shape[0])
    out = np.full(a.shape[0], np.nan)
    work = np.full(h.work_size, np.nan)
    product(h.kernel_args(), work, x, out)
    want = a @ x
    np.testing.assert_allclose(out, want, rtol=0, atol=1e-12 * np.abs(want).max())
