"""Iterative lifting: the minimum lifting force L_f of an object, on any trial runner.

* :mod:`deformctl.lift.search`: the trial-runner protocol, one object's search
  (:func:`find_min_lift_force`, the paper's ramp and the refined bisection), its result
  (:class:`LiftSearchResult`) and :class:`LiftAttempt`, the unit a lift log stores.
* :mod:`deformctl.lift.stage`: the ``lift`` stage over a catalog (:func:`lift_catalog`, one
  runner per object from a :class:`RunnerFactory`).
* :mod:`deformctl.lift.runners.rig`: an external rig command (:func:`rig_runner_factory`);
  :mod:`deformctl.lift.runners.sim`: the built-in simulator (:func:`sim_runner_factory`) and its
  sweep task.

The names below are imported from those modules when first used, so that ``import
deformctl.lift.search`` (the artifact layer needs :class:`LiftAttempt`) stays light and free of
import cycles, and the simulator is loaded only by code that runs it.

Example:
    >>> from deformctl.series import TrialOutcome
    >>> def runner(grip_force_n: float, attempt_index: int) -> TrialOutcome:
    ...     return TrialOutcome(grip_force_n, grip_force_n >= 7.0, 0.0)
    >>> find_min_lift_force(runner, weight_n=5.0, friction_mu=0.5).converged
    True
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover - what __getattr__ resolves, for type checkers
    from deformctl.catalog import rigid_grip_force_n, select_objects
    from deformctl.lift.runners.rig import RIG_SLIP_CRITERION, rig_runner_factory
    from deformctl.lift.runners.sim import sim_runner_factory
    from deformctl.lift.search import (
        DEFAULT_GROWTH,
        DEFAULT_MAX_ATTEMPTS,
        DEFAULT_TOLERANCE_REL,
        PROTOCOLS,
        AttemptError,
        LiftAttempt,
        LiftSearchResult,
        RigSearchAbortedError,
        SearchAbortedError,
        SearchProtocol,
        TrialRunner,
        find_min_lift_force,
        validate_search_options,
    )
    from deformctl.lift.stage import (
        CatalogLiftResult,
        LiftProgress,
        ObjectFailure,
        RunnerFactory,
        lift_catalog,
    )

_HOME = {
    **dict.fromkeys(("rigid_grip_force_n", "select_objects"), "deformctl.catalog"),
    **dict.fromkeys(("RIG_SLIP_CRITERION", "rig_runner_factory"), "deformctl.lift.runners.rig"),
    "sim_runner_factory": "deformctl.lift.runners.sim",
    **dict.fromkeys(
        (
            "DEFAULT_GROWTH",
            "DEFAULT_MAX_ATTEMPTS",
            "DEFAULT_TOLERANCE_REL",
            "PROTOCOLS",
            "AttemptError",
            "LiftAttempt",
            "LiftSearchResult",
            "RigSearchAbortedError",
            "SearchAbortedError",
            "SearchProtocol",
            "TrialRunner",
            "find_min_lift_force",
            "validate_search_options",
        ),
        "deformctl.lift.search",
    ),
    **dict.fromkeys(
        ("CatalogLiftResult", "LiftProgress", "ObjectFailure", "RunnerFactory", "lift_catalog"),
        "deformctl.lift.stage",
    ),
}

__all__ = [
    "DEFAULT_GROWTH",
    "DEFAULT_MAX_ATTEMPTS",
    "DEFAULT_TOLERANCE_REL",
    "PROTOCOLS",
    "RIG_SLIP_CRITERION",
    "AttemptError",
    "CatalogLiftResult",
    "LiftAttempt",
    "LiftProgress",
    "LiftSearchResult",
    "ObjectFailure",
    "RigSearchAbortedError",
    "RunnerFactory",
    "SearchAbortedError",
    "SearchProtocol",
    "TrialRunner",
    "find_min_lift_force",
    "lift_catalog",
    "rig_runner_factory",
    "rigid_grip_force_n",
    "select_objects",
    "sim_runner_factory",
    "validate_search_options",
]


def __getattr__(name: str) -> Any:
    """Import a public name from its module on first use (see the module docstring)."""
    home = _HOME.get(name)
    if home is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(home), name)
    globals()[name] = value
    return value
