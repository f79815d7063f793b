"""Object size from a top and a side image, and slip from frames before and after a lift (OpenCV).

Two jobs, both on ordinary camera images:

* :func:`measure_object_size` measures an object's x, y, z size in cm from a *top* image and a
  *side* image that each contain a scale reference of known size (an ArUco marker by default, or a
  checkerboard). :func:`catalog_row` turns the result into an object-catalog row.
* :func:`detect_slip` decides from a frame before and a frame after a lift whether the object rose
  with the palms; :func:`slip_from_frames` is the ``(before_path, after_path) -> (lifted, slip_m)``
  callable the external rig runner of ``lift`` accepts.

Geometry the user must set up (the measurement is exact for boxes and right prisms under it)
-------------------------------------------------------------------------------------------
*Reference plane.* The marker (or checkerboard) defines a metric plane: its homography maps image
pixels to plane coordinates in cm, with the marker's own axes: ``x`` along the marker's printed top
edge (left to right), ``y`` along its left edge (top to bottom of the print).

*Top view.* The marker lies flat on the table beside the object (not touching it); the camera looks
down, roughly perpendicular to the table (tilts up to ~15 degrees are corrected). ``size_x_cm`` is
the side of the object's minimum-area rectangle that is more nearly parallel to the marker's x
axis, ``size_y_cm`` the other side; so orient the marker's top edge along the squeeze axis.

*Side view.* The marker stands upright (printed top edge up) in the plane of the object's front
face, beside the object, e.g. taped to a block flush with that face; the camera looks horizontally,
roughly perpendicular to that face, best from about the object's mid-height. ``size_z_cm`` is the
side of the minimum-area rectangle more nearly parallel to the marker's y axis (the vertical).

*Parallax.* The object is not flat: its top face (top view) is nearer to the camera than the
marker plane, and its back (side view) is farther. The silhouette mapped into the marker plane is
therefore the object's "shadow" cast from the camera centre, not its cross-section. We undo this
exactly for a right prism: the camera centre ``C`` (in the marker frame, from ``cv2.solvePnP`` with
the camera matrix) and the prism's extent along the plane normal (top view: from the table up to
``size_z``; side view: from the front face back by the object's depth) give, for every direction,
the cross-section's support value from the silhouette's (see :func:`_section_support`). The two
views depend on each other (the top needs the height, the side needs the depth), so they are
solved by a short fixed-point iteration. The correction is not small: the camera centre comes
from the camera matrix, and a wrong one moves the result. Pass the calibrated camera
(``camera=load_camera_calibration(FILE)``, OpenCV ``calibrateCamera`` output saved with
``cv2.FileStorage`` or a ROS ``camera_info`` YAML, see :mod:`deformctl.vision.camera`; or a bare
``camera_matrix``); the photos are then undistorted with its distortion coefficients first.
Without it a pinhole camera with a 60-degree horizontal field of view and the principal point at
the image centre is assumed: rendered 13.7 x 9.3 x 6.1 cm box, 45 cm away, read 12.85 x 8.70 cm
through a 45-degree camera (-6 %) and 14.12 x 9.61 cm through a 70-degree one (+3 %); with the
camera matrix every side came within 0.5 % (tests/vision/test_camera.py).

*Segmentation.* The object is the largest foreground region that is not the marker: by default
the difference from a smooth background (a surface per colour channel fitted robustly to the
image, growing from the median colour to a plane to a quadratic, which absorbs a smooth lighting
gradient; found on plain scenes with gradients up to 20 %; the background must cover most of the
photo) thresholded with Otsu's method; or a colour range
(HSV lower/upper); or the difference from an image of the empty scene. Use a uniform background
that differs from the object and keep the whole object inside the image.

Slip from frames
----------------
A fixed camera looks at the gripper from the side. The palms are tracked by template matching of
given regions (``x, y, w, h`` in the before frame, each containing a distinctive part of a palm
such as its lower end) or by ArUco markers on the palms; the object is the foreground between the
palms. Rises are measured upwards in the image (``-dy``) and converted to metres with the scale of
the markers in view (``marker_size_cm``) or an explicit ``scale_px_per_m``; all of them must lie
roughly in one plane perpendicular to the camera.
"""

from __future__ import annotations

from deformctl.vision.camera import CameraCalibration, load_camera_calibration, undistort
from deformctl.vision.reference import ImageSource, load_image
from deformctl.vision.size import (
    SizeMeasurement,
    ViewMeasurement,
    catalog_row,
    measure_object_size,
    measure_view,
)
from deformctl.vision.slip import SlipResult, detect_slip, slip_from_frames

__all__ = [
    "CameraCalibration",
    "ImageSource",
    "SizeMeasurement",
    "SlipResult",
    "ViewMeasurement",
    "catalog_row",
    "detect_slip",
    "load_camera_calibration",
    "load_image",
    "measure_object_size",
    "measure_view",
    "slip_from_frames",
    "undistort",
]
