"""``--scene-hz``: the rate of a simulated log's 3-D scene (``measure --sim``, ``lift --sim``)."""

from __future__ import annotations

from typing import Annotated

import typer

from deformctl.cli._options import HEAVY_DEFAULTS, default

#: :data:`deformctl.scene.DEFAULT_SCENE_HZ`, restated (the scene module imports numpy).
DEFAULT_SCENE_HZ = float(str(HEAVY_DEFAULTS["simulate_squeezes.scene_hz"]))

SceneHz = Annotated[
    float | None,
    typer.Option(
        "--scene-hz",
        metavar="HZ",
        help="Sim: frames per simulated second of the log's 3-D scene for Foxglove (/scene: "
        "palms, surface particles, stuck / slipping contacts; /palms: each palm's forces and "
        f"stick/slip); 0: none, at most 1/dt {default('simulate_squeezes.scene_hz')}.",
    ),
]


def scene_rate(value: float | None) -> float:
    """The rate ``--scene-hz`` asks for (its default when not given); checked where it is used
    (:func:`deformctl.scene.scene_every_steps`)."""
    return DEFAULT_SCENE_HZ if value is None else float(value)
