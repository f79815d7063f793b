"""The force ceiling of a lift: no grip force above it is ever requested.

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

Over all of them sits the rig's **absolute limit** (:func:`absolute_limit`): the maximum force the
rig states in its handshake (docs/rig-protocol.md), or :data:`DEFAULT_ABSOLUTE_MAX_FORCE_N` for a
rig that states none. No request exceeds ``min(ceiling, absolute limit)``: ``--max-force-n`` and a
catalog's ``max_force_n`` can lower the limit, never raise it. An object whose F_w is above it
gets "no safe grip" without an attempt. The simulator has no hardware to protect and no absolute
limit.

Why 500 N: the strongest electric parallel grippers sold for robot arms close with a few hundred
newtons at most (Robotiq 2F-85: 235 N, Franka Hand: 140 N peak); twice that is more than a
gripper that did not say otherwise can give, and far below the kilonewtons a unit or catalog
mistake asks for. A rig that can and may squeeze harder states its maximum in the handshake.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from deformctl.errors import InputDataError
from deformctl.quantities import MAX_FORCE_N, MAX_LIFT_RATIO

__all__ = [
    "CEILING_COLUMN",
    "DEFAULT_ABSOLUTE_MAX_FORCE_N",
    "DEFAULT_CEILING_RATIO",
    "SAFE_FORCE_COLUMNS",
    "ForceCeiling",
    "absolute_limit",
    "force_ceiling",
]

#: The default ceiling, in multiples of the object's F_w (module doc).
DEFAULT_CEILING_RATIO = MAX_LIFT_RATIO
#: The absolute limit of a rig that states none in a handshake, N (module doc).
DEFAULT_ABSOLUTE_MAX_FORCE_N = 500.0
#: :attr:`ForceCeiling.source` of an absolute limit the rig stated / the default one.
HANDSHAKE_SOURCE = "rig handshake"
ABSOLUTE_DEFAULT_SOURCE = "absolute default"
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
            HANDSHAKE_SOURCE: "the maximum force the rig stated",
            ABSOLUTE_DEFAULT_SOURCE: "the absolute limit of a rig that states none",
        }.get(self.source, f"the object's {self.source}")
        return f"force ceiling {self.max_force_n:.6g} N ({why})"


def absolute_limit(rig_max_force_n: float | None) -> ForceCeiling:
    """A rig's absolute limit: the maximum force it stated in its handshake (a finite number
    > 0, N), or :data:`DEFAULT_ABSOLUTE_MAX_FORCE_N` when it stated none (None).

    Raises:
        UsageError: a stated maximum that is not a finite number > 0 (exit 2).
    """
    if rig_max_force_n is None:
        return ForceCeiling(DEFAULT_ABSOLUTE_MAX_FORCE_N, ABSOLUTE_DEFAULT_SOURCE)
    value = MAX_FORCE_N.check(rig_max_force_n, label="the rig's max_force_n")
    return ForceCeiling(value, HANDSHAKE_SOURCE)


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
    absolute: ForceCeiling | None = None,
) -> ForceCeiling:
    """The ceiling of one object (module doc for the order), never above ``absolute``.

    Args:
        object_id: the object, for messages.
        f_w_n: its F_w, N.
        row: its catalog row (``max_force_n``, and safe-force columns when present).
        max_force_n: ``--max-force-n``, N (checked where it was given:
            :class:`~deformctl.lift.options.SearchOptions`), or None.
        coefficients: its coefficients row (``rupture_force_n`` / ``yield_force_n``), or None.
        path: the catalog's name, for messages.
        absolute: the runner's absolute limit (:func:`absolute_limit`; None: none, the
            simulator); the result is the smaller of it and the object's own ceiling.

    Raises:
        InputDataError: the catalog's ``max_force_n`` for the object breaks the rule of
            :data:`~deformctl.quantities.MAX_FORCE_N` (exit 65, naming the object).
    """
    own = _own_ceiling(object_id, f_w_n, row or {}, max_force_n, coefficients, path)
    if absolute is not None and absolute.max_force_n < own.max_force_n:
        return absolute
    return own


def _own_ceiling(
    object_id: str,
    f_w_n: float,
    row: Mapping[str, Any],
    max_force_n: float | None,
    coefficients: Mapping[str, Any] | None,
    path: str | None,
) -> ForceCeiling:
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
    if max_force_n is not None:  # checked once, by SearchOptions
        return ForceCeiling(float(max_force_n), "--max-force-n")
    ceiling = ForceCeiling(DEFAULT_CEILING_RATIO * f_w_n, "default")
    for source in (coefficients or {}, row):
        for column in SAFE_FORCE_COLUMNS:
            safe = _number(source.get(column))
            if safe is not None and 0 < safe < ceiling.max_force_n and math.isfinite(safe):
                ceiling = ForceCeiling(safe, column)
    return ceiling
