"""The lifting-force search's options, checked once: :class:`SearchOptions`.

The ``lift`` command builds a :class:`SearchOptions` from ``--protocol``, ``--growth``,
``--tolerance``, ``--max-attempts`` and ``--max-force-n``; the stage
(:func:`deformctl.lift.stage.lift_catalog`), the sweep task
(:class:`deformctl.lift.runners.sim.LiftTask`) and each object's search take it, and
:meth:`SearchOptions.as_dict` is what the outputs' provenance records. Each number's rule is its
:mod:`deformctl.quantities` entry.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

from deformctl.errors import UsageError
from deformctl.quantities import GROWTH, MAX_ATTEMPTS, MAX_FORCE_N, TOLERANCE_REL

SearchProtocol = Literal["refine", "paper", "seeded"]
#: The protocols ``lift --protocol`` chooses from; ``seeded`` is chosen by a start force
#: (:func:`~deformctl.lift.search.find_min_lift_force_seeded`, ``lift --start-model`` /
#: ``--start-table``).
PROTOCOLS: tuple[SearchProtocol, ...] = ("refine", "paper")

DEFAULT_GROWTH = 1.2  #: the paper's +20 % per attempt
DEFAULT_TOLERANCE_REL = 0.005  #: refine stops when (high - low) / high <= 0.5 %
DEFAULT_MAX_ATTEMPTS = 50  #: covers F_w * 1.2**40 (about 1500 x F_w) plus the bisection
#: seeded: the first attempt is at the predicted L_f times this (chosen by measurement:
#: ``bench/bench_seeded.py``, docs/guide "Starting from the model's prediction").
DEFAULT_RIG_TIMEOUT_S = 60.0  #: the longest one rig attempt may take, s (``lift --rig-timeout``)
DEFAULT_START_MARGIN = 1.005


@dataclass(frozen=True)
class SearchOptions:
    """How each object's lifting force is searched for (frozen; checked when built).

    Attributes:
        protocol: ``"refine"`` (the paper's ramp, then bisection to ``tolerance_rel``) or
            ``"paper"`` (the ramp only).
        growth: the ramp factor between attempts (> 1; the paper's 1.2).
        tolerance_rel: refine stops when ``(high - low) / high <= tolerance_rel``; in (0, 1).
        max_attempts: the most attempts per object (>= 1).
        max_force_n: the force ceiling of every object, N (``--max-force-n``, > 0); None: each
            object's own (the catalog's ``max_force_n``, else the default of
            :mod:`deformctl.lift.ceiling`). No attempt requests more.

    Raises:
        UsageError: an unknown protocol or a number outside its rule (exit 2).
    """

    protocol: SearchProtocol = "refine"
    growth: float = DEFAULT_GROWTH
    tolerance_rel: float = DEFAULT_TOLERANCE_REL
    max_attempts: int = DEFAULT_MAX_ATTEMPTS
    max_force_n: float | None = None

    def __post_init__(self) -> None:
        if self.protocol not in PROTOCOLS:
            raise UsageError(
                f"--protocol must be one of {', '.join(PROTOCOLS)}, got {self.protocol!r}"
            )
        GROWTH.check(self.growth)
        TOLERANCE_REL.check(self.tolerance_rel)
        MAX_ATTEMPTS.check(self.max_attempts)
        MAX_FORCE_N.check_optional(self.max_force_n)

    def as_dict(self) -> dict[str, Any]:
        """The options by name, for provenance (the ceiling only when given)."""
        out: dict[str, Any] = {
            "protocol": self.protocol,
            "growth": self.growth,
            "tolerance_rel": self.tolerance_rel,
            "max_attempts": self.max_attempts,
        }
        if self.max_force_n is not None:
            out["max_force_n"] = self.max_force_n
        return out


#: The default search (the command's defaults), for signatures.
DEFAULT_SEARCH = SearchOptions()
