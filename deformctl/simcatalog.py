"""Catalog rows as simulator objects: the checks ``measure --sim`` and ``lift --sim`` share.

A catalog row describes a real or a simulated object; only rows with *material values*
(``material_stiffness_n_per_cm`` and ``material_damping_ns_per_cm``, the simulator's ground truth
for D and λ) can be simulated. :func:`sim_specs` turns the selected rows into
:class:`~deformctl.sim.ObjectSpec` objects, refusing the first row that cannot be simulated with
one line naming the object, before anything runs.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

import pandas as pd

from deformctl.errors import InputDataError
from deformctl.sim import ObjectSpec, SimSettings

MATERIAL_COLUMNS = ("material_stiffness_n_per_cm", "material_damping_ns_per_cm")


def _missing(value: object) -> bool:
    if value is None:
        return True
    try:
        return not math.isfinite(float(value))  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return True


def sim_spec(obj: Mapping[str, Any], *, path: str | None = None) -> ObjectSpec:
    """The simulator object of one catalog row (a dict or a pandas Series).

    Args:
        obj: the catalog row (paper units; see ``schemas/catalog.columns.json``).
        path: the catalog's name, for the message.

    Raises:
        InputDataError: the row has no material values (a real object: nothing to simulate), or a
            value the simulator cannot use (e.g. ``friction_mu = 0``); the message names the
            object (exit 65).
    """
    oid = str(obj.get("object_id"))
    missing = [c for c in MATERIAL_COLUMNS if _missing(obj.get(c))]
    if missing:
        raise InputDataError(
            f"object {oid!r} has no material values ({', '.join(missing)} empty); "
            "--sim needs material_stiffness_n_per_cm and material_damping_ns_per_cm",
            path=path,
        )
    try:
        return ObjectSpec.from_catalog_row(obj)
    except InputDataError as err:
        raise InputDataError(err.message, path=path) from None


def sim_specs(catalog: pd.DataFrame, *, path: str | None = None) -> list[ObjectSpec]:
    """:func:`sim_spec` of every row, in order (checks all rows before returning)."""
    return [sim_spec(row, path=path) for row in catalog.to_dict("records")]


def settings_dict(settings: SimSettings) -> dict[str, Any]:
    """The simulator settings as a JSON-serialisable dict (for provenance)."""
    return dataclasses.asdict(settings)
