"""Hunt–Crossley lattices: springs whose force grows as the stretch to the power n, calibrated so
that the squeeze between the palms follows the object's ``f = k dⁿ + λ_hc dⁿ ḋ``.

The element law, and why the squeeze follows ``k dⁿ``
    Each element ``e`` (rest length ``L_e``, cell-shared weight ``w_e``, :mod:`.lattice`) with
    stretch ``s`` (compression negative) and stretch rate ``ṡ`` carries

        ``f_e = p_e |s|ⁿ sign(s) + τ p_e |s|ⁿ ṡ / L_e``,   ``p_e = κ w_e L_e^(1−n)``

    that is, in strain ``ε = s / L_e``: ``f_e = κ w_e L_e |ε|ⁿ (sign ε + τ ε̇)``, the same
    material in every element (for n = 1, ``p_e = κ w_e``: the Kelvin lattice with its one
    scale ``κ``). With the small-strain kinematics (``s`` linear in the displacements ``u``,
    ``SimSettings.nonlinear_springs=False``, the ``paper`` preset) the static squeeze is
    homogeneous of degree n: if ``u`` balances the palm force ``F`` at the closing ``d``, then
    ``t u`` balances ``tⁿ F`` at ``t d`` (every element force scales by ``tⁿ``, the palm
    constraints are linear). So the lattice's squeeze is exactly ``F = κ C_n dⁿ``, where
    ``C_n`` is the squeeze force of the lattice with ``κ = 1`` at unit closing. ``C_n`` is
    *measured* for each lattice by a static solve of that lattice (:func:`unit_squeeze_power`,
    Newton's method on its convex energy ``Σ p_e |s|ⁿ⁺¹ / (n + 1)``), as the linear lattice's
    ``κ`` is by :func:`deformctl.sim.statics.unit_squeeze_stiffness_n_per_m`; then
    ``κ = k / C_n``. The dampers, moving with the static mode ``S_e = s_e / d``, add
    ``τ κ G_n dⁿ ḋ`` with ``G_n = Σ w_e L_e^(1−n) |S_e|ⁿ⁺² / L_e`` (virtual work), so
    ``τ = r λ_hc / (κ G_n)`` gives the squeeze damping ``r λ_hc dⁿ ḋ`` and the width damper the
    rest (``r``: ``SimSettings.shear_damping_ratio``; the dampers' own mode differs a little from
    the springs', and the round trip through ``characterize`` finds λ within 1.5 %). The static
    solve holds the bottom layer in z, as the frictionless table does in the squeeze of
    ``measure --sim`` (2–4 % stiffer than floating; a floating squeeze reads k lower by that
    factor). The exact spring geometry (``nonlinear_springs=True``) breaks the homogeneity:
    tests/sim/test_hunt_crossley.py and ``make hc-check`` measure the squeeze against ``k dⁿ``.

The resting object
    A squeeze test measures d from the object as it rests, and ``k dⁿ`` is fitted to that. A
    power-law element has no stiffness at zero stretch: an object left to sag under its weight
    would be pre-compressed, and its squeeze stiffer than its law (n came back 6–13 % low).
    So a Hunt–Crossley object on the table starts in its unloaded shape, each element carrying
    its share of the weight as a constant tension ``f0_e`` (:func:`weight_prestress_n`, the
    linear lattice's distribution, which balances gravity and the table exactly), and its power
    law acts on the stretch from there: ``f_e = f0_e + p_e |s|ⁿ sign(s) + …``. As n → 1 this
    is the sagged linear lattice again under small-strain kinematics (with the exact geometry,
    up to the resting strain's share); n = 1 itself runs the linear code path. Two conventions
    keep the n → 1 object from being the Kelvin–Voigt object with the same D and λ: k is
    stated at the squeeze on the table (``C_n`` above), a Kelvin–Voigt D at the floating squeeze
    (the same lattice has ``D = k C_float / C_table``, 1–4 % lower), and the dampers follow
    ``λ_hc dⁿ ḋ``, which at n → 1 is ``λ (d / d_op) ḋ``, not ``λ ḋ``
    (tests/sim/test_hunt_crossley.py measures both).

The implicit step
    The step's matrix ``A = M + h C + h² K`` is built once per model (:mod:`.engine`). It holds
    the elements' tangent at the operating compression, ``K_e = n κ w_e ε_refⁿ⁻¹`` with
    ``ε_ref = d_op / size_x`` (the mean strain there), and their dampers at
    :data:`DAMPING_REFERENCE` times the operating force, ``C_e = 2 τ κ w_e ε_refⁿ`` (both the
    linear lattice's pattern, scaled). The exact element forces go to the right-hand side, so the
    step is backward Euler with a Jacobian that is exact at one state; like any frozen-Jacobian
    step it stays stable while the true tangent and damping are below about twice the frozen
    ones (plus the masses' share). Where the frozen tangent is larger than the true one (below
    F_op) the difference acts as a damping of about ``h`` times it (a lag of the order of the
    step: the squeeze tests measure it); where the frozen damping is larger it only slows the
    velocity's change within a step. The stiffness has room above F_op (the masses and the
    implicit damping carry it: squeezes to 5 F_op stay stable); the dampers, whose coefficient
    grows as ``|s|ⁿ``, do not: they stop growing at :data:`DAMPING_CAP` times their value in
    ``A``, at about ``DAMPING_CAP · DAMPING_REFERENCE · F_op`` (3.8 F_op) of squeeze force.
    A run that presses harder than that room allows has its matrix built at a higher reference
    (:func:`implicit_reference_m`: where the tangent is the run's peak tangent over
    :data:`TANGENT_ROOM`): on a light object the masses no longer carry the difference, and a
    squeeze to 500 F_w (the 1 % strain of a stiff, light object, whose law's tangent there is
    60 times the one at F_w) diverged. The dampers' cap moves with the reference. The
    width damper of the ``paper`` preset (``(1 − r) λ`` across the palms) becomes
    ``(1 − r) λ_hc min(d, d_cap)ⁿ`` the same way; the dampers' floor
    (``min_shear_retardation_s``) stays a linear damper on the frozen tangent.
"""

