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
from dataclasses import dataclass

import pandas as pd

from deformctl.catalog import SIZE_COLUMNS
from deformctl.characterize.quality import assess, quality_text
from deformctl.series import Rupture
from deformctl.units import N_PER_CM, NS_PER_CM

#: The object's own values ``characterize`` copies from the squeeze log into its row (NaN, or
#: ``""`` for ``source``, when the log does not have them), so that ``predict`` and
#: ``lift --sim`` need no catalog: the weight, the size and μ the log's object row stores
#: (``measure --weight-n``, ``--size-cm``, ``--friction-mu`` or the catalog of ``measure --sim``)
#: and where the squeezes came from (the log's ``source``: ``sim``, ``ros2_bag``, ``csv``).
OBJECT_COLUMNS: tuple[str, ...] = ("weight_n", *SIZE_COLUMNS, "friction_mu", "source")

COEFFICIENT_COLUMNS = (
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
    *OBJECT_COLUMNS,
)


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
        damping_bound_active: ``constrain_damping`` held λ at 0.
        damping_unidentifiable: λ was not identifiable (and is NaN).
        compression_min_cm, compression_max_cm: range of d over the samples used, cm.
        force_min_n, force_max_n: range of f over the samples used, N.
        window_samples: the SG window, samples.
        ruptures: the ruptures found in the squeezes (each fitted up to its rupture).
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
            damping_bound_active=self.damping_bound_active,
            ruptures=len(self.ruptures),
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
        }


def _positive(value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return math.nan
    number = float(value)
    return number if math.isfinite(number) and number > 0 else math.nan


def object_fields(obj: Mapping[str, object] | None) -> dict[str, object]:
    """The :data:`OBJECT_COLUMNS` of an object row of a squeeze log.

    A value that is missing, not a number or not > 0 is NaN. ``source`` is the log's own
    (``ros2_bag``, ``csv``, ...); a ``measure --sim`` object row, which stores the simulated
    peak force rather than a source, is ``sim``; ``""`` when the log does not say.
    """
    obj = obj or {}
    out: dict[str, object] = {c: _positive(obj.get(c)) for c in OBJECT_COLUMNS[:-1]}
    source = obj.get("source")
    if not isinstance(source, str) or not source:
        source = "sim" if "sim_peak_force_n" in obj else ""
    out["source"] = source
    return out


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
        }
    )
