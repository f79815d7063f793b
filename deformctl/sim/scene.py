"""The scene of a run, from its record: surface particles, palms, forces, stick and slip.

The step loops copy the particle positions into a frame buffer every ``frame_every`` steps when
asked (``Drive.frames``, :func:`deformctl.sim.engine.run_model`'s ``scene_every``); nothing else
in the step reads them, so a run with a scene computes the very numbers of a run without one.
Everything else a frame shows is already in the record of every step (palm positions, the palms'
normal and friction forces, the sliding accumulated at each palm): :func:`scene_frames` picks
the frame rows out of it and judges stick and slip from the per-step sliding speed
(:data:`deformctl.scene.STICK_SPEED_M_S`).
"""

from __future__ import annotations

import numpy as np

from deformctl.arraytypes import FloatArray, IntArray
from deformctl.scene import NO_PALM, STICK_SPEED_M_S, SceneFrames
from deformctl.sim.engine import Model, positions_m
from deformctl.sim.step import record as K

#: The drawn particles' diameter, as a fraction of the lattice's shortest element.
PARTICLE_DIAMETER_FRACTION = 0.35


def frame_buffer(model: Model, n_steps: int, every: int) -> FloatArray:
    """An empty frame buffer for ``n_steps`` steps with a frame every ``every`` steps (0: none),
    m, ``[n_frames, n, 3]``."""
    n_frames = 0 if every <= 0 else (n_steps - 1) // every + 1
    return np.zeros((n_frames, model.lattice.n_particles, 3))


def surface_particles(model: Model) -> IntArray:
    """Indices of the lattice's surface particles (an index at either end of some axis)."""
    grid = model.lattice.grid_index
    shape = np.asarray(model.lattice.shape)
    on_surface = np.any((grid == 0) | (grid == shape - 1), axis=1)
    return np.flatnonzero(on_surface).astype(np.int64)


def scene_frames(
    model: Model,
    rec: FloatArray,
    frames: FloatArray,
    every: int,
    q_final: FloatArray,
    *,
    start: bool = False,
) -> SceneFrames:
    """The scene of a run: its frame rows (0, every, 2 every, ...) and its last row.

    Args:
        model: the model that ran.
        rec: the run's record, ``[n_run, N_REC]`` (``n_run`` is short when it stopped early).
        frames: the positions the step loop copied (:func:`frame_buffer`), m.
        every: steps between frames (> 0).
        q_final: the DOF displacements at the end of the run (the last frame's positions when
            the last row is not a frame row).
        start: add a frame at t = 0 (the state before the first step: the model's base shape,
            the palms at rest) for a series whose samples start there (a squeeze's).
    """
    n_run = rec.shape[0]
    rows = list(range(0, n_run, every))
    positions = [frames[k] for k in range(len(rows))]
    if rows[-1] != n_run - 1:
        rows.append(n_run - 1)
        positions.append(positions_m(model, q_final))
    dt = model.settings.dt_s
    cum = rec[:, [K.REC_SLIP_L, K.REC_SLIP_R]]
    step_slip = np.diff(cum, axis=0, prepend=np.zeros((1, 2)))
    slips_step = step_slip > STICK_SPEED_M_S * dt
    surface = surface_particles(model)
    idx = np.asarray(rows)
    prev = np.concatenate([[-1], idx[:-1]])
    slip = cum[idx] - np.where(prev[:, None] >= 0, cum[np.maximum(prev, 0)], 0.0)
    slipping = np.array(
        [np.any(slips_step[p + 1 : r + 1], axis=0) for p, r in zip(prev, idx, strict=True)]
    )
    palm_x = rec[idx][:, [K.REC_PALM_XL, K.REC_PALM_XR]]
    if model.palm_x_dof[0] < 0:  # a free object: no palms
        palm_x = np.zeros((idx.size, 2))
    out = {
        "time_s": rec[idx, K.REC_TIME],
        "positions_m": np.stack(positions)[:, surface, :],
        "palm_x_m": palm_x,
        "palm_z_m": rec[idx, K.REC_PALM_Z],
        "normal_force_n": rec[idx][:, [K.REC_NORMAL_L, K.REC_NORMAL_R]],
        "tangential_force_n": rec[idx][:, [K.REC_FRICTION_L, K.REC_FRICTION_R]],
        "slip_m": slip,
        "slipping": slipping.reshape(idx.size, 2),
    }
    if start:
        out = {
            key: np.concatenate([_start_value(key, model, surface), value])
            for key, value in out.items()
        }
    base = model.base_x
    face = model.lattice.face_mask(0)
    spacing = float(model.lattice.rest_length_m.min())
    return SceneFrames(
        **out,
        particle_index=surface,
        contact_side=_contact_side(model, surface),
        palm_size_m=(
            spacing,
            float(np.ptp(base[:, 1])) or spacing,
            float(np.ptp(base[face, 2])) or spacing,
        ),
        palm_centre_m=(float(base[:, 1].mean()), float(base[face, 2].mean())),
        particle_diameter_m=PARTICLE_DIAMETER_FRACTION * spacing,
        table=bool(model.bottom_particles.size > 0),
    )


def _start_value(key: str, model: Model, surface: IntArray) -> np.ndarray:
    """The t = 0 frame's value of ``key``: the base shape, the palms at rest, no force."""
    if key == "positions_m":
        return np.asarray(model.base_x[surface][None, :, :])
    if key == "palm_x_m":
        return np.asarray(model.palm_x0[None, :])
    if key == "slipping":
        return np.zeros((1, 2), dtype=bool)
    if key in ("time_s", "palm_z_m"):
        return np.zeros(1)
    return np.zeros((1, 2))


def _contact_side(model: Model, surface: IntArray) -> IntArray:
    side = np.full(surface.size, NO_PALM, dtype=np.int64)
    if model.palm_x_dof[0] >= 0:
        for s in (0, 1):
            side[model.lattice.face_mask(s)[surface]] = s
    return side
