"""Iterative lifting: the minimum lifting force L_f of an object, on any trial runner.

* :mod:`deformctl.lift.search`: the trial-runner protocol, one object's search
  (``find_min_lift_force``: the paper's ramp and the refined bisection), its result
  (``LiftSearchResult``) and ``LiftAttempt`` (defined in :mod:`deformctl.series`, the unit a lift
  log stores). Its public names are re-exported here.
* :mod:`deformctl.lift.stage`: the ``lift`` stage over a catalog (``lift_catalog``, one runner
  per object from a ``RunnerFactory``; ``lift_catalog_files`` reads the catalog and writes the
  table and the log).
* :mod:`deformctl.lift.runners.rig`: an external rig command (``rig_runner_factory``);
  :mod:`deformctl.lift.runners.sim`: the built-in simulator (``sim_runner_factory``), its sweep
  task and ``lift_sweep``.

The search's names load on first use (PEP 562), so importing the package or one of its light
modules (``deformctl.lift.options``, which the command line's help reads) imports neither the
search's numpy nor the stage and the runners (the artifact layer, below every stage).

Example:
    >>> from deformctl.series import TrialOutcome
    >>> def runner(grip_force_n: float, attempt_index: int) -> TrialOutcome:
    ...     return TrialOutcome(grip_force_n, grip_force_n >= 7.0, 0.0)
    >>> find_min_lift_force(runner, weight_n=5.0, friction_mu=0.5).converged
    True
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from deformctl.lazy import lazy_face

# ruff: noqa: F401 - the imports below are the public names (deformctl.lazy.lazy_face)
if TYPE_CHECKING:  # for type checkers; at run time each loads on first use
    from deformctl.lift.search import (
        DEFAULT_GROWTH,
        DEFAULT_MAX_ATTEMPTS,
        DEFAULT_START_MARGIN,
        DEFAULT_TOLERANCE_REL,
        PROTOCOLS,
        AttemptError,
        LiftAttempt,
        LiftSearchResult,
        RigSearchAbortedError,
        SearchAbortedError,
        SearchOptions,
        SearchProtocol,
        TrialRunner,
        find_min_lift_force,
        find_min_lift_force_seeded,
        rigid_grip_force_n,
        validate_start_margin,
    )

__getattr__, __dir__ = lazy_face(globals())
