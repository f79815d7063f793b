"""Standard linear solid (Zener) lattices: a Maxwell arm beside every element's spring and damper,
calibrated so that the squeeze between the palms follows ``f = D d + λ ḋ + σ``,
``σ̇ = k2 ḋ − σ/τ``: the law ``characterize --model sls`` fits (its ``sls_stiffness_n_per_cm``
is D, ``sls_arm_stiffness_n_per_cm`` k2 and ``sls_relaxation_time_s`` τ; λ, a dashpot beside
the arm, is 0 for the Zener solid itself).

Why the squeeze follows the law
    The Kelvin lattice's springs are the unit lattice's weights ``w_e`` scaled by one factor,
    ``k_e = w_e D / C`` (``C``: the lattice's squeeze stiffness at unit scale, measured by a
    static solve, :func:`deformctl.sim.statics.unit_squeeze_stiffness_n_per_m`). Each arm's
    spring is the same element's spring times ``k2 / D``, ``k_a,e = w_e k2 / C``, and every arm
    has the same τ. In the frequency domain each element is then ``k_e (1 + (k2/D) sτ/(1 + sτ))``
    (its damper aside): the same complex factor on every element, so the lattice's quasi-static
    squeeze is the unit lattice's, scaled by it: ``D + k2 sτ / (1 + sτ)``, the Zener solid's
    modulus, exactly (small-strain springs; inertia aside, as for the Kelvin lattice). With
    ``k2 = 0`` or ``τ = inf`` (the arm a spring: a Kelvin solid of stiffness ``D + k2``) the
    arms vanish or join the springs, which ``tests/sim/test_sls.py`` checks against the Kelvin
    lattice. The calibration is the Kelvin lattice's (the object floating): squeezed on the
    table, as ``measure --sim`` squeezes, D and k2 read about 1.3 % high, as a Kelvin object's
    D does (``make sls-check`` prints the round trip).

The resting object
    A relaxed Zener solid carries a constant load on its springs alone: an object left on the
    table sags as the Kelvin lattice of stiffness D does (:func:`deformctl.sim.statics.
    resting_positions_m`), and its arms start unloaded there (each run starts from rest).

The implicit step
    :mod:`deformctl.sim.step.maxwell` integrates the arms; the step's matrix holds each arm as
    the damper ``c_a = h k_a / (1 + h/τ)`` (:func:`implicit_damping`), beside the elements'
    own dampers.
"""

from __future__ import annotations

import math

import numpy as np

from deformctl.arraytypes import FloatArray
from deformctl.sim.objects import ObjectSpec
from deformctl.sim.step.bundles import Maxwell

#: the arms of an object without any (a Kelvin or Hunt–Crossley material)
NO_ARMS = Maxwell(np.zeros(0), math.inf, np.zeros(0), np.zeros(0), np.zeros(0))


def arm_stiffness_n_per_m(spec: ObjectSpec, stiffness_n_per_m: FloatArray) -> FloatArray:
    """Each element's arm spring ``k_a,e = k_e k2 / D``, N/m, ``[m]`` (``k_e``: the Kelvin
    lattice's calibrated springs; empty when the object has no arms)."""
    if not spec.standard_linear_solid:
        return np.zeros(0)
    return np.asarray(stiffness_n_per_m * (spec.arm_stiffness_n_per_cm / spec.stiffness_n_per_cm))


def implicit_damping(spec: ObjectSpec, stiffness_n_per_m: FloatArray, h_s: float) -> FloatArray:
    """What the arms add to the elements' dampers in the implicit step's matrix,
    ``c_a = h k_a / (1 + h/τ)``, N·s/m, ``[m]`` (zeros without arms)."""
    if not spec.standard_linear_solid:
        return np.zeros_like(stiffness_n_per_m)
    arm = arm_stiffness_n_per_m(spec, stiffness_n_per_m)
    return np.asarray(h_s * arm / (1.0 + h_s / spec.relaxation_time_s))


def maxwell_arms(spec: ObjectSpec, stiffness_n_per_m: FloatArray) -> Maxwell:
    """The kernels' arms of ``spec`` (:data:`NO_ARMS` without any), unloaded."""
    if not spec.standard_linear_solid:
        return NO_ARMS
    arm = arm_stiffness_n_per_m(spec, stiffness_n_per_m)
    m = arm.shape[0]
    return Maxwell(arm, spec.relaxation_time_s, np.zeros(m), np.zeros(m), np.zeros(m))


def unloaded(arms: Maxwell) -> Maxwell:
    """``arms`` with fresh state arrays, all zero: a run starts from the relaxed object."""
    m = arms.stiffness.shape[0]
    return arms._replace(force=np.zeros(m), previous=np.zeros(m), base=np.zeros(m))


def arm_energy_j(arms: Maxwell) -> float:
    """The energy stored in the arms' springs, ``Σ σ² / (2 k_a)``, J."""
    if arms.stiffness.shape[0] == 0:
        return 0.0
    return float(np.sum(arms.force**2 / (2.0 * arms.stiffness)))
