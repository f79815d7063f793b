"""What the simulated lifting force depends on, per material law: the study of
:mod:`deformctl.repro.grip_study` (which found L_f / F_w = r(ω_n, ζ) for Kelvin–Voigt objects)
for Hunt–Crossley objects and standard linear solids.

``python -m deformctl.repro.grip_study_laws [--jobs 1]`` (``make grip-study-laws``, about 6
minutes on one core) simulates, with the default ``lift --sim`` preset and the ``refine`` search
to 0.2 %, in a 12 x 12 x 10 cm box:

1. **Hunt–Crossley, two groups.** Pairs with W, D and λ (stated at F_w) scaled by 4 at n = 2
   (μ = 0.5): the law's k and λ_hc scale by 4 too, so the pair is the same object at four times
   the load; L_f / F_w should agree.
2. **Hunt–Crossley, friction.** One object (D, λ at F_w) at μ = 0.25, 0.5 and 1, n = 2.
3. **Hunt–Crossley, the exponent.** L_f / F_w over n = 1 ... 3 at fixed (ω_n, ζ) from D and λ at
   F_w (ω_n = √(D/m), ζ = λ / (2 √(D m)); μ = 1), and the Kelvin–Voigt object of the *tangent*
   stiffness at F_w, n D (same λ): whether the tangent collapses n away.
4. **Standard linear solid, two groups.** W, D and k2 scaled by 4 (same τ) keep ω_n, k2 / D and
   ω_n τ (μ = 0.5).
5. **Standard linear solid, the arm.** L_f / F_w over k2 / D and τ (λ = 0, the Zener solid) at
   three ω_n from the relaxed D (μ = 1), beside the undamped Kelvin–Voigt objects of stiffness
   D (relaxed) and D + k2 (unrelaxed).

Each table prints as it is simulated; nothing is written. The numbers are quoted in
docs/explanation/model.md.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence

from deformctl.repro.grip_study import (
    SEARCH_TOLERANCE,
    Case,
    _run,
    critical_damping_ns_per_cm,
    omega,
)
from deformctl.units import GRAVITY_M_S2

#: (W N, D N/cm, ζ) of the Hunt–Crossley pairs (× 4 keeps ω_n and ζ at F_w).
HC_PAIRS = ((1.0, 10.0, 0.2), (3.0, 12.0, 0.0), (2.0, 5.0, 1.0))
#: (W N, D N/cm, ζ) of the Hunt–Crossley friction study.
HC_FRICTION_OBJECT = (5.0, 20.0, 0.3)
HC_FRICTIONS = (0.25, 0.5, 1.0)
#: (ω_n rad/s, W N, ζ) of the exponent study, and the exponents.
HC_POINTS = ((15.0, 80.0, 0.0), (15.0, 80.0, 0.5), (60.0, 10.0, 0.0), (60.0, 10.0, 0.5),
             (60.0, 10.0, 2.0), (240.0, 0.6, 0.2))  # fmt: skip
HC_EXPONENTS = (1.0, 1.5, 2.0, 2.5, 3.0)
#: (W N, D N/cm, k2 / D, τ s) of the standard linear solids' pairs.
SLS_PAIRS = ((1.0, 10.0, 1.0, 0.5), (3.0, 12.0, 3.0, 0.25), (2.0, 5.0, 0.25, 1.0))
#: (ω_n rad/s, W N) of the arm study, and its k2 / D and τ.
SLS_OMEGAS = ((15.0, 80.0), (60.0, 10.0), (240.0, 0.6))
SLS_RATIOS = (0.25, 1.0, 3.0)
SLS_TAUS = (0.25, 1.0)


def _d_of(om: float, w: float) -> float:
    """D, N/cm, of the natural frequency ``om`` (rad/s) at weight ``w`` (N)."""
    return om * om * (w / GRAVITY_M_S2) / 100.0


def _hc(w: float, d: float, zeta: float, mu: float, n: float) -> Case:
    return Case(w, d, zeta * critical_damping_ns_per_cm(w, d), mu, stiffness_exponent=n)


def _sls(w: float, d: float, ratio: float, tau: float, mu: float) -> Case:
    return Case(w, d, 0.0, mu, arm_stiffness_n_per_cm=ratio * d, relaxation_time_s=tau)


def _pairs(cases: list[Case], jobs: int) -> list[tuple[float, float]]:
    ratios = _run(cases, jobs)
    return [(ratios[2 * i], ratios[2 * i + 1]) for i in range(len(cases) // 2)]


def _hunt_crossley(jobs: int) -> None:
    print("1. Hunt–Crossley, two groups: W, D, λ x 4 at n = 2 (μ = 0.5)")
    cases = [
        c for w, d, z in HC_PAIRS for c in (_hc(w, d, z, 0.5, 2.0), _hc(4 * w, 4 * d, z, 0.5, 2.0))
    ]
    worst = 0.0
    print(f"{'W N':>6} {'D N/cm':>7} {'omega':>6} {'zeta':>5} {'ratio':>7} {'ratio x4':>8}  diff")
    for (w, d, z), (a, b) in zip(HC_PAIRS, _pairs(cases, jobs), strict=True):
        worst = max(worst, abs(b / a - 1))
        print(f"{w:>6g} {d:>7g} {omega(w, d):>6.1f} {z:>5g} {a:>7.4f} {b:>8.4f}  {b / a - 1:+.2%}")
    print(f"worst pair difference: {worst:.2%}\n", flush=True)

    print("2. Hunt–Crossley, friction: one object (D, λ at F_w) at each μ, n = 2")
    w, d, z = HC_FRICTION_OBJECT
    row = _run([_hc(w, d, z, mu, 2.0) for mu in HC_FRICTIONS], jobs)
    print(" ".join(f"mu {m:<4g}" for m in HC_FRICTIONS) + "  spread")
    print(" ".join(f"{r:>7.4f}" for r in row) + f"  {max(row) / min(row) - 1:6.2%}\n", flush=True)

    print("3. Hunt–Crossley, the exponent: L_f / F_w over n at (ω_n, ζ) of D, λ at F_w (μ = 1);")
    print("   kv(nD): the Kelvin–Voigt object of the tangent stiffness n D at F_w, same λ")
    cases = []
    for om, w, z in HC_POINTS:
        d = _d_of(om, w)
        cases += [_hc(w, d, z, 1.0, n) for n in HC_EXPONENTS]
        lam = z * critical_damping_ns_per_cm(w, d)
        cases += [Case(w, n * d, lam, 1.0) for n in HC_EXPONENTS[1:]]
    ratios = _run(cases, jobs)
    k = len(HC_EXPONENTS) + len(HC_EXPONENTS) - 1
    print(
        f"{'omega':>6} {'zeta':>5} "
        + " ".join(f"n {n:<5g}" for n in HC_EXPONENTS)
        + "  spread | "
        + " ".join(f"kv({n:g}D)" for n in HC_EXPONENTS[1:])
    )
    for i, (om, _w, z) in enumerate(HC_POINTS):
        row = ratios[i * k : i * k + len(HC_EXPONENTS)]
        tangent = ratios[i * k + len(HC_EXPONENTS) : (i + 1) * k]
        print(
            f"{om:>6g} {z:>5g} "
            + " ".join(f"{r:>7.4f}" for r in row)
            + f"  {max(row) / min(row) - 1:6.2%} | "
            + " ".join(f"{r:>7.4f}" for r in tangent)
        )
    print(flush=True)


def _standard_linear_solid(jobs: int) -> None:
    print("4. standard linear solid, two groups: W, D, k2 x 4 (same τ; μ = 0.5)")
    cases = [
        c
        for w, d, r, t in SLS_PAIRS
        for c in (_sls(w, d, r, t, 0.5), _sls(4 * w, 4 * d, r, t, 0.5))
    ]
    worst = 0.0
    print(f"{'W N':>6} {'D N/cm':>7} {'k2/D':>5} {'tau s':>5} {'ratio':>7} {'ratio x4':>8}  diff")
    for (w, d, r, t), (a, b) in zip(SLS_PAIRS, _pairs(cases, jobs), strict=True):
        worst = max(worst, abs(b / a - 1))
        print(f"{w:>6g} {d:>7g} {r:>5g} {t:>5g} {a:>7.4f} {b:>8.4f}  {b / a - 1:+.2%}")
    print(f"worst pair difference: {worst:.2%}\n", flush=True)

    print("5. standard linear solid, the arm: L_f / F_w over k2 / D and τ (λ = 0; μ = 1);")
    print("   kv(D): the undamped Kelvin–Voigt object of the relaxed D; kv(D+k2): of the unrelaxed")
    arms = [(r, t) for t in SLS_TAUS for r in SLS_RATIOS]
    cases = []
    for om, w in SLS_OMEGAS:
        d = _d_of(om, w)
        cases += [_sls(w, d, r, t, 1.0) for r, t in arms]
        cases += [Case(w, d, 0.0, 1.0)] + [Case(w, d * (1 + r), 0.0, 1.0) for r in SLS_RATIOS]
    ratios = _run(cases, jobs)
    k = len(arms) + 1 + len(SLS_RATIOS)
    print(
        f"{'omega':>6} "
        + " ".join(f"{r:g}/{t:g}s".rjust(8) for r, t in arms)
        + "    kv(D) "
        + " ".join(f"kv(D+{r:g}D)" for r in SLS_RATIOS)
    )
    for i, (om, _w) in enumerate(SLS_OMEGAS):
        row = ratios[i * k : (i + 1) * k]
        print(
            f"{om:>6g} "
            + " ".join(f"{r:>8.4f}" for r in row[: len(arms)])
            + "  "
            + " ".join(f"{r:>8.4f}" for r in row[len(arms) :])
        )
    print("   (each column k2/D / τ)", flush=True)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m deformctl.repro.grip_study_laws")
    parser.add_argument("--jobs", type=int, default=1, help="Processes (default 1).")
    parser.add_argument(
        "--law", choices=("hc", "sls", "both"), default="both", help="Which law to study."
    )
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    print(f"refine searches to {SEARCH_TOLERANCE:.1%}, 12 x 12 x 10 cm box\n")
    if args.law in ("hc", "both"):
        _hunt_crossley(args.jobs)
    if args.law in ("sls", "both"):
        _standard_linear_solid(args.jobs)
    print(f"\n{time.perf_counter() - t0:.0f} s wall")
    return 0


if __name__ == "__main__":
    sys.exit(main())
