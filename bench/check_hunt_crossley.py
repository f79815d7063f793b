"""The simulator's Hunt–Crossley material at the ``paper`` preset's own lattice (``make hc-check``,
about a minute): the squeeze against ``k dⁿ + λ_hc dⁿ ḋ`` and the round trip through
``characterize --model hc``, the longer companion of tests/sim/test_hunt_crossley.py and
tests/characterize/test_sim_roundtrip.py (which run 5 particles per side).

The object: a 10 cm cube, W = 5 N, μ = 0.5 (F_w = 5 N), D = 5 N/cm and λ at F_w, squeezed on
the table under gravity (as ``measure --sim`` squeezes) to 1.5 F_w. Columns: the largest relative
miss of the law over the loading samples from 10 % (and from 20 %) of the peak force, the static
miss after the hold, then the round trip's relative errors of n, k, D and λ (3 squeezes of
0.25 s ramp and 1 s hold; the same three squeezes floating, without gravity and table, after the
slash: the material test reads k lower by the table's share of the calibration).
"""

from __future__ import annotations

import numpy as np

from deformctl.characterize import characterize
from deformctl.presets import sim_preset
from deformctl.sim import ObjectSpec, squeeze, squeeze_many
from deformctl.units import CM

CASES = ((1.5, 0.0), (1.5, 3.0), (2.0, 0.0), (2.0, 2.0), (3.0, 0.0), (3.0, 1.0))


def _law_miss(n: float, damping: float) -> tuple[float, float, float]:
    spec = ObjectSpec("hc", (10.0, 10.0, 10.0), 5.0, 0.5, 5.0, damping, n)
    ramp = 2.0
    sq = squeeze(
        spec,
        peak_force_n=1.5 * spec.operating_force_n,
        ramp_s=ramp,
        hold_s=3.0 if damping else 0.3,
        settings=sim_preset("paper").settings,
        gravity=True,
    )
    d = np.maximum(sq.compression_m, 0.0)
    rate = np.gradient(sq.compression_m, sq.time_s)
    law = (spec.hc_stiffness_n_per_m_pow_n + spec.hc_damping_ns_per_m_pow_n_plus_1 * rate) * d**n
    f = sq.force_n
    miss = np.abs(f - law) / np.where(law > 0, law, np.inf)
    ramp_part = sq.time_s <= ramp
    from10 = float(miss[ramp_part & (f >= 0.1 * f.max())].max())
    from20 = float(miss[ramp_part & (f >= 0.2 * f.max())].max())
    static = abs(f[-1] - spec.hc_stiffness_n_per_m_pow_n * d[-1] ** n) / f[-1]
    return from10, from20, float(static)


def _round_trip(n: float, damping: float, gravity: bool) -> tuple[float, float, float, float]:
    spec = ObjectSpec("hc", (10.0, 10.0, 10.0), 5.0, 0.5, 5.0, damping, n)
    squeezes = squeeze_many(
        spec,
        3,
        peak_force_n=1.5 * spec.operating_force_n,
        ramp_s=0.25,
        hold_s=1.0,
        settings=sim_preset("paper").settings,
        gravity=gravity,
    )
    row = characterize(
        {"hc": squeezes}, model="hc", objects={"hc": {"weight_n": 5.0, "friction_mu": 0.5}}
    ).iloc[0]
    k = spec.hc_stiffness_n_per_m_pow_n * CM**n
    return (
        row["hc_exponent"] / n - 1.0,
        row["hc_stiffness_n_per_cm_pow_n"] / k - 1.0,
        row["deformability_n_per_cm"] / 5.0 - 1.0,
        row["damping_ns_per_cm"] / damping - 1.0 if damping else float("nan"),
    )


def _fast_ramp() -> tuple[float, float]:
    """n = 2, λ = 0, squeezed on the table with the 0.25 s ramp of ``measure --sim``: the largest
    relative miss of ``k dⁿ`` over the ramp from 40 % of the peak force, and at the peak."""
    spec = ObjectSpec("hc", (10.0, 10.0, 10.0), 5.0, 0.5, 5.0, 0.0, 2.0)
    sq = squeeze(
        spec, peak_force_n=7.5, ramp_s=0.25, hold_s=0.2, settings=sim_preset("paper").settings
    )
    law = spec.hc_stiffness_n_per_m_pow_n * np.maximum(sq.compression_m, 0.0) ** 2
    f = sq.force_n
    ramp = (sq.time_s <= 0.25) & (f >= 0.4 * f.max())
    miss = np.abs(f[ramp] - law[ramp]) / law[ramp]
    peak = int(np.argmax(f))
    return float(miss.max()), float(abs(f[peak] - law[peak]) / law[peak])


def _exact_springs(n: float, strain: float) -> float:
    """The ``table`` preset (geometrically exact springs), squeezed slowly on the table to
    ``strain`` of its width on its law: the static force's relative miss of ``k dⁿ``."""
    spec = ObjectSpec("hc", (10.0, 10.0, 10.0), 5.0, 0.5, 5.0, 0.0, n)
    sq = squeeze(
        spec,
        peak_force_n=spec.elastic_force_n(strain * 0.1),
        ramp_s=2.0,
        hold_s=1.0,
        settings=sim_preset("table").settings,
    )
    return float(sq.force_n[-1] / spec.elastic_force_n(sq.compression_m[-1]) - 1.0)


def main() -> None:
    print(
        "   n  λ (N·s/cm)  law miss ≥10 %  ≥20 %   static | round trip n, k, D, λ "
        "(table / floating)"
    )
    for n, damping in CASES:
        a, b, c = _law_miss(n, damping)
        line = f"{n:4.1f}  {damping:10.1f}  {a:13.2%}  {b:6.2%}  {c:7.3%} |"
        if damping:
            for gravity in (True, False):
                errs = _round_trip(n, damping, gravity)
                line += " " + ", ".join(f"{e:+.2%}" for e in errs) + (" /" if gravity else "")
        print(line, flush=True)
    ramp, peak = _fast_ramp()
    print(
        f"fast ramp (n = 2, λ = 0, 0.25 s): law miss {ramp:.2%} from 40 % of the peak force, "
        f"{peak:.2%} at the peak",
        flush=True,
    )
    hc2, linear = _exact_springs(2.0, 0.13), _exact_springs(1.0, 0.17)
    print(
        f"table preset (exact springs), static: n = 2 at 13 % strain {hc2:+.2%}, "
        f"linear at 17 % strain {linear:+.2%} of the law",
        flush=True,
    )


if __name__ == "__main__":
    main()
