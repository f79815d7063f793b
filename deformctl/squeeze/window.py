"""The Savitzky–Golay window a squeeze is smoothed with: its default and the one a log's
position sample rate calls for.

``measure`` judges ruptures and phases with the window ``characterize`` will fit with, so both
take it from here.
"""

from __future__ import annotations

import math

#: Default Savitzky–Golay window, s. Long enough that the derivative of 0.05 mm position noise is
#: small against squeeze rates of a few mm/s (noise in ``d'`` biases λ low, see ``fit_lsq``), short
#: enough that a cubic follows a squeeze of a few seconds (cubic smoothing bias < 0.1 % in tests).
DEFAULT_WINDOW_S = 0.2
#: Sample rate the default window was chosen for, Hz (see :func:`default_window_s`).
DEFAULT_WINDOW_RATE_HZ = 1000.0


def default_window_s(position_rate_hz: float | None) -> float:
    """The Savitzky–Golay window for a log whose positions were sampled at ``position_rate_hz``.

    A squeeze log from a rig may carry positions sampled far more slowly than its forces (a
    100 Hz pose topic beside a 1 kHz wrench topic); ingestion interpolates them onto the force
    timestamps, so a window of ``T`` seconds holds only ``N = rate · T`` independent position
    samples. The noise variance of an SG derivative scales as ``σ² / (N T²) = σ² / (rate T³)``,
    and that noise biases λ low (see :func:`deformctl.characterize.fit.fit_lsq`). The default
    keeps it at the level of :data:`DEFAULT_WINDOW_S` at :data:`DEFAULT_WINDOW_RATE_HZ`::

        T = DEFAULT_WINDOW_S · (DEFAULT_WINDOW_RATE_HZ / rate)^(1/3),  never below DEFAULT_WINDOW_S

    (100 Hz → 0.43 s, 500 Hz → 0.25 s, ≥ 1 kHz → 0.2 s). A longer window costs smoothing bias
    at the corners of the force profile, so squeezes should last several windows.

    Args:
        position_rate_hz: position sample rate, Hz; None (unknown) gives the default.

    Returns:
        The window, s.
    """
    if position_rate_hz is None or not math.isfinite(position_rate_hz) or position_rate_hz <= 0:
        return DEFAULT_WINDOW_S
    scale = (DEFAULT_WINDOW_RATE_HZ / position_rate_hz) ** (1.0 / 3.0)
    return DEFAULT_WINDOW_S * max(1.0, scale)
