"""Cutting a recording into squeezes: segmentation, ruptures and phases.

**Segmentation.** With ``segment=True`` a recording is split into squeezes where the force rises
above ``force_threshold_frac`` of the recording's peak force and falls back: runs above the
threshold that are closer than ``min_gap_s`` are merged, runs shorter than ``min_squeeze_s`` are
dropped, and the recording is cut at the midpoints of the quiet stretches between runs, so each
squeeze includes its unloaded lead-in and relaxation. With ``segment=False`` the recording is
one squeeze. Bags default to segmenting (a rig logs several squeezes per object, the paper
three); CSV exports default to one squeeze per file (one test per export).

**Cuts.** Every squeeze is then cut at a rupture and reduced to the ``phase`` asked for
(:mod:`deformctl.squeeze.rupture`), judged with the smoothing window ``characterize`` will
use for the recording's position rate.
"""

from __future__ import annotations

import itertools

import numpy as np

from deformctl.errors import InputDataError
from deformctl.measure.options import (
    DEFAULT_FORCE_THRESHOLD_FRAC,
    DEFAULT_MIN_GAP_S,
    DEFAULT_MIN_SQUEEZE_S,
    Segmentation,
)
from deformctl.series import FloatArray, Rupture, SqueezeSeries
from deformctl.squeeze.rupture import cut_rupture, phase_slice, slice_squeeze
from deformctl.squeeze.window import DEFAULT_WINDOW_S, default_window_s
from deformctl.units import s_to_ns


def segment_squeezes(
    time_s: FloatArray,
    force_n: FloatArray,
    *,
    force_threshold_frac: float = DEFAULT_FORCE_THRESHOLD_FRAC,
    min_gap_s: float = DEFAULT_MIN_GAP_S,
    min_squeeze_s: float = DEFAULT_MIN_SQUEEZE_S,
) -> list[slice]:
    """Index ranges of the squeezes in a recording (see the module docstring).

    Args:
        time_s: sample times ``[n]``, s, increasing.
        force_n: force felt ``[n]``, N.
        force_threshold_frac: threshold as a fraction of the recording's peak force.
        min_gap_s: runs above the threshold closer than this are one squeeze, s.
        min_squeeze_s: runs shorter than this are ignored, s.

    Returns:
        Slices into the arrays, in time order; empty when no squeeze is found.
    """
    peak = float(np.max(force_n))
    if not peak > 0:
        return []
    above = force_n > force_threshold_frac * peak
    edges = np.diff(above.astype(np.int8))
    starts: list[int] = (np.flatnonzero(edges == 1) + 1).tolist()
    stops: list[int] = (np.flatnonzero(edges == -1) + 1).tolist()
    if above[0]:
        starts.insert(0, 0)
    if above[-1]:
        stops.append(above.shape[0])
    runs: list[list[int]] = []
    for a, b in zip(starts, stops, strict=True):
        if runs and time_s[a] - time_s[runs[-1][1] - 1] < min_gap_s:
            runs[-1][1] = b
        else:
            runs.append([a, b])
    runs = [r for r in runs if time_s[r[1] - 1] - time_s[r[0]] >= min_squeeze_s]
    if not runs:
        return []
    cuts = [0]
    for (_, b0), (a1, _) in itertools.pairwise(runs):
        cuts.append((b0 + a1) // 2)
    cuts.append(time_s.shape[0])
    return [slice(cuts[i], cuts[i + 1]) for i in range(len(runs))]


def _to_squeezes(
    time_s: FloatArray,
    force_n: FloatArray,
    compression_m: FloatArray,
    *,
    object_id: str,
    segmentation: Segmentation,
    segment: bool,
    path: str,
    window_s: float | None = None,
    clock_origin_ns: int | None = None,
) -> tuple[list[SqueezeSeries], list[Rupture]]:
    """Cut a recording into squeezes, each up to its rupture and reduced to the phase asked for.

    ``segmentation`` says how (its ``segment``, None for the source's default, is resolved by the
    caller into ``segment``).

    ``clock_origin_ns`` is the source's clock at ``time_s = 0`` (ns since the Unix epoch) when
    the recording has one: each squeeze then carries its first sample's ``start_time_ns``.

    Returns:
        The squeezes and the ruptures found (one per ruptured squeeze, recording times set).

    Raises:
        InputDataError: no squeeze found, or ``phase="unloading"`` on a squeeze that ruptured.
    """
    phase = segmentation.phase
    window = DEFAULT_WINDOW_S if window_s is None else window_s
    if segment:
        slices = segment_squeezes(
            time_s,
            force_n,
            force_threshold_frac=segmentation.force_threshold_frac,
            min_gap_s=segmentation.min_gap_s,
            min_squeeze_s=segmentation.min_squeeze_s,
        )
        if not slices:
            raise InputDataError(
                "no squeeze found: the force never stays above "
                f"{segmentation.force_threshold_frac:g} of its peak for "
                f"{segmentation.min_squeeze_s:g} s",
                path=path,
            )
    else:
        slices = [slice(0, time_s.shape[0])]
    out = []
    ruptures: list[Rupture] = []
    for i, sl in enumerate(slices):
        t = time_s[sl]
        whole = SqueezeSeries(
            object_id=object_id,
            squeeze_index=i,
            time_s=t - t[0],
            force_n=force_n[sl],
            compression_m=compression_m[sl],
            start_time_ns=None
            if clock_origin_ns is None
            else clock_origin_ns + s_to_ns(float(t[0])),
        )
        sq, rupture = cut_rupture(whole, window_s=window, recording_offset_s=float(t[0]))
        if rupture is not None:
            ruptures.append(rupture)
            if phase == "unloading":
                raise InputDataError(
                    f"squeeze #{i} ruptured ({rupture.describe()}): it has no unloading phase; "
                    "use --phase loading or all",
                    path=path,
                )
        out.append(slice_squeeze(sq, phase_slice(sq.time_s, sq.force_n, phase, window_s=window)))
    return out, ruptures


def _detection_window_s(position_rate_hz: float) -> float:
    """The SG window rupture and phase detection use: the one ``characterize`` will use."""
    return default_window_s(position_rate_hz)
