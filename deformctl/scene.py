"""The scene of a simulated squeeze or lift attempt: what a 3-D viewer draws, frame by frame.

:class:`SceneFrames` is the contract between the simulator (:mod:`deformctl.sim`, which records it
at a chosen rate when asked, :func:`deformctl.sim.scene.scene_frames`) and the log writers
(:mod:`deformctl.artifacts.mcap.scene`, which turn it into Foxglove ``foxglove.SceneUpdate``
messages on ``/scene`` and per-palm contact messages on ``/palms``). It carries, at each frame,
the positions of the object's surface particles, both palms' positions, the normal and tangential
force each palm carries, and whether each palm's contact stuck or slipped since the previous
frame.

The rate is one quantity (:data:`~deformctl.quantities.SCENE_HZ`: frames per second of simulated
time, 0 for no scene) checked once, by :func:`check_scene_hz` (at most the simulator's step rate
1/dt), where the options type that carries it is built; :func:`scene_every_steps` only counts.

Stick and slip. Each palm grips its face of the lattice as one rigid patch
(:mod:`deformctl.sim.engine`, "Palm model"), so a palm's contact is in one state at a time: it
sticks (the patch moves with the palm; the contact solve holds that exactly) or it slides at the
friction bound. The simulator records, every step, the sliding accumulated at each palm; a step
*slips* when that sliding advanced faster than :data:`STICK_SPEED_M_S`. Measured on the paper's
four objects under both presets (lifts at 1x and 3x F_w): a sticking step's sliding speed is 0 or
round-off (at most 3e-17 m/s), a slipping step's at least 1.1e-6 m/s; the threshold sits between,
eight orders above the one and three below the other.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from deformctl.arraytypes import BoolArray, FloatArray, IntArray
from deformctl.errors import UsageError
from deformctl.quantities import SCENE_HZ

#: Scene frames per second of simulated time unless asked otherwise (a video's rate).
DEFAULT_SCENE_HZ = 30.0
#: A palm's contact slips in a step when the object slides against it faster than this, m/s.
STICK_SPEED_M_S = 1e-9
#: ``contact_side`` of a particle that touches no palm.
NO_PALM = -1


def check_scene_hz(scene_hz: float, dt_s: float) -> float:
    """``scene_hz`` as a float when it is a scene rate the simulator can record at time step
    ``dt_s``: the rule :data:`~deformctl.quantities.SCENE_HZ` and at most one frame per step.

    Raises:
        UsageError: ``scene_hz`` negative, not finite, or above the step rate ``1 / dt_s``
            (exit 2).
    """
    hz: float = SCENE_HZ.check(scene_hz)
    step_rate = 1.0 / dt_s
    if hz > step_rate * (1.0 + 1e-12):
        raise UsageError(
            f"--scene-hz {hz:g} is above the simulator's step rate {step_rate:g} Hz "
            f"(dt {dt_s:g} s): at most one frame per step"
        )
    return hz


def scene_every_steps(scene_hz: float, dt_s: float) -> int:
    """Steps between two scene frames for ``scene_hz`` frames per simulated second (0: none),
    a rate checked already (:func:`check_scene_hz`).

    The frames fall on every ``round(1 / (scene_hz dt))``-th step (at least every step), so the
    rate is ``scene_hz`` to within half a step.
    """
    if not scene_hz > 0:
        return 0
    return max(1, round(1.0 / dt_s / scene_hz))


@dataclass(frozen=True)
class SceneFrames:
    """The scene of one squeeze or lift attempt at ``k`` frames (SI units, world frame: z up,
    the table at z = 0, the palms normal to x).

    Attributes:
        time_s: frame times on the time base of the squeeze's or attempt's samples, s, ``[k]``.
        positions_m: the object's surface particles, m, ``[k, m, 3]``.
        particle_index: each surface particle's index in the lattice, ``[m]``.
        contact_side: the palm each particle touches (0 left, 1 right, :data:`NO_PALM`), ``[m]``.
        palm_x_m: x of the left and right palms' contact faces, m, ``[k, 2]``.
        palm_z_m: the palms' height above their start, m, ``[k]``.
        normal_force_n: normal force each palm (left, right) feels, N, ``[k, 2]``.
        tangential_force_n: vertical force each palm exerts on the object (+ up), N, ``[k, 2]``.
        slip_m: sliding at each palm since the previous frame (the first: since the start), m,
            ``[k, 2]``.
        slipping: whether each palm slipped in any step since the previous frame, ``[k, 2]``.
        palm_size_m: the drawn palms' size (thickness along x, the object's y and z extent), m.
        palm_centre_m: the palms' centre in y and z at the start, m, ``[2]``.
        particle_diameter_m: the drawn particles' diameter, m.
        table: whether the object starts on the table (drawn below z = 0).
    """

    time_s: FloatArray
    positions_m: FloatArray
    particle_index: IntArray
    contact_side: IntArray
    palm_x_m: FloatArray
    palm_z_m: FloatArray
    normal_force_n: FloatArray
    tangential_force_n: FloatArray
    slip_m: FloatArray
    slipping: BoolArray
    palm_size_m: tuple[float, float, float]
    palm_centre_m: tuple[float, float]
    particle_diameter_m: float
    table: bool

    def __post_init__(self) -> None:
        k = self.time_s.shape[0]
        m = self.particle_index.shape[0]
        shapes = {
            "positions_m": (self.positions_m.shape, (k, m, 3)),
            "contact_side": (self.contact_side.shape, (m,)),
            "palm_x_m": (self.palm_x_m.shape, (k, 2)),
            "palm_z_m": (self.palm_z_m.shape, (k,)),
            "normal_force_n": (self.normal_force_n.shape, (k, 2)),
            "tangential_force_n": (self.tangential_force_n.shape, (k, 2)),
            "slip_m": (self.slip_m.shape, (k, 2)),
            "slipping": (self.slipping.shape, (k, 2)),
        }
        for name, (got, want) in shapes.items():
            if got != want:
                raise ValueError(f"{name} has shape {got}, expected {want}")

    def __len__(self) -> int:
        return int(self.time_s.shape[0])

    def palm_centres_m(self, frame: int) -> FloatArray:
        """Centres of the drawn left and right palms at ``frame``, m, ``[2, 3]``: each palm's box
        lies outside the object, its inner face on the contact face."""
        half = 0.5 * self.palm_size_m[0]
        y, z0 = self.palm_centre_m
        z = z0 + float(self.palm_z_m[frame])
        xl, xr = (float(v) for v in self.palm_x_m[frame])
        return np.array([[xl - half, y, z], [xr + half, y, z]])
