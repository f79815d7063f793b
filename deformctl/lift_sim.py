"""The built-in simulator as a trial runner of the lifting-force search (``lift --sim``).

:func:`sim_runner_factory` wraps :func:`deformctl.sim.lift_attempt` in a
:class:`~deformctl.lift.RunnerFactory`: one runner per catalog object, each attempt a fresh
simulation from rest (grip ramp and settle, the lift profile's rise, the hold) judged by the slip
criterion. The lift profile and slip criterion are part of the protocol (the surplus
F_d = L_f − F_w comes from the lift's dynamics), so each row of the lift_results table records them
and the provenance records the simulator settings.

Defaults (from :mod:`deformctl.sim.protocols`): an S-curve rise to half the object's height with
peak acceleration 2 m/s², cruise speed 0.25 m/s, 50 ms jerk ramps, then a 0.5 s hold; slip is the
sliding accumulated at the palm contacts from the start of the rise (mean of both palms), and an
attempt lifts when it is at most 0.5 mm and the object is off the table at the end.

Example:
    >>> import pandas as pd
    >>> from deformctl.lift import lift_catalog
    >>> catalog = pd.read_csv("datasets/paper/objects.csv")  # doctest: +SKIP
    >>> run = lift_catalog(catalog, sim_runner_factory())  # doctest: +SKIP
    >>> run.table[["object_id", "lift_force_n", "f_w_n"]]  # doctest: +SKIP
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import pandas as pd

from deformctl.lift import RunnerFactory, TrialRunner
from deformctl.series import TrialOutcome
from deformctl.sim import LiftProfile, SimSettings, SlipCriterion, lift_attempt
from deformctl.sim.engine import check_lattice_size
from deformctl.simcatalog import settings_dict, sim_spec, sim_specs

__all__ = ["check_sim_catalog", "sim_runner_factory"]


def check_sim_catalog(
    catalog: pd.DataFrame, path: str | None = None, *, settings: SimSettings | None = None
) -> None:
    """Refuse catalog rows the simulator cannot run, before any attempt.

    Raises:
        InputDataError: a row without material values (or otherwise invalid), naming the catalog
            and the first such object (exit 65).
        UsageError: ``settings`` would give an object a lattice above ``max_particles`` (exit 2).
    """
    for spec in sim_specs(catalog, path=path):
        check_lattice_size(spec, settings or SimSettings())


def sim_runner_factory(
    *,
    profile: LiftProfile | None = None,
    settings: SimSettings | None = None,
    criterion: SlipCriterion | None = None,
) -> RunnerFactory:
    """A :class:`~deformctl.lift.RunnerFactory` whose attempts run in the built-in simulator.

    Args:
        profile: the lift profile (default :class:`~deformctl.sim.LiftProfile`: 2 m/s², 0.25 m/s,
            half the object's height, 0.5 s hold).
        settings: simulator settings (default :class:`~deformctl.sim.SimSettings`).
        criterion: the slip criterion (default :class:`~deformctl.sim.SlipCriterion`: contact
            slip <= 0.5 mm).

    Returns:
        The factory: ``name = "sim"``; each row gets ``lift_accel_m_s2``, ``lift_speed_m_s``
        (the profile's), ``lift_height_m`` (the rise actually used for that object),
        ``slip_tolerance_m`` and ``slip_criterion`` (``"contact"`` or ``"shortfall"``); a
        simulation failure of one object does not stop the others.
    """
    p = profile or LiftProfile()
    s = settings or SimSettings()
    c = criterion or SlipCriterion()

    def make(obj: Mapping[str, Any]) -> TrialRunner:
        spec = sim_spec(obj)

        def run(grip_force_n: float, attempt_index: int, /) -> TrialOutcome:
            return lift_attempt(spec, grip_force_n, profile=p, settings=s, criterion=c)

        return run

    def check(catalog: pd.DataFrame, path: str | None) -> None:
        check_sim_catalog(catalog, path, settings=s)

    def row_fields(obj: Mapping[str, Any]) -> Mapping[str, object]:
        return {
            "lift_accel_m_s2": p.accel_m_s2,
            "lift_speed_m_s": p.speed_m_s,
            "lift_height_m": p.rise_m(sim_spec(obj)),
            "slip_tolerance_m": c.tolerance_m,
            "slip_criterion": c.measure,
        }

    return RunnerFactory(
        name="sim",
        make=make,
        row_fields=row_fields,
        stop_on_failure=False,
        settings={
            "sim_settings": settings_dict(s),
            "lift_profile": p.as_dict(),
            "slip_criterion": {"measure": c.measure, "tolerance_m": c.tolerance_m},
        },
        check=check,
    )
