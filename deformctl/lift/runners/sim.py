"""The built-in simulator as a trial runner of the lifting-force search (``lift --sim``).

:func:`sim_runner_factory` wraps :func:`deformctl.sim.lift_attempt` in a
:class:`~deformctl.lift.stage.RunnerFactory`: one runner per catalog object, each attempt a fresh
simulation from rest (grip ramp and settle, the lift profile's rise, the hold) judged by the slip
criterion. The lift profile and slip criterion are part of the protocol (the surplus
F_d = L_f − F_w comes from the lift's dynamics), so each row of the lift_results table records them
and the provenance records the simulator settings.

Defaults (from :mod:`deformctl.sim.protocols`): an S-curve rise to half the object's height with
peak acceleration 2 m/s², cruise speed 0.25 m/s, 50 ms jerk ramps, then a 0.5 s hold; slip is the
sliding accumulated at the palm contacts from the start of the rise (mean of both palms), and an
attempt lifts when it is at most 0.5 mm and the object is off the table at the end.

At scale, :class:`LiftTask` is the sweep task of one object and :func:`lift_sweep` runs a whole
catalog into a dataset directory (:mod:`deformctl.parallel`, :mod:`deformctl.artifacts.dataset`),
row for row what :func:`~deformctl.lift.stage.lift_catalog` gives serially. The simulator
(numba, scipy) is imported inside the functions that run it, not with this module: a sweep's
fork server preloads the task's module, and a fork server that has loaded OpenBLAS and numba
hands its workers thread pools they cannot use.

Example:
    >>> import pandas as pd
    >>> from deformctl.lift.stage import lift_catalog
    >>> catalog = pd.read_csv("datasets/paper/objects.csv")  # doctest: +SKIP
    >>> run = lift_catalog(catalog, sim_runner_factory())  # doctest: +SKIP
    >>> run.table[["object_id", "lift_force_n", "f_w_n"]]  # doctest: +SKIP
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import pandas as pd

from deformctl.artifacts.dataset import (
    LogPartWriter,
    dataset_fingerprint,
    spec_rows,
    table_schema,
)
from deformctl.artifacts.provenance import Provenance, input_digest
from deformctl.catalog import CatalogObject, select_objects
from deformctl.errors import InputDataError
from deformctl.lift.objects import read_lift_objects
from deformctl.lift.options import DEFAULT_SEARCH, SearchOptions
from deformctl.lift.search import TrialRunner
from deformctl.lift.stage import RunnerFactory, lift_catalog
from deformctl.parallel import SweepOptions, SweepSummary, TaskOutput, run_sweep
from deformctl.scene import DEFAULT_SCENE_HZ, check_scene_hz

if TYPE_CHECKING:  # pragma: no cover - the simulator is imported where it runs (see below)
    from deformctl.presets import SimPreset
    from deformctl.series import TrialOutcome
    from deformctl.sim import LiftProfile, SimSettings, SlipCriterion

__all__ = [
    "LiftTask",
    "PlannedObject",
    "lift_sweep",
    "plan_sim_objects",
    "sim_runner_factory",
]


@dataclass(frozen=True)
class PlannedObject(CatalogObject):
    """A catalog object with its simulated lift attempt worked out (:func:`plan_sim_objects`):
    the budget check, the runner and the row's columns share :attr:`plan`, so the object's spec
    is built once.

    Attributes:
        plan: the attempt's :class:`~deformctl.sim.engine.RunPlan` (spec, particle count, steps,
            memory estimate).
    """

    plan: Any = None  # deformctl.sim.engine.RunPlan (the simulator is imported where it runs)

    @classmethod
    def planned(cls, obj: CatalogObject, plan: Any) -> PlannedObject:
        """``obj`` (already checked: not again) with ``plan``."""
        planned = object.__new__(cls)
        planned.__dict__.update(obj.__dict__)
        object.__setattr__(planned, "plan", plan)
        return planned


def _sim_plan(obj: CatalogObject, preset: SimPreset, scene_hz: float = 0.0) -> Any:
    """The object's plan: its own, else made from the row (a runner used without a plan)."""
    if isinstance(obj, PlannedObject):
        return obj.plan
    s, p = preset.settings, preset.profile
    return plan_sim_objects([obj], settings=s, profile=p, scene_hz=scene_hz)[0].plan


def plan_sim_objects(
    objects: Sequence[CatalogObject],
    path: str | None = None,
    *,
    settings: SimSettings | None = None,
    profile: LiftProfile | None = None,
    scene_hz: float = 0.0,
) -> list[PlannedObject]:
    """Each object with the plan of one simulated lift attempt (its scene at ``scene_hz``;
    :func:`deformctl.sim.protocols.plan_lift_attempt`), refusing, before any attempt, the
    objects the simulator cannot run. An object planned already is kept as it is.

    Raises:
        InputDataError: an object without material values (or otherwise invalid), naming the
            catalog and the first such object (exit 65).
        UsageError: an object's model, or its model plus the steps of one lift attempt under
            ``profile``, would exceed ``settings.memory_budget_gib`` (exit 2).
    """
    from deformctl.sim.protocols import plan_lift_attempt

    todo = [obj for obj in objects if not isinstance(obj, PlannedObject)]
    specs = iter([obj.to_sim_spec(path=path) for obj in todo])  # every row refused first
    return [
        obj
        if isinstance(obj, PlannedObject)
        else PlannedObject.planned(
            obj,
            plan_lift_attempt(next(specs), profile=profile, settings=settings, scene_hz=scene_hz),
        )
        for obj in objects
    ]


