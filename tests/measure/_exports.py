"""Synthetic exports of known Kelvin–Voigt squeezes, written as testing machines and grippers do.

:func:`kv_squeeze` is one squeeze with known D and λ (haversine force, exact compression,
seeded noise); :func:`write_export` writes it in a dialect: a preamble, units in the names or in
a units row, ``;`` with a decimal comma, quoted values with thousands separators, a byte-order
mark, another encoding, a force of either sign, in any unit. The tests know the answer.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from deformctl.testing.kelvin_voigt import kelvin_voigt_response

#: Unit → factor to SI (the test's own table, independent of the library's).
SI = {"s": 1.0, "ms": 1e-3, "N": 1.0, "kN": 1e3, "mN": 1e-3, "m": 1.0, "mm": 1e-3, "µm": 1e-6}


@dataclass(frozen=True)
class Squeeze:
    """Samples in SI: time s, force N, compression m."""

    t: np.ndarray
    f: np.ndarray
    d: np.ndarray


def kv_squeeze(
    d_n_per_cm: float = 20.0,
    lam_ns_per_cm: float = 3.0,
    *,
    peak_n: float = 10.0,
    rate_hz: float = 100.0,
    duration_s: float = 8.0,
    force_noise_n: float = 0.01,
    position_noise_m: float = 2e-6,
    seed: int = 0,
) -> Squeeze:
    """Two haversine force pulses on a Kelvin–Voigt object (exact compression) plus noise."""
    t = np.arange(round(duration_s * rate_hz) + 1) / rate_hz
    f, d = kelvin_voigt_response(
        t, d_n_per_cm, lam_ns_per_cm, peak_force_n=peak_n, profile="sine", duration_s=duration_s
    )
    rng = np.random.default_rng(seed)
    return Squeeze(
        t, f + rng.normal(0.0, force_noise_n, t.size), d + rng.normal(0.0, position_noise_m, t.size)
    )


def write_export(
    path: Path,
    s: Squeeze,
    *,
    names: Sequence[str] = ("Time (s)", "Load (N)", "Compression (mm)"),
    units: Sequence[str] = ("s", "N", "mm"),
    units_row: Sequence[str] | None = None,
    preamble: Sequence[str] = (),
    delimiter: str = ",",
    decimal: str = ".",
    thousands: str | None = None,
    quote: bool = False,
    force_sign: float = 1.0,
    encoding: str = "utf-8",
    bom: bool = False,
    digits: int = 6,
) -> Path:
    """Write ``s`` with the columns ``names`` holding time, force and compression in ``units``."""
    cols = [s.t / SI[units[0]], force_sign * s.f / SI[units[1]], s.d / SI[units[2]]]

    def cell(v: float) -> str:
        text = f"{v:,.{digits}f}" if thousands else f"{v:.{digits}f}"
        if thousands:
            text = text.replace(",", "\0").replace(".", decimal).replace("\0", thousands)
        elif decimal != ".":
            text = text.replace(".", decimal)
        return f'"{text}"' if quote else text

    lines = [*preamble, delimiter.join(names)]
    if units_row is not None:
        lines.append(delimiter.join(units_row))
    lines += [delimiter.join(cell(v) for v in row) for row in zip(*cols, strict=True)]
    data = ("\n".join(lines) + "\n").encode(encoding)
    path.write_bytes((b"\xef\xbb\xbf" if bom else b"") + data)
    return path
