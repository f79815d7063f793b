"""The coefficients of one object (:class:`CoefficientFit`) and the coefficients table's rows.

A fit (:mod:`deformctl.characterize.fit`) returns a :class:`CoefficientFit`: D and λ in the paper's
units with their standard errors, diagnostics and quality flags
(:mod:`deformctl.characterize.quality`); :meth:`CoefficientFit.row` is its row of the table,
columns :data:`COEFFICIENT_COLUMNS`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import pandas as pd

from deformctl.catalog import SIZE_COLUMNS
from deformctl.characterize.columns import (
    MATERIAL_COLUMNS,
    MATERIAL_DTYPES,
    empty_values,
    material_values,
)
from deformctl.characterize.quality import (
    BELOW_SQUEEZES_SHARE,
    SECANT_MISFIT_FRAC,
    assess,
    quality_text,
)
from deformctl.series import Rupture
from deformctl.squeeze.flags import LAG_ESTIMATED, LAG_GIVEN
from deformctl.units import CM, N_PER_CM, NS_PER_CM

#: The object's own values ``characterize`` copies from the squeeze log into its row (NaN, or
#: ``""`` for ``source``, when the log does not have them), so that ``predict`` and
#: ``lift --sim`` need no catalog: the weight, the size and μ the log's object row stores
#: (``measure --weight-n``, ``--size-cm``, ``--friction-mu`` or the catalog of ``measure --sim``)
#: and where the squeezes came from (the log's ``source``: ``sim``, ``ros2_bag``, ``csv``), and
#: the lag ``measure --lag-s`` took out of the force before the fit, with whether it was given or
#: estimated (``force_lag_s``, ``force_lag_source``: NaN and ``""`` when none).
OBJECT_COLUMNS: tuple[str, ...] = (
    "weight_n",
    *SIZE_COLUMNS,
    "friction_mu",
    "source",
    "force_lag_s",
    "force_lag_source",
)
#: The object columns that are numbers > 0 (NaN otherwise).
_POSITIVE_OBJECT_COLUMNS = ("weight_n", *SIZE_COLUMNS, "friction_mu")

if TYPE_CHECKING:  # pragma: no cover - typing only
    from deformctl.characterize.objectfit import ObjectFit

#: The columns of schema version 2, then the material columns of version 3
#: (:data:`deformctl.characterize.columns.MATERIAL_COLUMNS`).
BASE_COLUMNS = (
    "object_id",
    "deformability_n_per_cm",
    "damping_ns_per_cm",
    "method",
    "deformability_se_n_per_cm",
    "damping_se_ns_per_cm",
    "r2",
    "n_samples",
    "n_squeezes",
    "quality",
    "preload_n",
    "damping_excitation",
    "design_condition",
    "damping_bound_active",
    "compression_min_cm",
    "compression_max_cm",
    "force_min_n",
    "force_max_n",
    "window_samples",
    "ruptures",
    "rupture_time_s",
    "rupture_force_n",
)
COEFFICIENT_COLUMNS = (*BASE_COLUMNS, *MATERIAL_COLUMNS, *OBJECT_COLUMNS)


@dataclass(frozen=True)
class CoefficientFit:
    """Deformability and damping of one object, with fit quality.

    Attributes:
        deformability_n_per_cm: D, N/cm.
        damping_ns_per_cm: λ, N·s/cm (NaN when not identifiable).
        method: ``"lsq"`` or ``"paper"``.
        deformability_se_n_per_cm: standard error of D, N/cm (NaN when not estimable).
        damping_se_ns_per_cm: standard error of λ, N·s/cm (NaN when not estimable).
        r2: coefficient of determination of ``f ≈ D d + λ d'`` on the samples used.
        n_samples: samples used in the fit (after trimming and masking).
        n_squeezes: squeezes contributing.
        preload_n: the fitted contact preload (intercept), N; NaN when not fitted.
        damping_excitation: share of the rate's mean square independent of a constant and of d
            (0..1); λ needs it well above 0 (see
            :func:`deformctl.characterize.quality.damping_identifiable`).
        design_condition: condition number of the fitted design with unit-RMS columns.
        damping_bound_active: the bound λ ≥ 0 held λ at 0.
        damping_unidentifiable: λ was not identifiable (and is NaN).
        compression_min_cm, compression_max_cm: range of d over the samples used, cm.
        force_min_n, force_max_n: range of f over the samples used, N.
        window_samples: the SG window, samples.
        ruptures: the ruptures found in the squeezes (each fitted up to its rupture).
        material: the material columns (:mod:`deformctl.characterize.columns`).
        at_bound: a physical parameter of the chosen law sits at its bound.
        nonlinear_stiffness: the loading curve's tangent stiffness varies by more than 2×.
        relaxations: squeezes whose force relaxed at constant compression.
        secant_misfit: the law misses the recording where D is stated
            (:data:`deformctl.characterize.quality.SECANT_MISFIT_FRAC`).
        below_squeezes: a stiffening law states D far below every squeeze's peak force
            (:data:`deformctl.characterize.quality.BELOW_SQUEEZES_SHARE`).
    """

    deformability_n_per_cm: float
    damping_ns_per_cm: float
    method: str
    deformability_se_n_per_cm: float
    damping_se_ns_per_cm: float
    r2: float
    n_samples: int
    n_squeezes: int
    preload_n: float = math.nan
    damping_excitation: float = math.nan
    design_condition: float = math.nan
    damping_bound_active: bool = False
    damping_unidentifiable: bool = False
    compression_min_cm: float = math.nan
    compression_max_cm: float = math.nan
    force_min_n: float = math.nan
    force_max_n: float = math.nan
    window_samples: int = 0
    ruptures: tuple[Rupture, ...] = ()
    material: dict[str, object] = field(default_factory=empty_values)
    at_bound: bool = False
    nonlinear_stiffness: bool = False
    relaxations: int = 0
    secant_misfit: bool = False
    below_squeezes: bool = False

    @classmethod
    def from_object(cls, obj: ObjectFit) -> CoefficientFit:
        """The coefficients of a material fit (``objectfit.fit_object``)."""
        chosen = obj.chosen
        damping_names = {"damping_ns_per_m", "damping_ns_per_m_pow_n_plus_1"}
        damping_names |= {"arm_stiffness_n_per_m"} if chosen.model == "sls" else set()
        at_bound = tuple(chosen.at_bound)
        design = chosen.covariance
        return cls(
            deformability_n_per_cm=obj.deformability_n_per_m / N_PER_CM,
            damping_ns_per_cm=obj.damping_ns_per_m / NS_PER_CM,
            method="lsq",
            deformability_se_n_per_cm=obj.deformability_se_n_per_m / N_PER_CM,
            damping_se_ns_per_cm=obj.damping_se_ns_per_m / NS_PER_CM,
            r2=obj.sample_r2.get(chosen.model, chosen.r2),
            n_samples=obj.n_samples,
            n_squeezes=len(obj.grids),
            preload_n=chosen.params["preload_n"] if obj.fit_preload else math.nan,
            damping_excitation=obj.damping_excitation,
            design_condition=float(_condition(design)),
            damping_bound_active=bool(damping_names & set(at_bound)),
            damping_unidentifiable=not obj.damping_identifiable,
            compression_min_cm=obj.compression_range_m[0] / CM,
            compression_max_cm=obj.compression_range_m[1] / CM,
            force_min_n=obj.force_range_n[0],
            force_max_n=obj.force_range_n[1],
            window_samples=obj.window_samples,
            ruptures=obj.ruptures,
            material=material_values(obj),
            at_bound=bool(at_bound),
            nonlinear_stiffness=obj.loading.nonlinear,
            relaxations=len(obj.relaxations),
            secant_misfit=abs(obj.secant_residual_frac) > SECANT_MISFIT_FRAC,
            below_squeezes=_below_squeezes(obj),
        )

    @property
    def stiffness_n_per_m(self) -> float:
        """D in SI, N/m."""
        return self.deformability_n_per_cm * N_PER_CM

    @property
    def damping_ns_per_m(self) -> float:
        """λ in SI, N·s/m."""
        return self.damping_ns_per_cm * NS_PER_CM

    @property
    def flags(self) -> tuple[str, ...]:
        """The quality flags of this fit (:func:`~deformctl.characterize.quality.assess`; empty:
        ok)."""
        return assess(
            deformability_n_per_cm=self.deformability_n_per_cm,
            damping_ns_per_cm=self.damping_ns_per_cm,
            damping_se_ns_per_cm=self.damping_se_ns_per_cm,
            r2=self.r2,
            n_samples=self.n_samples,
            window_samples=self.window_samples,
            damping_unidentifiable=self.damping_unidentifiable,
            damping_bound_active=self.damping_bound_active and self.method != "lsq",
            ruptures=len(self.ruptures),
            at_bound=self.at_bound,
            nonlinear_stiffness=self.nonlinear_stiffness,
            relaxations=self.relaxations,
            secant_misfit=self.secant_misfit,
            below_squeezes=self.below_squeezes,
        )

    @property
    def quality(self) -> str:
        """``ok`` or the comma list of :attr:`flags`."""
        return quality_text(self.flags)

    def with_ranges(self, ranges: Mapping[str, float]) -> CoefficientFit:
        """This fit with the loading range fields (``compression_min_cm``, ...) set."""
        return dataclasses.replace(
            self,
            compression_min_cm=ranges["compression_min_cm"],
            compression_max_cm=ranges["compression_max_cm"],
            force_min_n=ranges["force_min_n"],
            force_max_n=ranges["force_max_n"],
        )

    def row(self, object_id: str) -> dict[str, object]:
        """The coefficients row of this fit (columns :data:`COEFFICIENT_COLUMNS`)."""
        first = self.ruptures[0] if self.ruptures else None
        return {
            "object_id": object_id,
            "deformability_n_per_cm": self.deformability_n_per_cm,
            "damping_ns_per_cm": self.damping_ns_per_cm,
            "method": self.method,
            "deformability_se_n_per_cm": self.deformability_se_n_per_cm,
            "damping_se_ns_per_cm": self.damping_se_ns_per_cm,
            "r2": self.r2,
            "n_samples": self.n_samples,
            "n_squeezes": self.n_squeezes,
            "quality": self.quality,
            "preload_n": self.preload_n,
            "damping_excitation": self.damping_excitation,
            "design_condition": self.design_condition,
            "damping_bound_active": self.damping_bound_active,
            "compression_min_cm": self.compression_min_cm,
            "compression_max_cm": self.compression_max_cm,
            "force_min_n": self.force_min_n,
            "force_max_n": self.force_max_n,
            "window_samples": self.window_samples,
            "ruptures": len(self.ruptures),
            "rupture_time_s": math.nan if first is None else first.time_s,
            "rupture_force_n": math.nan if first is None else first.force_n,
            **self.material,
            "yield_compression_cm": math.nan if first is None else first.compression_m / CM,
        }


def _positive(value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return math.nan
    number = float(value)
    return number if math.isfinite(number) and number > 0 else math.nan


def object_fields(obj: Mapping[str, object] | None) -> dict[str, object]:
    """The :data:`OBJECT_COLUMNS` of an object row of a squeeze log.

    A weight, size or μ that is missing, not a number or not > 0 is NaN. ``source`` is the log's
    own (``ros2_bag``, ``csv``, ...); a ``measure --sim`` object row, which stores the simulated
    peak force rather than a source, is ``sim``; ``""`` when the log does not say.
    ``force_lag_s`` is the lag the log says ``measure`` took out of the force (NaN when none or
    not a finite number) and ``force_lag_source`` where it came from (``given``, ``auto``;
    ``""`` otherwise).
    """
    obj = obj or {}
    out: dict[str, object] = {c: _positive(obj.get(c)) for c in _POSITIVE_OBJECT_COLUMNS}
    source = obj.get("source")
    if not isinstance(source, str) or not source:
        source = "sim" if "sim_peak_force_n" in obj else ""
    out["source"] = source
    lag, lag_source = obj.get("force_lag_s"), obj.get("force_lag_source")
    known = lag_source in (LAG_GIVEN, LAG_ESTIMATED) and _is_number(lag)
    out["force_lag_s"] = float(lag) if known else math.nan  # type: ignore[arg-type]
    out["force_lag_source"] = lag_source if known else ""
    return out


def _is_number(value: object) -> bool:
    return (
        isinstance(value, int | float)
        and not isinstance(value, bool)
        and math.isfinite(float(value))
    )


def _coefficient_frame(rows: Sequence[Mapping[str, object]]) -> pd.DataFrame:
    """The coefficient table of :meth:`CoefficientFit.row` rows.

    Every row holds the same types (str, float, int, bool; never None), so one frame of many
    rows equals the concatenation of their one-row frames, at a fraction of the cost.
    """
    blank = object_fields(None)
    df = pd.DataFrame([{**blank, **r} for r in rows], columns=list(COEFFICIENT_COLUMNS))
    return df.astype(
        {
            "n_samples": "int64",
            "n_squeezes": "int64",
            "window_samples": "int64",
            "ruptures": "int64",
            "damping_bound_active": "bool",
            **MATERIAL_DTYPES,
        }
    )


def _condition(covariance: object) -> float:
    """Condition number of the fitted parameters' covariance (NaN when there is none)."""
    import numpy as np

    c = np.asarray(covariance, dtype=np.float64)
    if c.size == 0 or not np.all(np.isfinite(c)):
        return math.nan
    d = np.sqrt(np.abs(np.diag(c)))
    if not np.all(d > 0):
        return math.nan
    return float(np.linalg.cond(c / np.outer(d, d)))


def _below_squeezes(obj: ObjectFit) -> bool:
    """A stiffening law (``hc``, ``exp``) states D where fewer than
    :data:`~deformctl.characterize.quality.BELOW_SQUEEZES_SHARE` of the loading samples are at or
    below the operating force (a linear law's D does not depend on the force)."""
    share = obj.loading_share_below_operating
    return obj.chosen.model in ("hc", "exp") and share < BELOW_SQUEEZES_SHARE
