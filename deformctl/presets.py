"""Named simulator presets: one choice of object model and lift protocol, recorded everywhere.

A preset fixes every setting the simulated lifting force depends on: the object model
(:class:`~deformctl.sim.SimSettings`: lattice, integrator, palm layers, damping split), the palm
motion (:class:`~deformctl.sim.LiftProfile`), the slip judgement
(:class:`~deformctl.sim.SlipCriterion`) and how the weight reaches the grip
(:class:`~deformctl.sim.SupportRelease`). ``measure --sim`` and ``lift --sim`` take
``--sim-preset NAME``; single options still override a preset's values, and every lift row, lift
log and squeeze log records the preset's name and its full settings.

``paper`` (the default)
    The model and protocol that reproduce the seed paper's simulated lifting forces (Table II's
    simulation column and Table III's expected column, 13 points). Where F_d comes from: the
    gripped object starts stress-free, its weight carried by a support (the paper's object
    "initially in an equilibrium state"); when the lift starts the support gives way at once and
    the palms accelerate at a constant ``a``, so the weight and the lift's inertia reach the grip as
    a step load on the body hanging between the palms. A weakly damped hanging mode overshoots
    (up to about twice the static load), a heavily damped one does not, so L_f / F_w falls with the
    damping ratio, as in the paper. The squeeze test measures the squeeze damping λ; the hanging
    (shear) modes see only the fraction ``r`` of it that the lattice's dampers carry, the rest acts
    across the gripped width. Two parameters are fitted (``make calibrate``,
    :mod:`deformctl.repro.calibrate`) to the 13 published points and read from
    ``datasets/calibration/paper.json``:

    * ``shear_damping_ratio`` r: shear damping over squeeze damping of the material, plausible
      0.02-0.5 (a bag of grains or fluid resists being squeezed, which forces its filling to flow,
      more than it resists shearing);
    * ``lift_accel_m_s2`` a: the constant acceleration of the paper's lift, plausible 0.2-2 m/s²
      (the paper does not state it; its sponge lifts at F_w, which bounds a / g).

    Fixed, not fitted: 8 particles along the longest side with massless palm surface layers,
    linear (small-strain) springs, BDF2 with dt = 1 ms, a 0.2 ms floor on the lattice dampers'
    retardation time (an undamped object would otherwise ring in its lattice-scale modes forever),
    cruise speed 0.25 m/s, a 0.3 s hold, and slip judged strictly (1 µm of contact sliding; an
    attempt ends as soon as it has slid that much).

``table``
    deformctl's first simulator: the object rests on the table, the palms lift it through a
    50 ms-jerk S-curve to 2 m/s², every damper is stiffness-proportional, the palm layers are
    ordinary particles, backward Euler, 5 particles per side, slip tolerance 0.5 mm. Its lifting
    force is about the rigid-body ``m (g + a) / (2 mu)`` for most objects (kept for comparison).

Example:
    >>> from deformctl.presets import sim_preset
    >>> sim_preset("table").settings.integrator
    'euler'
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from functools import lru_cache
from typing import TYPE_CHECKING, Any, Literal

from deformctl.errors import UsageError
from deformctl.resources import dataset_path

if TYPE_CHECKING:  # pragma: no cover - the simulator is imported where a preset is built
    from deformctl.series import TrialOutcome
    from deformctl.sim import LiftProfile, ObjectSpec, SimSettings, SlipCriterion, SupportRelease

PresetName = Literal["paper", "table"]
PRESET_NAMES: tuple[PresetName, ...] = ("paper", "table")
DEFAULT_PRESET: PresetName = "paper"

#: The file ``make calibrate`` writes and the paper preset reads (in ``deformctl.datasets``).
CALIBRATION_PARTS = ("calibration", "paper.json")
#: The fitted parameters of the paper preset and their plausible ranges (the fit's bounds).
CALIBRATED_PARAMETERS: dict[str, tuple[float, float]] = {
    "shear_damping_ratio": (0.02, 0.5),
    "lift_accel_m_s2": (0.2, 2.0),
}
#: The paper preset's fixed settings (see the module docstring).
PAPER_FIXED: dict[str, Any] = {
    "particles_per_side": 8,
    "dt_s": 1e-3,
    "integrator": "bdf2",
    "palm_layer": "surface",
    "nonlinear_springs": False,
    "min_shear_retardation_s": 2e-4,
    "lift_speed_m_s": 0.25,
    "lift_jerk_time_s": 0.0,
    "lift_hold_s": 0.3,
    "slip_tolerance_m": 1e-6,
    "slip_stop_early": True,
}


@dataclass(frozen=True)
class SimPreset:
    """A named, complete set of simulator settings.

    Attributes:
        name: ``"paper"`` or ``"table"`` (with ``+overrides`` appended when options changed it).
        settings: the object model and numerics.
        profile: the palm motion of a lift.
        criterion: the slip judgement.
        release: how the weight passes to the grip.
    """

    name: str
    settings: SimSettings
    profile: LiftProfile
    criterion: SlipCriterion
    release: SupportRelease

    def as_dict(self) -> dict[str, Any]:
        """Every setting, JSON-serialisable (for the artifacts' provenance)."""
        return {
            "name": self.name,
            "settings": dataclasses.asdict(self.settings),
            "profile": self.profile.as_dict(),
            "slip": dataclasses.asdict(self.criterion),
            "release": self.release.as_dict(),
        }

    def lift_attempt(
        self, spec: ObjectSpec, grip_force_n: float, *, scene_hz: float = 0.0, plan: Any = None
    ) -> TrialOutcome:
        """One simulated lift attempt of ``spec`` at ``grip_force_n`` under this preset (with
        its scene at ``scene_hz`` frames per simulated second; 0: none), run as ``plan`` says
        (:func:`deformctl.sim.protocols.plan_lift_attempt` under this preset; None: made here)."""
        from deformctl.sim import lift_attempt

        return lift_attempt(
            spec,
            grip_force_n,
            profile=self.profile,
            settings=self.settings,
            criterion=self.criterion,
            release=self.release,
            scene_hz=scene_hz,
            plan=plan,
        )

    def replace(
        self,
        *,
        settings: dict[str, Any] | None = None,
        profile: dict[str, Any] | None = None,
        criterion: dict[str, Any] | None = None,
    ) -> SimPreset:
        """A copy with single values overridden (None values are ignored).

        The name keeps the preset's and gains ``+overrides`` when something changed, so a row
        never claims a preset it did not use.
        """
        changes = {
            "settings": {k: v for k, v in (settings or {}).items() if v is not None},
            "profile": {k: v for k, v in (profile or {}).items() if v is not None},
            "criterion": {k: v for k, v in (criterion or {}).items() if v is not None},
        }
        new = SimPreset(
            name=self.name,
            settings=dataclasses.replace(self.settings, **changes["settings"]),
            profile=dataclasses.replace(self.profile, **changes["profile"]),
            criterion=dataclasses.replace(self.criterion, **changes["criterion"]),
            release=self.release,
        )
        if new != self:
            base = self.name.split("+")[0]
            new = dataclasses.replace(new, name=f"{base}+overrides")
        return new


def check_preset_name(name: str) -> PresetName:
    """``name`` if it is a preset's (exit 2 otherwise)."""
    if name not in PRESET_NAMES:
        raise UsageError(f"unknown sim preset {name!r}: choose {' or '.join(PRESET_NAMES)}")
    return name


@lru_cache(maxsize=1)
def paper_calibration() -> dict[str, Any]:
    """The contents of ``datasets/calibration/paper.json`` (written by ``make calibrate``).

    Raises:
        InputDataError: the file is missing a fitted parameter or holds one outside its range.
    """
    from deformctl.errors import InputDataError

    path = dataset_path(*CALIBRATION_PARTS)
    data: dict[str, Any] = json.loads(path.read_text(encoding="utf-8"))
    fitted = data.get("fitted", {})
    for key, (low, high) in CALIBRATED_PARAMETERS.items():
        value = fitted.get(key)
        if not (isinstance(value, int | float) and math.isfinite(value) and low <= value <= high):
            raise InputDataError(
                f"fitted {key} {value!r} is not in [{low}, {high}]", path=str(path)
            )
    return data


def paper_preset(
    shear_damping_ratio: float | None = None, lift_accel_m_s2: float | None = None
) -> SimPreset:
    """The paper preset, with the calibrated parameters (or the values given, e.g. to fit them)."""
    from deformctl.sim import LiftProfile, SimSettings, SlipCriterion, SupportRelease

    if shear_damping_ratio is None or lift_accel_m_s2 is None:
        fitted = paper_calibration()["fitted"]
        if shear_damping_ratio is None:
            shear_damping_ratio = float(fitted["shear_damping_ratio"])
        if lift_accel_m_s2 is None:
            lift_accel_m_s2 = float(fitted["lift_accel_m_s2"])
    f = PAPER_FIXED
    return SimPreset(
        name="paper",
        settings=SimSettings(
            particles_per_side=f["particles_per_side"],
            dt_s=f["dt_s"],
            integrator=f["integrator"],
            palm_layer=f["palm_layer"],
            nonlinear_springs=f["nonlinear_springs"],
            shear_damping_ratio=shear_damping_ratio,
            min_shear_retardation_s=f["min_shear_retardation_s"],
        ),
        profile=LiftProfile(
            accel_m_s2=lift_accel_m_s2,
            speed_m_s=f["lift_speed_m_s"],
            jerk_time_s=f["lift_jerk_time_s"],
            hold_s=f["lift_hold_s"],
        ),
        criterion=SlipCriterion(
            tolerance_m=f["slip_tolerance_m"], measure="contact", stop_early=f["slip_stop_early"]
        ),
        release=SupportRelease(mode="support", release_time_s=0.0),
    )


def table_preset() -> SimPreset:
    """The table preset: the simulator's library defaults (see the module docstring)."""
    from deformctl.sim import LiftProfile, SimSettings, SlipCriterion, SupportRelease

    return SimPreset(
        name="table",
        settings=SimSettings(),
        profile=LiftProfile(),
        criterion=SlipCriterion(),
        release=SupportRelease(),
    )


@lru_cache(maxsize=len(PRESET_NAMES))
def sim_preset(name: str = DEFAULT_PRESET) -> SimPreset:
    """The preset called ``name`` (``"paper"`` or ``"table"``), built (and its values checked)
    once per process: it is frozen, and the calibration it reads is read once.

    Raises:
        UsageError: an unknown name (exit 2).
    """
    return paper_preset() if check_preset_name(name) == "paper" else table_preset()


@dataclass(frozen=True)
class SimOptions:
    """The simulator options of ``measure --sim`` and ``lift --sim``: a preset and the single
    values that override it (None: the preset's).

    Built, it builds its preset once, which checks the name and every value (the simulator's
    settings types: so the simulator is imported when one is built). :meth:`as_dict` is what was
    asked for; the rows and logs record the preset :meth:`preset` returns (``NAME+overrides``
    when a value changed it).

    Attributes:
        preset_name: ``paper`` (the default) or ``table`` (``--sim-preset``).
        alpha_cm, dt_s, memory_budget_gib: the object model's lattice spacing, time step and
            memory budget (``--alpha-cm``, ``--dt-s``, ``--memory-budget-gib``).
        lift_accel_m_s2, lift_speed_m_s, lift_height_m, lift_hold_s: the lift profile
            (``lift --lift-accel-m-s2`` ...).
        slip_tolerance_m, slip_criterion: the slip judgement (``lift --slip-tolerance-m``,
            ``--slip-criterion``).

    Raises:
        UsageError: an unknown preset, or a value the simulator refuses (exit 2).
    """

    preset_name: str = DEFAULT_PRESET
    alpha_cm: float | None = None
    dt_s: float | None = None
    memory_budget_gib: float | None = None
    lift_accel_m_s2: float | None = None
    lift_speed_m_s: float | None = None
    lift_height_m: float | None = None
    lift_hold_s: float | None = None
    slip_tolerance_m: float | None = None
    slip_criterion: str | None = None
    _preset: SimPreset = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        preset = sim_preset(self.preset_name).replace(
            settings={
                "alpha_cm": self.alpha_cm,
                "dt_s": self.dt_s,
                "memory_budget_gib": self.memory_budget_gib,
            },
            profile={
                "accel_m_s2": self.lift_accel_m_s2,
                "speed_m_s": self.lift_speed_m_s,
                "height_m": self.lift_height_m,
                "hold_s": self.lift_hold_s,
            },
            criterion={"tolerance_m": self.slip_tolerance_m, "measure": self.slip_criterion},
        )
        object.__setattr__(self, "_preset", preset)

    def preset(self) -> SimPreset:
        """The preset with the values given (:meth:`SimPreset.replace`)."""
        return self._preset

    def as_dict(self) -> dict[str, Any]:
        """The options as given (None: the preset's value)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.init}
