"""The object catalog: its columns, and one typed, validated :class:`CatalogObject` per row.

A catalog is the input of ``measure --sim`` and ``lift``: one row per object, in the paper's units
(cm, N, N/cm, N·s/cm); the column spec with dtypes and descriptions is
``schemas/catalog.columns.json`` and :func:`deformctl.artifacts.read_catalog` checks a file
against it. This module is the only one that reads a row by its column names: everything else
takes a :class:`CatalogObject` and its typed attributes. Three rules live here and nowhere else:

* parsing a row (a column missing, not a number, not finite, or outside the bounds of its
  quantity, :mod:`deformctl.quantities`): :meth:`CatalogObject.from_row`;
* lifting needs F_w = W / (2 μ): :meth:`CatalogObject.f_w_n`, computed by
  :func:`rigid_grip_force_n` only;
* simulating needs the *material values* (the simulator's ground truth for D and λ, and the
  optional stiffness exponent n, 1 when absent): :meth:`CatalogObject.to_sim_spec`, which turns
  the row into the simulator's :class:`~deformctl.sim.ObjectSpec` (the simulator never sees
  catalog column names). With n > 1, D is the secant stiffness and λ the equivalent damping at
  the operating force F_w (what ``characterize`` writes), and the simulator uses Hunt–Crossley
  springs (:mod:`deformctl.sim.hunt_crossley`). With the optional Maxwell arm
  (``material_arm_stiffness_n_per_cm`` k2 > 0 and ``material_relaxation_time_s`` τ) the material is
  a standard linear solid: D its relaxed spring, λ a dashpot beside the arm (0 for the Zener solid
  ``characterize --model sls`` fits; :mod:`deformctl.sim.sls`).

The module imports nothing heavy (the simulator is imported when a spec is built), because the
population generator, the lift search and the command line all use it.

Example:
    >>> obj = CatalogObject.from_row({"object_id": "A", "size_x_cm": 17.8, "size_y_cm": 19.1,
    ...     "size_z_cm": 9.2, "weight_n": 0.7, "friction_mu": 0.5})
    >>> obj.f_w_n(), obj.has_material
    (0.7, False)
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from deformctl.errors import InputDataError, UsageError
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
    Quantity,
)

if TYPE_CHECKING:  # pragma: no cover - typing only; the simulator is imported when used
    import pandas as pd

    from deformctl.sim import ObjectSpec

#: The stiffness exponent n (optional, after the catalog columns; absent: 1, a linear material).
EXPONENT_COLUMN = "material_stiffness_exponent"
#: A standard linear solid's Maxwell arm (optional): its spring k2 (absent: 0, no arm) and its
#: relaxation time τ (needed when k2 > 0; an empty cell is allowed when k2 is 0).
ARM_COLUMN = "material_arm_stiffness_n_per_cm"
RELAXATION_COLUMN = "material_relaxation_time_s"
#: The law columns' values of an object that is neither Hunt–Crossley nor a standard linear
#: solid (exponent 1, no arm, no relaxation time): a Kelvin–Voigt row, and an absent column's.
KELVIN_VOIGT_LAW_VALUES: dict[str, float] = {
    EXPONENT_COLUMN: 1.0,
    ARM_COLUMN: 0.0,
    RELAXATION_COLUMN: float("nan"),
}
#: The catalog columns, in order; the two material columns are the simulator's ground truth.
CATALOG_COLUMNS: tuple[str, ...] = (
    "object_id",
    "size_x_cm",
    "size_y_cm",
    "size_z_cm",
    "weight_n",
    "friction_mu",
    "material_stiffness_n_per_cm",
    "material_damping_ns_per_cm",
)
SIZE_COLUMNS: tuple[str, str, str] = ("size_x_cm", "size_y_cm", "size_z_cm")
MATERIAL_COLUMNS: tuple[str, str] = ("material_stiffness_n_per_cm", "material_damping_ns_per_cm")

#: The quantity of each numeric column: its rule (:mod:`deformctl.quantities`), in its unit.
COLUMN_QUANTITIES: dict[str, Quantity] = {
    "size_x_cm": SIZE_CM,
    "size_y_cm": SIZE_CM,
    "size_z_cm": SIZE_CM,
    "weight_n": WEIGHT_N,
    "friction_mu": FRICTION_MU,
    "material_stiffness_n_per_cm": STIFFNESS_N_PER_CM,
    "material_damping_ns_per_cm": DAMPING_NS_PER_CM,
    EXPONENT_COLUMN: STIFFNESS_EXPONENT,
    ARM_COLUMN: ARM_STIFFNESS_N_PER_CM,
    RELAXATION_COLUMN: RELAXATION_TIME_S,
}
#: Physical bounds of each numeric column, ``(lowest, highest)``, in the column's unit
#: (inclusive; μ: :data:`deformctl.quantities.FRICTION_MU`, 0.01 <= μ <= 3):
#: what a gripper can hold and the simulator can integrate (:mod:`deformctl.quantities` says why).
#: The catalog spec (``schemas/catalog.columns.json``) states the same numbers as
#: ``minimum``/``maximum``, so every reader refuses an out-of-bounds row before any numerics
#: (tests/fuzz/test_hostile_bounds.py checks the two agree).
BOUNDS: dict[str, tuple[float, float]] = {
    column: (q.low, q.high) for column, q in COLUMN_QUANTITIES.items()
}

__all__ = [
    "ARM_COLUMN",
    "BOUNDS",
    "CATALOG_COLUMNS",
    "COLUMN_QUANTITIES",
    "EXPONENT_COLUMN",
    "MATERIAL_COLUMNS",
    "RELAXATION_COLUMN",
    "SIZE_COLUMNS",
    "CatalogObject",
    "MeasuredObject",
    "catalog_frame",
    "catalog_objects",
    "catalog_row",
    "catalog_weights",
    "check_object_values",
    "object_record",
    "rigid_grip_force_n",
    "select_objects",
]


def _plain(value: Any) -> Any:
    """numpy scalars as Python scalars; NaN and missing values as None."""
    if isinstance(value, np.generic):
        value = value.item()
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return None
    return value


def _absent(row: Mapping[str, Any], key: str) -> bool:
    return key not in row or _plain(row[key]) is None


def _number(row: Mapping[str, Any], key: str, object_id: str) -> float:
    """``row[key]`` as a finite float, or one line naming the object and the column."""
    if key not in row:
        raise InputDataError(f"object {object_id!r}: missing column {key!r}")
    value = row[key]
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InputDataError(f"object {object_id!r}: {key} is not a number: {value!r}") from None
    if not math.isfinite(number):
        raise InputDataError(f"object {object_id!r}: {key} is missing or not finite ({value!r})")
    if key in COLUMN_QUANTITIES:
        COLUMN_QUANTITIES[key].check_data(number, where=f"object {object_id!r}", name=key)
    return number


@dataclass(frozen=True)
class CatalogObject(Mapping[str, Any]):
    """One catalog row, parsed once: typed attributes in the catalog's units.

    It is also a read-only mapping of the row as read (every column, extra ones such as ``name``
    included), so it can be passed wherever a catalog row is expected; :meth:`record` is the
    row with plain values (what a log stores).

    Attributes:
        object_id: the object's unique id.
        size_cm: box size along (x, y, z), cm; x is the squeeze axis, z is up.
        weight_n: weight W, N.
        friction_mu: palm/object Coulomb friction coefficient μ (> 0, see :data:`BOUNDS`).
        material_stiffness_n_per_cm: the simulator's ground-truth D, N/cm, or None (a real
            object).
        material_damping_ns_per_cm: the simulator's ground-truth λ, N·s/cm, or None.
        material_stiffness_exponent: the material's stiffness exponent n in [1, 3] (1 when the
            column is absent: linear).
        material_arm_stiffness_n_per_cm: a standard linear solid's arm spring k2, N/cm (0 when
            the column is absent: no arm).
        material_relaxation_time_s: the arm's relaxation time τ, s (None without an arm).
    """

    object_id: str
    size_cm: tuple[float, float, float]
    weight_n: float
    friction_mu: float
    material_stiffness_n_per_cm: float | None = None
    material_damping_ns_per_cm: float | None = None
    material_stiffness_exponent: float = 1.0
    material_arm_stiffness_n_per_cm: float = 0.0
    material_relaxation_time_s: float | None = None
    row: Mapping[str, Any] = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self) -> None:
        """Check the sizes, W and μ (each its :mod:`deformctl.quantities` rule): a lift and the
        simulator rely on them. (:meth:`from_row` checks every column as it reads it.)

        Raises:
            InputDataError: a value outside its rule, naming the object (exit 65).
        """
        where = f"object {self.object_id!r}"
        for column, value in zip(SIZE_COLUMNS, self.size_cm, strict=True):
            SIZE_CM.check_data(value, where=where, name=column)
        WEIGHT_N.check_data(self.weight_n, where=where)
        FRICTION_MU.check_data(self.friction_mu, where=where)

    @classmethod
    def from_row(cls, row: Mapping[str, Any], *, path: str | None = None) -> CatalogObject:
        """Parse one catalog row (a dict or a pandas Series).

        Args:
            row: the row, keyed by catalog column (see :data:`CATALOG_COLUMNS`); other columns
                are kept in :attr:`row`.
            path: the catalog's name, for the message.

        Raises:
            InputDataError: no ``object_id``, or a size, weight or friction column that is
                missing, not a number, not finite or outside :data:`BOUNDS`, or a
                ``material_stiffness_exponent`` column whose cell is not a number in [1, 3]
                (empty and NaN included: leave the column out for a linear material); one line
                naming the object and the column (exit 65); likewise a
                ``material_arm_stiffness_n_per_cm`` cell, and a ``material_relaxation_time_s``
                cell that is missing with ``k2 > 0`` or not a number in (0, 10⁴] s.
        """
        raw = {str(k): v for k, v in row.items()}
        oid = _plain(raw.get("object_id"))
        if oid is None or str(oid) == "":
            raise InputDataError("catalog row without 'object_id'", path=path)
        object_id = str(oid)
        try:
            size = tuple(_number(raw, c, object_id) for c in SIZE_COLUMNS)
            weight = _number(raw, "weight_n", object_id)
            mu = _number(raw, "friction_mu", object_id)
            kv = KELVIN_VOIGT_LAW_VALUES
            exponent = (
                _number(raw, EXPONENT_COLUMN, object_id)
                if EXPONENT_COLUMN in raw
                else kv[EXPONENT_COLUMN]
            )
            arm = _number(raw, ARM_COLUMN, object_id) if ARM_COLUMN in raw else kv[ARM_COLUMN]
            tau = (
                _number(raw, RELAXATION_COLUMN, object_id)
                if arm > 0.0 or not _absent(raw, RELAXATION_COLUMN)
                else None
            )
        except InputDataError as err:
            raise InputDataError(err.message, path=path) from None
        material = [_plain(raw.get(c)) for c in MATERIAL_COLUMNS]
        stiffness, damping = (
            float(v)
            if isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
            else None
            for v in material
        )
        checked = {  # each value checked as it was read: not again
            "object_id": object_id,
            "size_cm": (size[0], size[1], size[2]),
            "weight_n": weight,
            "friction_mu": mu,
            "material_stiffness_n_per_cm": stiffness,
            "material_damping_ns_per_cm": damping,
            "material_stiffness_exponent": exponent,
            "material_arm_stiffness_n_per_cm": arm,
            "material_relaxation_time_s": tau,
            "row": raw,
        }
        obj = object.__new__(cls)
        for name, value in checked.items():
            object.__setattr__(obj, name, value)
        return obj

    # ---- the row as a read-only mapping

    def __getitem__(self, key: str) -> Any:
        """The value of column ``key`` as read."""
        return self.row[key]

    def __iter__(self) -> Iterator[str]:
        """The column names, in the row's order."""
        return iter(self.row)

    def __len__(self) -> int:
        """The number of columns of the row."""
        return len(self.row)

    def record(self) -> dict[str, Any]:
        """The row with plain values (Python scalars; NaN and missing as None), e.g. for a log."""
        return {key: _plain(value) for key, value in self.row.items()}

    # ---- the rules of each use

    @property
    def has_material(self) -> bool:
        """True when the row has both material values (the object can be simulated)."""
        return (
            self.material_stiffness_n_per_cm is not None
            and self.material_damping_ns_per_cm is not None
        )

    def f_w_n(self) -> float:
        """F_w = W / (2 μ), N, the rigid-object force a lift search starts at (W and μ are
        checked when the object is built)."""
        return rigid_grip_force_n(self.weight_n, self.friction_mu)

    def to_sim_spec(self, *, path: str | None = None) -> ObjectSpec:
        """The simulator's object for this row.

        Raises:
            InputDataError: the row has no material values (a real object: nothing to
                simulate), one of them is missing or not a number, or a value the simulator
                cannot use (e.g. ``friction_mu = 0``); naming the object (exit 65).
        """
        from deformctl.sim import ObjectSpec  # deferred: numba and scipy

        needs = "the simulator needs material_stiffness_n_per_cm and material_damping_ns_per_cm"
        missing = [c for c in MATERIAL_COLUMNS if _absent(self.row, c)]
        if len(missing) == len(MATERIAL_COLUMNS):
            raise InputDataError(
                f"object {self.object_id!r} has no material values ({', '.join(missing)} "
                f"empty); {needs}",
                path=path,
            )
        try:
            stiffness, damping = (_number(self.row, c, self.object_id) for c in MATERIAL_COLUMNS)
            return ObjectSpec.from_checked(  # the row's values were checked as read
                object_id=self.object_id,
                size_cm=self.size_cm,
                weight_n=self.weight_n,
                friction_mu=self.friction_mu,
                stiffness_n_per_cm=stiffness,
                damping_ns_per_cm=damping,
                stiffness_exponent=self.material_stiffness_exponent,
                arm_stiffness_n_per_cm=self.material_arm_stiffness_n_per_cm,
                relaxation_time_s=(
                    math.inf
                    if self.material_relaxation_time_s is None
                    else self.material_relaxation_time_s
                ),
            )
        except InputDataError as err:
            message = err.message if missing == [] else f"{err.message}; {needs}"
            raise InputDataError(message, path=path) from None


