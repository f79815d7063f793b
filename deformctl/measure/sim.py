"""The simulator source of ``measure``: squeezes of catalog objects in :mod:`deformctl.sim`
(``measure --sim``; see :func:`simulate_squeezes` for the default force rule).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from deformctl.catalog import CatalogObject, catalog_objects
from deformctl.errors import UsageError
from deformctl.measure.options import (
    DEFAULT_SQUEEZE_PROTOCOL,
    DEFAULT_SQUEEZE_STRAIN,
    SqueezeProtocol,
)
from deformctl.scene import DEFAULT_SCENE_HZ, check_scene_hz
from deformctl.series import SqueezeSeries

if TYPE_CHECKING:  # pragma: no cover - typing only; the simulator is imported when used
    from deformctl.sim import ObjectSpec, SimSettings
    from deformctl.sim.engine import RunPlan


#: a Hunt–Crossley object's default squeezes reach at least this multiple of F_w
HC_MIN_PEAK_OVER_F_W = 1.5
#: ... and at most this multiple of F_w: the grip's working range. The lifting force L_f is at
#: most about 2 F_w (an undamped object; docs/explanation/model.md) and a bound is at most 1.1 L_f,
#: so the largest squeeze's 0..3 F_w covers every force a grip applies. A stiffening object
#: squeezed far past it (the 1 % strain of a light, stiff object: up to 1,300 F_w in the seed-1
#: law mix) states D at F_w from a few samples at the start of a fast ramp: P1224 of that mix
#: (D 30 N/cm at F_w) read 664 N/cm at 500 F_w, 139 N/cm at 46 F_w and 30.4 N/cm at 3 F_w.
HC_MAX_PEAK_OVER_F_W = 3.0

SqueezeProgress = Callable[[str, int, int], None]
"""``progress(object_id, objects_done, objects_total)``, called after each object's squeezes."""


def default_peak_force_n(spec: ObjectSpec, strain: float = DEFAULT_SQUEEZE_STRAIN) -> float:
    """The default peak squeeze force: ``D · strain · size_x``, N (the static force for ``strain``).

    A Hunt–Crossley object (:attr:`~deformctl.sim.ObjectSpec.hunt_crossley`) is squeezed to the
    static force for ``strain`` on its own law, ``k (strain · size_x)ⁿ``, kept between
    :data:`HC_MIN_PEAK_OVER_F_W` and :data:`HC_MAX_PEAK_OVER_F_W` times F_w, the force its D and
    λ are stated at: a stiffening material's D depends on the force, and a fit of squeezes far
    below or far above F_w states it there by extrapolation (the 1 % strain is a small fraction
    of F_w for a soft, heavy object and hundreds of F_w for a light, stiff one). A linear law's
    D does not depend on the force: Kelvin–Voigt and standard-linear-solid objects keep the
    strain rule.

    Args:
        spec: the object (catalog D in N/cm, size in cm).
        strain: compression as a fraction of the object's width between the palms.
    """
    if spec.hunt_crossley:
        at_strain = spec.elastic_force_n(strain * spec.size_m[0])
        f_w = spec.operating_force_n
        return min(max(at_strain, HC_MIN_PEAK_OVER_F_W * f_w), HC_MAX_PEAK_OVER_F_W * f_w)
    return spec.stiffness_n_per_m * strain * spec.size_m[0]


def _object_seed(seed: int, index: int) -> int:
    """A per-object noise seed derived from the run seed (independent streams per object)."""
    return int(np.random.SeedSequence([seed, index]).generate_state(1)[0])


