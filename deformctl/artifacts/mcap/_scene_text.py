"""The ``/scene`` messages of a run as JSON text, their spheres written by a compiled loop.

A frame draws one sphere per surface particle, three positions each with 0.1 µm decimals: at
30 frames a second that is millions of numbers per lift, and Python's ``%``-formatting of them
cost more than the rest of the log together. :meth:`SpheresWriter.messages` writes the same text
with one numba loop over all the frames of a run, each frame's message whole (the head and tail
around its spheres given as text): no Python work per sphere, little per frame.

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


#: "00" to "99", two characters each: the decimals are written two at a time
_PAIRS = np.frombuffer("".join(f"{i:02d}" for i in range(100)).encode(), np.uint8).copy()


@njit(cache=True, boundscheck=False, inline="always")
def _put(out: NDArray[np.uint8], at: int, text: NDArray[np.uint8], lo: int, hi: int) -> int:
    n = hi - lo
    out[at : at + n] = text[lo:hi]
    return at + n


@njit(cache=True, boundscheck=False, inline="always")
def _fixed(out: NDArray[np.uint8], at: int, x: float, pairs: NDArray[np.uint8]) -> int:
    """``x`` as ``%.7f`` would write it (see the module), from ``out[at]``; the next index."""
    negative = x < 0.0 or (x == 0.0 and np.signbit(x))
    # unsigned arithmetic by constants: LLVM turns each division into a multiply
    q = np.uint64(np.rint(abs(x) * _SCALE))
    if negative:
        out[at] = 45  # '-'
        at += 1
    ten, hundred = np.uint64(10), np.uint64(100)
    whole = q // np.uint64(10_000_000)
    frac = q - whole * np.uint64(10_000_000)
    if whole < ten:  # below 10 m: one digit
        out[at] = np.uint8(48) + np.uint8(whole)
        at += 1
    else:
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
    # seven decimals: one, then three pairs
    low = 2 * (frac % hundred)
    frac //= hundred
    mid = 2 * (frac % hundred)
    frac //= hundred
    high = 2 * (frac % hundred)
    out[at + 1] = np.uint8(48) + np.uint8(frac // hundred)
    out[at + 2] = pairs[high]
    out[at + 3] = pairs[high + 1]
    out[at + 4] = pairs[mid]
    out[at + 5] = pairs[mid + 1]
    out[at + 6] = pairs[low]
    out[at + 7] = pairs[low + 1]
    return at + 1 + _DECIMALS


@njit(cache=True, boundscheck=False)
def _loop_writes(xyz: NDArray[np.float64]) -> bool:
    """Whether the loop writes every value of one frame ``[m, 3]``: finite, below
    :data:`_LOOP_LIMIT_M`, none within :data:`_TIE_WINDOW` of a half once scaled."""
    for i in range(xyz.shape[0]):
        for c in range(3):
            scaled = abs(xyz[i, c]) * _SCALE
            if not scaled < _LOOP_LIMIT_M * _SCALE:  # NaN too
                return False
            if abs(scaled - np.floor(scaled) - 0.5) < _TIE_WINDOW:
                return False
    return True


@njit(cache=True, boundscheck=False)
def _messages(
    xyz: NDArray[np.float64],
    colour: NDArray[np.int64],
    heads: NDArray[np.uint8],
    head_cuts: NDArray[np.int64],
    tails: NDArray[np.uint8],
    tail_cuts: NDArray[np.int64],
    pieces: NDArray[np.uint8],
    ends: NDArray[np.uint8],
    end_cuts: NDArray[np.int64],
    per_sphere: int,
    pairs: NDArray[np.uint8],
) -> tuple[NDArray[np.uint8], NDArray[np.int64], NDArray[np.bool_]]:
    """Every frame's message, one after another: its head, its spheres, its tail. A frame the
    loop does not write (:func:`_loop_writes`) gets its head and tail only and ``written`` false.
    Returns the text, the messages' bounds ``[k + 1]`` and ``written`` ``[k]``.

    ``pieces``: a sphere's text up to x, then between x and y and between y and z (the first
    ``pieces.size - 10`` bytes, then 5 and 5); ``ends``: its text after z for each colour, with
    a comma (dropped after a frame's last sphere)."""
    k, m = xyz.shape[0], xyz.shape[1]
    out = np.empty(heads.size + tails.size + k * m * per_sphere, np.uint8)
    bounds = np.zeros(k + 1, np.int64)
    written = np.zeros(k, np.bool_)
    start = pieces.size - 10
    lead, before_y, before_z = pieces[:start], pieces[start : start + 5], pieces[start + 5 :]
    at = 0
    for f in range(k):
        at = _put(out, at, heads, head_cuts[f], head_cuts[f + 1])
        if m > 0 and _loop_writes(xyz[f]):
            written[f] = True
            for i in range(m):
                out[at : at + start] = lead
                at = _fixed(out, at + start, xyz[f, i, 0], pairs)
                out[at : at + 5] = before_y
                at = _fixed(out, at + 5, xyz[f, i, 1], pairs)
                out[at : at + 5] = before_z
                at = _fixed(out, at + 5, xyz[f, i, 2], pairs)
                j = colour[f, i]
                at = _put(out, at, ends, end_cuts[j], end_cuts[j + 1])
            at -= 1  # the last sphere's comma
        at = _put(out, at, tails, tail_cuts[f], tail_cuts[f + 1])
        bounds[f + 1] = at
    return out, bounds, written


def _bytes_and_cuts(parts: list[str] | list[bytes]) -> tuple[NDArray[np.uint8], NDArray[np.int64]]:
    encoded = [p.encode() if isinstance(p, str) else p for p in parts]
    cuts = np.zeros(len(encoded) + 1, np.int64)
    np.cumsum([len(e) for e in encoded], out=cuts[1:])
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
        self._pieces, _ = _bytes_and_cuts(['{"pose":{"position":{"x":', ',"y":', ',"z":'])
        rest = '},"orientation":' + orientation + '},"size":' + size + ',"color":'
        self._ends, self._end_cuts = _bytes_and_cuts([rest + c + "}," for c in colours])
        # fixed text, an end, three numbers of at most 1 + 12 + 1 + 7 characters
        self._per_sphere = self._pieces.size + int(np.diff(self._end_cuts).max()) + 3 * 21
        self._python_template = '{"pose":{"position":{"x":%.7f,"y":%.7f,"z":%.7f' + rest + "%s}"
        self._colour_text = list(colours)

    def _python_spheres(self, xyz: NDArray[np.float64], colour: NDArray[np.int64]) -> bytes:
        return ",".join(
            self._python_template % (x, y, z, self._colour_text[c])
            for (x, y, z), c in zip(xyz.tolist(), colour.tolist(), strict=True)
        ).encode()

    def messages(
        self,
        xyz: NDArray[np.float64],
        colour: NDArray[np.int64],
        heads: list[bytes],
        tails: list[bytes],
    ) -> list[bytes]:
        """One message per frame, ``heads[f]``, frame ``f``'s spheres, ``tails[f]``, written in
        one compiled pass over all the frames: particle positions ``[k, m, 3]`` (m) and colour
        indices ``[k, m]``."""
        k = xyz.shape[0]
        head_text, head_cuts = _bytes_and_cuts(heads)
        tail_text, tail_cuts = _bytes_and_cuts(tails)
        out, bounds, written = _messages(
            np.ascontiguousarray(xyz, dtype=np.float64),
            np.ascontiguousarray(colour, dtype=np.int64),
            head_text,
            head_cuts,
            tail_text,
            tail_cuts,
            self._pieces,
            self._ends,
            self._end_cuts,
            self._per_sphere,
            _PAIRS,
        )
        view = out.data
        texts = [view[bounds[f] : bounds[f + 1]].tobytes() for f in range(k)]
        for f in np.flatnonzero(~written).tolist():  # Python's text where the loop cannot vouch
            texts[f] = heads[f] + self._python_spheres(xyz[f], colour[f]) + tails[f]
        return texts

    def frame(self, xyz: NDArray[np.float64], colour: NDArray[np.int64]) -> bytes:
        """The spheres of one frame: particle positions ``[m, 3]`` (m) and colour indices
        ``[m]``."""
        return self.messages(xyz[None], colour[None], [b""], [b""])[0]


def compile_writer() -> None:
    """Compile (or load) the loop once: a one-sphere frame."""
    SpheresWriter("{}", "{}", ["{}"]).frame(np.zeros((1, 3)), np.zeros(1, np.int64))
