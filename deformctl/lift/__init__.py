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

Only the search is imported with the package: the stage and the runners import the artifact
layer, which sits below every stage.

Example:
    >>> from deformctl.series import TrialOutcome
    >>> def runner(grip_force_n: float, attempt_index: int) -> TrialOutcome:
    ...     return TrialOutcome(grip_force_n, grip_force_n >= 7.0, 0.0)
    >>> find_min_lift_force(runner, weight_n=5.0, friction_mu=0.5).converged
    True
"""

from __future__ import annotations

from deformctl.lift.search import *  # noqa: F403 - the package's face is the search
from deformctl.lift.search import __all__ as __all__