def catalog_objects(catalog: pd.DataFrame, *, path: str | None = None) -> list[CatalogObject]:
    """Every row of a catalog as a :class:`CatalogObject`, in order (all parsed before returning).

    Raises:
        InputDataError: see :meth:`CatalogObject.from_row`.
    """
    return [CatalogObject.from_row(rec, path=path) for rec in catalog.to_dict("records")]


def catalog_frame(objects: Sequence[CatalogObject]) -> pd.DataFrame:
    """The rows of ``objects`` as a DataFrame (the inverse of :func:`catalog_objects`)."""
    import pandas as pd

    return pd.DataFrame([obj.record() for obj in objects])


def catalog_weights(catalog: pd.DataFrame) -> dict[str, float]:
    """``object_id`` → ``weight_n`` (N) of every row of a validated catalog (to join weights)."""
    weights = catalog["weight_n"].to_numpy(dtype=np.float64)
    return dict(zip(catalog["object_id"].astype(str), weights.tolist(), strict=True))


def select_objects(catalog: pd.DataFrame, object_ids: Sequence[str] | None) -> pd.DataFrame:
    """The catalog rows of ``object_ids``, in that order (all rows when None).

    Repeated ids are taken once.

    Raises:
        UsageError: an empty list, an empty id, or an id the catalog does not have (exit 2).
    """
    if object_ids is None:
        return catalog.reset_index(drop=True)
    wanted = list(dict.fromkeys(object_ids))
    if not wanted:
        raise UsageError("no object ids given")
    if any(not oid for oid in wanted):
        raise UsageError("an object id is empty")
    known = list(catalog["object_id"])
    unknown = [oid for oid in wanted if oid not in set(known)]
    if unknown:
        shown = ", ".join(known[:10]) + (", ..." if len(known) > 10 else "")
        raise UsageError(f"unknown object id {unknown[0]!r} (the catalog has: {shown})")
    position = {oid: i for i, oid in enumerate(known)}
    return catalog.iloc[[position[oid] for oid in wanted]].reset_index(drop=True)


