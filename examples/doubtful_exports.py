"""Write two CSV exports whose coefficients are doubtful, to see ``characterize`` flag them.

Usage::

    python examples/doubtful_exports.py OUTDIR

writes (columns ``t`` in s, ``load`` in N, ``pos`` the compression in mm):

* ``OUTDIR/utm.csv``: a universal testing machine compresses a foam block (D = 20 N/cm,
  λ = 3 N·s/cm) at a constant 0.5 mm/s from a 0.5 N seating preload, 100 Hz. λ·ḋ is then a
  constant force, indistinguishable from the preload: λ cannot be identified.
* ``OUTDIR/apple.csv``: a force-controlled gripper ramps its force at 5 N/s on a fruit
  (D = 13 N/cm, λ = 0.33 N·s/cm, 1 kHz) until it ruptures at 2 s: the force collapses to 40 %
  while the gripper keeps closing.

Both have 1 % force noise and 10 µm (UTM) or 50 µm (gripper) position noise; then::

    deformctl measure csv OUTDIR/utm.csv --columns time=t,force=load,compression=pos \\
        --units compression=mm --object-id foam --weight-n 0.7 -o OUTDIR/utm.mcap
    deformctl characterize OUTDIR/utm.mcap -o OUTDIR/utm.parquet
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from deformctl.characterize import kelvin_voigt_piecewise_linear


def _write(path: Path, t: np.ndarray, f: np.ndarray, d_m: np.ndarray, pos_noise_m: float) -> None:
    rng = np.random.default_rng(0)
    f = f + rng.normal(0.0, 0.01 * float(np.max(f)), t.size)
    d_mm = 1e3 * (d_m + rng.normal(0.0, pos_noise_m, t.size))
    rows = np.column_stack([t, f, d_mm])
    np.savetxt(path, rows, delimiter=",", header="t,load,pos", comments="", fmt="%.6f")


def utm() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Constant 0.5 mm/s over 5 mm at 100 Hz from a 0.5 N preload: (t s, f N, d m)."""
    t = np.arange(0.0, 10.0, 0.01)
    v = 0.5e-3
    d = v * t
    return t, 0.5 + 2000.0 * d + 300.0 * v, d


def apple() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A 5 N/s force ramp on a Kelvin–Voigt fruit that ruptures at 2 s: (t s, f N, d m)."""
    t = np.arange(0.0, 3.0, 0.001)
    f = 5.0 * t
    d = kelvin_voigt_piecewise_linear(t, np.array([0.0, 3.0]), np.array([0.0, 15.0]), 1300.0, 33.0)
    i = int(np.searchsorted(t, 2.0))
    rate = (d[i] - d[i - 10]) / (t[i] - t[i - 10])
    after = t >= 2.0
    f = np.where(after, f[i] * (0.4 + 0.6 * np.exp(-(t - 2.0) / 0.01)), f)
    d = np.where(after, d[i] + 2.0 * rate * (t - 2.0), d)
    return t, f, d


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("outdir", type=Path)
    args = parser.parse_args()
    args.outdir.mkdir(parents=True, exist_ok=True)
    _write(args.outdir / "utm.csv", *utm(), pos_noise_m=1e-5)
    _write(args.outdir / "apple.csv", *apple(), pos_noise_m=5e-5)


if __name__ == "__main__":
    main()
