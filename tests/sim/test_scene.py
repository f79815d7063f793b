"""deformctl.sim.scene: a run's scene changes no simulated number, and shows the simulator's state.

The frames are checked against an independent reading of the state: the same run cut short at
the frame's step, whose final DOF displacements the step loop returns (not the frame copy).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from deformctl.errors import UsageError
from deformctl.scene import NO_PALM
from deformctl.sim import (
    LiftProfile,
    ObjectSpec,
    SimSettings,
    SupportRelease,
    lift_attempt,
    squeeze,
)
from deformctl.sim.engine import build_model, positions_m, run_model
from deformctl.sim.scene import frame_buffer, scene_frames, surface_particles
from deformctl.sim.step import record as K

SPEC = ObjectSpec("cube", (4.0, 4.0, 4.0), 1.0, 0.5, 10.0, 0.5)
FAST = SimSettings(particles_per_side=4, dt_s=2e-3, grip_settle_s=0.02)
F_W = SPEC.mass_kg * 9.81 / (2 * SPEC.friction_mu)


def _same_outcome(a: object, b: object) -> None:
    sa, sb = a.series, b.series  # type: ignore[attr-defined]
    for name in ("time_s", "palm_z_m", "object_com_z_m", "slip_m", "friction_force_n"):
        assert np.array_equal(getattr(sa, name), getattr(sb, name)), name
    assert np.array_equal(sa.normal_force_n, sb.normal_force_n)
    assert a.lifted == b.lifted  # type: ignore[attr-defined]
    assert a.details == b.details  # type: ignore[attr-defined]


@pytest.mark.parametrize("mode", ["table", "support"])
def test_a_scene_changes_no_simulated_number(mode: str) -> None:
    release = SupportRelease(mode=mode)  # type: ignore[arg-type]
    for grip in (0.8 * F_W, 3.0 * F_W):
        off = lift_attempt(SPEC, grip, settings=FAST, release=release)
        assert off.scene is None
        for hz in (30.0, 1.0 / FAST.dt_s):  # a frame every 17 steps, and every step
            on = lift_attempt(SPEC, grip, settings=FAST, release=release, scene_hz=hz)
            assert on.scene is not None
            _same_outcome(off, on)
    sq_off = squeeze(SPEC, peak_force_n=1.0, ramp_s=0.02, hold_s=0.02, settings=FAST)
    sq_on = squeeze(SPEC, peak_force_n=1.0, ramp_s=0.02, hold_s=0.02, settings=FAST, scene_hz=100.0)
    for name in ("time_s", "force_n", "compression_m", "palm_left_x_m", "palm_right_x_m"):
        assert np.array_equal(getattr(sq_off, name), getattr(sq_on, name)), name


def _cut_run(grip: float, rows: int) -> tuple[object, np.ndarray, np.ndarray]:
    """The table-mode lift attempt of :func:`lift_attempt` run for its first ``rows`` steps
    only, scene off: (model, final q, record)."""
    model = build_model(SPEC, FAST, gripped=True, resting=True, table=True)
    n_grip = max(1, round((FAST.grip_ramp_s + FAST.grip_settle_s) / FAST.dt_s))
    t = np.arange(rows + 1) * FAST.dt_s
    force = grip * np.clip(t / FAST.grip_ramp_s, 0.0, 1.0)
    profile = LiftProfile()
    vz = profile.velocity_m_s(t - n_grip * FAST.dt_s, profile.rise_m(SPEC))
    q, _, rec = run_model(model, force, vz)
    return model, q, rec


def test_frames_are_the_simulator_state_at_their_steps() -> None:
    grip = 0.8 * F_W  # slips: the state moves at the contacts too
    out = lift_attempt(SPEC, grip, settings=FAST, scene_hz=50.0)
    scene = out.scene
    assert scene is not None
    assert out.series is not None
    every = 10  # 50 Hz at 2 ms
    assert np.allclose(np.diff(scene.time_s)[:-1], every * FAST.dt_s)
    for k in (0, 3, len(scene) - 1):
        row = round(scene.time_s[k] / FAST.dt_s) - 1
        model, q_cut, rec = _cut_run(grip, row + 1)
        surface = surface_particles(model)  # type: ignore[arg-type]
        assert np.array_equal(scene.positions_m[k], positions_m(model, q_cut)[surface])  # type: ignore[arg-type]
        assert scene.time_s[k] == rec[-1, K.REC_TIME] == out.series.time_s[row]
        assert scene.palm_z_m[k] == rec[-1, K.REC_PALM_Z] == out.series.palm_z_m[row]
        assert np.array_equal(scene.palm_x_m[k], rec[-1, [K.REC_PALM_XL, K.REC_PALM_XR]])
        assert np.array_equal(scene.normal_force_n[k], rec[-1, [K.REC_NORMAL_L, K.REC_NORMAL_R]])
        assert np.array_equal(
            scene.tangential_force_n[k], rec[-1, [K.REC_FRICTION_L, K.REC_FRICTION_R]]
        )
    assert np.array_equal(scene.particle_index, surface)
    faces = [model.lattice.face_mask(side)[surface] for side in (0, 1)]  # type: ignore[attr-defined]
    for side in (0, 1):  # the particles on each palm's face are its contacts
        assert np.array_equal(scene.contact_side == side, faces[side])
    assert np.all(scene.contact_side[~faces[0] & ~faces[1]] == NO_PALM)


def test_stick_and_slip_fire_on_slip_and_stay_silent_on_a_firm_grip() -> None:
    slips = lift_attempt(SPEC, 0.8 * F_W, settings=FAST, scene_hz=50.0)
    holds = lift_attempt(SPEC, 3.0 * F_W, settings=FAST, scene_hz=50.0)
    assert slips.scene is not None
    assert holds.scene is not None
    assert not slips.lifted
    assert holds.lifted
    assert slips.scene.slipping.any()
    assert not holds.scene.slipping.any()
    assert np.all(holds.scene.slip_m <= 1e-15)
    # each frame's sliding adds up to the palm's accumulated sliding: nothing lost between frames
    _, _, rec = _cut_run(0.8 * F_W, len(slips.series.time_s))  # type: ignore[union-attr]
    np.testing.assert_allclose(
        slips.scene.slip_m.sum(axis=0), rec[-1, [K.REC_SLIP_L, K.REC_SLIP_R]], rtol=1e-12
    )
    # a frame counts as slipping exactly when its palm slid faster than the threshold somewhere
    moved = slips.scene.slip_m > 0
    assert np.all(slips.scene.slipping <= moved)


def test_a_squeeze_scene_starts_at_rest_at_t0() -> None:
    sq = squeeze(SPEC, peak_force_n=1.0, ramp_s=0.02, hold_s=0.02, settings=FAST, scene_hz=100.0)
    scene = sq.scene
    assert scene is not None
    model = build_model(SPEC, FAST, gripped=True, gravity=True, table=True)
    assert scene.time_s[0] == 0.0
    assert np.array_equal(scene.positions_m[0], model.base_x[surface_particles(model)])
    assert scene.time_s[-1] == sq.time_s[-1]
    rows = [round(v / FAST.dt_s) for v in scene.time_s]  # the squeeze's samples start at t = 0
    assert sq.palm_left_x_m is not None
    np.testing.assert_array_equal(scene.palm_x_m[:, 0], sq.palm_left_x_m[rows])
    assert scene.table


def test_the_frame_buffer_covers_every_frame_step() -> None:
    model = build_model(SPEC, FAST, gripped=True)
    assert frame_buffer(model, 100, 0).shape[0] == 0
    assert frame_buffer(model, 100, 10).shape == (10, model.lattice.n_particles, 3)
    assert frame_buffer(model, 101, 10).shape[0] == 11
    rec = np.zeros((5, 17))
    frames = frame_buffer(model, 5, 2)
    scene = scene_frames(model, rec, frames, 2, np.zeros(model.n_dof))
    assert len(scene) == 3  # rows 0, 2, 4


def test_a_rate_above_the_step_rate_is_refused_before_simulating() -> None:
    with pytest.raises(UsageError, match="step rate"):
        lift_attempt(SPEC, F_W, settings=FAST, scene_hz=501.0)
    with pytest.raises(UsageError, match=">= 0"):
        squeeze(SPEC, peak_force_n=1.0, settings=FAST, scene_hz=-1.0)


def test_the_scene_counts_in_the_memory_budget() -> None:
    from deformctl.sim.engine import (
        GIB,
        SCENE_FRAME_BYTES_PER_PARTICLE,
        STEP_BYTES,
        memory_estimate_bytes,
        plan_run,
    )

    n_steps = 500
    n = 4**3  # particles_per_side=4 on a cube
    without = memory_estimate_bytes(SPEC, FAST) + n_steps * STEP_BYTES
    frames = (n_steps + 2) * n * SCENE_FRAME_BYTES_PER_PARTICLE  # a frame every step
    tight = dataclasses.replace(FAST, memory_budget_gib=(without + 0.5 * frames) / GIB)
    plan_run(SPEC, tight, n_steps, "squeeze")  # fits without its scene
    plan_run(SPEC, tight, n_steps, "squeeze", frame_every=10)  # a frame every 10 steps fits
    with pytest.raises(UsageError, match="memory"):
        plan_run(SPEC, tight, n_steps, "squeeze", frame_every=1)
    with pytest.raises(UsageError, match="memory"):  # refused before simulating
        squeeze(SPEC, peak_force_n=1.0, ramp_s=0.5, hold_s=0.5, settings=tight, scene_hz=500.0)
