"""The scene renderer of the vision tests; it lives in :mod:`deformctl.vision.synth`."""

from deformctl.vision.synth import (
    Box,
    Camera,
    Checkerboard,
    Gripper,
    Marker,
    Scene,
    box_scenes,
    box_views,
    camera_side,
    camera_tilted_down,
    focal_for_hfov,
    gripper_frame,
    render,
)

__all__ = [
    "Box",
    "Camera",
    "Checkerboard",
    "Gripper",
    "Marker",
    "Scene",
    "box_scenes",
    "box_views",
    "camera_side",
    "camera_tilted_down",
    "focal_for_hfov",
    "gripper_frame",
    "render",
]
