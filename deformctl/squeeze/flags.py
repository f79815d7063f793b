"""The recording's flags: the defects and doubts ``measure`` finds in a recording, by name, and
what each means.

``measure`` raises them (:mod:`deformctl.measure.defects`, :mod:`deformctl.plausibility`) and
stores them in the squeeze log's object row (``recording_flags``); ``characterize`` adds them to
the object's ``quality`` (:mod:`deformctl.characterize.quality`) and names their meaning in its
warning line. Both read the names here (a light module: every ``--help`` reads the quality
policy).
"""

from __future__ import annotations

LOGGING_GAP = "logging_gap"
COARSE_FORCE = "coarse_force"
FORCE_LAG = "force_lag"
#: ``force_lag_source`` of a squeeze log's object row, when ``measure`` took a lag out of the
#: force (``force_lag_s``): given (``--lag-s SECONDS``, a latency known from the rig: no lag is
#: left, ``characterize`` fits none) or estimated (``--lag-s auto``: the estimate is the latency
#: less λ/D, so the shift takes λ with it and ``characterize`` withholds λ).
LAG_GIVEN = "given"
LAG_ESTIMATED = "auto"
#: The squeezes give energy back (their force-compression loops run the wrong way): the samples
#: run backwards in time, or the force lags the position (:mod:`deformctl.measure.ros2_bag`).
ENERGY_RETURNED = "energy_returned"
#: The two-sided plausibility flags (:mod:`deformctl.plausibility`): a recorded number that a unit
#: slip explains better than the object.
FORCE_UNIT_DOUBTFUL = "force_unit_doubtful"
COMPRESSION_UNIT_DOUBTFUL = "compression_unit_doubtful"
TIME_UNIT_DOUBTFUL = "time_unit_doubtful"
#: The recording's doubt flags (``measure``); the implied damping ratio's flag
#: (``damping_ratio_implausible``) is ``characterize``'s, which fits λ.
DOUBT_FLAGS: tuple[str, ...] = (FORCE_UNIT_DOUBTFUL, COMPRESSION_UNIT_DOUBTFUL, TIME_UNIT_DOUBTFUL)

#: Every recording flag, in the order ``quality`` lists them (the doubt flags last), and what it
#: means.
RECORDING_FLAGS: dict[str, str] = {
    LOGGING_GAP: "the recording has a gap of more than 5 sample intervals",
    COARSE_FORCE: "the force's resolution is coarser than 2 % of its peak",
    FORCE_LAG: "the force lags the position; λ is low by D × the lag (measure --lag-s SECONDS "
    "with the rig's latency; --lag-s auto keeps D, not λ)",
    ENERGY_RETURNED: "the squeezes give energy back, which no passive object does: the "
    "samples run backwards in time, or the force lags the position; λ is wrong",
    FORCE_UNIT_DOUBTFUL: "the peak force is implausible for a soft object (below 50 mN or "
    "above 3 kN, or a secant stiffness above 5000 N/cm): a unit slip such as kN read as N",
    COMPRESSION_UNIT_DOUBTFUL: "the peak compression is below 20 µm (or a secant stiffness "
    "above 5000 N/cm): a unit slip such as m read as mm",
    TIME_UNIT_DOUBTFUL: "no time unit stated and a sample rate below 10 Hz or an implied "
    "damping ratio above 1000: ms stamps read as s",
}
