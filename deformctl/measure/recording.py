"""A rig recording: what the readers return, and the compression from a position signal.

The one reader of both sources (:func:`~deformctl.measure.stage.read_recording`) returns a
:class:`Recording`: the squeezes as
``list[SqueezeSeries]`` in SI units with compression ``d`` as defined in :mod:`deformctl.series`
(total compression between the palms, positive when squeezed), plus the source streams' sample
rates, which ``measure`` stores with the object so that ``characterize`` can widen its
differentiation window for slow position topics.

**Where the compression comes from.** A position signal is one of:

* ``gap``: the distance between the palms (e.g. a parallel gripper's opening width):
  ``d = gap(t0) − gap(t)``.
* ``palm``: the travel of one palm along the squeeze axis while its partner moves symmetrically
  (mirror-image arms, as in the paper's rig): ``d = 2 · s · (p(t) − p(t0))``, with the sign
  ``s = ±1`` chosen so that ``d`` is positive at the sample of peak force (so it does not matter
  whether the logged palm is the left or the right one).
* ``travel``: a position whose travel is the compression (a testing machine's crosshead
  travel, a gripper's jaw travel; the CSV default for a ``position`` column):
  ``d = s · (p(t) − p(t0))``, the sign found as for ``palm``.
* ``compression`` (CSV only): the compression itself, e.g. a testing machine's crosshead travel
  against a fixed anvil: ``d = c(t) − c(t0)``.

The zero of compression is the median position over the recording's lead-in (the samples from
the start of the force/position overlap until the force first reaches half the segmentation
threshold), so the recording must start with the palms touching the unloaded object
(``compression_zero="lead_in"``, the default for bags, whose position noise would otherwise
enter every compression through one sample), or the first sample (``"first"``, the default for
CSV exports of testing machines, which start at the contact point). Every squeeze in a recording
is referenced to that same zero: an object that has not fully recovered between squeezes is
still measured from its unloaded shape.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from deformctl.errors import InputDataError
from deformctl.plausibility import compression_has_wrong_sign
from deformctl.reprs import short_repr
from deformctl.series import FloatArray, Rupture, SqueezeSeries


@dataclass(frozen=True)
class Recording:
    """The squeezes read from one recording, with the sample rates of its source streams.

    Attributes:
        squeezes: the squeezes, in SI.
        force_rate_hz: median sample rate of the (first) force stream, Hz.
        position_rate_hz: median sample rate of the position stream, Hz. Position is
            interpolated onto the force timestamps, so a slow position stream carries fewer
            independent samples than the squeezes have; ``characterize`` widens its
            differentiation window for it (see :func:`deformctl.characterize.default_window_s`).
        source, phase, ruptures: see :meth:`log_fields`.
        flags: the recording's defects (:mod:`deformctl.measure.defects`), which
            ``characterize`` adds to the object's quality.
        force_lag_s: the lag of the force behind the position that the reader took out of the
            force (it moved the force that much earlier), s; None when it took none out.
        force_lag_source: where that lag came from: ``given`` (``--lag-s SECONDS``, a latency
            the user knows) or ``auto`` (``--lag-s auto``, estimated from the recording); ``""``
            with no lag taken out.
        defects: each defect's flag, line and numbers.
        details: what the reader found in the file and did (a CSV's layout, columns, units,
            preamble, force sign, lag), stored with the object under the source's name.
        notes: lines for stderr about what was found (the columns chosen, a sign flipped).
        warnings: lines for stderr about doubtful input (a unit assumed, each defect).
    """

    __repr__ = short_repr

    squeezes: list[SqueezeSeries]
    force_rate_hz: float
    position_rate_hz: float
    source: str = ""
    phase: str = "all"
    ruptures: tuple[Rupture, ...] = ()
    flags: tuple[str, ...] = ()
    force_lag_s: float | None = None
    force_lag_source: str = ""
    defects: tuple[Mapping[str, Any], ...] = ()
    details: Mapping[str, Any] = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()

    @property
    def notices(self) -> tuple[str, ...]:
        """What a user must read of this recording besides its columns, one line each: the
        notes after the first (the force's sign flipped, the position's reading, a lag shifted
        out), each rupture cut off, then each warning (a unit assumed, a defect) prefixed
        ``warning:``. The single-file and the many-files forms of ``measure`` print the same
        lines, each after the file's name."""
        lines = list(self.notes[1:])
        lines += [f"warning: rupture in {r.describe()}: cut off" for r in self.ruptures]
        lines += [f"warning: {w}" for w in self.warnings]
        return tuple(lines)

    def log_fields(self) -> dict[str, Any]:
        """What a squeeze log stores with the object besides its catalog values.

        ``force_rate_hz`` and ``position_rate_hz``; ``source`` (``ros2_bag`` or ``csv``: the
        log is a rig recording, which ``characterize`` fits with a preload by default),
        ``phase`` and ``ruptures`` (the points where squeezes were cut, see
        :class:`deformctl.series.Rupture`); ``recording_flags`` and ``recording_defects`` (the
        recording's defects); ``force_lag_s`` and ``force_lag_source`` when a lag was taken out
        of the force (``characterize`` then knows the lag is accounted for, see
        :func:`deformctl.characterize.default_lag`); and, under the source's name (``csv``), the
        :attr:`details`.
        """
        out: dict[str, Any] = {
            "force_rate_hz": self.force_rate_hz,
            "position_rate_hz": self.position_rate_hz,
        }
        if self.source:
            out["source"] = self.source
        if self.phase != "all":
            out["phase"] = self.phase
        if self.ruptures:
            out["ruptures"] = [r.to_record() for r in self.ruptures]
        if self.flags:
            out["recording_flags"] = list(self.flags)
            out["recording_defects"] = [dict(d) for d in self.defects]
        if self.force_lag_s is not None:
            out["force_lag_s"] = self.force_lag_s
            out["force_lag_source"] = self.force_lag_source
        if self.details:
            out[self.source or "recording"] = dict(self.details)
        return out


