"""The Kelvin elements by runs (deformctl.sim.step.runs): the same forces as the element-by-element
loop, bit for bit, on lattices and on element lists of any order.

Known truth: the element loop ``_element_rhs`` (the sums the step used before the runs) and the
plain NumPy element forces ``spring_forces_numpy``; a lattice's elements form one run per family.
"""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit

from deformctl.arraytypes import FloatArray, IntArray
from deformctl.sim.hunt_crossley import LINEAR_LAW
from deformctl.sim.lattice import build_lattice
from deformctl.sim.sls import NO_ARMS
from deformctl.sim.step import Body, element_runs, spring_forces_numpy, with_scratch
from deformctl.sim.step.forces import _element_rhs
from deformctl.sim.step.runs import _element_rhs_runs

RNG = np.random.default_rng(44)


@njit(cache=False)
def _by_runs(body: Body, x: FloatArray, vel: FloatArray, h: float) -> FloatArray:
    runs = body.runs
    for p in range(x.shape[0]):
        for a in range(3):
            runs.xs[a, p] = x[p, a]
            runs.vs[a, p] = vel[p, a]
    _element_rhs_runs(runs, body.retardation, body.nonlinear, h)
    return runs.out.T.copy()


def _body(
    edges: IntArray,
    rest: FloatArray,
    n0: FloatArray,
    k: FloatArray,
    x: FloatArray,
    nonlinear: bool,
    retardation: float = 0.02,
) -> Body:
    runs = with_scratch(element_runs(edges, rest, n0, k), x.shape[0])
    n = x.shape[0]
    dof_of = np.arange(3 * n)
    arrays = (x.copy(), dof_of, np.ones(n), edges, rest, n0, k)
    return Body(*arrays, retardation, nonlinear, LINEAR_LAW, NO_ARMS, runs)


def _both(body: Body, x: FloatArray, vel: FloatArray, h: float) -> tuple[FloatArray, FloatArray]:
    loop = np.zeros_like(x)
    _element_rhs(body, x, vel, h, loop)
    return loop, _by_runs(body, x, vel, h)


@pytest.mark.parametrize("nonlinear", [True, False])
@pytest.mark.parametrize(
    ("size", "alpha", "surface"),
    [
        ((0.09, 0.09, 0.09), 0.006, False),
        ((0.1, 0.05, 0.03), 0.01, True),
        ((0.02, 0.3, 0.01), 0.01, False),
    ],
)
def test_runs_give_the_element_loops_forces_bit_for_bit_on_a_lattice(
    size: tuple[float, float, float], alpha: float, surface: bool, nonlinear: bool
) -> None:
    lat = build_lattice(size, alpha, palm_surface=surface)
    k = 50.0 * lat.unit_stiffness
    x = lat.positions_m + RNG.normal(0.0, 0.1 * alpha, lat.positions_m.shape)
    vel = RNG.normal(0.0, 0.05, x.shape)
    body = _body(lat.edges, lat.rest_length_m, lat.direction, k, x, nonlinear)
    loop, runs = _both(body, x, vel, 1e-3)
    assert loop.tobytes() == runs.tobytes()
    assert np.abs(runs).max() > 0.0
    # one run per element family (the lattice's nine directions, fewer on a flat box)
    assert body.runs.seg.shape[0] == 9
    assert body.runs.real.sum() == lat.edges.shape[0]
    # a family shares its rest direction and length bit for bit (its run reads them once),
    # except the five families along x when half slabs lie at the palm surfaces
    assert (body.runs.seg[:, 4] == 1).sum() == (4 if surface else 9)


def test_runs_give_the_element_loops_forces_bit_for_bit_on_any_element_order() -> None:
    n = 60
    x = RNG.normal(0.0, 0.05, (n, 3))
    vel = RNG.normal(0.0, 0.1, (n, 3))
    pairs = RNG.integers(0, n, (400, 2))
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]  # repeats, both signs of offset, any order
    d = x[pairs[:, 1]] - x[pairs[:, 0]]
    rest = np.linalg.norm(d, axis=1) * RNG.uniform(0.9, 1.1, pairs.shape[0])
    n0 = d / np.linalg.norm(d, axis=1)[:, None]
    k = RNG.uniform(10.0, 100.0, pairs.shape[0])
    for nonlinear in (True, False):
        body = _body(pairs, rest, n0, k, x, nonlinear)
        loop, runs = _both(body, x, vel, 2e-3)
        assert loop.tobytes() == runs.tobytes()


def test_runs_are_the_kelvin_element_forces() -> None:
    lat = build_lattice((0.05, 0.04, 0.03), 0.01)
    k = 80.0 * lat.unit_stiffness
    retardation = 0.05
    x = lat.positions_m + RNG.normal(0.0, 1e-3, lat.positions_m.shape)
    vel = RNG.normal(0.0, 0.2, x.shape)
    body = _body(lat.edges, lat.rest_length_m, lat.direction, k, x, True, retardation)
    # h = 0: the exact springs and their axial dampers alone
    expected = spring_forces_numpy(x, vel, lat.edges, lat.rest_length_m, k, retardation * k)
    np.testing.assert_allclose(_by_runs(body, x, vel, 0.0), expected, rtol=1e-12, atol=1e-15)