def sim_runner_factory(
    *,
    preset: SimPreset | None = None,
    profile: LiftProfile | None = None,
    settings: SimSettings | None = None,
    criterion: SlipCriterion | None = None,
    scene_hz: float = DEFAULT_SCENE_HZ,
) -> RunnerFactory:
    """A :class:`~deformctl.lift.stage.RunnerFactory` whose attempts run in the simulator.

    Args:
        preset: the simulator preset (:mod:`deformctl.presets`; default the ``paper`` preset):
            the object model, lift profile, slip criterion and support release.
        profile, settings, criterion: replace the preset's lift profile, simulator settings or
            slip criterion (the row's ``sim_preset`` then reads ``NAME+overrides``).
        scene_hz: record each attempt's scene (:mod:`deformctl.scene`) at this many frames per
            simulated second for the lift log (0: none); it changes no simulated number.

    Returns:
        The factory: ``name = "sim"``; each row gets ``sim_preset``, ``lift_accel_m_s2``,
        ``lift_speed_m_s`` (the profile's), ``lift_height_m`` (the rise actually used for that
        object), ``slip_tolerance_m`` and ``slip_criterion`` (``"contact"`` or ``"shortfall"``);
        a simulation failure of one object does not stop the others.

    Raises:
        UsageError: ``scene_hz`` negative or above the step rate 1/dt (before any attempt).
    """
    from deformctl.presets import sim_preset

    chosen = preset or sim_preset()
    if profile is not None or settings is not None or criterion is not None:
        chosen = chosen.replace(
            profile=dataclasses.asdict(profile) if profile is not None else None,
            settings=dataclasses.asdict(settings) if settings is not None else None,
            criterion=dataclasses.asdict(criterion) if criterion is not None else None,
        )
    return _runner_factory(chosen, check_scene_hz(scene_hz, chosen.settings.dt_s))


def _runner_factory(preset: SimPreset, scene_hz: float) -> RunnerFactory:
    """:func:`sim_runner_factory` of a preset and a scene rate checked already."""
    p, s, c, r = preset.profile, preset.settings, preset.criterion, preset.release
    return RunnerFactory(
        name="sim",
        make=_SimRunnerMaker(preset, scene_hz),
        row_fields=_SimRowFields(preset),
        stop_on_failure=False,
        settings={
            "sim_preset": preset.name,
            "sim_settings": dataclasses.asdict(s),
            "lift_profile": p.as_dict(),
            "slip_criterion": dataclasses.asdict(c),
            "support_release": r.as_dict(),
            "scene_hz": scene_hz,
        },
        prepare=_SimPrepare(preset, scene_hz),
        material_features=True,
    )


# The factory's parts are picklable classes, not closures: a single-file lift on several local
# processes (``--workers``) sends the factory to its workers.


@dataclass(frozen=True)
class _SimAttempt:
    """One object's trial runner: each attempt a fresh simulation under the preset, run as
    its plan says (spec, steps, scene frames)."""

    preset: SimPreset
    plan: Any  # deformctl.sim.engine.RunPlan

    def __call__(self, grip_force_n: float, attempt_index: int, /) -> TrialOutcome:
        return self.preset.lift_attempt(self.plan.spec, grip_force_n, plan=self.plan)


@dataclass(frozen=True)
class _SimRunnerMaker:
    #: loaded by the fork server of local workers (:mod:`deformctl.sim._warm_worker`)
    worker_preload: ClassVar[tuple[str, ...]] = ("deformctl.sim._warm_worker",)

    preset: SimPreset
    scene_hz: float = 0.0

    def __call__(self, obj: CatalogObject, max_force_n: float) -> TrialRunner:
        return _SimAttempt(self.preset, _sim_plan(obj, self.preset, self.scene_hz))


@dataclass(frozen=True)
class _SimPrepare:
    preset: SimPreset
    scene_hz: float = 0.0

    def __call__(self, objects: Sequence[CatalogObject], path: str | None) -> list[PlannedObject]:
        s, p = self.preset.settings, self.preset.profile
        return plan_sim_objects(objects, path, settings=s, profile=p, scene_hz=self.scene_hz)


@dataclass(frozen=True)
class _SimRowFields:
    preset: SimPreset

    def __call__(self, obj: CatalogObject) -> Mapping[str, object]:
        p, c = self.preset.profile, self.preset.criterion
        return {
            "sim_preset": self.preset.name,
            "lift_accel_m_s2": p.accel_m_s2,
            "lift_speed_m_s": p.speed_m_s,
            "lift_height_m": p.rise_m(_sim_plan(obj, self.preset).spec),
            "slip_tolerance_m": c.tolerance_m,
            "slip_criterion": c.measure,
        }


