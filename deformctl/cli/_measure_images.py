"""``deformctl measure --images TOP SIDE``: an object's catalog row from a top and a side image.

Unlike the recording sources of ``measure`` (which write a squeeze log), the images source writes
an object-catalog row: ``size_x_cm`` and ``size_y_cm`` from the top view, ``size_z_cm`` from the
side view (:func:`deformctl.vision.measure_object_size`), with the given weight and friction.
The catalog is created, overwritten with ``--force``, or extended with ``--append`` (an atomic
rewrite that keeps the file's format and extra columns and refuses an ``object_id`` it has).
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import pandas as pd
import typer

from deformctl.artifacts import (
    Provenance,
    atomic_output,
    check_input_path,
    check_output_path,
    read_catalog,
    validate_frame,
    write_catalog,
    write_table,
)
from deformctl.artifacts.io import is_stdio
from deformctl.errors import DeformctlError, InputDataError, UsageError

DEFAULT_MARKER_DICT = "DICT_4X4_50"
_PARQUET_MAGIC = b"PAR1"


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

    def given(self) -> dict[str, object]:
        """Flag -> value of every option given (for refusing them with another source)."""
        flags = {
            "--marker-size-cm": self.marker_size_cm,
            "--marker-dict": self.marker_dict,
            "--marker-id": self.marker_id,
            "--checkerboard": self.checkerboard,
            "--square-size-cm": self.square_size_cm,
            "--color-range": self.color_range,
            "--background": self.background,
            "--debug-dir": self.debug_dir,
            "--append": self.append,
        }
        return {flag: value for flag, value in flags.items() if value not in (None, False)}


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


def _check_options(opts: ImageOptions) -> dict[str, Any]:
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


def _is_parquet(path: str) -> bool:
    with open(path, "rb") as f:
        return f.read(4) == _PARQUET_MAGIC


def _append_row(
    path: str, row: Mapping[str, object], existing: pd.DataFrame, provenance: Provenance
) -> int:
    """Rewrite the catalog at ``path`` with ``row`` added, atomically, in the file's own format.

    Returns:
        The number of rows written.
    """
    table = pd.concat([existing, pd.DataFrame([dict(row)])], ignore_index=True)
    table.attrs = {}
    if _is_parquet(path):
        return len(write_table(table, path, "catalog", provenance=provenance, force=True))
    norm = validate_frame(table, "catalog", path=path)
    with atomic_output(path, force=True) as tmp:
        norm.to_csv(tmp, index=False)
    return len(norm)


def measure_images(
    images: Sequence[str],
    opts: ImageOptions,
    *,
    object_id: str,
    weight_n: float,
    friction_mu: float | None,
    output: str,
    force: bool,
) -> None:
    """Measure the object in ``images = (top, side)`` and write (or append) its catalog row.

    Checks, in order (nothing is written when one fails): options (exit 2), the input images
    exist (66), the output may be written (1) and, with ``--append``, the catalog is valid and
    does not have ``object_id`` yet (65); then the images are measured (65 on a bad image).

    Raises:
        UsageError, MissingInputError, OutputExistsError, InputDataError: see above.
    """
    top, side = images
    kwargs = _check_options(opts)
    if friction_mu is None:
        raise UsageError("--images needs --friction-mu (the catalog requires friction_mu)")
    if opts.append and force:
        raise UsageError("--append and --force cannot be used together")
    if opts.append and is_stdio(output):
        raise UsageError("--append needs a catalog file, not - (stdout)")
    _check_row_values({"object_id": object_id, "weight_n": weight_n, "friction_mu": friction_mu})
    inputs = [top, side, *(opts.background or ())]
    for path in inputs:
        if is_stdio(path):
            raise UsageError("--images and --background read files, not - (stdin)")
        check_input_path(path)
    existing: pd.DataFrame | None = None
    if opts.append and os.path.exists(output):
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
    from deformctl.vision import catalog_row, measure_object_size  # deferred: OpenCV

    size = measure_object_size(
        top,
        side,
        background_image=None if opts.background is None else tuple(opts.background),  # type: ignore[arg-type]
        debug_dir=opts.debug_dir,
        **kwargs,
    )
    row = catalog_row(size, object_id=object_id, weight_n=weight_n, friction_mu=friction_mu)
    settings = {
        "source": "images",
        "reference": "checkerboard" if "checkerboard" in kwargs else "aruco",
        **{k: v for k, v in kwargs.items() if k != "color_range"},
        "color_range": kwargs.get("color_range"),
        "background": list(opts.background) if opts.background else None,
        "measured_size_cm": [size.size_x_cm, size.size_y_cm, size.size_z_cm],
        "side_visible_width_cm": size.side.size_along_x_cm,
    }
    provenance = Provenance.from_invocation(inputs, settings=settings)
    if existing is not None:
        n_rows = _append_row(output, row, existing, provenance)
    else:
        n_rows = len(write_catalog(pd.DataFrame([row]), output, provenance=provenance, force=force))
    where = "stdout" if is_stdio(output) else output
    typer.echo(
        f"{where}: {object_id!r} {row['size_x_cm']} x {row['size_y_cm']} x {row['size_z_cm']} cm "
        f"(x, y from the top view, z from the side view; {n_rows} row(s) in the catalog)",
        err=True,
    )


def _check_row_values(values: Mapping[str, object]) -> None:
    weight = values["weight_n"]
    mu = values["friction_mu"]
    if not values["object_id"]:
        raise UsageError("--object-id must not be empty")
    if not (isinstance(weight, float | int) and math.isfinite(weight) and weight > 0):
        raise UsageError(f"--weight-n must be a number > 0, got {weight}")
    if not (isinstance(mu, float | int) and math.isfinite(mu) and mu > 0):
        raise UsageError(f"--friction-mu must be a number > 0, got {mu}")


__all__ = ["ImageOptions", "measure_images", "parse_checkerboard", "parse_color_range"]
