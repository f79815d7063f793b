#!/usr/bin/env python3
"""Draw one frame of a simulated log's 3-D scene (``/scene``) with matplotlib, from the log alone.

Usage: draw_scene_frame.py LOG PNG [--object ID] [--index K] [--frame N]

Reads the ``foxglove.SceneUpdate`` messages of LOG (a ``lift sim`` or ``measure sim`` log),
checks the one it draws against the JSON Schema Foxglove publishes
(``schemas/foxglove/SceneUpdate.json``), and draws the frame Foxglove's 3-D panel would show at
that moment: the palms (cubes), the object's surface particles (spheres; those on a palm's face
green while the contact sticks, red when it slipped since the previous frame) and the table. The
frame is number N (default: the middle; negative counts from the end) of squeeze or attempt K
(default: the last) of object ID (default: the first in the log). Every position and colour
drawn comes from the message itself.

The figure of docs/guide/simulator.md is made by ``make scene-figure``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from deformctl.artifacts.io import read_input_bytes
from deformctl.artifacts.mcap import load_mcap
from deformctl.artifacts.mcap.scene import SceneMessage, check_scene_update, scene_frames_of


def _meta(entity: dict[str, Any]) -> dict[str, str]:
    return {kv["key"]: kv["value"] for kv in entity["metadata"]}


def pick_frame(
    messages: list[SceneMessage], object_id: str | None, index: int | None, frame: int | None
) -> SceneMessage:
    """The chosen ``/scene`` message (see the module docs for the defaults)."""
    runs: dict[tuple[str, int], list[SceneMessage]] = {}
    for m in messages:
        meta = _meta(m.update["entities"][0])
        runs.setdefault((meta["object_id"], int(meta["index"])), []).append(m)
    if not runs:
        raise SystemExit("error: the log has no /scene messages (written with --scene-hz 0?)")
    oid = object_id or next(iter(runs))[0]
    indices = sorted(k for o, k in runs if o == oid)
    if not indices:
        raise SystemExit(f"error: no scene of object {oid!r} in the log")
    k = indices[-1] if index is None else index
    if (oid, k) not in runs:
        raise SystemExit(f"error: object {oid!r} has no run {k} (it has {indices})")
    frames = runs[(oid, k)]
    n = len(frames) // 2 if frame is None else frame
    if n < 0:
        n += len(frames)
    if not 0 <= n < len(frames):
        raise SystemExit(f"error: run {k} of {oid!r} has frames 0..{len(frames) - 1}")
    return frames[n]


def _box_faces(centre: np.ndarray, size: np.ndarray) -> list[np.ndarray]:
    lo, hi = centre - size / 2, centre + size / 2
    corners = np.array(
        [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    )
    faces = [(0, 1, 3, 2), (4, 5, 7, 6), (0, 1, 5, 4), (2, 3, 7, 6), (0, 2, 6, 4), (1, 3, 7, 5)]
    return [corners[list(f)] for f in faces]


def _xyz(v: dict[str, float]) -> np.ndarray:
    return np.array([v["x"], v["y"], v["z"]])


def draw(message: SceneMessage, png: Path) -> None:
    """Draw ``message`` (a ``foxglove.SceneUpdate``) into ``png`` (metres shown as cm)."""
    fig = plt.figure(figsize=(7.0, 5.2), dpi=110)
    ax = fig.add_subplot(projection="3d")
    cm = 100.0
    entities = {e["id"]: e for e in message.update["entities"]}
    for name in ("table", "palms"):
        for cube in entities.get(name, {}).get("cubes", []):
            c = cube["color"]
            faces = _box_faces(_xyz(cube["pose"]["position"]) * cm, _xyz(cube["size"]) * cm)
            ax.add_collection3d(
                Poly3DCollection(faces, facecolor=(c["r"], c["g"], c["b"], c["a"] * 0.6),
                                 edgecolor=(0.2, 0.2, 0.3, 0.4), linewidth=0.4)
            )  # fmt: skip
    spheres = entities["object"]["spheres"]
    pos = np.array([_xyz(s["pose"]["position"]) for s in spheres]) * cm
    colours = np.array([[s["color"][k] for k in "rgba"] for s in spheres])
    ax.scatter(pos[:, 0], pos[:, 1], pos[:, 2], c=colours, s=18, depthshade=False)
    meta = _meta(entities["object"])
    stamp = entities["object"]["timestamp"]
    span = np.ptp(pos, axis=0).max() * 0.75
    mid = pos.mean(axis=0)
    ax.set(xlim=(mid[0] - span, mid[0] + span), ylim=(mid[1] - span, mid[1] + span),
           zlim=(max(mid[2] - span, -1.0), mid[2] + span))  # fmt: skip
    ax.set_xlabel("x (cm)")
    ax.set_ylabel("y (cm)")
    ax.set_zlabel("z (cm)")
    ax.view_init(elev=22, azim=-60)
    ax.set_box_aspect((1, 1, 1))
    ax.set_title(
        f"object {meta['object_id']}, {meta['run']} {meta['index']}, "
        f"t = {float(meta['time_s']):.3f} s (log time {stamp['sec']}.{stamp['nsec']:09d} s)\n"
        "green: contact sticks, red: contact slipped since the last frame",
        fontsize=9,
    )
    fig.tight_layout()
    fig.savefig(png)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("log")
    parser.add_argument("png")
    parser.add_argument("--object", dest="object_id")
    parser.add_argument("--index", type=int)
    parser.add_argument("--frame", type=int)
    args = parser.parse_args(argv)
    contents = load_mcap(read_input_bytes(args.log), args.log)
    messages = scene_frames_of(contents, validate=False)
    message = pick_frame(messages, args.object_id, args.index, args.frame)
    check_scene_update(message.update, path=args.log)  # the frame drawn matches the schema
    draw(message, Path(args.png))
    print(f"wrote {args.png}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