def simulate_squeezes(
    catalog: pd.DataFrame,
    *,
    protocol: SqueezeProtocol = DEFAULT_SQUEEZE_PROTOCOL,
    settings: SimSettings | None = None,
    seed: int = 0,
    progress: SqueezeProgress | None = None,
    path: str | None = None,
    first_index: int = 0,
    scene_hz: float = DEFAULT_SCENE_HZ,
) -> tuple[list[dict[str, Any]], list[SqueezeSeries]]:
    """Simulate ``protocol.squeezes`` force-controlled squeezes of every catalog object.

    Each object is squeezed ``protocol.squeezes`` times from rest by :func:`deformctl.sim.squeeze`
    (as :func:`deformctl.sim.squeeze_many` does): a linear force ramp over ``protocol.ramp_s``
    then a hold of ``protocol.hold_s``, at peak forces ``linspace(0.5, 1, squeezes) · F_peak``
    (so the squeezes probe different force levels). The palms are massless, so the force felt
    is the commanded force; the positions are the palms'.

    Args:
        catalog: catalog rows to squeeze (already selected), with material values.
        protocol: the squeezes (:class:`~deformctl.measure.options.SqueezeProtocol`): their
            number, the peak force (``peak_force_n`` for every object, or the strain rule
            :func:`default_peak_force_n` per object, with ``strain`` below
            ``settings.max_squeeze_strain``), ramp, hold, gravity and noise.
        settings: simulator settings (default: those of the default preset, ``paper``, as the
            command's; :func:`deformctl.presets.sim_preset`).
        seed: noise seed; object ``i`` gets its own stream derived from (seed, i) and squeeze
            ``j`` of it that stream's seed + j. Same inputs and seed give the same bytes.
        progress: called after each object (its squeezes done), with objects done and total.
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
        UsageError: a strain at or above the simulator's densification limit.
        SimulationError: the simulation produced a non-finite state.
    """
    from deformctl.presets import sim_preset
    from deformctl.sim.protocols import plan_squeeze

    s, p = settings or sim_preset().settings, protocol
    check_squeeze_settings(p, s, scene_hz)
    objects = catalog_objects(catalog, path=path)
    specs = [obj.to_sim_spec(path=path) for obj in objects]  # every row refused first
    plans = [
        plan_squeeze(spec, ramp_s=p.ramp_s, hold_s=p.hold_s, settings=s, scene_hz=scene_hz)
        for spec in specs
    ]
    return squeeze_objects(
        objects,
        plans,
        protocol=protocol,
        settings=s,
        seed=seed,
        progress=progress,
        first_index=first_index,
        scene_hz=scene_hz,
    )


def check_squeeze_settings(
    protocol: SqueezeProtocol, settings: SimSettings, scene_hz: float
) -> None:
    """Refuse a strain at or above the densification limit, or a bad scene rate.

    Raises:
        UsageError: either one (exit 2).
    """
    if not protocol.strain < settings.max_squeeze_strain:
        raise UsageError(
            f"strain must be in (0, {settings.max_squeeze_strain:g}) (the densification limit), "
            f"got {protocol.strain:g}"
        )
    check_scene_hz(scene_hz, settings.dt_s)


def squeeze_objects(
    objects: Sequence[CatalogObject],
    plans: Sequence[RunPlan],
    *,
    protocol: SqueezeProtocol,
    settings: SimSettings,
    seed: int = 0,
    progress: SqueezeProgress | None = None,
    first_index: int = 0,
    scene_hz: float = DEFAULT_SCENE_HZ,
) -> tuple[list[dict[str, Any]], list[SqueezeSeries]]:
    """:func:`simulate_squeezes` of objects already parsed, each with its squeeze's plan
    (:func:`deformctl.sim.protocols.plan_squeeze` under ``protocol``, ``settings`` and
    ``scene_hz``: the spec built and the steps counted once), under settings already checked
    (:func:`check_squeeze_settings`)."""
    from deformctl.sim import squeeze

    s, p = settings, protocol
    records = [obj.record() for obj in objects]
    rate_hz = 1.0 / s.dt_s
    out_objects: list[dict[str, Any]] = []
    out: list[SqueezeSeries] = []
    squeezes = p.squeezes
    for i, (plan, rec) in enumerate(zip(plans, records, strict=True)):
        spec = plan.spec
        peak = (
            p.peak_force_n if p.peak_force_n is not None else default_peak_force_n(spec, p.strain)
        )
        base_seed = _object_seed(seed, first_index + i)
        for j in range(squeezes):
            out.append(
                squeeze(
                    spec,
                    peak_force_n=peak * _force_scale(j, squeezes),
                    ramp_s=p.ramp_s,
                    hold_s=p.hold_s,
                    settings=s,
                    squeeze_index=j,
                    gravity=p.gravity,
                    noise_force_n=p.noise_force_n,
                    noise_position_m=p.noise_position_m,
                    seed=base_seed + j,
                    scene_hz=scene_hz,
                    plan=plan,
                )
            )
        if progress is not None:
            progress(spec.object_id, i + 1, len(plans))
        out_objects.append(
            {**rec, "force_rate_hz": rate_hz, "position_rate_hz": rate_hz, "sim_peak_force_n": peak}
        )
    return out_objects, out


def _force_scale(j: int, n: int) -> float:
    """Squeeze ``j`` of ``n``: the factor on the peak force, ``linspace(0.5, 1, n)[j]``."""
    return 1.0 if n == 1 else float(np.linspace(0.5, 1.0, n)[j])
