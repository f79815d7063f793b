"""The spheres of a ``/scene`` frame as JSON text, written by a compiled loop.

A frame draws one sphere per surface particle, three positions each with 0.1 µm decimals: at
30 frames a second that is millions of numbers per lift, and Python's ``%``-formatting of them
cost more than the rest of the log together. :func:`spheres_json` writes the same text with one
numba loop per frame.

Each position is written as ``%.7f`` writes it, from ``rint(|x| 1e7)``. Python rounds the exact
binary value; the scaled product carries a rounding error of at most 2.3e-6 (|x| below
:data:`_LOOP_LIMIT_M`), so the two agree unless the scaled value lies within that error of a half.
A frame with a value within :data:`_TIE_WINDOW` of a half (about one frame in fifty), or a value
that is not finite or not below :data:`_LOOP_LIMIT_M`, is written by Python's formatting instead:
the text is always exactly ``%.7f``'s (``tests/artifacts/test_mcap_scene.py``).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

#: |x| written by the loop is below this, m: |x| 1e7 < 1e10, so the product's error is < 2.3e-6
_LOOP_LIMIT_M = 1e3
#: a scaled value whose fraction is this close to a half goes to Python's rounding
_TIE_WINDOW = 1e-5
_SCALE = 1e7
_DECIMALS = 7


@njit(cache=True, boundscheck=False)
def _put(out: NDArray[np.uint8], at: int, text: NDArray[np.uint8], lo: int, hi: int) -> int:
    n = hi - lo
    out[at : at + n] = text[lo:hi]
    return at + n


@njit(cache=True, boundscheck=False)
def _fixed(out: NDArray[np.uint8], at: int, x: float) -> int:
    """``x`` as ``%.7f`` would write it (see the module), from ``out[at]``; the next index."""
    negative = x < 0.0 or (x == 0.0 and np.signbit(x))
    # unsigned arithmetic by constants: LLVM turns each division by 10 into a multiply
    q = np.uint64(np.rint(abs(x) * _SCALE))
    if negative:
        out[at] = 45  # '-'
        at += 1
    ten = np.uint64(10)
    whole = q // np.uint64(10_000_000)
    frac = q - whole * np.uint64(10_000_000)
    n = 1
    scan = whole // ten
    while scan > 0:
        n += 1
        scan //= ten
    for j in range(n - 1, -1, -1):
        out[at + j] = np.uint8(48) + np.uint8(whole % ten)
        whole //= ten
    at += n
    out[at] = 46  # '.'
    at += 1
    for j in range(_DECIMALS - 1, -1, -1):
        out[at + j] = np.uint8(48) + np.uint8(frac % ten)
        frac //= ten
    return at + _DECIMALS


@njit(cache=True, boundscheck=False)
def _spheres(
    xyz: NDArray[np.float64],
    colour: NDArray[np.int64],
    pieces: NDArray[np.uint8],
    cuts: NDArray[np.int64],
    colours: NDArray[np.uint8],
    colour_cuts: NDArray[np.int64],
    capacity: int,
) -> NDArray[np.uint8]:
    out = np.empty(capacity, np.uint8)
    at = 0
    for i in range(xyz.shape[0]):
        if i > 0:
            out[at] = 44  # ','
            at += 1
        for c in range(3):
            at = _put(out, at, pieces, cuts[c], cuts[c + 1])
            at = _fixed(out, at, xyz[i, c])
        at = _put(out, at, pieces, cuts[3], cuts[4])
        k = colour[i]
        at = _put(out, at, colours, colour_cuts[k], colour_cuts[k + 1])
        at = _put(out, at, pieces, cuts[4], cuts[5])
    return out[:at]


def _bytes_and_cuts(parts: list[str]) -> tuple[NDArray[np.uint8], NDArray[np.int64]]:
    encoded = [p.encode() for p in parts]
    cuts = np.concatenate([[0], np.cumsum([len(e) for e in encoded])]).astype(np.int64)
    return np.frombuffer(b"".join(encoded), np.uint8).copy(), cuts


class SpheresWriter:
    """Writes one frame's spheres: ``{"pose":{"position":{"x":…,"y":…,"z":…},"orientation":
    <orientation>},"size":<size>,"color":<colour>}``, comma-separated, one per particle.

    Args:
        orientation: the JSON of every sphere's orientation.
        size: the JSON of every sphere's size.
        colours: the JSON of each colour a particle can take (indexed by :meth:`frame`'s
            ``colour``).
    """

    def __init__(self, orientation: str, size: str, colours: list[str]) -> None:
        self._pieces, self._cuts = _bytes_and_cuts(
            [
                '{"pose":{"position":{"x":',
                ',"y":',
                ',"z":',
                '},"orientation":' + orientation + '},"size":' + size + ',"color":',
                "}",
            ]
        )
        self._colours, self._colour_cuts = _bytes_and_cuts(colours)
        longest_colour = int(np.diff(self._colour_cuts).max())
        # fixed text, a colour, three numbers of at most 1 + 12 + 1 + 7 characters, a comma
        self._per_sphere = int(self._cuts[-1]) + longest_colour + 3 * 21 + 1
        self._python_template = (
            '{"pose":{"position":{"x":%.7f,"y":%.7f,"z":%.7f},"orientation":'
            + orientation
            + '},"size":'
            + size
            + ',"color":%s}'
        )
        self._colour_text = list(colours)

    def frame(self, xyz: NDArray[np.float64], colour: NDArray[np.int64]) -> bytes:
        """The spheres of one frame: particle positions ``[m, 3]`` (m) and colour indices
        ``[m]``."""
        if xyz.shape[0] == 0:
            return b""
        scaled = np.abs(xyz) * _SCALE
        near_half = np.abs(scaled - np.floor(scaled) - 0.5) < _TIE_WINDOW
        if (
            not (np.isfinite(xyz).all() and scaled.max() < _LOOP_LIMIT_M * _SCALE)
            or near_half.any()
        ):
            return ",".join(
                self._python_template % (x, y, z, self._colour_text[c])
                for (x, y, z), c in zip(xyz.tolist(), colour.tolist(), strict=True)
            ).encode()
        text = _spheres(
            np.ascontiguousarray(xyz, dtype=np.float64),
            np.ascontiguousarray(colour, dtype=np.int64),
            self._pieces,
            self._cuts,
            self._colours,
            self._colour_cuts,
            self._per_sphere * xyz.shape[0],
        )
        return text.tobytes()


def compile_writer() -> None:
    """Compile (or load) the loop once: a one-sphere frame."""
    SpheresWriter("{}", "{}", ["{}"]).frame(np.zeros((1, 3)), np.zeros(1, np.int64))