from __future__ import annotations

import math
from collections.abc import Hashable
from dataclasses import dataclass
from functools import lru_cache
from typing import Protocol

import numpy as np
import scipy.sparse
import scipy.sparse.linalg
from numpy.typing import NDArray

from deformctl.arraytypes import FloatArray
from deformctl.errors import SimulationError
from deformctl.sim.lattice import (
    Lattice,
    bottom_z_dofs,
    build_lattice,
    palm_dof_map,
    table_weight_problem,
)
from deformctl.sim.objects import ObjectSpec
from deformctl.sim.step.bundles import HuntCrossley
from deformctl.sim.step.laws import hunt_crossley_springs


class Settings(Hashable, Protocol):
    """What this module reads of :class:`deformctl.sim.engine.SimSettings` (the engine imports
    this module, so it is not imported here)."""

    @property
    def palm_layer(self) -> str: ...

    @property
    def shear_damping_ratio(self) -> float: ...

    @property
    def min_shear_retardation_s(self) -> float: ...

    def alpha_m(self, spec: ObjectSpec) -> float: ...


#: the implicit step's damping matrix holds the Hunt–Crossley dampers at the compression of this
#: multiple of the operating force (its stiffness matrix, the tangent at the operating force)
DAMPING_REFERENCE = 2.0
#: the Hunt–Crossley dampers stop growing at this multiple of their value in the implicit step
#: (a frozen damping matrix is unstable below half the true damping)
DAMPING_CAP = 1.9
#: a run that presses harder has its implicit step built at a higher reference compression, so that
#: the true tangent at the run's largest force is at most this multiple of the frozen one
#: (:func:`implicit_reference_m`; a frozen-Jacobian step diverges above twice it once the masses
#: and dampers no longer carry the difference: a light, stiff object)
TANGENT_ROOM = 1.5
#: the calibration's static solve: closing, as a fraction of the width (any closing gives the
#: same C_n under small-strain kinematics; tests/sim/test_hunt_crossley.py checks it)
CALIBRATION_STRAIN = 0.01
#: Newton stops when the free DOFs' force residual is this small relative to the palm force
NEWTON_TOLERANCE = 1e-11
NEWTON_MAX_ITERATIONS = 200
#: the line search's allowance for the energy's rounding, relative to the size of its terms (a sum
#: over thousands of elements: far above the double's 1e-16, far below any real decrease)
ENERGY_ROUNDING = 1e-12


def _stretch_matrix(
    lattice: Lattice, dof_of: NDArray[np.int64], n_dof: int
) -> scipy.sparse.csr_matrix:
    """``B`` with ``s = B u``: each element's small-strain stretch from the DOF displacements."""
    e = lattice.edges
    m = e.shape[0]
    rows = np.repeat(np.arange(m), 6)
    cols = np.concatenate(
        [dof_of[3 * e[:, 1, None] + np.arange(3)], dof_of[3 * e[:, 0, None] + np.arange(3)]], axis=1
    ).ravel()
    vals = np.concatenate([lattice.direction, -lattice.direction], axis=1).ravel()
    b = scipy.sparse.coo_matrix((vals, (rows, cols)), shape=(m, n_dof)).tocsr()
    b.sum_duplicates()
    return b


