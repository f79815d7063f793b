"""What ``lift`` lifts: a catalog, or a coefficients table whose objects carry their own values.

:func:`read_lift_objects` reads either. A coefficients table from ``characterize``
carries each object's weight, size and μ as the squeeze log recorded them; as a catalog its
measured D and λ become the object's material (``material_stiffness_n_per_cm``,
``material_damping_ns_per_cm``), so ``lift coefficients.parquet --sim`` lifts, in the simulator,
the object that was measured: what a user checks a prediction against before the rig. They are
kept as ``deformability_n_per_cm`` and ``damping_ns_per_cm`` too, what ``--start-model``
predicts from (:func:`deformctl.lift.seeded.object_features`), on the rig as in the simulator.
An object whose chosen law is Hunt–Crossley (``model`` ``hc``) becomes a Hunt–Crossley material
(``material_stiffness_exponent`` = ``hc_exponent``) with its D and λ restated at F_w = W/(2μ),
where the catalog states them (:mod:`deformctl.sim.hunt_crossley`), whatever force
``characterize`` stated them at. An object whose chosen law is the standard linear solid
(``model`` ``sls``) becomes one: D its relaxed spring ``sls_stiffness_n_per_cm``, the Maxwell arm
``sls_arm_stiffness_n_per_cm`` and ``sls_relaxation_time_s``, and no dashpot beside it (λ = 0:
the fitted law has none; :mod:`deformctl.sim.sls`).

Example:
    >>> import pandas as pd
    >>> table = pd.DataFrame({"object_id": ["A"], "deformability_n_per_cm": [30.0],
    ...     "damping_ns_per_cm": [0.5], "weight_n": [2.9], "size_x_cm": [6.0],
    ...     "size_y_cm": [6.0], "size_z_cm": [8.0], "friction_mu": [0.6]})
    >>> row = catalog_from_coefficients(table).iloc[0]
    >>> row["material_stiffness_n_per_cm"], row["weight_n"]
    (30.0, 2.9)
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from deformctl.artifacts.io import display_name, read_input_bytes
from deformctl.catalog import (
    ARM_COLUMN,
    EXPONENT_COLUMN,
    KELVIN_VOIGT_LAW_VALUES,
    MATERIAL_COLUMNS,
    RELAXATION_COLUMN,
    SIZE_COLUMNS,
)
from deformctl.errors import InputDataError, SchemaError
from deformctl.physics import rigid_grip_force_n

__all__ = ["OBJECT_FLAGS", "catalog_from_coefficients", "read_lift_objects"]

#: Each catalog value a coefficients table must carry to be lifted, and the ``measure`` flag that
#: records it in the squeeze log (and so, through ``characterize``, in the table).
OBJECT_FLAGS: dict[str, str] = {
    **dict.fromkeys(SIZE_COLUMNS, "--size-cm"),
    "weight_n": "--weight-n",
    "friction_mu": "--friction-mu",
}
_MEASURED = ("deformability_n_per_cm", "damping_ns_per_cm")
_MATERIAL = dict(zip(_MEASURED, MATERIAL_COLUMNS, strict=True))


def catalog_from_coefficients(table: pd.DataFrame, path: str | None = None) -> pd.DataFrame:
    """The catalog rows of a coefficients table's objects (measured D and λ as their material).

    Raises:
        InputDataError: an object without one of :data:`OBJECT_FLAGS`' values (the column
            missing, or NaN for some objects), naming the column, the objects and the
            ``measure`` flag that records it (exit 65).
    """
    from deformctl.table import format_ids

    ids = table["object_id"].astype(str)
    out = pd.DataFrame({"object_id": ids})
    for column, flag in OBJECT_FLAGS.items():
        values = (
            pd.to_numeric(table[column], errors="coerce").to_numpy(dtype=np.float64)
            if column in table.columns
            else np.full(len(table), math.nan)
        )
        bad = ~(np.isfinite(values) & (values > 0))
        if bad.any():
            raise InputDataError(
                f"{column} is missing for {format_ids(ids[bad])}: a coefficients table lifts "
                f"only objects whose squeeze log recorded it (measure {flag}, or a catalog "
                "with it to measure sim)",
                path=path,
            )
        out[column] = values
    for measured, material in _MATERIAL.items():
        values = pd.to_numeric(table[measured], errors="coerce").to_numpy(dtype=np.float64)
        out[material] = values
        out[measured] = values  # what a start model predicts from, with a rig too
    _hunt_crossley_material(table, out)
    _standard_linear_solid_material(table, out)
    return out


def _hunt_crossley_material(table: pd.DataFrame, out: pd.DataFrame) -> None:
    """The Hunt–Crossley objects' material in ``out``: ``material_stiffness_exponent`` = n, and
    D and λ at F_w from the fitted ``k`` (N/cmⁿ) and ``λ_hc`` (N·s/cmⁿ⁺¹):
    ``d_w = (F_w / k)^(1/n)``, ``D = F_w / d_w``, ``λ = λ_hc d_wⁿ`` (nothing when no object's law
    is ``hc``)."""
    needed = {"model", "hc_exponent", "hc_stiffness_n_per_cm_pow_n"}
    if not needed <= set(table.columns):
        return
    hc = (table["model"].astype(str) == "hc").to_numpy()
    if not hc.any():
        return

    def column(name: str) -> np.ndarray:
        if name not in table.columns:
            return np.full(len(table), math.nan)
        return pd.to_numeric(table[name], errors="coerce").to_numpy(dtype=np.float64)

    n, k = column("hc_exponent"), column("hc_stiffness_n_per_cm_pow_n")
    lam = column("hc_damping_ns_per_cm_pow_n_plus_1")
    f_w = np.asarray(
        rigid_grip_force_n(
            out["weight_n"].to_numpy(np.float64), out["friction_mu"].to_numpy(np.float64)
        )
    )
    with np.errstate(divide="ignore", invalid="ignore"):
        d_w = (f_w / k) ** (1.0 / n)
        out[MATERIAL_COLUMNS[0]] = np.where(hc, f_w / d_w, out[MATERIAL_COLUMNS[0]])
        out[MATERIAL_COLUMNS[1]] = np.where(hc, lam * d_w**n, out[MATERIAL_COLUMNS[1]])
    out[EXPONENT_COLUMN] = np.where(hc, n, KELVIN_VOIGT_LAW_VALUES[EXPONENT_COLUMN])


def _standard_linear_solid_material(table: pd.DataFrame, out: pd.DataFrame) -> None:
    """The standard linear solids' material in ``out``: D = ``sls_stiffness_n_per_cm``, λ = 0,
    ``material_arm_stiffness_n_per_cm`` and ``material_relaxation_time_s`` from the fit (0 and
    empty for the other objects; nothing when no object's law is ``sls``)."""
    needed = {"model", "sls_stiffness_n_per_cm", "sls_arm_stiffness_n_per_cm"}
    if not needed <= set(table.columns) or "sls_relaxation_time_s" not in table.columns:
        return
    sls = (table["model"].astype(str) == "sls").to_numpy()
    if not sls.any():
        return

    def column(name: str) -> np.ndarray:
        return pd.to_numeric(table[name], errors="coerce").to_numpy(dtype=np.float64)

    out[MATERIAL_COLUMNS[0]] = np.where(
        sls, column("sls_stiffness_n_per_cm"), out[MATERIAL_COLUMNS[0]]
    )
    out[MATERIAL_COLUMNS[1]] = np.where(sls, 0.0, out[MATERIAL_COLUMNS[1]])
    kv = KELVIN_VOIGT_LAW_VALUES
    out[ARM_COLUMN] = np.where(sls, column("sls_arm_stiffness_n_per_cm"), kv[ARM_COLUMN])
    out[RELAXATION_COLUMN] = np.where(sls, column("sls_relaxation_time_s"), kv[RELAXATION_COLUMN])


def read_lift_objects(path: str) -> pd.DataFrame:
    """The objects to lift from ``path``: a catalog (CSV or Parquet; ``-`` for stdin), or a
    coefficients table (:func:`catalog_from_coefficients`), validated as a catalog.

    Raises:
        MissingInputError: ``path`` does not exist (exit 66).
        InputDataError, SchemaError: not a catalog nor a coefficients table, or an object
            without a value it needs (exit 65).
    """
    from deformctl.artifacts.schema import validate_frame
    from deformctl.artifacts.tables import (
        PARQUET_MAGIC,
        _frame_from_arrow,
        read_catalog_bytes,
        read_parquet_bytes,
    )

    data = read_input_bytes(path)
    name = display_name(path)
    if data[:4] == PARQUET_MAGIC:
        arrow, meta = read_parquet_bytes(data, path)
        if meta is not None and meta.get("kind") == "coefficients":
            table = _frame_from_arrow(arrow, meta, "coefficients", path)
            if len(table) == 0:
                raise InputDataError("the coefficients table holds no objects", path=name)
            catalog = validate_frame(catalog_from_coefficients(table, name), "catalog", path=name)
            catalog.attrs = {"kind": "catalog", "from": "coefficients"}
            return catalog
        if meta is not None and meta.get("kind") not in ("catalog", None):
            raise SchemaError(
                f"is a {meta.get('kind')} table; lift reads a catalog or a coefficients table",
                path=name,
            )
    return read_catalog_bytes(data, path)