def check_object_values(
    size_cm: Sequence[float] | None, friction_mu: float | None, weight_n: float | None = None
) -> tuple[float, float, float] | None:
    """The rules of a measured object's values (each :mod:`deformctl.quantities` entry's);
    ``size_cm`` as a tuple. None: not given.

    ``measure --csv`` checks the command line's values with it once, before the files (whose
    ``--objects-from`` rows may override them), so a bad flag gets the same line as elsewhere.

    Raises:
        UsageError: not three sizes, or a value outside its rule (exit 2).
    """
    WEIGHT_N.check_optional(weight_n)
    FRICTION_MU.check_optional(friction_mu)
    if size_cm is None:
        return None
    if len(size_cm) != 3:
        raise UsageError(f"--size-cm takes three sizes (x, y, z), got {list(size_cm)}")
    x, y, z = (SIZE_CM.check(v) for v in size_cm)
    return (x, y, z)


@dataclass(frozen=True)
class MeasuredObject:
    """An object measured on a rig (``measure --bag/--csv/--images``), checked when built.

    Attributes:
        object_id: its id, non-empty.
        weight_n: weight W, N (:data:`deformctl.quantities.WEIGHT_N`).
        size_cm: ``(x, y, z)`` size, cm, each :data:`deformctl.quantities.SIZE_CM`; x is the
            squeeze axis. None: not known.
        friction_mu: palm–object friction μ (:data:`deformctl.quantities.FRICTION_MU`), or None.

    Raises:
        UsageError: an empty id or a value outside its rule (these come from flags; exit 2).
    """

    object_id: str
    weight_n: float
    size_cm: tuple[float, float, float] | None = None
    friction_mu: float | None = None

    def __post_init__(self) -> None:
        if not self.object_id or not self.object_id.strip():
            raise UsageError("--object-id must not be empty")
        WEIGHT_N.check(self.weight_n)
        object.__setattr__(self, "size_cm", check_object_values(self.size_cm, self.friction_mu))

    @property
    def size_x_cm(self) -> float | None:
        """The size along the squeeze axis, cm (None when not known)."""
        return None if self.size_cm is None else self.size_cm[0]

    def record(self) -> dict[str, object]:
        """The catalog-like row a squeeze log stores for it (see :func:`object_record`)."""
        row: dict[str, object] = {"object_id": self.object_id, "weight_n": float(self.weight_n)}
        if self.size_cm is not None:
            for column, value in zip(SIZE_COLUMNS, self.size_cm, strict=True):
                row[column] = float(value)
        if self.friction_mu is not None:
            row["friction_mu"] = float(self.friction_mu)
        return row


