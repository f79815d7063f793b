"""The text of a synthetic export: a recording written as an instrument writes it.

:func:`draw_layout` picks, from a seeded generator, how the file is written; :func:`export_bytes`
writes a :class:`Samples` recording in that layout and returns the bytes
and the options a user would pass with it (the encoding the tool's error line names, the unit
a header leaves out). Styles (:data:`STYLES`):

* ``names``: one header row with units in the names (``Time (s),Load (N),Compression (mm)``),
  the position column called ``Compression``, ``Displacement`` or ``Position`` (a testing
  machine's crosshead travel: each equals the compression);
* ``bluehill``: two header rows (``Time,Displacement,Force`` then ``(s),(mm),(kN)``), quoted
  values, the force in kN to 4 decimals (0.1 N resolution);
* ``gbk``: a Chinese header (时间 (s), 位移 (mm), 力 (N)) in GBK (``--encoding gbk``);
* ``gripper``: a gripper log: an unnamed index column, Unix time, force (N), commanded force,
  ``Pos`` (mm, grows while closing; no unit in the header: ``--units position=mm``), an online
  stiffness estimate and a text column (the controller's state).

Around any style: line ends ``\\n``, ``\\r\\n`` or ``\\r``; a blank first line; a metadata
preamble of 0–8 lines, one of them sometimes a cell over 128 KiB; a text column; ``;`` with a
decimal comma; the compressive force written negative.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from deformctl.series import FloatArray

STYLES: tuple[str, ...] = ("names", "bluehill", "gbk", "gripper")
LINE_ENDS: tuple[str, ...] = ("\n", "\r\n", "\r")
#: A giant cell is this long (above the csv module's 128 KiB field limit).
GIANT_CELL_CHARS = 140_000
_STEPS = ("approach", "load", "hold", "release", "rest")


@dataclass(frozen=True)
class Samples:
    """A recording in SI: time s, force N (compressive positive), compression m."""

    t: FloatArray
    f: FloatArray
    d: FloatArray


def draw_layout(rng: np.random.Generator) -> dict[str, Any]:
    """How one export is written (every choice from ``rng``)."""
    style = str(rng.choice(STYLES, p=[0.4, 0.2, 0.15, 0.25]))
    return {
        "style": style,
        "line_end": str(rng.choice(LINE_ENDS)),
        "blank_first": bool(rng.random() < 0.15),
        "preamble": int(rng.integers(0, 9)) if rng.random() < 0.5 else 0,
        "giant_cell": bool(rng.random() < 0.03),
        "text_column": bool(rng.random() < 0.25),
        "semicolon": bool(style == "names" and rng.random() < 0.15),
        "negative": bool(rng.random() < 0.3),
        "position_name": str(rng.choice(["Compression", "Displacement", "Position"])),
    }


def _fmt(v: float, digits: int, decimal: str) -> str:
    text = f"{v:.{digits}f}"
    return text.replace(".", decimal) if decimal != "." else text


def export_bytes(s: Samples, layout: dict[str, Any]) -> tuple[bytes, dict[str, Any]]:
    """The CSV bytes of ``s`` in ``layout`` and the options a user passes with them."""
    style = layout["style"]
    sign = -1.0 if layout["negative"] else 1.0
    delim, decimal = (";", ",") if layout["semicolon"] else (",", ".")
    options: dict[str, Any] = {}
    encoding = "utf-8"
    lines: list[str] = []
    if layout["blank_first"]:
        lines.append("")
    for k in range(layout["preamble"]):
        lines.append(f"Parameter {k + 1}: {k * 3 + 1} units;")
    if layout["giant_cell"]:
        lines.append("Notes: " + "0" * GIANT_CELL_CHARS)
    n = s.t.shape[0]
    text_col = [_STEPS[min(i * len(_STEPS) // n, len(_STEPS) - 1)] for i in range(n)]
    cols: list[Sequence[str]]
    if style == "bluehill":
        names = ["Time", "Displacement", "Force"]
        if layout["text_column"]:
            names.append("Step")
        lines.append(delim.join(f'"{x}"' for x in names))
        lines.append(delim.join(f'"{x}"' for x in ["(s)", "(mm)", "(kN)", "()"][: len(names)]))
        cols = [
            [f'"{_fmt(v, 3, decimal)}"' for v in s.t],
            [f'"{_fmt(v, 5, decimal)}"' for v in s.d * 1e3],
            [f'"{_fmt(v, 4, decimal)}"' for v in sign * s.f / 1e3],
        ]
        if layout["text_column"]:
            cols.append([f'"{x}"' for x in text_col])
    elif style == "gbk":
        encoding = "gbk"
        options["encoding"] = "gbk"
        names = ["时间 (s)", "位移 (mm)", "力 (N)"]
        cols = [
            [_fmt(v, 4, decimal) for v in s.t],
            [_fmt(v, 5, decimal) for v in s.d * 1e3],
            [_fmt(v, 5, decimal) for v in sign * s.f],
        ]
        if layout["text_column"]:
            names.append("备注")
            cols.append(text_col)
        lines.append(delim.join(names))
    elif style == "gripper":
        names = ["", "time", "force", "commanded_force", "Pos", "stiffness_estimate", "state"]
        options["units"] = {"time": "s", "force": "N", "position": "mm"}
        t0 = 1.7e9 + float(np.floor(1e3 * s.t[0]))
        command = np.maximum.accumulate(s.f)
        cols = [
            [str(i) for i in range(n)],
            [f"{t0 + v:.4f}" for v in s.t],
            [_fmt(v, 5, decimal) for v in sign * s.f],
            [_fmt(v, 4, decimal) for v in command],
            [_fmt(v, 4, decimal) for v in s.d * 1e3],
            [_fmt(v, 3, decimal) for v in s.f / np.maximum(s.d * 1e3, 1e-3)],
            text_col,
        ]
        lines.append(delim.join(names))
    else:
        pos = layout["position_name"]
        names = ["Time (s)", "Load (N)", f"{pos} (mm)"]
        cols = [
            [_fmt(v, 4, decimal) for v in s.t],
            [_fmt(v, 5, decimal) for v in sign * s.f],
            [_fmt(v, 5, decimal) for v in s.d * 1e3],
        ]
        if layout["text_column"]:
            names.insert(2, "Comment")
            cols.insert(2, text_col)
        lines.append(delim.join(names))
    lines.extend(delim.join(row) for row in zip(*cols, strict=True))
    end = layout["line_end"]
    text = end.join(lines) + end
    return text.encode(encoding), options
