"""The simulator's standard linear solid at the ``paper`` preset's own lattice (``make
sls-check``, about a minute): the squeeze against ``D d + σ``, ``σ̇ = k2 ḋ − σ/τ``, and the round
trip through ``characterize --model sls``, the longer companion of tests/sim/test_sls.py (which
runs 5 particles per side).

The object: a 10 cm cube, W = 5 N, μ = 0.5 (F_w = 5 N), D = 5 N/cm, λ = 0 (the Zener solid), at
the corners and the centre of ``population --grip``'s ranges of k2 / D (0.25-3) and τ
(0.25-1 s). Columns: the largest relative miss of the law (evaluated on the simulated
compression; floating) over a 0.25 s ramp to 1.5 F_w from 40 % of the peak force, and over the
1 s hold that follows (below 40 % the object's own inertia rings: the Kelvin solid of the same
D, λ = 0, misses ``D d`` as much there), then the round trip's relative errors of D, k2 and τ
(the three squeezes of ``measure --sim``: 0.25 s ramp, 1 s hold, to 0.5, 0.75 and 1 of 1.5 F_w;
on the table under gravity, then floating, after the slash: the table's share of the Kelvin
calibration reads D and k2 about 1.3 % high).
"""

from __future__ import annotations

import numpy as np

from deformctl.characterize import characterize
from deformctl.characterize.laws import maxwell_strain
from deformctl.presets import sim_preset
from deformctl.sim import ObjectSpec, squeeze, squeeze_many
from deformctl.units import N_PER_CM

CASES = ((0.25, 0.25), (3.0, 0.25), (1.0, 0.5), (0.25, 1.0), (3.0, 1.0))
D_N_PER_CM = 5.0


def _spec(ratio: float, tau: float) -> ObjectSpec:
    return ObjectSpec(
        "sls", (10.0, 10.0, 10.0), 5.0, 0.5, D_N_PER_CM, 0.0,
        arm_stiffness_n_per_cm=ratio * D_N_PER_CM, relaxation_time_s=tau,
    )  # fmt: skip


def _law_miss(spec: ObjectSpec) -> tuple[float, float]:
    sq = squeeze(spec, peak_force_n=7.5, ramp_s=0.25, hold_s=1.0,
                 settings=sim_preset("paper").settings, gravity=False)  # fmt: skip
    d = sq.compression_m
    dt = float(sq.time_s[1] - sq.time_s[0])
    arm = spec.arm_stiffness_n_per_cm * N_PER_CM * maxwell_strain(d, dt, spec.relaxation_time_s)
    law = spec.stiffness_n_per_m * d + arm
    f = sq.force_n
    miss = np.abs(f - law) / np.where(law > 0, law, np.inf)
    loading = (sq.time_s <= 0.25) & (f >= 0.4 * f.max())
    return float(miss[loading].max()), float(miss[sq.time_s > 0.25].max())


def _round_trip(spec: ObjectSpec, gravity: bool) -> tuple[float, float, float]:
    squeezes = squeeze_many(spec, 3, peak_force_n=7.5, ramp_s=0.25, hold_s=1.0,
                            settings=sim_preset("paper").settings, gravity=gravity)  # fmt: skip
    row = characterize(
        {"sls": squeezes}, model="sls", objects={"sls": {"weight_n": 5.0, "friction_mu": 0.5}}
    ).iloc[0]
    return (
        row["sls_stiffness_n_per_cm"] / spec.stiffness_n_per_cm - 1.0,
        row["sls_arm_stiffness_n_per_cm"] / spec.arm_stiffness_n_per_cm - 1.0,
        row["sls_relaxation_time_s"] / spec.relaxation_time_s - 1.0,
    )


def main() -> None:
    print("k2/D  τ (s)  law miss: ramp ≥40 %, hold | round trip D, k2, τ (table / floating)")
    worst = 0.0
    for ratio, tau in CASES:
        spec = _spec(ratio, tau)
        ramp, hold = _law_miss(spec)
        line = f"{ratio:4.2f}  {tau:5.2f}  {ramp:16.2%}, {hold:5.2%} |"
        for gravity in (True, False):
            errs = _round_trip(spec, gravity)
            worst = max(worst, *(abs(e) for e in errs))
            line += " " + ", ".join(f"{e:+.2%}" for e in errs) + (" /" if gravity else "")
        print(line, flush=True)
    print(f"worst round-trip error: {worst:.2%} (required: within 3 %)", flush=True)


if __name__ == "__main__":
    main()
