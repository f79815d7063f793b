"""The step's physical laws (deformctl.sim.step.laws): each matches its closed form, and each is
the only place its formula is written (the step loops, the right-hand side and the static solve
call it; none restates it).

Known truth: the Coulomb bound ``μ max(N, 0)``; the Hunt–Crossley element ``p |s|ⁿ sign(s)``
(homogeneous of degree n, odd in s) and its damper ``τ p min(|s|, s_cap)ⁿ / L``; a static solve
of a power-law lattice balances the closed-form element forces.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import numpy as np
import pytest

import deformctl.sim.hunt_crossley as hc_module
import deformctl.sim.step as step_package
from deformctl.sim.hunt_crossley import power_static
from deformctl.sim.lattice import bottom_z_dofs, build_lattice, palm_dof_map
from deformctl.sim.step.laws import (
    coulomb_bound,
    hunt_crossley_damping,
    hunt_crossley_spring,
    hunt_crossley_springs,
)

STEP = Path(step_package.__file__).resolve().parent
RNG = np.random.default_rng(46)


def test_the_coulomb_bound_is_mu_times_the_pushing_normal() -> None:
    for mu, normal in zip(RNG.uniform(0.0, 2.0, 50), RNG.uniform(-10.0, 10.0, 50), strict=True):
        assert coulomb_bound(mu, normal) == (mu * normal if normal > 0 else 0.0)
    assert coulomb_bound(0.5, 0.0) == 0.0
    assert coulomb_bound(0.0, 7.0) == 0.0
    assert coulomb_bound(0.3, 4.0) == pytest.approx(1.2, rel=1e-15)


@pytest.mark.parametrize("n", [1.0, 1.5, 2.0, 2.7, 3.0])
def test_the_hunt_crossley_spring_is_p_abs_s_to_the_n_with_the_sign_of_s(n: float) -> None:
    p = RNG.uniform(1e3, 1e6, 40)
    s = RNG.uniform(-1e-2, 1e-2, 40)
    expected = p * np.abs(s) ** n * np.sign(s)
    got = np.array([hunt_crossley_spring(pi, si, n) for pi, si in zip(p, s, strict=True)])
    np.testing.assert_allclose(got, expected, rtol=1e-14, atol=0.0)
    np.testing.assert_array_equal(hunt_crossley_springs(p, s, n), got)  # the array form
    # odd in s, homogeneous of degree n, none at rest
    assert hunt_crossley_spring(2.0, -0.01, n) == -hunt_crossley_spring(2.0, 0.01, n)
    ratio = hunt_crossley_spring(2.0, 0.006, n) / hunt_crossley_spring(2.0, 0.002, n)
    assert ratio == pytest.approx(3.0**n, rel=1e-13)
    assert hunt_crossley_spring(2.0, 0.0, n) == 0.0
    if n == 1.0:  # the Kelvin spring
        assert hunt_crossley_spring(2.0, -0.25, n) == -0.5


def test_the_hunt_crossley_damper_grows_as_the_spring_up_to_its_cap() -> None:
    p, n, tau, rest = 5e4, 2.0, 0.3, 0.02
    cap = 0.004
    for s in (-0.003, 0.001, 0.0035):
        assert hunt_crossley_damping(p, s, n, tau, cap, rest) == pytest.approx(
            tau * p * abs(s) ** n / rest, rel=1e-14
        )
    capped = tau * p * cap**n / rest
    for s in (0.004, -0.005, 0.05):
        assert hunt_crossley_damping(p, s, n, tau, cap, rest) == pytest.approx(capped, rel=1e-14)
    assert hunt_crossley_damping(p, 0.0, n, tau, cap, rest) == 0.0


def test_the_static_solve_balances_the_closed_form_element_forces() -> None:
    lattice = build_lattice((0.05, 0.04, 0.03), 0.01)
    n = 1.8
    dof_of, n_dof, px, pz = palm_dof_map(lattice, gripped=True)
    power = lattice.unit_stiffness * lattice.rest_length_m ** (1.0 - n)
    u0 = np.zeros(n_dof)
    u0[px[0]], u0[px[1]] = 2e-4, -2e-4
    fixed = np.union1d(np.array([px[0], px[1], pz[0], pz[1]]), bottom_z_dofs(lattice, dof_of))
    u, b = power_static(lattice, power, n, dof_of, u0, fixed, np.zeros(n_dof))
    s = b @ u
    f = power * np.abs(s) ** n * np.sign(s)  # the closed form, not the law function
    residual = b.T @ f
    free = np.setdiff1d(np.arange(n_dof), fixed)
    assert np.abs(residual[free]).max() <= 1e-9 * np.abs(residual[[px[0]]]).max()
    # the palms push into the object: the energy's gradient points the way each palm closes
    assert residual[px[1]] < 0.0 < residual[px[0]]


def _sources() -> dict[str, str]:
    paths = [*sorted(STEP.glob("*.py")), Path(hc_module.__file__).resolve()]
    return {p.name: p.read_text() for p in paths if p.name != "laws.py"}


def _calls(text: str, name: str) -> int:
    return sum(
        isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == name
        for node in ast.walk(ast.parse(text))
    )


def test_the_integrators_and_the_static_solve_call_the_laws() -> None:
    sources = _sources()
    # the palms' bound and the table's bound (in the PGS sweep and after it) of the direct loop;
    # the palms' and the table's of the iterative one
    assert _calls(sources["direct.py"], "coulomb_bound") == 3
    assert _calls(sources["iterative.py"], "coulomb_bound") == 2
    assert _calls(sources["forces.py"], "hunt_crossley_spring") == 1
    assert _calls(sources["forces.py"], "hunt_crossley_damping") == 1
    assert _calls(sources["hunt_crossley.py"], "hunt_crossley_springs") == 2


def test_no_caller_restates_a_law() -> None:
    for name, text in _sources().items():
        # a friction coefficient times anything is the Coulomb bound
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult):
                for side in (node.left, node.right):
                    assert not (isinstance(side, ast.Name) and side.id in ("mu", "mu_table")), name
        # |s|ⁿ sign(s): the element law
        assert "np.sign(" not in text, name
        assert not re.search(r"np\.abs\([^)]*\)\s*\*\*\s*n\b", text), name
        assert not re.search(r"\*\*\s*n_exp\b", text), name
