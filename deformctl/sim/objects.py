"""The simulated object: a box with a weight, a friction coefficient and Kelvin material constants.

Sizes are in cm, stiffness in N/cm and damping in N·s/cm (the paper's units at the edge); the
spec keeps those units in its field names and offers SI properties for the physics. A catalog row
becomes a spec through :meth:`deformctl.catalog.CatalogObject.to_sim_spec`: the simulator does not
read catalogs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from deformctl.errors import InputDataError
from deformctl.physics import rigid_grip_force_n
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
    """

    object_id: str
    size_cm: tuple[float, float, float]
    weight_n: float
    friction_mu: float
    stiffness_n_per_cm: float
    damping_ns_per_cm: float

    def __post_init__(self) -> None:
        oid = self.object_id
        size = tuple(float(s) for s in self.size_cm)
        if len(size) != 3 or not all(math.isfinite(s) and s > 0 for s in size):
            raise InputDataError(f"object {oid!r}: size must be three positive lengths (cm)")
        object.__setattr__(self, "size_cm", size)
        checks = (
            ("weight_n", self.weight_n, False),
            ("friction_mu", self.friction_mu, False),
            ("stiffness_n_per_cm", self.stiffness_n_per_cm, False),
            ("damping_ns_per_cm", self.damping_ns_per_cm, True),
        )
        for name, value, zero_ok in checks:
            v = float(value)
            if not math.isfinite(v) or v < 0 or (v == 0 and not zero_ok):
                need = ">= 0" if zero_ok else "> 0"
                raise InputDataError(f"object {oid!r}: {name} must be finite and {need}, got {v}")

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
    def retardation_time_s(self) -> float:
        """Kelvin–Voigt retardation time lambda/D, s."""
        return self.damping_ns_per_cm / self.stiffness_n_per_cm


def f_w_n(spec: ObjectSpec) -> float:
    """Quasi-static lifting force per palm of a rigid object, W/(2 mu), N.

    :func:`deformctl.physics.rigid_grip_force_n` of the spec's weight and friction.
    """
    return rigid_grip_force_n(spec.weight_n, spec.friction_mu)