@lru_cache(maxsize=16)
def _unit_power(
    size_m: tuple[float, float, float], alpha_m: float, palm_surface: bool, exponent: float
) -> tuple[Lattice, float, float]:
    lattice = build_lattice(size_m, alpha_m, palm_surface=palm_surface)
    c_n, g_n = unit_squeeze_power(lattice, exponent)
    return lattice, c_n, g_n


def unit_squeeze_power(
    lattice: Lattice, exponent: float, *, on_table: bool = True
) -> tuple[float, float]:
    """``(C_n, G_n)`` of the lattice with ``κ = 1`` (see the module docs): the squeeze force at
    unit closing (N/mⁿ) and the dampers' squeeze coefficient per unit ``τ``; measured by a static
    solve under the squeeze's boundary conditions (each face bonded to its palm in x and z, the
    palms fixed in z, free in y; small-strain kinematics) and, ``on_table`` (the squeeze of
    ``measure --sim``), the bottom layer held in z by the frictionless table; else floating (the
    linear lattice's calibration, :func:`deformctl.sim.statics.unit_squeeze_stiffness_n_per_m`).

    Raises:
        SimulationError: Newton's method did not converge (not seen; a message, not a hang).
    """
    n = float(exponent)
    dof_of, n_dof, px, pz = palm_dof_map(lattice, gripped=True)
    rest = lattice.rest_length_m
    p = lattice.unit_stiffness * rest ** (1.0 - n)
    closing = CALIBRATION_STRAIN * float(np.ptp(lattice.positions_m[:, 0]))
    u = np.zeros(n_dof)
    u[px[0]], u[px[1]] = 0.5 * closing, -0.5 * closing
    fixed = np.array([px[0], px[1], pz[0], pz[1]])
    if on_table:
        fixed = np.union1d(fixed, bottom_z_dofs(lattice, dof_of))
    u, b = power_static(lattice, p, n, dof_of, u, fixed, np.zeros(n_dof))
    s = b @ u
    force = float((b[:, [px[0]]].T @ hunt_crossley_springs(p, s, n))[0])
    mode = s / closing
    return force / closing**n, float(np.sum(p * np.abs(mode) ** (n + 2.0) / rest))


def power_static(
    lattice: Lattice,
    power: FloatArray,
    exponent: float,
    dof_of: NDArray[np.int64],
    u: FloatArray,
    fixed: NDArray[np.int64],
    load: FloatArray,
) -> tuple[FloatArray, scipy.sparse.csr_matrix]:
    """Static equilibrium of the power-law lattice (``f_e = power_e |s|ⁿ sign(s)``, small-strain
    stretches ``s = B u``) under ``load`` (N, per DOF) with the DOFs ``fixed`` held at their
    values in ``u``: Newton's method with a line search (Armijo, up to the energy's rounding,
    :data:`ENERGY_ROUNDING`) on the convex energy
    ``Σ power_e |s|ⁿ⁺¹ / (n + 1) − load · u``, from the linear lattice's solution (weights
    :attr:`Lattice.unit_stiffness`); rigid modes are held by a ``1e-10`` relative ridge.

    Returns:
        ``(u, B)``: the displacements ``[n_dof]`` and the stretch matrix.

    Raises:
        SimulationError: no convergence in :data:`NEWTON_MAX_ITERATIONS` steps.
    """
    n = float(exponent)
    n_dof = u.shape[0]
    b = _stretch_matrix(lattice, dof_of, n_dof)
    free = np.setdiff1d(np.arange(n_dof), fixed)
    bf = b[:, free].tocsc()
    bft = bf.T.tocsr()
    lf = load[free]

    def energy(v: FloatArray) -> tuple[float, float]:  # the energy and its terms' magnitude
        s = b @ v
        stored, work = (
            float(np.sum(power * np.abs(s) ** (n + 1.0)) / (n + 1.0)),
            float(lf @ v[free]),
        )
        return stored - work, stored + abs(work)

    def solve(weights: FloatArray, rhs: FloatArray) -> FloatArray:
        h = (bft @ scipy.sparse.diags(weights) @ bf).tocsc()
        eps = 1e-10 * float(h.diagonal().mean())
        h = h + eps * scipy.sparse.identity(free.size, format="csc")
        return np.asarray(scipy.sparse.linalg.spsolve(h, rhs))

    u = u.copy()
    w = lattice.unit_stiffness
    u[free] += solve(w, lf - bft @ (w * (b @ u)))
    scale = 0.0
    for _ in range(NEWTON_MAX_ITERATIONS):
        s = b @ u
        f = hunt_crossley_springs(power, s, n)
        grad = bft @ f - lf
        scale = max(scale, float(np.linalg.norm(b.T @ f)), float(np.linalg.norm(lf)))
        if float(np.linalg.norm(grad)) <= NEWTON_TOLERANCE * scale:
            return u, b
        floor = 1e-6 * float(np.abs(s).max())
        step = solve(n * power * np.maximum(np.abs(s), floor) ** (n - 1.0), -grad)
        e0, size = energy(u)
        slope = float(grad @ step)
        # near the solution Newton's decrease is below the energy's rounding: not a reason to
        # shorten the step (it stalled the line search: no convergence at n = 1)
        slack = ENERGY_ROUNDING * size
        t = 1.0
        while t > 1e-8 and energy(_moved(u, free, step, t))[0] > e0 + 1e-4 * t * slope + slack:
            t *= 0.5
        u = _moved(u, free, step, t)
    raise SimulationError(
        f"the Hunt–Crossley static solve (n = {n:g}) did not converge on a lattice of "
        f"{lattice.shape} particles"
    )


