"""Unit constants. SI inside the code; the paper's units (cm, N/cm, N·s/cm) at the edges.

Multiply a value in the named unit by the constant to get SI, divide to go back::

    stiffness_n_per_m = deformability_n_per_cm * N_PER_CM
"""

from __future__ import annotations

GRAVITY_M_S2 = 9.80665  #: standard gravity, m/s²

CM = 0.01  #: metres per centimetre
MM = 0.001  #: metres per millimetre
N_PER_CM = 100.0  #: (N/m) per (N/cm)
NS_PER_CM = 100.0  #: (N·s/m) per (N·s/cm)
NS_PER_S = 1_000_000_000  #: nanoseconds per second


def s_to_ns(t_s: float) -> int:
    """Seconds to integer nanoseconds (rounded), as MCAP log times want."""
    return round(t_s * NS_PER_S)
