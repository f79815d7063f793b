"""Shared helpers for the simulator tests: a plain bisection over lift attempts."""

from __future__ import annotations

from deformctl.sim import (
    LiftProfile,
    ObjectSpec,
    SimSettings,
    SlipCriterion,
    SupportRelease,
    lift_attempt,
)


def min_lift_force_n(
    spec: ObjectSpec,
    lo_n: float,
    hi_n: float,
    *,
    rel_tol: float = 0.002,
    profile: LiftProfile | None = None,
    settings: SimSettings | None = None,
    criterion: SlipCriterion | None = None,
    release: SupportRelease | None = None,
) -> float:
    """Smallest grip force in [lo, hi] that lifts ``spec`` (lo must slip, hi must lift)."""
    kw = {"profile": profile, "settings": settings, "criterion": criterion, "release": release}
    assert not lift_attempt(spec, lo_n, **kw).lifted, "lower bracket lifts"
    assert lift_attempt(spec, hi_n, **kw).lifted, "upper bracket slips"
    while hi_n - lo_n > rel_tol * hi_n:
        mid = 0.5 * (lo_n + hi_n)
        if lift_attempt(spec, mid, **kw).lifted:
            hi_n = mid
        else:
            lo_n = mid
    return hi_n
