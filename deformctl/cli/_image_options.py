"""``deformctl measure images``: its options, and their checks.

The options are :class:`ImageOptions`; :func:`check_image_options` turns them into the library's
:class:`~deformctl.measure.options.ScaleReference` and
:class:`~deformctl.measure.options.ObjectMask`.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from typing import Annotated

import typer

from deformctl.cli._options import HEAVY_DEFAULTS, OptionGroup
from deformctl.errors import UsageError
from deformctl.measure.options import ObjectMask, ScaleReference, parse_hsv_pair

DEFAULT_MARKER_DICT = str(HEAVY_DEFAULTS["measure_object_size.marker_dict"])

MarkerSizeCm = Annotated[
    float | None,
    typer.Option(
        "--marker-size-cm",
        metavar="S",
        help="Images: side of the ArUco marker's black square, cm.",
    ),
]
MarkerDict = Annotated[
    str | None,
    typer.Option(
        "--marker-dict",
        metavar="DICT",
        help=f"Images: ArUco dictionary [default: {DEFAULT_MARKER_DICT}].",
    ),
]
MarkerId = Annotated[
    int | None,
    typer.Option(
        "--marker-id", metavar="N", help="Images: use the marker with this id (others ignored)."
    ),
]
Checkerboard = Annotated[
    str | None,
    typer.Option(
        "--checkerboard",
        metavar="COLSxROWS",
        help="Images: a checkerboard (inner corners) instead of a marker.",
    ),
]
SquareSizeCm = Annotated[
    float | None,
    typer.Option(
        "--square-size-cm", metavar="S", help="Images: the checkerboard's square side, cm."
    ),
]
ColorRange = Annotated[
    str | None,
    typer.Option(
        "--color-range",
        metavar="H,S,V:H,S,V",
        help="Images: the object is this HSV range (OpenCV, H 0-179).",
    ),
]
Background = Annotated[
    tuple[str, str] | None,
    typer.Option(
        "--background",
        metavar="TOP_BG SIDE_BG",
        help="Images: the empty scenes; the object is what differs.",
    ),
]
DebugDir = Annotated[
    str | None,
    typer.Option(
        "--debug-dir",
        metavar="DIR",
        help="Images: write annotated images (marker, contour, sizes) here.",
    ),
]
CameraMatrix = Annotated[
    str | None,
    typer.Option(
        "--camera-matrix",
        metavar="FILE",
        help="Images: the camera's calibration, OpenCV calibrateCamera output saved by "
        "cv2.FileStorage (YAML or JSON: camera_matrix, distortion_coefficients) or a ROS "
        "camera_info YAML; photos are undistorted with it [default: a 60° horizontal field of "
        "view, no distortion, with a warning].",
    ),
]
Append = Annotated[
    bool,
    typer.Option("--append", help="Images: add the row to the catalog -o (created if missing)."),
]


@dataclass(frozen=True)
class ImageOptions:
    """The image options as given on the command line (None / False: not given)."""

    marker_size_cm: float | None = None
    marker_dict: str | None = None
    marker_id: int | None = None
    checkerboard: str | None = None
    square_size_cm: float | None = None
    color_range: str | None = None
    background: tuple[str, str] | None = None
    debug_dir: str | None = None
    append: bool = False
    camera_matrix: str | None = None


#: The image options as one :class:`ImageOptions`.
IMAGE = OptionGroup(
    "opts",
    (
        ("marker_size_cm", MarkerSizeCm, None),
        ("marker_dict", MarkerDict, None),
        ("marker_id", MarkerId, None),
        ("checkerboard", Checkerboard, None),
        ("square_size_cm", SquareSizeCm, None),
        ("color_range", ColorRange, None),
        ("background", Background, None),
        ("debug_dir", DebugDir, None),
        ("append", Append, False),
        ("camera_matrix", CameraMatrix, None),
    ),
    ImageOptions,
)


def parse_checkerboard(text: str) -> tuple[int, int]:
    """Parse ``COLSxROWS`` (inner corners, e.g. ``7x5``; each >= 2, checked by
    :class:`~deformctl.measure.options.ScaleReference`).

    Raises:
        UsageError: not two integers joined by ``x``.
    """
    match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if not match:
        raise UsageError(
            f"--checkerboard: expected COLSxROWS inner corners, each >= 2 (e.g. 7x5), got {text!r}"
        )
    return int(match[1]), int(match[2])


def parse_color_range(text: str) -> tuple[tuple[int, int, int], tuple[int, int, int]]:
    """Parse ``H,S,V:H,S,V`` (OpenCV HSV; lower, then upper bound; the ranges are checked by
    :class:`~deformctl.measure.options.ObjectMask`).

    Raises:
        UsageError: a malformed range.
    """
    pair = parse_hsv_pair(text)
    if pair is None:
        raise UsageError(
            f"--color-range: expected H,S,V:H,S,V (lower:upper, OpenCV HSV), got {text!r}"
        )
    return pair


def check_image_options(opts: ImageOptions) -> tuple[ScaleReference, ObjectMask]:
    """The options as the library's scale reference and object mask (each checked when built).

    Raises:
        UsageError: see :class:`~deformctl.measure.options.ScaleReference` and
            :class:`~deformctl.measure.options.ObjectMask`; a ``--debug-dir`` that is a file.
    """
    checkerboard = None if opts.checkerboard is None else parse_checkerboard(opts.checkerboard)
    reference = ScaleReference(
        marker_size_cm=opts.marker_size_cm,
        marker_dict=opts.marker_dict,
        marker_id=opts.marker_id,
        checkerboard=checkerboard,
        square_size_cm=opts.square_size_cm,
    )
    color = None if opts.color_range is None else parse_color_range(opts.color_range)
    mask = ObjectMask(color_range=color, background=opts.background)
    debug_dir = opts.debug_dir
    if debug_dir is not None and os.path.exists(debug_dir) and not os.path.isdir(debug_dir):
        raise UsageError(f"--debug-dir {opts.debug_dir!r} exists and is not a directory")
    return reference, mask
