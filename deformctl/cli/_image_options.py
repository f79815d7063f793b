"""``deformctl measure --images``: its options, and their checks.

The options are :class:`ImageOptions`; :func:`check_image_options` turns them into
:func:`deformctl.vision.measure_object_size`'s reference and segmentation arguments.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from typing import Annotated, Any

import typer

from deformctl.cli._options import HEAVY_DEFAULTS
from deformctl.errors import UsageError

DEFAULT_MARKER_DICT = str(HEAVY_DEFAULTS["measure_object_size.marker_dict"])

Images = Annotated[
    tuple[str, str] | None,
    typer.Option(
        "--images",
        metavar="TOP SIDE",
        help="Source: a top and a side image with a scale reference; writes a catalog row "
        "(object size from the images) instead of a squeeze log.",
    ),
]
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
    """The ``--images`` options as given on the command line (None / False: not given)."""

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

    def given(self) -> dict[str, object]:
        """Flag -> value of every option given (for refusing them with another source)."""
        return {k: v for k, v in self.flags().items() if v not in (None, False)}

    def flags(self) -> dict[str, object]:
        """Flag -> value of every option."""
        return {
            "--marker-size-cm": self.marker_size_cm,
            "--marker-dict": self.marker_dict,
            "--marker-id": self.marker_id,
            "--checkerboard": self.checkerboard,
            "--square-size-cm": self.square_size_cm,
            "--color-range": self.color_range,
            "--background": self.background,
            "--debug-dir": self.debug_dir,
            "--append": self.append,
            "--camera-matrix": self.camera_matrix,
        }


#: The flags of :class:`ImageOptions` (only ``--images`` takes them).
FLAGS = tuple(ImageOptions().flags())


def parse_checkerboard(text: str) -> tuple[int, int]:
    """Parse ``COLSxROWS`` (inner corners, e.g. ``7x5``).

    Raises:
        UsageError: not two integers >= 2 joined by ``x``.
    """
    match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if not match or int(match[1]) < 2 or int(match[2]) < 2:
        raise UsageError(
            f"--checkerboard: expected COLSxROWS inner corners, each >= 2 (e.g. 7x5), got {text!r}"
        )
    return int(match[1]), int(match[2])


def parse_color_range(text: str) -> tuple[tuple[int, int, int], tuple[int, int, int]]:
    """Parse ``H,S,V:H,S,V`` (OpenCV HSV: H 0..179, S and V 0..255; lower, then upper bound).

    Raises:
        UsageError: a malformed range, a value out of range, or a lower bound above the upper.
    """
    bounds: list[tuple[int, int, int]] = []
    parts = text.split(":")
    for part in parts if len(parts) == 2 else []:
        values = part.split(",")
        if len(values) != 3 or not all(v.strip().isdigit() for v in values):
            break
        bounds.append((int(values[0]), int(values[1]), int(values[2])))
    if len(bounds) != 2:
        raise UsageError(
            f"--color-range: expected H,S,V:H,S,V (lower:upper, OpenCV HSV), got {text!r}"
        )
    lower, upper = bounds
    for bound in bounds:
        if bound[0] > 179 or bound[1] > 255 or bound[2] > 255:
            raise UsageError(f"--color-range: H must be 0..179, S and V 0..255, got {text!r}")
    if any(lo > hi for lo, hi in zip(lower, upper, strict=True)):
        raise UsageError(f"--color-range: lower bound above the upper bound in {text!r}")
    return lower, upper


def check_image_options(opts: ImageOptions) -> dict[str, Any]:
    """Check the options; return :func:`measure_object_size`'s reference/segmentation kwargs."""
    kwargs: dict[str, Any] = {"marker_dict": opts.marker_dict or DEFAULT_MARKER_DICT}
    if opts.checkerboard is not None:
        extra = {
            "--marker-size-cm": opts.marker_size_cm,
            "--marker-dict": opts.marker_dict,
            "--marker-id": opts.marker_id,
        }
        used = [flag for flag, value in extra.items() if value is not None]
        if used:
            raise UsageError(f"{', '.join(used)} cannot be used with --checkerboard")
        if opts.square_size_cm is None:
            raise UsageError("--checkerboard needs --square-size-cm")
        kwargs["checkerboard"] = parse_checkerboard(opts.checkerboard)
        kwargs["square_size_cm"] = _positive(opts.square_size_cm, "--square-size-cm")
    else:
        if opts.square_size_cm is not None:
            raise UsageError("--square-size-cm needs --checkerboard")
        if opts.marker_size_cm is None:
            raise UsageError(
                "--images needs --marker-size-cm (the side of the marker's black square) "
                "or --checkerboard COLSxROWS with --square-size-cm"
            )
        kwargs["marker_size_cm"] = _positive(opts.marker_size_cm, "--marker-size-cm")
        if opts.marker_id is not None:
            if opts.marker_id < 0:
                raise UsageError(f"--marker-id must be >= 0, got {opts.marker_id}")
            kwargs["marker_id"] = opts.marker_id
    if opts.color_range is not None and opts.background is not None:
        raise UsageError("--color-range and --background cannot be used together")
    if opts.color_range is not None:
        kwargs["color_range"] = parse_color_range(opts.color_range)
    debug_dir = opts.debug_dir
    if debug_dir is not None and os.path.exists(debug_dir) and not os.path.isdir(debug_dir):
        raise UsageError(f"--debug-dir {opts.debug_dir!r} exists and is not a directory")
    return kwargs


def _positive(value: float, flag: str) -> float:
    if not (math.isfinite(value) and value > 0):
        raise UsageError(f"{flag} must be a number > 0, got {value:g}")
    return float(value)
