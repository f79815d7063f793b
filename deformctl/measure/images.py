"""The images source of ``measure``: an object's catalog row from a top and a side image.

Unlike the recording sources (which write a squeeze log), the images source writes an
object-catalog row: ``size_x_cm`` and ``size_y_cm`` from the top view, ``size_z_cm`` from the
side view (:func:`deformctl.vision.measure_object_size`), with the given weight and friction.
The catalog is created, overwritten with ``force``, or extended with ``append`` (an atomic
rewrite that keeps the file's format and extra columns and refuses an ``object_id`` it has).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import pandas as pd

from deformctl.artifacts import (
    Provenance,
    check_input_path,
    check_output_path,
    read_catalog,
    write_catalog,
)
from deformctl.artifacts.io import is_stdio
from deformctl.artifacts.tables import append_catalog_row
from deformctl.catalog import MeasuredObject
from deformctl.errors import DeformctlError, InputDataError, UsageError
from deformctl.measure.options import ObjectMask, ScaleReference
from deformctl.reprs import short_repr

if TYPE_CHECKING:  # pragma: no cover - typing only; OpenCV is imported when used
    from deformctl.vision import SizeMeasurement


DEFAULT_MASK = ObjectMask()  #: the difference from a smooth background


@dataclass(frozen=True)
class ImagesResult:
    """What :func:`measure_images` measured and wrote.

    Attributes:
        size: the measurement (sizes, the views, the height correction and whether the
            field of view was assumed).
        rows: the rows of the catalog written.
    """

    __repr__ = short_repr

    size: SizeMeasurement
    rows: int


def measure_images(
    images: Sequence[str],
    obj: MeasuredObject,
    *,
    reference: ScaleReference,
    mask: ObjectMask = DEFAULT_MASK,
    output: str,
    force: bool = False,
    append: bool = False,
    camera_matrix: str | None = None,
    debug_dir: str | None = None,
) -> ImagesResult:
    """Measure the object in ``images = (top, side)`` and write (or append) its catalog row.

    Checks, in order (nothing is written when one fails): options (exit 2), the input images
    exist (66), the output may be written (1) and, with ``append``, the catalog is valid and
    does not have ``object_id`` yet (65); then the images are measured (65 on a bad image).

    Args:
        images: the top and the side image.
        obj: the object's id, weight and friction (required: a catalog row needs it).
        reference: the scale reference in both photos.
        mask: how the object is told from the scene (a colour range, or the empty scenes).
        output: the catalog (``-`` for stdout).
        force: overwrite an existing catalog.
        append: add the row to the catalog (created if missing).
        camera_matrix: the camera's calibration file.
        debug_dir: write annotated images here.

    Raises:
        UsageError, MissingInputError, OutputExistsError, InputDataError: see above.
    """
    top, side = images
    object_id, friction_mu = obj.object_id, obj.friction_mu
    if friction_mu is None:
        raise UsageError("measure images needs --friction-mu (the catalog requires friction_mu)")
    if append and force:
        raise UsageError("--append and --force cannot be used together")
    if append and is_stdio(output):
        raise UsageError("--append needs a catalog file, not - (stdout)")
    inputs = [top, side, *(mask.background or ())]
    if camera_matrix is not None:
        inputs.append(camera_matrix)
    for path in inputs:
        if is_stdio(path):
            raise UsageError("--images, --background and --camera-matrix read files, not -")
        check_input_path(path)
    existing: pd.DataFrame | None = None
    if append and os.path.exists(output):
        check_input_path(output)
        existing = read_catalog(output)
        if object_id in set(existing["object_id"]):
            raise InputDataError(
                f"object_id {object_id!r} is in the catalog already; choose another "
                "--object-id or remove its row first",
                path=output,
            )
    elif not force and not is_stdio(output) and os.path.exists(output):
        raise DeformctlError(
            "exists already, not overwriting (use --force to replace it, or --append to add "
            "the row)",
            path=output,
        )
    else:
        check_output_path(output, force)
    from deformctl.vision import (  # deferred: OpenCV
        catalog_row,
        load_camera_calibration,
        measure_object_size,
    )

    camera = None if camera_matrix is None else load_camera_calibration(camera_matrix)
    size = measure_object_size(
        top, side, debug_dir=debug_dir, camera=camera, **reference.kwargs(), **mask.kwargs()
    )
    row = catalog_row(size, object_id=object_id, weight_n=obj.weight_n, friction_mu=friction_mu)
    settings = {
        "source": "images",
        **reference.as_dict(),
        **mask.as_dict(),
        "camera": None
        if camera is None
        else {
            "file": camera.path,
            "source": camera.source,
            "camera_matrix": camera.camera_matrix.tolist(),
            "distortion_coefficients": camera.distortion.tolist(),
        },
        "assumed_hfov_deg": size.assumed_hfov_deg,
        "height_correction_pct": size.height_correction_pct,
        "measured_size_cm": [size.size_x_cm, size.size_y_cm, size.size_z_cm],
        "side_visible_width_cm": size.side.size_along_x_cm,
    }
    provenance = Provenance.from_invocation(inputs, settings=settings)
    if existing is not None:
        n_rows = append_catalog_row(output, row, existing, provenance=provenance)
    else:
        n_rows = len(write_catalog(pd.DataFrame([row]), output, provenance=provenance, force=force))
    return ImagesResult(size=size, rows=n_rows)
