"""The two protocols (force-controlled squeeze, lift attempt) and a free run for validation.

Each protocol builds (or reuses, cached) a :class:`~deformctl.sim.engine.Model`, precomputes its
palm command schedule as arrays, and runs the whole attempt in one numba call.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from deformctl.arraytypes import FloatArray
from deformctl.errors import SimulationError, UsageError
from deformctl.physics import rigid_grip_force_n
from deformctl.quantities import (
    LIFT_ACCEL_M_S2,
    LIFT_HEIGHT_M,
    LIFT_HOLD_S,
    LIFT_JERK_TIME_S,
    LIFT_SPEED_M_S,
    RELEASE_TIME_S,
    SIM_SLIP_TOLERANCE_M,
)
from deformctl.scene import check_scene_hz, scene_every_steps
from deformctl.series import LiftAttemptSeries, SqueezeSeries, TrialOutcome
from deformctl.sim import first_use
from deformctl.sim.engine import (
    RunPlan,
    SimSettings,
    build_model,
    clear_model_cache,
    plan_run,
    run_model,
)
from deformctl.sim.hunt_crossley import implicit_reference_m
from deformctl.sim.objects import ObjectSpec
from deformctl.sim.scene import frame_buffer, scene_frames
from deformctl.sim.step import record as K
from deformctl.units import GRAVITY_M_S2


@dataclass(frozen=True)
class LiftProfile:
    """Palm motion of a lift: an S-curve (jerk-limited) rise, then a hold.

    Acceleration rises from 0 to ``accel_m_s2`` along a half-cosine of ``jerk_time_s``, stays
    there until the palms reach ``speed_m_s``, falls back to 0 along a half-cosine; the palms
    cruise, then decelerate with the mirror image and stop after ``height_m``; then they hold
    still for ``hold_s``. If the height is too short to reach ``speed_m_s`` the cruise speed is
    lowered (and, if needed, the jerk time shortened) so that the peak acceleration is always
    ``accel_m_s2``. The acceleration plateau makes the friction demand m (g + a_max) act for a
    finite time, so the smallest lifting force of a rigid object is sharp. ``jerk_time_s = 0``
    gives the trapezoidal velocity profile: the acceleration steps to ``accel_m_s2`` at the start
    of the rise (a constant-acceleration lift).

    Attributes:
        accel_m_s2: peak acceleration a_max, m/s².
        speed_m_s: cruise speed, m/s.
        height_m: rise, m; ``None`` means half the object height (the paper's protocol).
        hold_s: hold after the rise, s.
        jerk_time_s: duration of each acceleration ramp, s (0: acceleration steps).
    """

    accel_m_s2: float = 2.0
    speed_m_s: float = 0.25
    height_m: float | None = None
    hold_s: float = 0.5
    jerk_time_s: float = 0.05

    def __post_init__(self) -> None:
        LIFT_ACCEL_M_S2.check(self.accel_m_s2)
        LIFT_SPEED_M_S.check(self.speed_m_s)
        LIFT_HEIGHT_M.check_optional(self.height_m)
        LIFT_HOLD_S.check(self.hold_s)
        LIFT_JERK_TIME_S.check(self.jerk_time_s)

    @property
    def peak_accel_m_s2(self) -> float:
        """Peak palm acceleration, m/s²."""
        return self.accel_m_s2

    def rise_m(self, spec: ObjectSpec) -> float:
        """The rise for ``spec``: ``height_m`` or half the object height, m."""
        return self.height_m if self.height_m is not None else 0.5 * spec.size_m[2]

    def phases(self, rise_m: float) -> tuple[float, float, float]:
        """(cruise speed m/s, jerk time s, cruise time s) actually used for ``rise_m``."""
        a = self.accel_m_s2
        v = self.speed_m_s
        tj = min(self.jerk_time_s, v / a)
        if v * (v / a + tj) > rise_m:
            v = a * (-tj + math.sqrt(tj * tj + 4.0 * rise_m / a)) / 2.0
            if v < a * tj:
                tj = math.sqrt(rise_m / (2.0 * a))
                v = a * tj
        cruise = (rise_m - v * (v / a + tj)) / v
        return v, tj, max(cruise, 0.0)

    def velocity_m_s(self, t_s: FloatArray, rise_m: float) -> FloatArray:
        """Palm velocity at times ``t_s`` after the start of the rise, m/s, ``[n]``."""
        a = self.accel_m_s2
        v, tj, cruise = self.phases(rise_m)
        t_acc = v / a + tj
        plateau_end = t_acc - tj

        def ramp_phase(t: FloatArray) -> FloatArray:
            # velocity during an acceleration phase starting at t = 0, for 0 <= t <= t_acc
            if tj <= 0.0:
                return np.asarray(np.minimum(a * t, v))
            up = 0.5 * a * (t - tj / np.pi * np.sin(np.pi * t / tj))
            mid = 0.5 * a * tj + a * (t - tj)
            down_t = t_acc - t
            down = v - 0.5 * a * (down_t - tj / np.pi * np.sin(np.pi * down_t / tj))
            return np.where(t < tj, up, np.where(t < plateau_end, mid, down))

        t = np.asarray(t_s, dtype=np.float64)
        t_dec = t_acc + cruise
        out = np.zeros_like(t)
        out = np.where((t >= 0) & (t < t_acc), ramp_phase(np.clip(t, 0, t_acc)), out)
        out = np.where((t >= t_acc) & (t < t_dec), v, out)
        tail = np.clip(t - t_dec, 0, t_acc)
        out = np.where((t >= t_dec) & (t < t_dec + t_acc), v - ramp_phase(tail), out)
        return np.asarray(out)

    def rise_time_s(self, rise_m: float) -> float:
        """Duration of the rise (acceleration, cruise, deceleration), s."""
        v, tj, cruise = self.phases(rise_m)
        return 2.0 * (v / self.accel_m_s2 + tj) + cruise

    def as_dict(self) -> dict[str, float | None]:
        """The profile's parameters, JSON-serialisable (for artifacts' provenance)."""
        return {
            "accel_m_s2": self.accel_m_s2,
            "speed_m_s": self.speed_m_s,
            "height_m": self.height_m,
            "hold_s": self.hold_s,
            "jerk_time_s": self.jerk_time_s,
        }


@dataclass(frozen=True)
class SlipCriterion:
    """When a lift attempt counts as slipped.

    Attributes:
        tolerance_m: allowed slip, m. Default 0.5 mm: a rigid object gripped 1 % below its
            friction limit slides about this much under the default profile, so the lifting
            force a search finds is within ~1 % of the friction limit, while genuine drops slide
            by centimetres.
        measure: ``"contact"`` (default): the sliding accumulated at the palm contacts from the
            start of the rise, mean of both palms. ``"shortfall"``: the palms' rise minus the
            object's centre-of-mass rise at the end of the hold (includes elastic sag).
        stop_early: end an attempt as soon as its contact slip exceeds ``tolerance_m`` (the
            verdict is final then: the accumulated slip only grows) instead of simulating the
            rest of the rise and the hold. Saves most of a slipped attempt's cost; its recorded
            series ends there. Only with ``measure = "contact"``. Default off (the ``paper``
            preset turns it on).
    """

    tolerance_m: float = 0.5e-3
    measure: Literal["contact", "shortfall"] = "contact"
    stop_early: bool = False

    def __post_init__(self) -> None:
        SIM_SLIP_TOLERANCE_M.check(self.tolerance_m)
        if self.measure not in ("contact", "shortfall"):
            raise UsageError(f"slip measure must be 'contact' or 'shortfall', got {self.measure!r}")


@dataclass(frozen=True)
class SupportRelease:
    """How the object's weight passes from its support to the grip in a lift attempt.

    Attributes:
        mode: ``"table"`` (default): the object rests on the table under its own weight and stays
            on it while the grip force ramps; the table stays, and the weight leaves it as the
            palms rise, over the time the rise needs to stretch the gripped body by its sag.
            ``"support"``: until the rise starts, a support carries every particle's weight, so
            the gripped object is stress-free (the paper's object "initially in an equilibrium
            state"); at the start of the rise the support gives way over ``release_time_s`` and
            the whole weight passes into the grip as a step load on the hanging body. There is
            no table in this mode.
        release_time_s: how long the support takes to give way (``"support"`` only), s: the
            weight rises along a half-cosine from 0 to W over this time; 0: at once.
    """

    mode: Literal["table", "support"] = "table"
    release_time_s: float = 0.0

    def __post_init__(self) -> None:
        if self.mode not in ("table", "support"):
            raise UsageError(f"support release mode must be table or support, got {self.mode!r}")
        RELEASE_TIME_S.check(self.release_time_s)

    def gravity_scale(self, t_s: FloatArray, t_release_s: float) -> FloatArray | None:
        """The fraction of the weight acting at times ``t_s`` (None: all of it, always)."""
        if self.mode == "table":
            return None
        if self.release_time_s == 0.0:
            return np.asarray(np.where(t_s > t_release_s, 1.0, 0.0))
        phase = np.clip((t_s - t_release_s) / self.release_time_s, 0.0, 1.0)
        return np.asarray(0.5 - 0.5 * np.cos(np.pi * phase))

    def as_dict(self) -> dict[str, object]:
        """JSON-serialisable parameters (for artifacts' provenance and attempt details)."""
        return {"mode": self.mode, "release_time_s": self.release_time_s}


def _kernels_ready() -> None:
    """Before a process's first run: compile every kernel once, on one stderr line, if these
    sources' kernels were never compiled (:mod:`deformctl.sim.first_use`)."""
    first_use.ensure_compiled(compile_kernels)


#: a small object: every kernel runs, none for long
_WARM_SPEC = ObjectSpec("warmup", (4.0, 4.0, 4.0), 1.0, 0.5, 10.0, 0.5)
#: ... and a standard linear solid (its Maxwell arms' kernels)
_WARM_SLS = ObjectSpec(
    "warmup-sls",
    (4.0, 4.0, 4.0),
    1.0,
    0.5,
    10.0,
    0.0,
    arm_stiffness_n_per_cm=5.0,
    relaxation_time_s=0.5,
)


def compile_kernels() -> float:
    """Run every simulator kernel once (compiling or loading it), with the argument types of a
    real run: a squeeze and a lift attempt of a Kelvin–Voigt object and of a standard linear
    solid with the direct solver and the iterative one
    (multigrid CG), backward Euler and BDF2; returns the wall time, s."""
    first_use.mark_compiled()  # the runs below must not ask again (and mark at the end)
    t0 = time.perf_counter()
    for solver in ("direct", "iterative"):
        for integrator in ("euler", "bdf2"):
            settings = SimSettings(
                particles_per_side=4, solver=solver, integrator=integrator, grip_settle_s=0.01
            )
            for spec in (_WARM_SPEC, _WARM_SLS):
                squeeze(spec, peak_force_n=1.0, ramp_s=0.005, hold_s=0.005, settings=settings)
                for mode in ("table", "support"):
                    lift_attempt(spec, 2.0, settings=settings, release=SupportRelease(mode=mode))
    clear_model_cache()
    first_use.mark_compiled()
    return time.perf_counter() - t0


def _check_finite(rec: FloatArray, what: str, spec: ObjectSpec) -> None:
    if not np.all(np.isfinite(rec)):
        raise SimulationError(f"object {spec.object_id!r}: non-finite state during {what}")


def plan_squeeze(
    spec: ObjectSpec,
    *,
    ramp_s: float = 0.25,
    hold_s: float = 1.0,
    settings: SimSettings | None = None,
    scene_hz: float = 0.0,
) -> RunPlan:
    """The plan of one squeeze of ``spec`` (:func:`squeeze`'s arguments): its steps, a scene
    frame every so many steps (``scene_hz`` checked already: :func:`deformctl.scene.check_scene_hz`)
    and its memory, refused (exit 2) above the memory budget, or for a negative duration."""
    s = settings or SimSettings()
    if not (ramp_s >= 0 and hold_s >= 0):  # an endless squeeze is refused by the budget
        raise UsageError("ramp_s and hold_s must be >= 0")
    every = scene_every_steps(scene_hz, s.dt_s)
    return plan_run(spec, s, max(1.0, round((ramp_s + hold_s) / s.dt_s, 0)), "squeeze", every)


def squeeze(
    spec: ObjectSpec,
    *,
    peak_force_n: float,
    ramp_s: float = 0.25,
    hold_s: float = 1.0,
    settings: SimSettings | None = None,
    squeeze_index: int = 0,
    gravity: bool = True,
    noise_force_n: float = 0.0,
    noise_position_m: float = 0.0,
    seed: int | None = None,
    scene_hz: float = 0.0,
    plan: RunPlan | None = None,
) -> SqueezeSeries:
    """Force-controlled squeeze: both palms push with ``F(t)``, a linear ramp to the peak, a hold.

    The object starts at rest (on the table under gravity, or floating with ``gravity=False``,
    which also removes the table), the palms touching its x faces. Samples every step, starting
    with t = 0.

    Args:
        peak_force_n: commanded normal force of each palm after the ramp, N.
        ramp_s: ramp duration, s (0: a force step).
        hold_s: hold duration at the peak, s.
        noise_force_n, noise_position_m: std of Gaussian sensor noise added to the recorded force
            and palm positions (0: exact). seed: noise seed (``np.random.default_rng``).
        scene_hz: record the scene (:class:`deformctl.scene.SceneFrames`, noise-free) at this
            many frames per simulated second, from t = 0 (0: none; at most 1/dt).
        plan: the squeeze's plan (:func:`plan_squeeze` of the same spec, durations, settings and
            scene rate), made once for an object's squeezes; None: made here.

    Returns:
        the squeeze series (force felt, compression, commanded force, palm x positions; its
        ``scene`` when asked).
    """
    s = settings or SimSettings()
    if not (math.isfinite(peak_force_n) and peak_force_n > 0):
        raise UsageError(f"peak_force_n must be > 0, got {peak_force_n}")
    if plan is None:
        scene_hz = check_scene_hz(scene_hz, s.dt_s)
        plan = plan_squeeze(spec, ramp_s=ramp_s, hold_s=hold_s, settings=s, scene_hz=scene_hz)
    n_steps, every = int(plan.steps), plan.frame_every
    _kernels_ready()
    reference = implicit_reference_m(spec, peak_force_n)  # a stable step at the peak's tangent
    model = build_model(
        spec, s, gripped=True, gravity=gravity, table=gravity, reference_m=reference
    )
    t = np.arange(n_steps + 1, dtype=np.float64) * s.dt_s
    force = peak_force_n * (np.clip(t / ramp_s, 0.0, 1.0) if ramp_s > 0 else np.ones_like(t))
    if ramp_s == 0:
        force[0] = 0.0
    frames = frame_buffer(model, n_steps, every) if every else None
    q_end, _, rec = run_model(model, force, np.zeros(n_steps + 1), frame_every=every, frames=frames)
    _check_finite(rec, "squeeze", spec)
    scene = None
    if frames is not None:
        scene = scene_frames(model, rec, frames, every, q_end, start=True)
    xl = np.concatenate([[model.palm_x0[0]], rec[:, K.REC_PALM_XL]])
    xr = np.concatenate([[model.palm_x0[1]], rec[:, K.REC_PALM_XR]])
    felt = np.concatenate([[0.0], 0.5 * (rec[:, K.REC_NORMAL_L] + rec[:, K.REC_NORMAL_R])])
    if noise_force_n > 0 or noise_position_m > 0:
        rng = np.random.default_rng(seed)
        felt = felt + rng.normal(0.0, noise_force_n, felt.shape) if noise_force_n > 0 else felt
        if noise_position_m > 0:
            xl = xl + rng.normal(0.0, noise_position_m, xl.shape)
            xr = xr + rng.normal(0.0, noise_position_m, xr.shape)
    gap = xr - xl
    return SqueezeSeries(
        object_id=spec.object_id,
        squeeze_index=squeeze_index,
        time_s=t,
        force_n=felt,
        compression_m=gap[0] - gap,
        commanded_force_n=force,
        palm_left_x_m=xl,
        palm_right_x_m=xr,
        scene=scene,
    )


def squeeze_many(
    spec: ObjectSpec,
    n: int,
    *,
    peak_force_n: float,
    force_scales: tuple[float, ...] | None = None,
    seed: int | None = None,
    **kwargs: object,
) -> list[SqueezeSeries]:
    """``n`` squeezes of ``spec``, each from rest, at peak forces ``peak_force_n * scale_i``.

    Args:
        force_scales: one factor per squeeze; default ``linspace(0.5, 1, n)`` (``[1]`` for n = 1),
            so the squeezes probe different force levels.
        seed: base noise seed; squeeze ``i`` uses ``seed + i`` (when noise is requested).
        **kwargs: passed to :func:`squeeze` (ramp_s, hold_s, settings, gravity, noise...).
    """
    if n < 1:
        raise UsageError(f"number of squeezes must be >= 1, got {n}")
    if force_scales is None:
        scales = tuple(float(x) for x in np.linspace(0.5, 1.0, n)) if n > 1 else (1.0,)
    else:
        scales = tuple(force_scales)
    if len(scales) != n:
        raise UsageError(f"force_scales has {len(scales)} entries for {n} squeezes")
    return [
        squeeze(
            spec,
            peak_force_n=peak_force_n * float(scale),
            squeeze_index=i,
            seed=None if seed is None else seed + i,
            **kwargs,  # type: ignore[arg-type]
        )
        for i, scale in enumerate(scales)
    ]


def _grip_steps(settings: SimSettings) -> int:
    """Steps of a lift attempt's grip: its force ramp and settle, before the rise."""
    return max(1, round((settings.grip_ramp_s + settings.grip_settle_s) / settings.dt_s))


def plan_lift_attempt(
    spec: ObjectSpec,
    *,
    profile: LiftProfile | None = None,
    settings: SimSettings | None = None,
    scene_hz: float = 0.0,
) -> RunPlan:
    """The plan of one lift attempt of ``spec`` (:func:`lift_attempt`'s arguments): its steps
    (the grip, the rise, the hold), a scene frame every so many steps (``scene_hz`` checked
    already: :func:`deformctl.scene.check_scene_hz`) and its memory, refused (exit 2) above the
    memory budget."""
    s, p = settings or SimSettings(), profile or LiftProfile()
    every = scene_every_steps(scene_hz, s.dt_s)
    rise = float(np.ceil(p.rise_time_s(p.rise_m(spec)) / s.dt_s))
    n_steps = _grip_steps(s) + rise + round(p.hold_s / s.dt_s, 0)
    return plan_run(spec, s, n_steps, "lift attempt", every)


def lift_attempt(
    spec: ObjectSpec,
    grip_force_n: float,
    *,
    profile: LiftProfile | None = None,
    settings: SimSettings | None = None,
    criterion: SlipCriterion | None = None,
    release: SupportRelease | None = None,
    stop_when_slipped: bool | None = None,
    scene_hz: float = 0.0,
    plan: RunPlan | None = None,
) -> TrialOutcome:
    """Grip ``spec`` with ``grip_force_n`` per palm, raise the palms along ``profile``, hold.

    Phases: the object rests on the table (or, with ``release.mode == "support"``, is held
    stress-free by a support); the grip force ramps from 0 over ``settings.grip_ramp_s`` and
    settles for ``settings.grip_settle_s``; the palms rise by ``profile.rise_m(spec)`` (the
    support gives way as the rise starts) and hold for ``profile.hold_s``. Slip is counted from
    the start of the rise. ``lifted`` is true when the slip (``criterion.measure``) is within
    ``criterion.tolerance_m`` and the object is off the table at the end.

    With ``stop_when_slipped`` (default: ``criterion.stop_early``) and the contact slip measure,
    the attempt stops as soon as its slip exceeds the tolerance: the verdict is then final (the
    accumulated slip only grows), and the recorded series ends there.

    ``scene_hz`` > 0 records the attempt's scene (:class:`deformctl.scene.SceneFrames`) at that
    many frames per simulated second, on the series' time base, ending with its last sample (at
    most 1/dt; it changes no simulated number). ``plan``: the attempt's plan
    (:func:`plan_lift_attempt` of the same spec, profile, settings and scene rate), made once for
    an object's attempts; None: made here.
    """
    s = settings or SimSettings()
    p = profile or LiftProfile()
    c = criterion or SlipCriterion()
    r = release or SupportRelease()
    if not (math.isfinite(grip_force_n) and grip_force_n >= 0):
        raise UsageError(f"grip_force_n must be finite and >= 0, got {grip_force_n}")
    if plan is None:
        scene_hz = check_scene_hz(scene_hz, s.dt_s)
        plan = plan_lift_attempt(spec, profile=p, settings=s, scene_hz=scene_hz)
    every, n_steps = plan.frame_every, int(plan.steps)
    on_table = r.mode == "table"
    _kernels_ready()
    reference = implicit_reference_m(spec, grip_force_n)  # a stable step at the grip's tangent
    model = build_model(
        spec, s, gripped=True, resting=on_table, table=on_table, reference_m=reference
    )
    dt = s.dt_s
    rise = p.rise_m(spec)
    n_grip = _grip_steps(s)
    n_planned = n_steps
    t = np.arange(n_steps + 1, dtype=np.float64) * dt
    if s.grip_ramp_s > 0:
        force = grip_force_n * np.clip(t / s.grip_ramp_s, 0.0, 1.0)
    else:
        force = np.full(n_steps + 1, float(grip_force_n))
    t_lift = n_grip * dt
    palm_vz = p.velocity_m_s(t - t_lift, rise)
    early = c.stop_early if stop_when_slipped is None else stop_when_slipped
    stop = c.tolerance_m if early and c.measure == "contact" else None
    frames = frame_buffer(model, n_steps, every) if every else None
    q_end, _, rec = run_model(
        model,
        force,
        palm_vz,
        gravity_scale=r.gravity_scale(t, t_lift),
        stop_slip_m=stop,
        stop_from_step=n_grip,
        frame_every=every,
        frames=frames,
    )
    _check_finite(rec, "lift attempt", spec)
    scene = None if frames is None else scene_frames(model, rec, frames, every, q_end)
    n_steps = rec.shape[0]
    slip_l = rec[:, K.REC_SLIP_L] - rec[n_grip - 1, K.REC_SLIP_L]
    slip_r = rec[:, K.REC_SLIP_R] - rec[n_grip - 1, K.REC_SLIP_R]
    slip = np.where(np.arange(n_steps) >= n_grip - 1, 0.5 * (slip_l + slip_r), 0.0)
    time = rec[:, K.REC_TIME]
    palm_z = rec[:, K.REC_PALM_Z]
    com_z = rec[:, K.REC_COM_Z]
    friction = rec[:, K.REC_FRICTION_L] + rec[:, K.REC_FRICTION_R]
    normal = 0.5 * (rec[:, K.REC_NORMAL_L] + rec[:, K.REC_NORMAL_R])
    shortfall = float(palm_z[-1] - (com_z[-1] - com_z[n_grip - 1]))
    slip_final = float(slip[-1])
    measured = slip_final if c.measure == "contact" else shortfall
    off_table = not on_table or bool(rec[-1, K.REC_TABLE_N] == 0.0 and rec[-1, K.REC_MIN_Z] > 0.0)
    lifted = bool(measured <= c.tolerance_m and off_table)
    series = LiftAttemptSeries(
        time_s=time,
        palm_z_m=palm_z,
        object_com_z_m=com_z,
        slip_m=slip,
        friction_force_n=friction,
        normal_force_n=normal,
    )
    details: dict[str, object] = {
        "slip_left_m": float(slip_l[-1]),
        "slip_right_m": float(slip_r[-1]),
        "shortfall_m": shortfall,
        "peak_friction_n": float(friction.max()),
        "off_table": off_table,
        "lift_start_s": t_lift,
        "rise_m": rise,
        "profile": p.as_dict(),
        "release": r.as_dict(),
        "stopped_early": n_steps < n_planned,
        "slip_measure": c.measure,
        "min_particle_z_m": float(rec[:, K.REC_MIN_Z].min()),
        "max_palm_penetration_m": float(rec[:, K.REC_PENETRATION].max()),
        "max_speed_m_s": float(rec[:, K.REC_MAX_SPEED].max()),
        "slip_tolerance_m": c.tolerance_m,
    }
    return TrialOutcome(
        grip_force_n=float(grip_force_n),
        lifted=lifted,
        slip_m=measured,
        series=series,
        details=details,
        scene=scene,
    )


@dataclass(frozen=True)
class FreeRunSeries:
    """A free object (no palms) falling or resting on the table; every step.

    Attributes:
        time_s: ``[n]``; com_m: centre of mass, m, ``[n, 3]``; table_force_n: table reaction, N,
        ``[n]``; min_z_m: lowest particle height, m, ``[n]``.
    """

    time_s: FloatArray
    com_m: FloatArray
    table_force_n: FloatArray
    min_z_m: FloatArray
    extras: dict[str, float] = field(default_factory=dict)


def free_run(
    spec: ObjectSpec,
    *,
    duration_s: float,
    drop_height_m: float = 0.0,
    settings: SimSettings | None = None,
    table: bool = True,
) -> FreeRunSeries:
    """Release ``spec`` undeformed and at rest with its bottom ``drop_height_m`` above the table."""
    s = settings or SimSettings()
    n_steps = int(plan_run(spec, s, max(1, round(duration_s / s.dt_s)), "free run").steps)
    _kernels_ready()
    model = build_model(
        spec, s, gripped=False, gravity=True, table=table, resting=False, lift_m=drop_height_m
    )
    zeros = np.zeros(n_steps + 1)
    _, _, rec = run_model(model, zeros, zeros)
    _check_finite(rec, "free run", spec)
    com = np.stack([rec[:, K.REC_COM_X], rec[:, K.REC_COM_Y], rec[:, K.REC_COM_Z]], axis=1)
    com[:, 2] += float(np.average(model.base_x[:, 2], weights=model.particle_masses_kg))
    return FreeRunSeries(
        time_s=rec[:, K.REC_TIME],
        com_m=com,
        table_force_n=rec[:, K.REC_TABLE_N],
        min_z_m=rec[:, K.REC_MIN_Z],
    )


def rigid_lift_force_n(spec: ObjectSpec, profile: LiftProfile) -> float:
    """Grip force per palm lifting a rigid object through ``profile``: m (g + a_max)/(2 mu), N
    (:func:`deformctl.physics.rigid_grip_force_n` of the object's weight at the peak
    acceleration)."""
    return rigid_grip_force_n(
        spec.mass_kg * (GRAVITY_M_S2 + profile.peak_accel_m_s2), spec.friction_mu
    )
