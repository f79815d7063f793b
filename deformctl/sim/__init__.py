"""Particle-lattice Kelvin simulator: physics only, no file I/O.

Public API: :class:`ObjectSpec`, :class:`SimSettings`, :class:`LiftProfile`,
:class:`SlipCriterion`, :func:`squeeze`, :func:`squeeze_many`, :func:`lift_attempt`,
:func:`f_w_n` (W/(2 μ), the rigid-object hold), :func:`rigid_lift_force_n` (m (g + a)/(2 μ),
the rigid-object limit of a lift), and
:func:`free_run` for validation. The simulator reads no catalogs: a catalog row becomes an
:class:`ObjectSpec` through :meth:`deformctl.catalog.CatalogObject.to_sim_spec`. The model and the
integrator are described in :mod:`deformctl.sim.engine`.
"""

from __future__ import annotations

# first: numba's cache of every kernel is keyed by all the kernel sources (see the module)
from deformctl.sim import _kernel_cache  # noqa: F401
from deformctl.sim.engine import SimSettings
from deformctl.sim.objects import ObjectSpec, f_w_n
from deformctl.sim.protocols import (
    FreeRunSeries,
    LiftProfile,
    SlipCriterion,
    SupportRelease,
    free_run,
    lift_attempt,
    rigid_lift_force_n,
    squeeze,
    squeeze_many,
)

__all__ = [
    "FreeRunSeries",
    "LiftProfile",
    "ObjectSpec",
    "SimSettings",
    "SlipCriterion",
    "SupportRelease",
    "f_w_n",
    "free_run",
    "lift_attempt",
    "rigid_lift_force_n",
    "squeeze",
    "squeeze_many",
]