def weight_prestress_n(lattice: Lattice, particle_weight_n: FloatArray) -> FloatArray:
    """The tensions, N, ``[m]``, with which the lattice in its start shape carries its weight on a
    frictionless table (the bottom layer held in z): the linear lattice's distribution
    (weights :attr:`Lattice.unit_stiffness`), which balances gravity exactly, at any scale.

    A Hunt–Crossley object starts in its unloaded shape carrying these as a pre-stress, and its
    power law acts on the stretch from there (module docs, "The resting object")."""
    dof_of, n_dof, fixed, load = table_weight_problem(lattice, particle_weight_n)
    w = lattice.unit_stiffness
    u, b = power_static(lattice, w, 1.0, dof_of, np.zeros(n_dof), fixed, load)
    return np.asarray(w * (b @ u))


def _moved(u: FloatArray, free: NDArray[np.int64], step: FloatArray, t: float) -> FloatArray:
    out = u.copy()
    out[free] += t * step
    return out


@dataclass(frozen=True)
class HuntCrossleyElements:
    """A Hunt–Crossley lattice's element constants (:func:`hc_elements`).

    Attributes:
        lattice: the lattice.
        tangent_n_per_m: each element's tangent at the reference strain, N/m, ``[m]`` (the
            implicit matrix's stiffness).
        damping_ns_per_m: each element's damping at the reference strain, N·s/m, ``[m]`` (the
            implicit matrix's damping, the linear floor included).
        power: ``p_e``, N/mⁿ, ``[m]``.
        retardation_s: ``τ`` of the element dampers.
        floor_s: the linear dampers' retardation (``min_shear_retardation_s``) on the tangent.
        reference_strain: ``ε_ref``.
        cap_strain: the strain at which the dampers stop growing.
        width_damping_ns_per_m: the width damper at the compression of
            :data:`DAMPING_REFERENCE` times the operating force, N·s/m.
        reference_m: the implicit step's reference compression (``d_op`` or above), m.
        unit_force: ``C_n`` of the lattice; unit_damping: ``G_n``.
    """

    lattice: Lattice
    tangent_n_per_m: FloatArray
    damping_ns_per_m: FloatArray
    power: FloatArray
    retardation_s: float
    floor_s: float
    reference_strain: float
    cap_strain: float
    width_damping_ns_per_m: float
    reference_m: float
    unit_force: float
    unit_damping: float


