"""The object catalog's columns: the input of ``measure`` and ``lift``, one row per object.

Kept in a module of its own, with no heavy imports, because the simulator, the population
generator and the CLI all name these columns. Units are in the names (cm, N, N/cm, N·s/cm); the
full column spec with dtypes and descriptions is ``schemas/catalog.columns.json``.
"""

from __future__ import annotations

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
