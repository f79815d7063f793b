"""The physical laws of the step, one ``@njit`` function each: the Coulomb bound and the
Hunt–Crossley element force.

Each law is written here once and called wherever it acts:

* :func:`coulomb_bound` by both step loops (:func:`deformctl.sim.step.direct.integrate` and
  :func:`deformctl.sim.step.iterative.integrate_iterative`), for the palms (μ times the commanded
  grip force, times the step) and for the table (μ_table times the table row's normal impulse);
* :func:`hunt_crossley_spring` and :func:`hunt_crossley_damping` by the step's right-hand side
  (:func:`deformctl.sim.step.forces._element_rhs_hc`), and :func:`hunt_crossley_spring` by the
  static solves of a Hunt–Crossley lattice through its array form :func:`hunt_crossley_springs`
  (:func:`deformctl.sim.hunt_crossley.power_static`,
  :func:`~deformctl.sim.hunt_crossley.unit_squeeze_power`).

The kernels inline them (``inline="always"``), so a step costs what it cost with the law written
out, and each keeps the operation order it had there (the same bits).
tests/sim/step/test_laws.py checks each against its closed form and that no caller restates it.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from deformctl.arraytypes import FloatArray


@njit(cache=True, inline="always")
def coulomb_bound(mu: float, normal: float) -> float:
    """The largest tangential force (or impulse) a Coulomb contact carries, ``μ max(N, 0)``, in
    the unit of ``normal`` (N, or N·s for an impulse): a contact that pulls carries none."""
    return mu * max(normal, 0.0)


@njit(cache=True, inline="always")
def hunt_crossley_spring(power: float, stretch: float, exponent: float) -> float:
    """A Hunt–Crossley element's elastic force, ``p |s|ⁿ sign(s)``, N (positive pulls its ends
    together; :mod:`deformctl.sim.hunt_crossley`).

    Args:
        power: ``p_e``, N/mⁿ.
        stretch: ``s``, m (compression negative).
        exponent: ``n``.
    """
    spring = power * abs(stretch) ** exponent
    if stretch < 0.0:
        spring = -spring
    return spring


@njit(cache=True, inline="always")
def hunt_crossley_damping(
    power: float, stretch: float, exponent: float, retardation: float, cap_m: float, rest_m: float
) -> float:
    """A Hunt–Crossley element's damping coefficient, ``τ p min(|s|, s_cap)ⁿ / L``, N·s/m: the
    damper grows with the stretch as the spring does, up to the cap (the implicit step's limit,
    :data:`deformctl.sim.hunt_crossley.DAMPING_CAP`).

    Args:
        power: ``p_e``, N/mⁿ; stretch: ``s``, m; exponent: ``n``.
        retardation: ``τ``, s.
        cap_m: ``s_cap``, m: the stretch beyond which the damper stops growing.
        rest_m: the element's rest length ``L``, m.
    """
    return retardation * power * min(abs(stretch), cap_m) ** exponent / rest_m


@njit(cache=True)
def hunt_crossley_springs(power: FloatArray, stretch: FloatArray, exponent: float) -> FloatArray:
    """:func:`hunt_crossley_spring` of every element, N, ``[m]`` (the static solve's form)."""
    out = np.empty(stretch.shape[0])
    for e in range(stretch.shape[0]):
        out[e] = hunt_crossley_spring(power[e], stretch[e], exponent)
    return out