def _rate_hz(time_s: FloatArray) -> float:
    """Median sample rate of increasing timestamps ``[n]`` (n ≥ 2), Hz."""
    return float(1.0 / np.median(np.diff(time_s)))


def _check_stream(name: str, time_s: FloatArray, values: FloatArray, path: str) -> None:
    """Refuse NaN samples and timestamps that do not strictly increase."""
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        raise InputDataError(
            f"{name}: {bad.size} NaN/inf sample(s), first at index {int(bad[0])}", path=path
        )
    steps = np.diff(time_s)
    back = np.flatnonzero(steps <= 0)
    if back.size:
        i = int(back[0]) + 1
        raise InputDataError(
            f"{name}: non-monotonic timestamps, sample {i} at {time_s[i]:.9f} s does not follow "
            f"sample {i - 1} at {time_s[i - 1]:.9f} s",
            path=path,
        )
    if time_s.shape[0] < 2:
        raise InputDataError(f"{name}: only {time_s.shape[0]} sample(s)", path=path)


def _unloaded_reference(position: FloatArray, force_n: FloatArray, threshold_frac: float) -> float:
    """Position of the unloaded object: the median over the lead-in before the first squeeze.

    The lead-in is the run of samples from the start whose force stays below half the
    segmentation threshold; one noisy sample would put its noise into every compression.
    """
    peak = float(np.max(force_n))
    loaded = np.flatnonzero(force_n >= 0.5 * threshold_frac * peak)
    n_lead = int(loaded[0]) if loaded.size else position.shape[0]
    return float(np.median(position[: max(n_lead, 1)]))


def _convention(kind: str, increases_when: str | None) -> str | None:
    """When the position grows for a position kind: ``closing``, ``opening`` or None (auto:
    one palm's or a travel's sign is the one positive at the peak force)."""
    if increases_when is not None:
        return increases_when
    return {"gap": "opening", "compression": "closing"}.get(kind)


def _compression(
    position: FloatArray,
    force_n: FloatArray,
    kind: str,
    path: str,
    threshold_frac: float,
    zero: str,
    increases_when: str | None = None,
    what: str = "the position",
) -> FloatArray:
    """Compression ``[n]`` (m) from a gap, a symmetric palm's travel, a travel, or a direct
    compression.

    ``increases_when`` says whether the position grows as the gripper closes or opens; None
    means the kind's convention (a gap grows when opening, a compression when closing) or, for
    one palm's travel, the sign that makes d positive at the peak force.

    Raises:
        InputDataError: the position never moves, or d is negative where the object is loaded
            (the message names the ``--position-increases-when`` that flips it).
    """
    if zero == "first":
        rel = position - position[0]
    else:  # lead_in
        rel = position - _unloaded_reference(position, force_n, threshold_frac)
    convention = _convention(kind, increases_when)
    if convention is None:  # one palm, auto: positive at the peak force
        peak = int(np.argmax(force_n))
        sign = 1.0 if rel[peak] >= 0 else -1.0
    else:
        sign = 1.0 if convention == "closing" else -1.0
    d = (2.0 if kind == "palm" else 1.0) * sign * rel  # travel, gap, compression: 1
    if float(np.max(np.abs(d))) <= 0.0:
        raise InputDataError(
            "no compression: the position signal never moves (zero displacement)", path=path
        )
    if convention is not None and compression_has_wrong_sign(d, force_n):
        other = "opening" if convention == "closing" else "closing"
        loaded = float(np.median(d[force_n >= 0.5 * float(np.max(force_n))]))
        raise InputDataError(
            f"compression has the wrong sign: {what} moves the other way as the force rises "
            f"(compression {loaded:.3g} m where loaded); if it grows as the gripper "
            f"{'closes' if other == 'closing' else 'opens'}, pass --position-increases-when "
            f"{other}",
            path=path,
        )
    return np.asarray(d, dtype=np.float64)
