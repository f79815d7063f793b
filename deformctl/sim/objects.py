"""The simulated object: a box with a weight, a friction coefficient and Kelvin material constants.

Sizes are in cm, stiffness in N/cm and damping in N·s/cm (the paper's units at the edge); the
spec keeps those units in its field names and offers SI properties for the physics. A catalog row
becomes a spec through :meth:`deformctl.catalog.CatalogObject.to_sim_spec`: the simulator does not
read catalogs.
"""

from __future__ import annotations

from dataclasses import dataclass

from deformctl.errors import InputDataError
from deformctl.physics import rigid_grip_force_n
from deformctl.quantities import (
    DAMPING_NS_PER_CM,
    FRICTION_MU,
    SIZE_CM,
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
    """

    object_id: str
    size_cm: tuple[float, float, float]
    weight_n: float
    friction_mu: float
    stiffness_n_per_cm: float
    damping_ns_per_cm: float

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
