"""The force ceiling of a lift: no grip force above it is ever requested (issue 34 point 4).

Each object's ceiling, N, is the first of:

1. the catalog's ``max_force_n`` for the object (a column a user adds per object);
2. ``lift --max-force-n`` (one value for every object);
3. the default, :data:`DEFAULT_CEILING_RATIO` × F_w, lowered to the object's safe force when one
   is known (``rupture_force_n`` or ``yield_force_n`` from ``characterize``'s coefficients, in
   the catalog or the ``--coefficients`` table): squeezing harder than that breaks the object.

Why 10 × F_w: the lifting force of a deformable object is L_f = F_w + F_d; in the simulated
population L_f / F_w is about 2 for an undamped object and falls with damping
(docs/explanation/model.md), and the paper's measured objects lie below 2. A search that needs
five times the largest ratio seen is a unit or catalog mistake (a weight in grams, a μ of
0.005), not an object, and must not turn into a grip of kilonewtons. A search that would need
more than its ceiling stops with "no safe grip" for that object; a seeded start above it is
clamped to it (a warning says so); the rig request carries ``max_force_n`` so the driver can
enforce it too (docs/rig-protocol.md).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, cast, overload

from deformctl.errors import InputDataError
from deformctl.quantities import MAX_FORCE_N, MAX_LIFT_RATIO

__all__ = [
    "CEILING_COLUMN",
    "DEFAULT_CEILING_RATIO",
    "SAFE_FORCE_COLUMNS",
    "ForceCeiling",
    "force_ceiling",
    "validate_max_force",
]

#: The default ceiling, in multiples of the object's F_w (module doc).
DEFAULT_CEILING_RATIO = MAX_LIFT_RATIO
#: The catalog column that sets one object's ceiling, N.
CEILING_COLUMN = "max_force_n"
#: Coefficient columns holding a force the object does not survive, N (``characterize``).
SAFE_FORCE_COLUMNS = ("rupture_force_n", "yield_force_n")


@dataclass(frozen=True)
class ForceCeiling:
    """One object's ceiling and where it comes from.

    Attributes:
        max_force_n: the largest grip force any attempt may request, N.
        source: ``"catalog"``, ``"--max-force-n"``, ``"default"`` (10 × F_w) or the safe-force
            column that lowered the default (``"rupture_force_n"``, ``"yield_force_n"``).
    """

    max_force_n: float
    source: str

    def describe(self) -> str:
        """e.g. ``"force ceiling 52.3 N (10 x F_w)"``, for messages."""
        why = {
            "catalog": "the catalog's max_force_n",
            "--max-force-n": "--max-force-n",
            "default": f"{DEFAULT_CEILING_RATIO:g} x F_w",
        }.get(self.source, f"the object's {self.source}")
        return f"force ceiling {self.max_force_n:.6g} N ({why})"


@overload
def validate_max_force(value: None, what: str = ...) -> None: ...
@overload
def validate_max_force(value: float, what: str = ...) -> float: ...
def validate_max_force(value: Any, what: str = MAX_FORCE_N.flag) -> float | None:
    """``value`` as a ceiling, N, under the one rule of :data:`~deformctl.quantities.MAX_FORCE_N`
    (a finite number > 0; None passes: no ceiling given).

    Raises:
        UsageError: it is not (``what`` names the flag; exit 2).
    """
    return cast(float | None, MAX_FORCE_N.check_optional(value, label=what))


def _number(value: Any) -> float | None:
    if value is None or isinstance(value, bool | str):
        return None
    try:
        number = float(value)
    except (TypeError, ValueError):
        return None
    return None if math.isnan(number) else number


def force_ceiling(
    object_id: str,
    f_w_n: float,
    *,
    row: Mapping[str, Any] | None = None,
    max_force_n: float | None = None,
    coefficients: Mapping[str, Any] | None = None,
    path: str | None = None,
) -> ForceCeiling:
    """The ceiling of one object (module doc for the order).

    Args:
        object_id: the object, for messages.
        f_w_n: its F_w, N.
        row: its catalog row (``max_force_n``, and safe-force columns when present).
        max_force_n: ``--max-force-n``, N, or None.
        coefficients: its coefficients row (``rupture_force_n`` / ``yield_force_n``), or None.
        path: the catalog's name, for messages.

    Raises:
        InputDataError: the catalog's ``max_force_n`` for the object breaks the rule of
            :data:`~deformctl.quantities.MAX_FORCE_N` (exit 65, naming the object).
    """
    row = row or {}
    if CEILING_COLUMN in row:
        raw = row[CEILING_COLUMN]
        if raw is not None and not (isinstance(raw, float) and math.isnan(raw)):
            value = _number(raw)
            where = f"object {object_id!r}"
            if value is None:  # not a number at all: the rule's words, with the text given
                raise InputDataError(
                    f"{where}: {CEILING_COLUMN} {MAX_FORCE_N.problem(raw)}", path=path
                )
            return ForceCeiling(MAX_FORCE_N.check_data(value, where=where, path=path), "catalog")
    if max_force_n is not None:
        return ForceCeiling(validate_max_force(max_force_n, "--max-force-n"), "--max-force-n")
    ceiling = ForceCeiling(DEFAULT_CEILING_RATIO * f_w_n, "default")
    for source in (coefficients or {}, row):
        for column in SAFE_FORCE_COLUMNS:
            safe = _number(source.get(column))
            if safe is not None and 0 < safe < ceiling.max_force_n and math.isfinite(safe):
                ceiling = ForceCeiling(safe, column)
    return ceiling