def object_record(
    object_id: str,
    weight_n: float,
    *,
    size_cm: Sequence[float] | None = None,
    friction_mu: float | None = None,
    force_rate_hz: float | None = None,
    position_rate_hz: float | None = None,
) -> dict[str, object]:
    """The catalog-like row a squeeze log stores for a measured (not catalogued) object.

    Keys: ``object_id``, ``weight_n``; ``size_x_cm``, ``size_y_cm``, ``size_z_cm`` and
    ``friction_mu`` when given; ``force_rate_hz`` and ``position_rate_hz`` (the source streams'
    sample rates, which ``characterize`` uses to choose its differentiation window) when known.

    Args:
        object_id: catalog id, non-empty.
        weight_n, size_cm, friction_mu: as :class:`MeasuredObject`, which checks them.
        force_rate_hz: force stream sample rate, Hz.
        position_rate_hz: position stream sample rate, Hz.

    Raises:
        UsageError: an empty id or a value out of range (these come from command-line flags).
    """
    size = (
        None
        if size_cm is None
        else (size_cm[0], size_cm[1], size_cm[2])
        if len(size_cm) == 3
        else tuple(size_cm)
    )
    row = MeasuredObject(object_id, weight_n, size, friction_mu).record()  # type: ignore[arg-type]
    if force_rate_hz is not None:
        row["force_rate_hz"] = float(force_rate_hz)
    if position_rate_hz is not None:
        row["position_rate_hz"] = float(position_rate_hz)
    return row


def catalog_row(
    object_id: str,
    size_cm: Sequence[float],
    weight_n: float,
    friction_mu: float | None = None,
) -> dict[str, object]:
    """A new catalog row for a measured object, in catalog column order (sizes to 0.01 cm).

    Returns:
        ``{"object_id", "size_x_cm", "size_y_cm", "size_z_cm", "weight_n"}`` plus
        ``"friction_mu"`` when given.

    Raises:
        UsageError: an empty id, or a weight or friction outside its rule (as
            :class:`MeasuredObject`).
    """
    MeasuredObject(object_id, weight_n, friction_mu=friction_mu)
    row: dict[str, object] = {"object_id": object_id}
    for column, value in zip(SIZE_COLUMNS, size_cm, strict=True):
        row[column] = round(float(value), 2)
    row["weight_n"] = float(weight_n)
    if friction_mu is not None:
        row["friction_mu"] = float(friction_mu)
    return row