@dataclass(frozen=True)
class LiftTask:
    """``lift --sim`` for one catalog object (a picklable sweep task).

    Attributes:
        preset: the :class:`~deformctl.presets.SimPreset` (model, profile, slip, release).
        search: the search options.
        log_epoch_ns: where each part's lift log begins, ns since the Unix epoch (None: the
            log writer's fixed epoch, 2000-01-01).
        scene_hz: scene frames per simulated second in the part logs (0: none; checked when
            the task is built, :func:`deformctl.scene.check_scene_hz`).
    """

    #: loaded by the fork server of local workers (:mod:`deformctl.sim._warm_worker`)
    worker_preload: ClassVar[tuple[str, ...]] = ("deformctl.sim._warm_worker",)

    preset: SimPreset
    search: SearchOptions = DEFAULT_SEARCH
    log_epoch_ns: int | None = None
    scene_hz: float = DEFAULT_SCENE_HZ

    def __post_init__(self) -> None:
        hz = check_scene_hz(self.scene_hz, self.preset.settings.dt_s)
        object.__setattr__(self, "scene_hz", hz)

    def factory(self) -> RunnerFactory:
        """The task's runner factory (:func:`sim_runner_factory`; the rate checked already)."""
        return _runner_factory(self.preset, self.scene_hz)

    def __call__(self, item: dict[str, Any]) -> TaskOutput:
        """One object's search: its lift_results row, its attempts as the payload.

        Raises:
            InputDataError: the object cannot be lifted or simulated (recorded as failed).
        """
        factory = self.factory()
        planned = item.get("_planned")  # the object planned by the sweep (its spec built there)
        obj = CatalogObject.from_row(item) if planned is None else planned
        run = lift_catalog([obj], factory, search=self.search)
        error = run.error_message()
        return TaskOutput(
            rows=spec_rows(run.table, "lift_results"),
            payload=(run.objects[0], list(run.attempts)),
            error=error,
            error_type="NotConverged" if error else "ObjectFailed",
        )


def _planned_items(catalog: pd.DataFrame, task: LiftTask) -> list[dict[str, Any]]:
    """The sweep's items: each row the simulator can run as its object planned here (under
    ``"_planned"``: the spec built once, the budgets judged before any worker starts); a row it
    refuses as the row itself, to fail alone in its worker (``DIR/_failures/``).

    Raises:
        UsageError: an object's model or lift attempt above the budget (exit 2).
    """
    s, p = task.preset.settings, task.preset.profile
    items: list[dict[str, Any]] = []
    for record in catalog.to_dict("records"):
        try:
            obj = CatalogObject.from_row(record)
            planned = plan_sim_objects([obj], settings=s, profile=p, scene_hz=task.scene_hz)
        except InputDataError:
            items.append(record)
            continue
        items.append({"object_id": record["object_id"], "_planned": planned[0]})
    return items


def lift_sweep(
    catalog_path: str,
    task: LiftTask,
    *,
    output: str,
    sweep: SweepOptions,
    object_ids: Sequence[str] | None = None,
    force: bool = False,
) -> SweepSummary:
    """``lift --sim -o DIR/``: one search per catalog object through the sweep executor.

    Each part's rows go to ``DIR/part-k.parquet`` and its attempts to the lift log
    ``DIR/_logs/part-k.mcap``; a row the simulator refuses, or a search that does not converge, is
    recorded in ``DIR/_failures/`` and the others go on. The rows are those of
    :func:`~deformctl.lift.stage.lift_catalog_files`, row for row.

    Args:
        catalog_path: the catalog (``-`` for stdin), hashed into the fingerprint.
        task: the simulator and search settings.
        output: the dataset directory.
        sweep: where to run (workers, scheduler), partition size, resume.
        object_ids: these objects, in this order (None: all).
        force: overwrite the sweep files of an existing directory.
    """
    factory = task.factory()
    catalog = select_objects(read_lift_objects(catalog_path), object_ids)
    items = _planned_items(catalog, task)
    search = task.search.as_dict()
    ceiling = search.pop("max_force_n", None)
    run_settings = {"runner": factory.name, **factory.settings, **search}
    if task.log_epoch_ns is not None:
        run_settings["log_epoch_ns"] = task.log_epoch_ns
    if ceiling is not None:  # a resumed run must use the same ceiling
        run_settings["max_force_n"] = ceiling
    provenance = Provenance.from_invocation([catalog_path], settings=run_settings)
    fingerprint = dataset_fingerprint(
        "lift", "lift_results", run_settings, {"catalog": input_digest(catalog_path)}
    )
    return run_sweep(
        task,
        items,
        out_dir=output,
        schema=table_schema("lift_results"),
        fingerprint=fingerprint,
        part_writer=LogPartWriter("lift_log", provenance, task.log_epoch_ns),
        force=force,
        **sweep.run_kwargs(),
    )
