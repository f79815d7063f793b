"""The known material parameters of the characterize tests, in SI: one set per material law
(``kv`` Kelvin–Voigt, ``hc`` Hunt–Crossley, ``sls`` standard linear solid, ``exp`` exponential
stiffening)."""

from __future__ import annotations

#: Each law's true parameters (SI).
TRUTH: dict[str, dict[str, float]] = {
    "kv": {"stiffness_n_per_m": 1000.0, "damping_ns_per_m": 100.0},
    "hc": {
        "stiffness_n_per_m_pow_n": 1000.0 / 0.01**0.8,  # 1000 N/m secant at 10 mm
        "exponent": 1.8,
        "damping_ns_per_m_pow_n_plus_1": 100.0 / 0.01**1.8,
    },
    "sls": {"stiffness_n_per_m": 800.0, "arm_stiffness_n_per_m": 1200.0, "relaxation_time_s": 0.5},
    "exp": {  # the tangent stiffness grows e^1.5 = 4.5× over 10 mm
        "stiffness_n_per_m": 500.0,
        "stiffening_per_m": 150.0,
        "damping_ns_per_m": 50.0,
    },
}