def hc_elements(
    size_m: tuple[float, float, float],
    alpha_m: float,
    palm_surface: bool,
    *,
    exponent: float,
    stiffness_n_per_m_pow_n: float,
    damping_ns_per_m_pow_n_plus_1: float,
    reference_m: float,
    shear_damping_ratio: float,
    floor_s: float,
) -> HuntCrossleyElements:
    """The element constants of a Hunt–Crossley object (see the module docs).

    Args:
        exponent, stiffness_n_per_m_pow_n, damping_ns_per_m_pow_n_plus_1: n, k and λ_hc.
        reference_m: the implicit step's reference compression, m: the operating compression
            d_op, or above it for a run that presses harder (:func:`implicit_reference_m`).
        shear_damping_ratio: r: the lattice's dampers carry ``r λ_hc``, the width damper the
            rest (as for a Kelvin object, :class:`~deformctl.sim.engine.SimSettings`).
        floor_s: ``min_shear_retardation_s``.
    """
    n = float(exponent)
    lattice, c_n, g_n = _unit_power(size_m, alpha_m, palm_surface, n)
    kappa = stiffness_n_per_m_pow_n / c_n
    tau = shear_damping_ratio * damping_ns_per_m_pow_n_plus_1 / (kappa * g_n)
    eps = reference_m / size_m[0]
    w = lattice.unit_stiffness
    tangent = n * kappa * w * eps ** (n - 1.0)
    # the dampers at DAMPING_REFERENCE F_op, that is at the strain DAMPING_REFERENCE^(1/n) eps
    damping = DAMPING_REFERENCE * tau * kappa * w * eps**n + floor_s * tangent
    width = (1.0 - shear_damping_ratio) * damping_ns_per_m_pow_n_plus_1 * reference_m**n
    width *= DAMPING_REFERENCE
    return HuntCrossleyElements(
        lattice=lattice,
        tangent_n_per_m=tangent,
        damping_ns_per_m=damping,
        power=kappa * w * lattice.rest_length_m ** (1.0 - n),
        retardation_s=tau,
        floor_s=floor_s,
        reference_strain=eps,
        cap_strain=(DAMPING_CAP * DAMPING_REFERENCE) ** (1.0 / n) * eps,
        width_damping_ns_per_m=width,
        reference_m=reference_m,
        unit_force=c_n,
        unit_damping=g_n,
    )


#: the law of a Kelvin body (its elements are the linear ones; nothing here is read)
LINEAR_LAW = HuntCrossley(1.0, np.zeros(1), 0.0, 0.0, 1.0, 1.0, np.zeros(1))


def implicit_reference_m(spec: ObjectSpec, peak_force_n: float) -> float | None:
    """The reference compression of the implicit step for a run whose palms press with at most
    ``peak_force_n`` (N): ``None`` (the operating compression ``d_op``) unless the law's tangent
    at that force, ``n k d_peakⁿ⁻¹``, exceeds :data:`TANGENT_ROOM` times the tangent at ``d_op``;
    then the compression where the tangent is the peak's over :data:`TANGENT_ROOM`,
    ``d_peak · TANGENT_ROOM^(−1/(n−1))``. Below it the frozen tangent exceeds the true one, a lag
    of the order of the step (module docs); above it the step stays stable whatever the mass
    and the damping (the massless, undamped step's factor ``1 − K_true/K_frozen`` stays in
    (−1, 1)).

    A Kelvin object (or ``peak_force_n`` not above 0) gives ``None``.
    """
    if not spec.hunt_crossley or not peak_force_n > 0:
        return None
    n = spec.stiffness_exponent
    d_peak = (peak_force_n / spec.hc_stiffness_n_per_m_pow_n) ** (1.0 / n)
    reference = d_peak * math.exp(-math.log(TANGENT_ROOM) / (n - 1.0))
    return reference if reference > spec.operating_compression_m else None


@lru_cache(maxsize=16)
def spec_elements(
    spec: ObjectSpec, settings: Settings, reference_m: float | None = None
) -> HuntCrossleyElements:
    """:func:`hc_elements` of a Hunt–Crossley object under ``settings``, its implicit step built
    at ``reference_m`` (default: the operating compression; :func:`implicit_reference_m`)."""
    return hc_elements(
        spec.size_m,
        settings.alpha_m(spec),
        settings.palm_layer == "surface",
        exponent=spec.stiffness_exponent,
        stiffness_n_per_m_pow_n=spec.hc_stiffness_n_per_m_pow_n,
        damping_ns_per_m_pow_n_plus_1=spec.hc_damping_ns_per_m_pow_n_plus_1,
        reference_m=spec.operating_compression_m if reference_m is None else reference_m,
        shear_damping_ratio=settings.shear_damping_ratio,
        floor_s=settings.min_shear_retardation_s,
    )


def hc_law(spec: ObjectSpec, settings: Settings, reference_m: float | None = None) -> HuntCrossley:
    """The kernels' :class:`~deformctl.sim.step.bundles.HuntCrossley` of ``spec`` (the linear
    :data:`LINEAR_LAW` for a Kelvin object), its step built at ``reference_m``
    (:func:`spec_elements`)."""
    if not spec.hunt_crossley:
        return LINEAR_LAW
    el = spec_elements(spec, settings, reference_m)
    return HuntCrossley(
        spec.stiffness_exponent,
        el.power,
        el.retardation_s,
        el.cap_strain,
        DAMPING_REFERENCE ** (1.0 / spec.stiffness_exponent) * el.reference_m,
        el.cap_strain / el.reference_strain * el.reference_m,
        np.zeros(el.power.shape[0]),
    )
