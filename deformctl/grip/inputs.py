"""The rules of a grip model's inputs (W, D, λ, μ), as arrays: the one line for a bad value.

Each rule is its quantity's (:mod:`deformctl.quantities`); :mod:`deformctl.grip.fast` checks
every prediction's inputs with them.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence

import numpy as np

from deformctl.grip.groups import NEGATIVE_DAMPING_TOLERANCE_NS_PER_CM
from deformctl.quantities import (
    DAMPING_NS_PER_CM,
    FRICTION_MU,
    STIFFNESS_N_PER_CM,
    WEIGHT_N,
    Quantity,
)

#: Each input's rule: its quantity's (:mod:`deformctl.quantities`, the one rule every command
#: uses), except that λ down to -0.05 N·s/cm is a fit's noise around 0 and counts as 0
#: (:data:`~deformctl.grip.groups.NEGATIVE_DAMPING_TOLERANCE_NS_PER_CM`).
INPUT_RULES: dict[str, Quantity] = {
    "weight_n": WEIGHT_N,
    "deformability_n_per_cm": STIFFNESS_N_PER_CM,
    "damping_ns_per_cm": dataclasses.replace(
        DAMPING_NS_PER_CM, low=-NEGATIVE_DAMPING_TOLERANCE_NS_PER_CM
    ),
    "friction_mu": FRICTION_MU,
}
#: The largest friction coefficient accepted (:data:`deformctl.quantities.FRICTION_MU`).
MAX_FRICTION_MU = FRICTION_MU.high


def input_rule(col: str) -> str:
    """The rule of input ``col`` in words, e.g. ``must be a number in [0.01, 3]``."""
    if col == "damping_ns_per_cm":
        rule = DAMPING_NS_PER_CM.rule
        return f"must be {rule} (a fitted {INPUT_RULES[col].low:g} counts as 0)"
    return f"must be {INPUT_RULES[col].rule}"


def _bad(rule: Quantity, values: np.ndarray) -> np.ndarray:
    """Where ``values`` break ``rule`` (NaN and infinities too)."""
    with np.errstate(invalid="ignore"):
        low = values <= rule.low if rule.low_open else values < rule.low
        high = values >= rule.high if rule.high_open else values > rule.high
        bad: np.ndarray = ~np.isfinite(values) | low | high
    return bad


def input_problem(col: str, value: float, ids: str) -> str | None:
    """The one line for a bad value of input ``col`` (None when it is fine); the checks are the
    quantities' rules (:data:`INPUT_RULES`), NaN and infinities refused."""
    if not math.isfinite(value):
        return f"{col} is NaN or not a finite number for {ids}"
    if _bad(INPUT_RULES[col], np.asarray([value], dtype=np.float64))[0]:
        return f"{col} {input_rule(col)}; it is {value:g} for {ids}"
    return None


def input_problems(
    values: Mapping[str, np.ndarray], names: Sequence[str] | np.ndarray
) -> list[tuple[str, str]]:
    """``(column, line)`` for every input column with a bad value, naming up to 5 rows
    (:func:`input_problem`'s rule, on arrays)."""
    out: list[tuple[str, str]] = []
    labels = np.asarray(names, dtype=object)
    for col, arr in values.items():
        bad = _bad(INPUT_RULES[col], arr)
        if bad.any():
            first = int(np.flatnonzero(bad)[0])
            line = input_problem(col, float(arr[first]), _ids(labels[bad]))
            assert line is not None
            if not math.isfinite(float(arr[first])):
                line = f"{col} is NaN or not a finite number for {_ids(labels[~np.isfinite(arr)])}"
            out.append((col, line))
    return out


def _ids(labels: np.ndarray, limit: int = 5) -> str:
    items = [str(x) for x in labels]
    shown = ", ".join(items[:limit])
    return f"{shown} and {len(items) - limit} more" if len(items) > limit else shown
