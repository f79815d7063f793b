"""``deformctl measure images TOP SIDE``: an object's catalog row from a top and a side image.

The options are checked (:func:`deformctl.cli._image_options.check_image_options`) and
:func:`deformctl.measure.images.measure_images` measures the images and writes the row; this
module prints what it found.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import typer

from deformctl.artifacts.io import is_stdio
from deformctl.cli._image_options import ImageOptions, check_image_options

if TYPE_CHECKING:  # pragma: no cover - OpenCV and the catalog writer load when it runs
    from deformctl.catalog import MeasuredObject


def measure_images(
    images: Sequence[str],
    opts: ImageOptions,
    obj: MeasuredObject,
    *,
    output: str,
    force: bool,
    quiet: bool = False,
) -> None:
    """Measure the object in ``images = (top, side)`` and write (or append) its catalog row;
    print the size found unless ``quiet`` (warnings print).

    Raises:
        UsageError, MissingInputError, OutputExistsError, InputDataError: see
            :func:`deformctl.measure.images.measure_images`.
    """
    from deformctl.measure.images import measure_images as measure_images_to_catalog

    reference, mask = check_image_options(opts)
    result = measure_images_to_catalog(
        images,
        obj,
        reference=reference,
        mask=mask,
        output=output,
        force=force,
        append=opts.append,
        camera_matrix=opts.camera_matrix,
        debug_dir=opts.debug_dir,
    )
    size = result.size
    if size.assumed_hfov_deg is not None:
        typer.echo(
            f"warning: {images[0]}: no --camera-matrix: assumed a {size.assumed_hfov_deg:g}° "
            f"horizontal field of view; the height correction applied to the top view is "
            f"{size.height_correction_pct:+.1f} % and depends on that guess (give the camera's "
            "calibration for sizes within 2 %)",
            err=True,
        )
    if quiet:
        return
    where = "stdout" if is_stdio(output) else output
    typer.echo(
        f"{where}: {obj.object_id!r} {round(size.size_x_cm, 2)} x {round(size.size_y_cm, 2)} x "
        f"{round(size.size_z_cm, 2)} cm "
        f"(x, y from the top view, z from the side view; {result.rows} row(s) in the catalog)",
        err=True,
    )


__all__ = ["measure_images"]
