"""The coefficients table's material columns: the chosen law, every law's parameters, and what a
grip needs (operating force, small-strain stiffness, stiffening, rupture and yield, hysteresis).

The paper's units at the edge: stiffness N/cm, damping N·s/cm; HC's ``k`` in N/cmⁿ and ``λ`` in
N·s/cmⁿ⁺¹. A law that was not fitted (``--model kv`` leaves HC and SLS out; ``--method paper``
fits none) has NaN columns.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from deformctl.units import CM, N_PER_CM

if TYPE_CHECKING:  # pragma: no cover - typing only
    from deformctl.characterize.materials import MaterialFit
    from deformctl.characterize.objectfit import ObjectFit

#: Each law's columns: (column, SI parameter, factor from SI, or None for HC's powers of cm).
_LAW_COLUMNS: dict[str, tuple[tuple[str, str], ...]] = {
    "kv": (
        ("kv_deformability_n_per_cm", "stiffness_n_per_m"),
        ("kv_damping_ns_per_cm", "damping_ns_per_m"),
    ),
    "hc": (
        ("hc_stiffness_n_per_cm_pow_n", "stiffness_n_per_m_pow_n"),
        ("hc_exponent", "exponent"),
        ("hc_damping_ns_per_cm_pow_n_plus_1", "damping_ns_per_m_pow_n_plus_1"),
    ),
    "sls": (
        ("sls_stiffness_n_per_cm", "stiffness_n_per_m"),
        ("sls_arm_stiffness_n_per_cm", "arm_stiffness_n_per_m"),
        ("sls_relaxation_time_s", "relaxation_time_s"),
    ),
    "exp": (
        ("exp_stiffness_n_per_cm", "stiffness_n_per_m"),
        ("exp_stiffening_per_cm", "stiffening_per_m"),
        ("exp_damping_ns_per_cm", "damping_ns_per_m"),
    ),
}


def _se_name(column: str) -> str:
    """``kv_damping_ns_per_cm`` → ``kv_damping_se_ns_per_cm``; ``hc_exponent`` →
    ``hc_exponent_se``; ``sls_relaxation_time_s`` → ``sls_relaxation_time_se_s``."""
    units = (
        "_n_per_cm_pow_n",
        "_ns_per_cm_pow_n_plus_1",
        "_n_per_cm",
        "_ns_per_cm",
        "_per_cm",
        "_s",
    )
    for unit in units:
        if column.endswith(unit):
            return column[: -len(unit)] + "_se" + unit
    return column + "_se"


#: Every law's columns, its standard errors, AIC and BIC.
LAW_COLUMNS: tuple[str, ...] = tuple(
    name
    for law, cols in _LAW_COLUMNS.items()
    for name in (
        *(c for pair in cols for c in (pair[0], _se_name(pair[0]))),
        f"{law}_r2",
        f"{law}_aic",
        f"{law}_bic",
    )
)

#: The material columns after the original ones, in order.
MATERIAL_COLUMNS: tuple[str, ...] = (
    "model",
    "operating_force_n",
    "operating_force_source",
    "deformability_at_force_n",
    "deformability_source",
    "deformability_small_strain_n_per_cm",
    "stiffening_ratio",
    "tangent_stiffness_spread",
    "secant_residual_frac",
    "lag_s",
    "params_at_bound",
    "hysteresis_energy_j",
    "yield_compression_cm",
    "relaxation_force_drop_frac",
    "n_speeds",
    "residual_rms_by_speed",
    *LAW_COLUMNS,
)

#: Column → pandas dtype of the material columns that are not float64.
MATERIAL_DTYPES: dict[str, str] = {
    "model": "str",
    "operating_force_source": "str",
    "deformability_source": "str",
    "params_at_bound": "str",
    "residual_rms_by_speed": "str",
    "n_speeds": "int64",
}


def _factor(column: str, exponent: float) -> float:
    """SI → the column's unit."""
    if column.endswith("_n_per_cm_pow_n"):
        return CM**exponent
    if column.endswith("_ns_per_cm_pow_n_plus_1"):
        return CM ** (exponent + 1.0)
    if column.endswith(("_n_per_cm", "_ns_per_cm")):
        return 1.0 / N_PER_CM
    if column.endswith("_per_cm"):  # a rate per metre → per cm
        return CM
    return 1.0


def law_values(fit: MaterialFit | None, law: str, r2: float = math.nan) -> dict[str, object]:
    """One law's columns (NaN when it was not fitted); ``r2`` on the samples."""
    out: dict[str, object] = {}
    exponent = math.nan if fit is None else fit.params.get("exponent", 1.0)
    for column, param in _LAW_COLUMNS[law]:
        factor = _factor(column, exponent)
        value = math.nan if fit is None else fit.params[param] * factor
        se = math.nan if fit is None else fit.se[param] * factor
        out[column] = value
        out[_se_name(column)] = se
    out[f"{law}_r2"] = math.nan if fit is None else r2
    out[f"{law}_aic"] = math.nan if fit is None else fit.aic
    out[f"{law}_bic"] = math.nan if fit is None else fit.bic
    return out


def empty_values(model: str = "") -> dict[str, object]:
    """The material columns of a row without a material fit (``--method paper``)."""
    out: dict[str, object] = dict.fromkeys(MATERIAL_COLUMNS, math.nan)
    out.update(
        model=model,
        operating_force_source="",
        deformability_source="",
        params_at_bound="",
        residual_rms_by_speed="",
        n_speeds=0,
    )
    return out


def material_values(obj: ObjectFit) -> dict[str, object]:
    """The material columns of one object's fit."""
    chosen = obj.chosen
    out = empty_values(chosen.model)
    first = obj.ruptures[0] if obj.ruptures else None
    relax = max((r.drop_frac for r in obj.relaxations), default=math.nan)
    speeds = "; ".join(f"{1e3 * v:.4g} mm/s: {r:.3g} N" for v, r in obj.per_speed)
    out.update(
        operating_force_n=obj.operating_force_n,
        operating_force_source=obj.operating_force_source,
        deformability_at_force_n=obj.operating_force_n,
        deformability_source=obj.deformability_source,
        deformability_small_strain_n_per_cm=obj.loading.small_strain_n_per_m / N_PER_CM,
        stiffening_ratio=obj.loading.stiffening_ratio,
        tangent_stiffness_spread=obj.loading.tangent_spread,
        secant_residual_frac=obj.secant_residual_frac,
        lag_s=chosen.params.get("lag_s", math.nan),
        params_at_bound=",".join(chosen.at_bound),
        hysteresis_energy_j=obj.hysteresis_energy_j,
        yield_compression_cm=math.nan if first is None else first.compression_m / CM,
        relaxation_force_drop_frac=relax,
        n_speeds=len(obj.per_speed),
        residual_rms_by_speed=speeds,
    )
    for law in _LAW_COLUMNS:
        out.update(law_values(obj.fit(law), law, obj.sample_r2.get(law, math.nan)))
    return out
