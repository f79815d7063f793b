"""A calibrated camera for ``measure --images --camera-matrix FILE``: reading it and undistorting.

Two file kinds are read, told apart by their content:

* OpenCV's ``calibrateCamera`` result saved with ``cv2.FileStorage``, YAML (``%YAML:1.0``,
  ``!!opencv-matrix``) or JSON (``"type_id": "opencv-matrix"``): nodes ``camera_matrix``
  (3x3) and ``distortion_coefficients`` (1xN or Nx1), optionally ``image_width`` and
  ``image_height``. A hand-written JSON with plain lists (``"camera_matrix": [[fx, 0, cx], ...]``,
  as ``json.dump(K.tolist())`` gives) is read too.
* ROS ``camera_info`` YAML (``camera_calibration``'s ``ost.yaml``): ``image_width``,
  ``image_height``, ``camera_matrix: {rows: 3, cols: 3, data: [...]}`` and
  ``distortion_coefficients: {rows: 1, cols: N, data: [...]}``.

The distortion coefficients are OpenCV's (k1, k2, p1, p2[, k3[, k4, k5, k6[, s1..s4[, τx, τy]]]]),
which is also ROS's ``plumb_bob`` / ``rational_polynomial`` order. :func:`undistort` removes the
distortion from a photo and keeps the camera matrix, so that the undistorted photo is a pinhole
image with the same ``K``.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from deformctl.arraytypes import FloatArray
from deformctl.errors import InputDataError, MissingInputError

#: Lengths of an OpenCV distortion vector.
_DISTORTION_LENGTHS = (0, 4, 5, 8, 12, 14)


@dataclass(frozen=True)
class CameraCalibration:
    """A pinhole camera with lens distortion.

    Attributes:
        camera_matrix: ``K``, 3x3, px.
        distortion: OpenCV distortion coefficients ``[n]`` (n in 0, 4, 5, 8, 12, 14).
        image_size: ``(width, height)`` px the calibration was made at, when the file says.
        source: ``"opencv"`` (FileStorage YAML/JSON, or plain JSON) or ``"ros"`` (camera_info).
        path: the file it was read from.
    """

    camera_matrix: FloatArray
    distortion: FloatArray
    image_size: tuple[int, int] | None
    source: str
    path: str

    @property
    def horizontal_fov_deg(self) -> float | None:
        """The horizontal field of view, degrees (None without an image size)."""
        if self.image_size is None:
            return None
        return math.degrees(2.0 * math.atan(self.image_size[0] / 2.0 / self.camera_matrix[0, 0]))

    def check_image(self, shape: tuple[int, ...], what: str, path: str | None) -> None:
        """Refuse a photo of another size than the calibration's.

        Raises:
            InputDataError: the sizes differ.
        """
        if self.image_size is None:
            return
        w, h = self.image_size
        if (int(shape[1]), int(shape[0])) != (w, h):
            raise InputDataError(
                f"the {what} is {shape[1]}x{shape[0]} px but the camera calibration "
                f"{self.path} is for {w}x{h} px images; calibrate at the photos' resolution",
                path=path,
            )


def undistort(img: NDArray[np.uint8], camera: CameraCalibration) -> NDArray[np.uint8]:
    """The photo without lens distortion, for the same camera matrix (unchanged if none)."""
    if not np.any(camera.distortion):
        return img
    return np.asarray(cv2.undistort(img, camera.camera_matrix, camera.distortion), np.uint8)


def load_camera_calibration(path: str | os.PathLike[str]) -> CameraCalibration:
    """Read a camera calibration file (see the module docstring for the formats).

    Raises:
        MissingInputError: the file does not exist.
        InputDataError: not a calibration file of either kind, a missing or malformed
            ``camera_matrix``, a distortion vector of another length than 4, 5, 8, 12 or 14,
            a non-positive focal length or image size.
    """
    name = os.fspath(path)
    if not os.path.isfile(name):
        raise MissingInputError("no such camera calibration file", path=name)
    try:
        with open(name, encoding="utf-8") as fh:
            text = fh.read()
    except (OSError, UnicodeDecodeError) as err:
        raise InputDataError(f"cannot read the camera calibration ({err})", path=name) from None
    head = text.lstrip()
    if head.startswith("%YAML"):
        fields, source = _from_file_storage(name), "opencv"
    elif head.startswith("{"):
        try:
            fields = json.loads(text)
        except json.JSONDecodeError as err:
            msg = f"not valid JSON ({err.msg}, line {err.lineno})"
            raise InputDataError(msg, path=name) from None
        source = "opencv"
    else:
        fields, source = _from_yaml(text, name), "ros"
    if not isinstance(fields, dict):
        raise InputDataError("not a camera calibration (expected a mapping)", path=name)
    return _calibration(fields, source, name)


def _from_file_storage(name: str) -> dict[str, Any]:
    """The nodes of an OpenCV FileStorage YAML file, matrices as nested lists."""
    try:
        fs = cv2.FileStorage(name, cv2.FILE_STORAGE_READ)
    except cv2.error as err:
        msg = str(err).strip().splitlines()[-1] if str(err).strip() else "parse error"
        raise InputDataError(f"not an OpenCV FileStorage file ({msg})", path=name) from None
    try:
        if not fs.isOpened():
            raise InputDataError("not an OpenCV FileStorage file", path=name)
        out: dict[str, Any] = {}
        for key in ("camera_matrix", "distortion_coefficients"):
            node = fs.getNode(key)
            if node.empty() or node.isNone():
                continue
            mat = node.mat()
            out[key] = None if mat is None else np.asarray(mat, dtype=np.float64).tolist()
        for key in ("image_width", "image_height"):
            node = fs.getNode(key)
            if not node.empty() and (node.isReal() or node.isInt()):
                out[key] = node.real()
        return out
    finally:
        fs.release()


def _from_yaml(text: str, name: str) -> Any:
    import yaml

    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as err:
        where = getattr(err, "problem_mark", None)
        line = f", line {where.line + 1}" if where is not None else ""
        raise InputDataError(f"not valid YAML{line}", path=name) from None


def _numbers(value: Any, key: str, name: str) -> FloatArray:
    """A matrix given as nested lists, a flat list, or ``{rows, cols, data}`` / FileStorage JSON."""
    if isinstance(value, dict):
        if "data" not in value:
            raise InputDataError(f"{key} has no data", path=name)
        data = value["data"]
        rows, cols = value.get("rows"), value.get("cols")
    else:
        data, rows, cols = value, None, None
    try:
        arr = np.asarray(data, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputDataError(f"{key} must hold numbers", path=name) from None
    if isinstance(rows, int) and isinstance(cols, int) and arr.size != rows * cols:
        raise InputDataError(f"{key} says {rows}x{cols} but holds {arr.size} numbers", path=name)
    if not np.all(np.isfinite(arr)):
        raise InputDataError(f"{key} has non-finite values", path=name)
    return arr


def _calibration(fields: dict[str, Any], source: str, name: str) -> CameraCalibration:
    if fields.get("camera_matrix") is None:
        raise InputDataError(
            "no camera_matrix (expected OpenCV calibrateCamera output saved with cv2.FileStorage, "
            "or a ROS camera_info YAML)",
            path=name,
        )
    k = _numbers(fields["camera_matrix"], "camera_matrix", name)
    if k.size != 9:
        raise InputDataError(f"camera_matrix must be 3x3, got {k.size} numbers", path=name)
    k = k.reshape(3, 3)
    if k[0, 0] <= 0 or k[1, 1] <= 0 or k[2, 2] != 1 or np.any(k[2, :2] != 0):
        raise InputDataError(
            "camera_matrix is not a pinhole matrix [[fx, s, cx], [0, fy, cy], [0, 0, 1]] with "
            "fx, fy > 0",
            path=name,
        )
    raw = fields.get("distortion_coefficients")
    dist = np.zeros(0) if raw is None else _numbers(raw, "distortion_coefficients", name).ravel()
    if dist.size not in _DISTORTION_LENGTHS:
        raise InputDataError(
            f"distortion_coefficients must have 4, 5, 8, 12 or 14 values, got {dist.size}",
            path=name,
        )
    size: tuple[int, int] | None = None
    if fields.get("image_width") is not None or fields.get("image_height") is not None:
        try:
            w, h = float(fields["image_width"]), float(fields["image_height"])
        except (KeyError, TypeError, ValueError):
            msg = "image_width and image_height must be numbers"
            raise InputDataError(msg, path=name) from None
        if not (w >= 1 and h >= 1 and w == int(w) and h == int(h)):
            raise InputDataError(
                f"image size must be whole pixels >= 1, got {w:g}x{h:g}", path=name
            )
        size = (int(w), int(h))
    return CameraCalibration(k, dist, size, source, name)


__all__ = ["CameraCalibration", "load_camera_calibration", "undistort"]
