"""The simulator source of ``measure``: squeezes of catalog objects in :mod:`deformctl.sim`
(``measure --sim``; see :func:`simulate_squeezes` for the default force rule).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from deformctl.catalog import catalog_objects
from deformctl.errors import UsageError
from deformctl.scene import DEFAULT_SCENE_HZ, scene_every_steps
from deformctl.series import SqueezeSeries

if TYPE_CHECKING:  # pragma: no cover - typing only; the simulator is imported when used
    from deformctl.sim import ObjectSpec, SimSettings


#: Default peak squeeze strain: the peak force of the last (largest) squeeze is the force that
#: holds the object at this compression, F = D · strain · size_x (catalog D). At 1 % the lattice
#: is in its small-strain range, where its stiffness is the catalog D; the simulator's own
#: helper measured it exact at 1 % and 16 % softer at 17 % strain, and at 5 % the backbone
#: softening already leaks into the λ fit (see README, measure --sim).
DEFAULT_SQUEEZE_STRAIN = 0.01
DEFAULT_SIM_SQUEEZES = 3  #: squeezes per object (the paper's X = 3)
DEFAULT_SIM_RAMP_S = 0.25  #: force ramp of each squeeze, s
DEFAULT_SIM_HOLD_S = 1.0  #: hold at the peak force, s

SqueezeProgress = Callable[[str, int, int], None]
"""``progress(object_id, squeezes_done, squeezes_total)``, called after each simulated squeeze."""


def default_peak_force_n(spec: ObjectSpec, strain: float = DEFAULT_SQUEEZE_STRAIN) -> float:
    """The default peak squeeze force: ``D · strain · size_x``, N (the static force for ``strain``).

    Args:
        spec: the object (catalog D in N/cm, size in cm).
        strain: compression as a fraction of the object's width between the palms.
    """
    return spec.stiffness_n_per_m * strain * spec.size_m[0]


def _object_seed(seed: int, index: int) -> int:
    """A per-object noise seed derived from the run seed (independent streams per object)."""
    return int(np.random.SeedSequence([seed, index]).generate_state(1)[0])


def simulate_squeezes(
    catalog: pd.DataFrame,
    *,
    squeezes: int = DEFAULT_SIM_SQUEEZES,
    settings: SimSettings | None = None,
    peak_force_n: float | None = None,
    strain: float = DEFAULT_SQUEEZE_STRAIN,
    ramp_s: float = DEFAULT_SIM_RAMP_S,
    hold_s: float = DEFAULT_SIM_HOLD_S,
    gravity: bool = True,
    noise_force_n: float = 0.0,
    noise_position_m: float = 0.0,
    seed: int = 0,
    progress: SqueezeProgress | None = None,
    path: str | None = None,
    first_index: int = 0,
    scene_hz: float = DEFAULT_SCENE_HZ,
) -> tuple[list[dict[str, Any]], list[SqueezeSeries]]:
    """Simulate ``squeezes`` force-controlled squeezes of every catalog object.

    Each object is squeezed ``squeezes`` times from rest by :func:`deformctl.sim.squeeze` (as
    :func:`deformctl.sim.squeeze_many` does): a linear force ramp over ``ramp_s`` then a hold of
    ``hold_s``, at peak forces ``linspace(0.5, 1, squeezes) · F_peak`` (so the squeezes probe
    different force levels). The
    palms are massless, so the force felt is the commanded force; the positions are the palms'.

    Args:
        catalog: catalog rows to squeeze (already selected), with material values.
        squeezes: squeezes per object (>= 1).
        settings: simulator settings (default :class:`~deformctl.sim.SimSettings`).
        peak_force_n: peak force of the largest squeeze, N, for every object; None (default)
            uses :func:`default_peak_force_n` with ``strain`` per object.
        strain: the default rule's strain (0 < strain < ``settings.max_squeeze_strain``).
        ramp_s: force ramp, s (>= 0). hold_s: hold at the peak, s (>= 0, ramp + hold > 0).
        gravity: object on the table under gravity (default); False floats it without a table
            (a pure material test: no pre-stress from the object's own weight).
        noise_force_n: std of Gaussian noise on the force felt, N (>= 0).
        noise_position_m: std of Gaussian noise on each palm position, m (>= 0).
        seed: noise seed; object ``i`` gets its own stream derived from (seed, i) and squeeze
            ``j`` of it that stream's seed + j. Same inputs and seed give the same bytes.
        progress: called after each squeeze.
        path: the catalog's name, for messages.
        first_index: the position of ``catalog``'s first row in the whole run's catalog: row
            ``i`` gets the noise stream of object ``first_index + i``, so squeezing a slice of
            a catalog (a sweep's one object) gives the bytes of the whole run.
        scene_hz: record each squeeze's scene (:mod:`deformctl.scene`, noise-free) at this many
            frames per simulated second for the log (0: none; at most 1/dt).

    Returns:
        ``(objects, squeezes)``: the objects' catalog rows (NaN as None) plus
        ``force_rate_hz``/``position_rate_hz`` (1/dt) and ``sim_peak_force_n`` (the largest
        squeeze's peak force), and every squeeze in object order.

    Raises:
        InputDataError: a row without material values or with values the simulator refuses
            (names the object; raised before any simulation).
        UsageError: an option out of range.
        SimulationError: the simulation produced a non-finite state.
    """
    from deformctl.sim import SimSettings, squeeze

    s = settings or SimSettings()
    if isinstance(squeezes, bool) or not isinstance(squeezes, int) or squeezes < 1:
        raise UsageError(f"squeezes must be an integer >= 1, got {squeezes!r}")
    if peak_force_n is not None and not (math.isfinite(peak_force_n) and peak_force_n > 0):
        raise UsageError(f"peak force must be a finite number > 0 N, got {peak_force_n}")
    if not (math.isfinite(strain) and 0 < strain < s.max_squeeze_strain):
        raise UsageError(
            f"strain must be in (0, {s.max_squeeze_strain:g}) (the densification limit), "
            f"got {strain}"
        )
    if not (math.isfinite(ramp_s) and ramp_s >= 0 and math.isfinite(hold_s) and hold_s >= 0):
        raise UsageError(f"ramp and hold must be >= 0 s, got {ramp_s} and {hold_s}")
    if ramp_s + hold_s <= 0:
        raise UsageError("ramp + hold must be > 0 s")
    for name, value in (("force", noise_force_n), ("position", noise_position_m)):
        if not (math.isfinite(value) and value >= 0):
            raise UsageError(f"{name} noise must be a finite number >= 0, got {value}")
    scene_every_steps(scene_hz, s.dt_s)  # refuses a bad rate before any squeeze
    objects_in = catalog_objects(catalog, path=path)
    specs = [obj.to_sim_spec(path=path) for obj in objects_in]
    records = [obj.record() for obj in objects_in]
    rate_hz = 1.0 / s.dt_s
    objects: list[dict[str, Any]] = []
    out: list[SqueezeSeries] = []
    total = squeezes * len(specs)
    for i, (spec, rec) in enumerate(zip(specs, records, strict=True)):
        peak = peak_force_n if peak_force_n is not None else default_peak_force_n(spec, strain)
        base_seed = _object_seed(seed, first_index + i)
        for j in range(squeezes):
            out.append(
                squeeze(
                    spec,
                    peak_force_n=peak * _force_scale(j, squeezes),
                    ramp_s=ramp_s,
                    hold_s=hold_s,
                    settings=s,
                    squeeze_index=j,
                    gravity=gravity,
                    noise_force_n=noise_force_n,
                    noise_position_m=noise_position_m,
                    seed=base_seed + j,
                    scene_hz=scene_hz,
                )
            )
            if progress is not None:
                progress(spec.object_id, i * squeezes + j + 1, total)
        objects.append(
            {**rec, "force_rate_hz": rate_hz, "position_rate_hz": rate_hz, "sim_peak_force_n": peak}
        )
    return objects, out


def _force_scale(j: int, n: int) -> float:
    """Squeeze ``j`` of ``n``: the factor on the peak force, ``linspace(0.5, 1, n)[j]``."""
    return 1.0 if n == 1 else float(np.linspace(0.5, 1.0, n)[j])
