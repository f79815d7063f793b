"""The multigrid V-cycle and CG of the iterative solver (deformctl.sim.multigrid).

The V-cycle returns ``A z`` with ``z`` (read from its last sweep instead of a matrix-vector
product): checked against the product itself, and CG's solution against a direct solve of the
free DOFs' subsystem.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.sparse
import scipy.sparse.linalg

from deformctl.sim import ObjectSpec, SimSettings
from deformctl.sim.engine import build_model
from deformctl.sim.lattice import shape_dof_map
from deformctl.sim.multigrid import (
    Hierarchy,
    build_hierarchy,
    interpolation,
    pcg,
    solve,
    stencil_scratch_offsets,
    v_cycle,
)
from deformctl.sim.multigrid.levels import _cholesky_into
from deformctl.sim.multigrid.transfer import _grid_prolong_add, _grid_restrict

CUBE = ObjectSpec("cube", (10.0, 10.0, 10.0), 5.0, 0.5, 30.0, 1.0)


def _model_hierarchy(n: int) -> tuple[Hierarchy, scipy.sparse.csr_matrix, tuple[int, int, int]]:
    model = build_model(
        CUBE, SimSettings(particles_per_side=n, solver="iterative"), gripped=True, table=True
    )
    h = model.hierarchy
    assert h is not None
    n0 = int(h.n[0])
    ptr = h.a_ptr[: n0 + 1]
    a = scipy.sparse.csr_matrix(
        (h.a_val[ptr[0] : ptr[-1]], h.a_idx[ptr[0] : ptr[-1]], ptr - ptr[0]), shape=(n0, n0)
    )
    return h, a, model.lattice.shape


def _v_cycle(h: Hierarchy, fixed: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    n0 = int(h.n[0])
    tot = int(h.n.sum())
    z, az = np.empty(n0), np.empty(n0)
    sts = h.stencil_args()
    grid = int(stencil_scratch_offsets(sts.shape, sts.halo)[-1])
    fixed_all, cf = h.fixed_levels(fixed)
    v_cycle(
        h.kernel_args(), fixed_all, b, z, az, np.empty(tot), np.empty(tot), np.empty(tot),
        np.empty(grid), cf,
    )  # fmt: skip
    return z, az


def _cg(h: Hierarchy, fixed: np.ndarray, b: np.ndarray, rel_tol: float) -> tuple[int, np.ndarray]:
    """CG from zero to ``rel_tol`` of the free right-hand side: its iterations and solution."""
    x = np.zeros(b.size)
    work = np.zeros(h.work_size)
    tol = rel_tol * float(np.linalg.norm(np.where(fixed, 0, b)))
    its = pcg(h.kernel_args(), fixed, b, x, tol, 100, work, work[:0], False)
    return int(its), x


def _without_stencil(h: Hierarchy) -> Hierarchy:
    return dataclasses.replace(h, stencils=())


def test_diagonal_positions_point_at_every_rows_diagonal() -> None:
    h, a, _ = _model_hierarchy(9)
    assert h.levels >= 2
    for lvl in range(h.levels):
        off, r0, n = int(h.vec_off[lvl]), int(h.row_off[lvl]), int(h.n[lvl])
        pos = h.a_diag[off : off + n]
        assert np.array_equal(h.a_idx[pos], np.arange(n))
        assert np.all(pos >= h.a_ptr[r0 : r0 + n])
        assert np.all(pos < h.a_ptr[r0 + 1 : r0 + n + 1])
    assert np.allclose(h.a_val[h.a_diag[: h.n[0]]], a.diagonal(), rtol=0, atol=0)


@pytest.mark.parametrize("levels", ["several", "rows", "one"])
def test_v_cycle_returns_a_times_its_result(levels: str) -> None:
    """With the finest level swept as a stencil (default), by rows, or a single level."""
    h, a, shape = _model_hierarchy(9)
    assert h.stencil is not None
    if levels == "rows":
        h = _without_stencil(h)
    if levels == "one":
        h = build_hierarchy(shape, True, a, max_coarse=10**6)
        assert h.levels == 1
    rng = np.random.default_rng(3)
    n0 = a.shape[0]
    fixed = np.zeros(n0, dtype=bool)
    fixed[rng.choice(n0, n0 // 7, replace=False)] = True
    b = rng.normal(size=n0)
    z, az = _v_cycle(h, fixed, b)
    assert np.all(z[fixed] == 0.0)
    assert np.all(az[fixed] == 0.0)
    want = np.where(fixed, 0.0, a @ z)
    assert np.max(np.abs(az - want)) <= 1e-12 * np.max(np.abs(want))
    # a preconditioner: z is a descent direction of the free residual, and reduces it
    free = ~fixed
    assert float(b[free] @ z[free]) > 0
    assert np.linalg.norm((b - a @ z)[free]) < 0.5 * np.linalg.norm(b[free])


@pytest.mark.parametrize("n", [7, 11])
def test_cg_solves_the_free_subsystem(n: int) -> None:
    """Fixed DOFs keep their value; the free ones solve A_FF x_F = b_F - A_FC x_C."""
    h, a, _ = _model_hierarchy(n)
    rng = np.random.default_rng(n)
    n0 = a.shape[0]
    fixed = np.zeros(n0, dtype=bool)
    fixed[rng.choice(n0, n0 // 10, replace=False)] = True
    free = ~fixed
    b = rng.normal(size=n0)
    x0 = np.where(fixed, rng.normal(size=n0), 0.0)
    x = solve(h, fixed, b, rel_tol=1e-11, x0=x0)
    aff = a[free][:, free].tocsc()
    want = scipy.sparse.linalg.spsolve(aff, b[free] - a[free][:, fixed] @ x0[fixed])
    assert np.array_equal(x[fixed], x0[fixed])
    assert np.max(np.abs(x[free] - want)) <= 1e-8 * np.max(np.abs(want))


def test_cg_converges_at_a_rate_independent_of_the_lattice() -> None:
    """About a tenth per iteration whatever the size: 1e-8 takes the same count at 7^3 and 13^3."""
    counts = []
    for n in (7, 13):
        h, a, _ = _model_hierarchy(n)
        n0 = a.shape[0]
        b = np.random.default_rng(0).normal(size=n0)
        its, x = _cg(h, np.zeros(n0, dtype=bool), b, 1e-8)
        assert its <= 100
        assert np.linalg.norm(b - a @ x) <= 1.01e-8 * np.linalg.norm(b)
        counts.append(its)
    assert counts[1] <= counts[0] + 2, counts
    assert counts[1] <= 12, counts


def test_cg_with_a_known_initial_product_skips_nothing_it_needs() -> None:
    """Given ``A x0`` (``ax_known``), CG takes the same iterations to the same solution as when it
    forms the product itself, from a nonzero guess with fixed DOFs; a wrong product is not
    silently fixed (the answer then differs), so the flag really replaces the product."""
    h, a, _ = _model_hierarchy(7)
    assert h.stencil is not None
    n0 = a.shape[0]
    rng = np.random.default_rng(3)
    fixed = rng.random(n0) < 0.1
    b = rng.normal(size=n0)
    x0 = rng.normal(size=n0)
    tol = 1e-9 * float(np.linalg.norm(b))

    def run(ax: np.ndarray, known: bool) -> tuple[int, np.ndarray, np.ndarray]:
        x = x0.copy()
        work = np.zeros(h.work_size)
        its = pcg(h.kernel_args(), fixed, b, x, tol, 100, work, ax, known)
        return its, x, work[:n0].copy()

    its_self, x_self, _ = run(np.empty(0), False)
    its_known, x_known, r_known = run(a @ x0, True)
    assert its_self == its_known <= 100
    np.testing.assert_allclose(x_known, x_self, rtol=0, atol=1e-12 * np.abs(x_self).max())
    free = ~fixed
    # the returned residual is b - A x on the free DOFs (to the recursion's drift), 0 on fixed
    true_r = np.where(free, b - a @ x_known, 0.0)
    np.testing.assert_allclose(r_known, true_r, rtol=0, atol=1e-9 * np.linalg.norm(b))
    assert np.all(r_known[fixed] == 0.0)
    np.testing.assert_array_equal(x_known[fixed], x0[fixed])
    _, x_wrong, _ = run(a @ x0 + 1.0, True)
    assert np.abs(x_wrong - x_self).max() > 1e-3


@pytest.mark.parametrize("part", ["whole", "half", "scattered"])
def test_fixed_dofs_do_not_slow_cg(part: str) -> None:
    """The object on the table holds its bottom particles' z (fixed DOFs). The coarse levels
    hold the coarse DOFs that interpolate onto them and the coarsest solves its free block, so
    every coarse correction is the free subsystem's: CG converges about as fast as with nothing
    fixed. (When the coarse levels ignored the fixed DOFs, the whole face, half of it and a
    scattered half took 13, 12 and 12 iterations to 1e-8; now 9, 11 and 10, against 9 free.)"""
    n = 12
    model = build_model(
        CUBE, SimSettings(particles_per_side=n, solver="iterative"), gripped=True, table=True
    )
    h = model.hierarchy
    assert h is not None
    assert h.levels >= 3
    n0 = int(h.n[0])
    z = model.base_x[:, 2]
    bottom = np.flatnonzero(np.isclose(z, z.min()))
    rng = np.random.default_rng(1)
    if part == "half":
        x = model.base_x[bottom, 0]
        bottom = bottom[x <= np.median(x)]
    elif part == "scattered":
        bottom = bottom[rng.random(bottom.size) < 0.5]
    fixed = np.zeros(n0, dtype=bool)
    fixed[model.dof_of[3 * bottom + 2]] = True
    b = rng.normal(size=n0)
    free_its, _ = _cg(h, np.zeros(n0, dtype=bool), b, 1e-8)
    held_its, _ = _cg(h, fixed, b, 1e-8)
    assert free_its <= 10
    assert held_its <= free_its + (0 if part == "whole" else 2), (part, free_its, held_its)
    # the coarse levels hold DOFs too, and the coarsest solves its free block exactly
    fixed_all, cf = h.fixed_levels(fixed)
    assert fixed_all[int(h.vec_off[1]) :].any()
    assert cf[0] == 1.0


@pytest.mark.parametrize("m", [1, 2, 7, 60, 200])
def test_the_coarse_factor_is_the_cholesky_factor(m: int) -> None:
    """The coarsest level's free block is factored by a written-out Cholesky (not LAPACK's
    threaded one): its lower triangle is numpy's factor to rounding, and ``L L^T`` is the
    matrix."""
    rng = np.random.default_rng(m)
    g = rng.normal(size=(m, m))
    a = g @ g.T + m * np.eye(m)
    out = np.full(m * m, np.nan)
    _cholesky_into(a, out)
    lower = np.tril(np.nan_to_num(out.reshape(m, m), nan=0.0))
    assert np.all(np.isfinite(np.tril(out.reshape(m, m))))
    np.testing.assert_allclose(lower, np.linalg.cholesky(a), rtol=1e-12, atol=1e-12 * m)
    np.testing.assert_allclose(lower @ lower.T, a, rtol=1e-13, atol=1e-12 * np.abs(a).max())


def test_the_coarse_factor_refuses_an_indefinite_block() -> None:
    a = np.array([[1.0, 2.0], [2.0, 1.0]])  # eigenvalues 3 and -1
    with pytest.raises(ValueError, match="not positive definite"):
        _cholesky_into(a, np.zeros(4))


@pytest.mark.parametrize("shape", [(5, 4, 3), (6, 7, 2), (9, 8, 6), (2, 5, 4), (3, 3, 3)])
@pytest.mark.parametrize("gripped", [True, False])
def test_grid_transfer_is_the_interpolation_and_its_transpose(
    shape: tuple[int, int, int], gripped: bool
) -> None:
    """The V-cycle's transfer between the two stencil levels, by axis factors on the lattice
    coordinates, is ``P^T r`` down and ``x += P x_c`` (free DOFs, every coordinate of a DOF) up,
    with ``P`` the compressed-row interpolation: odd, even and two-point axes, palm DOFs merged
    or not."""
    p, cshape, cdof = interpolation(shape, gripped)
    dof, n_f, _, _ = shape_dof_map(shape, gripped)
    rep = np.full(n_f, -1, dtype=np.int64)
    for c in range(dof.size - 1, -1, -1):
        rep[dof[c]] = c  # the first coordinate of each DOF
    nx, ny, nz = shape
    cx, cy = cshape[0], cshape[1]
    part = np.full(3 * cx * nz * (ny + cy), np.nan)
    rng = np.random.default_rng(7)
    r = rng.normal(size=n_f)
    down = np.full(p.shape[1], np.nan)
    fs, cs = np.array(shape, dtype=np.int64), np.array(cshape, dtype=np.int64)
    _grid_restrict(fs, cs, dof, rep, cdof, r, part, down)
    want = p.T @ r
    np.testing.assert_allclose(down, want, rtol=0, atol=1e-14 * abs(want).max())
    fixed = rng.random(n_f) < 0.2
    xc = rng.normal(size=p.shape[1])
    halo = 3
    xg = rng.normal(size=3 * (nx * ny * nz + 2 * halo))
    up = xg.copy()
    _grid_prolong_add(fs, cs, dof, cdof, fixed, xc, part, halo, up)
    t = p @ xc
    expect = xg.copy()
    free = ~fixed[dof]
    expect[3 * halo : 3 * halo + dof.size][free] += t[dof][free]
    np.testing.assert_allclose(up, expect, rtol=0, atol=1e-14 * abs(expect).max())
