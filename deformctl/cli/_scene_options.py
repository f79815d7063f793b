"""``--scene-hz``: the rate of a simulated log's 3-D scene (``measure --sim``, ``lift --sim``)."""

from __future__ import annotations

from typing import Annotated

import typer

from deformctl.scene import DEFAULT_SCENE_HZ

SceneHz = Annotated[
    float | None,
    typer.Option(
        "--scene-hz",
        metavar="HZ",
        help="Sim: frames per simulated second of the log's 3-D scene for Foxglove (/scene: "
        "palms, surface particles, stuck / slipping contacts; /palms: each palm's forces and "
        f"stick/slip); 0: none, at most 1/dt [default: {DEFAULT_SCENE_HZ:g}].",
    ),
]


def scene_rate(value: float | None) -> float:
    """The rate ``--scene-hz`` asks for (its default when not given); checked where it is used
    (:func:`deformctl.scene.scene_every_steps`)."""
    return DEFAULT_SCENE_HZ if value is None else float(value)
