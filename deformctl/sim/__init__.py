"""Particle-lattice Kelvin simulator: physics only, no file I/O.

Public API: :class:`ObjectSpec`, :class:`SimSettings`, :class:`LiftProfile`,
:class:`SlipCriterion`, :func:`squeeze`, :func:`squeeze_many`, :func:`lift_attempt`,
:func:`rigid_lift_force_n`, :func:`f_w_n`, and :func:`free_run` for validation. The model and the
integrator are described in :mod:`deformctl.sim.engine`.
"""

from __future__ import annotations

from deformctl.sim.engine import SimSettings
from deformctl.sim.objects import ObjectSpec, f_w_n, rigid_lift_force_n
from deformctl.sim.protocols import (
    FreeRunSeries,
    LiftProfile,
    SlipCriterion,
    free_run,
    lift_attempt,
    squeeze,
    squeeze_many,
)

__all__ = [
    "FreeRunSeries",
    "LiftProfile",
    "ObjectSpec",
    "SimSettings",
    "SlipCriterion",
    "f_w_n",
    "free_run",
    "lift_attempt",
    "rigid_lift_force_n",
    "squeeze",
    "squeeze_many",
]
