"""The simulated object: a box with a weight, a friction coefficient and its material law.

The material is Kelvin–Voigt (``f = D d + λ ḋ`` between the palms) or, with a stiffness exponent
``n > 1``, Hunt–Crossley (``f = k dⁿ + λ_hc dⁿ ḋ``). A Hunt–Crossley object is given as a catalog
gives it: D is the *secant* stiffness at the operating force ``F_op = F_w = W / (2 μ)`` (what
``characterize`` writes as ``deformability_n_per_cm`` by default) and λ the equivalent damping
``λ_hc d_opⁿ`` at the operating compression ``d_op = F_op / D``; so ``k = F_op / d_opⁿ`` and
``λ_hc = λ / d_opⁿ`` (:attr:`ObjectSpec.hc_stiffness_n_per_m_pow_n`,
:attr:`ObjectSpec.hc_damping_ns_per_m_pow_n_plus_1`). As n → 1 the elastic law tends to the
Kelvin–Voigt one (``k → D``), the damping does not: ``λ_hc dⁿ ḋ → λ (d / d_op) ḋ``, λ at the
operating compression only (n = 1 itself is the Kelvin–Voigt object).

With an arm stiffness ``k2 > 0`` the material is a standard linear solid (Zener): D is its
relaxed spring, and a Maxwell arm (``k2`` in series with a dashpot ``k2 τ``) acts beside it and
beside the dashpot λ (0 for the Zener solid ``characterize --model sls`` fits):
``f = D d + λ ḋ + σ``, ``σ̇ = k2 ḋ − σ/τ`` (:mod:`deformctl.sim.sls`). A material is
Hunt–Crossley or a standard linear solid, not both.

Sizes are in cm, stiffness in N/cm and damping in N·s/cm (the paper's units at the edge); the
spec keeps those units in its field names and offers SI properties for the physics. A catalog row
becomes a spec through :meth:`deformctl.catalog.CatalogObject.to_sim_spec`: the simulator does not
read catalogs.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

from deformctl.errors import InputDataError
from deformctl.physics import rigid_grip_force_n
from deformctl.quantities import (
    ARM_STIFFNESS_N_PER_CM,
    DAMPING_NS_PER_CM,
    FRICTION_MU,
    RELAXATION_TIME_S,
    SIZE_CM,
    STIFFNESS_EXPONENT,
    STIFFNESS_N_PER_CM,
    WEIGHT_N,
)
from deformctl.units import CM, GRAVITY_M_S2, N_PER_CM, NS_PER_CM


@dataclass(frozen=True)
class ObjectSpec:
    """One box-shaped deformable object.

    Attributes:
        object_id: catalog id.
        size_cm: box size along (x, y, z), cm; x is the squeeze axis, z is up.
        weight_n: weight W, N (mass W/g).
        friction_mu: Coulomb friction coefficient between the palms and the object (static =
            kinetic).
        stiffness_n_per_cm: the object's squeeze stiffness D between the palms, N/cm.
        damping_ns_per_cm: the object's squeeze damping lambda between the palms, N·s/cm.
        stiffness_exponent: n in [1, 3]: 1 (default) a Kelvin–Voigt object; above 1 a
            Hunt–Crossley object whose D and lambda are stated at the operating force (see the
            module docs).
        arm_stiffness_n_per_cm: k2, the Maxwell arm's spring, N/cm: 0 (default) no arm; above 0
            a standard linear solid (see the module docs).
        relaxation_time_s: τ, the arm's relaxation time, s (``inf``, the default: the arm, if
            any, is a spring).
    """

    object_id: str
    size_cm: tuple[float, float, float]
    weight_n: float
    friction_mu: float
    stiffness_n_per_cm: float
    damping_ns_per_cm: float
    stiffness_exponent: float = 1.0
    arm_stiffness_n_per_cm: float = 0.0
    relaxation_time_s: float = math.inf

    def __post_init__(self) -> None:
        where = f"object {self.object_id!r}"
        size = tuple(float(s) for s in self.size_cm)
        if len(size) != 3:
            raise InputDataError(f"{where}: size must be three lengths (cm)")
        for axis, value in zip("xyz", size, strict=True):
            SIZE_CM.check_data(value, where=where, name=f"size {axis}")
        object.__setattr__(self, "size_cm", size)
        # each quantity's one rule (deformctl.quantities): the catalog's bounds
        WEIGHT_N.check_data(float(self.weight_n), where=where)
        FRICTION_MU.check_data(float(self.friction_mu), where=where)
        STIFFNESS_N_PER_CM.check_data(float(self.stiffness_n_per_cm), where=where)
        DAMPING_NS_PER_CM.check_data(float(self.damping_ns_per_cm), where=where)
        STIFFNESS_EXPONENT.check_data(float(self.stiffness_exponent), where=where)
        ARM_STIFFNESS_N_PER_CM.check_data(float(self.arm_stiffness_n_per_cm), where=where)
        if not math.isinf(float(self.relaxation_time_s)):
            RELAXATION_TIME_S.check_data(float(self.relaxation_time_s), where=where)
        elif self.relaxation_time_s < 0:
            raise InputDataError(f"{where}: a relaxation time must be > 0 s")
        self._check_one_law()

    @classmethod
    def from_checked(cls, **values: Any) -> ObjectSpec:
        """An object from values each already checked against its rule (a catalog row's, read
        by :meth:`deformctl.catalog.CatalogObject.to_sim_spec`): only the rule between them,
        one material law, is checked; an absent field takes its default.

        Raises:
            InputDataError: a Hunt–Crossley material with a Maxwell arm (exit 65).
        """
        spec = object.__new__(cls)
        for f in dataclasses.fields(cls):
            object.__setattr__(spec, f.name, values.pop(f.name, f.default))
        if values:
            raise TypeError(f"ObjectSpec has no field {next(iter(values))!r}")
        spec._check_one_law()
        return spec

    def _check_one_law(self) -> None:
        if self.hunt_crossley and self.standard_linear_solid:
            raise InputDataError(
                f"object {self.object_id!r}: a material is Hunt–Crossley (stiffness exponent "
                f"{self.stiffness_exponent:g}) or a standard linear solid (arm stiffness "
                f"{self.arm_stiffness_n_per_cm:g} N/cm), not both"
            )

    @property
    def size_m(self) -> tuple[float, float, float]:
        """Box size (x, y, z), m."""
        return (self.size_cm[0] * CM, self.size_cm[1] * CM, self.size_cm[2] * CM)

    @property
    def mass_kg(self) -> float:
        """Mass W/g, kg."""
        return self.weight_n / GRAVITY_M_S2

    @property
    def stiffness_n_per_m(self) -> float:
        """Squeeze stiffness D, N/m."""
        return self.stiffness_n_per_cm * N_PER_CM

    @property
    def damping_ns_per_m(self) -> float:
        """Squeeze damping lambda, N·s/m."""
        return self.damping_ns_per_cm * NS_PER_CM

    @property
    def hunt_crossley(self) -> bool:
        """Whether the material stiffens (``n > 1``: Hunt–Crossley springs in the lattice)."""
        return self.stiffness_exponent != 1.0

    @property
    def standard_linear_solid(self) -> bool:
        """Whether the material relaxes (``k2 > 0``: Maxwell arms in the lattice)."""
        return self.arm_stiffness_n_per_cm > 0.0

    @property
    def operating_force_n(self) -> float:
        """F_op, the force D and lambda are stated at: F_w = W / (2 mu), N."""
        return f_w_n(self)

    @property
    def operating_compression_m(self) -> float:
        """d_op = F_op / D, the compression at the operating force, m."""
        return self.operating_force_n / self.stiffness_n_per_m

    @property
    def hc_stiffness_n_per_m_pow_n(self) -> float:
        """Hunt–Crossley k = F_op / d_opⁿ, N/mⁿ (D itself when n = 1)."""
        return self.operating_force_n / self.operating_compression_m**self.stiffness_exponent

    @property
    def hc_damping_ns_per_m_pow_n_plus_1(self) -> float:
        """Hunt–Crossley lambda_hc = lambda / d_opⁿ, N·s/m^(n+1) (not lambda at n = 1: the
        damper ``lambda_hc d ḋ`` there is lambda at d_op only)."""
        return self.damping_ns_per_m / self.operating_compression_m**self.stiffness_exponent

    def elastic_force_n(self, compression_m: float) -> float:
        """The rate-free squeeze force at a compression, N: ``D d`` or ``k dⁿ``."""
        d = max(float(compression_m), 0.0)
        if not self.hunt_crossley:
            return self.stiffness_n_per_m * d
        return self.hc_stiffness_n_per_m_pow_n * d**self.stiffness_exponent


def f_w_n(spec: ObjectSpec) -> float:
    """Quasi-static lifting force per palm of a rigid object, W/(2 mu), N.

    :func:`deformctl.physics.rigid_grip_force_n` of the spec's weight and friction.
    """
    return rigid_grip_force_n(spec.weight_n, spec.friction_mu)
