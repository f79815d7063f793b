"""The index table: each object's attributes joined with its minimum lifting force, and lookups.

The paper (section III.C) stores what iterative lifting learned in an *index table*: given weight,
deformability and damping, read off the lifting force. :func:`build_index_table` joins the
coefficients (``characterize``) and the lift results (``lift``) on ``object_id``;
:func:`lookup` returns the nearest entry, :func:`interpolate` an inverse-distance weighted
estimate from the ``k`` nearest.

Index table columns (:data:`INDEX_COLUMNS`), in the paper's units:

=========================== ======= ===========================================================
``object_id``               --      catalog id
``weight_n``                N       weight W
``deformability_n_per_cm``  N/cm    D
``damping_ns_per_cm``       N·s/cm  λ
``lift_force_n``            N       minimum lifting force L_f (per palm)
``friction_mu``             --      friction coefficient used by the lift
``f_w_n``                   N       F_w = W / (2 μ), the rigid-object force (physics baseline)
``converged``               --      whether the lifting-force search converged
=========================== ======= ===========================================================

Distances are measured in *standardized units*: each key column is divided by its standard
deviation over the table (population std, ``ddof = 0``, as ``StandardScaler`` does), so one unit
is one standard deviation of that attribute; a column with no spread is compared in its own
units. The distance is the Euclidean norm of the standardized differences.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np
import pandas as pd

from deformctl.catalog import rigid_grip_force_n
from deformctl.errors import InputDataError, SchemaError, UsageError
from deformctl.grip.groups import NEGATIVE_DAMPING_TOLERANCE_NS_PER_CM
from deformctl.quantities import (
    DAMPING_NS_PER_CM,
    FRICTION_MU,
    MAX_LIFT_RATIO,
    STIFFNESS_N_PER_CM,
    WEIGHT_N,
)

#: The columns of an index table, in order.
INDEX_COLUMNS: tuple[str, ...] = (
    "object_id",
    "weight_n",
    "deformability_n_per_cm",
    "damping_ns_per_cm",
    "lift_force_n",
    "friction_mu",
    "f_w_n",
    "converged",
)

#: The attributes a lookup matches on (the model's features), in order.
LOOKUP_KEYS: tuple[str, ...] = ("weight_n", "deformability_n_per_cm", "damping_ns_per_cm")

#: Columns the two inputs must have. ``weight_n`` and ``friction_mu`` may come from either side
#: (the lift results are preferred); ``f_w_n`` is computed as W / (2 μ) when the lift results
#: do not carry it.
COEFFICIENT_COLUMNS: tuple[str, ...] = ("object_id", "deformability_n_per_cm", "damping_ns_per_cm")
LIFT_COLUMNS: tuple[str, ...] = ("object_id", "lift_force_n", "converged")

#: An L_f below F_w by more than this (relative) cannot come from a lift search, which never
#: reports a force below F_w (a rounding of the search tolerance is allowed).
F_W_TOLERANCE_REL = 0.005
#: The index table's quality column: ``ok``, or the coefficients' flags (``table
#: --allow-flagged``); a lookup names a flagged entry it returns.
QUALITY_COLUMN = "quality"

#: How many offending ids an error message names before "and N more".
MAX_IDS_IN_MESSAGE = 5


def format_ids(ids: Iterable[object], limit: int = MAX_IDS_IN_MESSAGE) -> str:
    """Name up to ``limit`` ids, then ``and N more``: ``"A, B, C and 4 more"``."""
    items = [str(i) for i in ids]
    shown = ", ".join(items[:limit])
    return f"{shown} and {len(items) - limit} more" if len(items) > limit else shown


def _require_columns(frame: pd.DataFrame, columns: Iterable[str], what: str) -> None:
    for col in columns:
        if col not in frame.columns:
            raise SchemaError(f"{what} have no column {col!r}", field=col)


def _duplicates(frame: pd.DataFrame, what: str) -> None:
    dup = frame["object_id"][frame["object_id"].duplicated()].unique()
    if len(dup):
        raise InputDataError(f"{what} list object(s) more than once: {format_ids(sorted(dup))}")


#: The columns with documented bounds (:mod:`deformctl.quantities`, the catalog's): a row
#: outside them is refused by every stage that reads the table (``table``, ``train``,
#: ``table --lookup``, ``adapt``, ``lift --start-table``), as the catalog refuses it.
DOCUMENTED_BOUNDS = {
    "weight_n": WEIGHT_N,
    "friction_mu": FRICTION_MU,
    "deformability_n_per_cm": STIFFNESS_N_PER_CM,
    "damping_ns_per_cm": DAMPING_NS_PER_CM,
}


def impossible_rows(table: pd.DataFrame, *, coefficients: bool = True) -> list[str]:
    """What is physically impossible in the rows of an index table, one clause per problem.

    Coefficients (``coefficients=True``): D ≤ 0 or not finite, λ < 0 (beyond a fit's noise,
    :data:`~deformctl.grip.groups.NEGATIVE_DAMPING_TOLERANCE_NS_PER_CM`) or not finite. Weights
    and μ ≤ 0 or not finite. Any of them outside its documented bounds
    (:data:`DOCUMENTED_BOUNDS`: W 0.001-5000 N, μ 0.01-3, D 0.01-1e5 N/cm, λ up to 1e4
    N·s/cm). Lifting forces: L_f not finite or ≤ 0, L_f below F_w by more than
    :data:`F_W_TOLERANCE_REL` (a search never reports less than F_w), or above
    :data:`~deformctl.quantities.MAX_LIFT_RATIO` × F_w (a unit or catalog mistake). F_w is
    the ``f_w_n`` column, else W / (2 μ); without either the F_w checks are skipped.

    Returns:
        e.g. ``["deformability_n_per_cm <= 0 for B (-20)", "lift_force_n above 10 x F_w for
        C (1e+308 N, F_w 2.9 N)"]``; empty when every row is possible.
    """
    ids = table["object_id"].astype(str).to_numpy()
    out: list[str] = []

    def col(name: str) -> np.ndarray | None:
        if name not in table.columns:
            return None
        return pd.to_numeric(table[name], errors="coerce").to_numpy(dtype=np.float64)

    def named(bad: np.ndarray, values: np.ndarray, unit: str = "") -> str:
        first = values[bad][0]
        return f"{format_ids(ids[bad])} ({first:.6g}{unit}{', ...' if bad.sum() > 1 else ''})"

    checks: list[tuple[str, str, str]] = [("weight_n", "<= 0", " N"), ("friction_mu", "<= 0", "")]
    if coefficients:
        checks += [("deformability_n_per_cm", "<= 0", " N/cm"), ("damping_ns_per_cm", "< 0", "")]
    checks.append(("lift_force_n", "<= 0", " N"))
    for name, rule, unit in checks:
        values = col(name)
        if values is None:
            continue
        finite = np.isfinite(values)
        if (~finite).any():
            out.append(f"{name} not a finite number for {named(~finite, values, unit)}")
        floor = -NEGATIVE_DAMPING_TOLERANCE_NS_PER_CM if name == "damping_ns_per_cm" else 0.0
        bad = finite & ((values < floor) if rule == "< 0" else (values <= 0))
        if bad.any():
            out.append(f"{name} {rule} for {named(bad, values, unit)}")
        quantity = DOCUMENTED_BOUNDS.get(name)
        if quantity is not None:  # the catalog's documented bounds (quantities), past the sign
            low = floor if name == "damping_ns_per_cm" else quantity.low  # a fit's noise at 0
            outside = finite & ~bad & ((values < low) | (values > quantity.high))
            if outside.any():
                out.append(
                    f"{name} outside its documented bounds [{quantity.low:g}, {quantity.high:g}]"
                    f" for {named(outside, values, unit)}"
                )
    lift, f_w = col("lift_force_n"), col("f_w_n")
    if f_w is None and "weight_n" in table.columns and "friction_mu" in table.columns:
        with np.errstate(divide="ignore", invalid="ignore"):
            f_w = rigid_grip_force_n(col("weight_n"), col("friction_mu"))  # type: ignore[arg-type]
    if lift is not None and f_w is not None:
        ok = np.isfinite(lift) & np.isfinite(f_w) & (lift > 0) & (f_w > 0)
        below = ok & (lift < f_w * (1 - F_W_TOLERANCE_REL))
        above = ok & (lift > MAX_LIFT_RATIO * f_w)
        for bad, what in ((below, "below F_w"), (above, f"above {MAX_LIFT_RATIO:g} x F_w")):
            if bad.any():
                first = int(np.flatnonzero(bad)[0])
                out.append(
                    f"lift_force_n {what} for {format_ids(ids[bad])} "
                    f"({lift[first]:.6g} N, F_w {f_w[first]:.6g} N)"
                )
    return out


def refuse_impossible_rows(
    table: pd.DataFrame,
    what: str,
    *,
    coefficients: bool = True,
    hint: str = "",
    path: str | None = None,
) -> None:
    """Raise when :func:`impossible_rows` finds anything.

    Raises:
        InputDataError: one line, ``"impossible rows in {what}: ...; ..."`` (exit 65; prefixed
            with ``path`` when given).
    """
    problems = impossible_rows(table, coefficients=coefficients)
    if problems:
        raise InputDataError(f"impossible rows in {what}: {'; '.join(problems)}{hint}", path=path)


def _pick(
    name: str, lift: pd.DataFrame, coefficients: pd.DataFrame, joined: pd.DataFrame
) -> pd.Series:
    """Column ``name`` from the lift side if present, else from the coefficients side."""
    lift_col, coef_col = f"{name}__lift", f"{name}__coef"
    if name in lift.columns and name in coefficients.columns:
        a = joined[lift_col].to_numpy(dtype=float)
        b = joined[coef_col].to_numpy(dtype=float)
        both = ~np.isnan(a) & ~np.isnan(b)  # (a coefficients table has NaN where the log had none)
        bad = both & ~np.isclose(a, b, rtol=1e-6, atol=0.0)
        if bad.any():
            ids = joined["object_id"][bad]
            raise InputDataError(
                f"{name} differs between the coefficients and the lift results for "
                f"{format_ids(ids)}"
            )
        return pd.Series(np.where(np.isnan(a), b, a), index=joined.index)
    if name in lift.columns:
        return joined[lift_col]
    if name in coefficients.columns:
        return joined[coef_col]
    raise SchemaError(f"neither the coefficients nor the lift results have {name!r}", field=name)


#: The index table's ``source`` of a lift results ``runner``: a simulated or a rig lift.
SOURCES: dict[str, str] = {"sim": "sim", "rig": "rig"}


def _sources(joined: pd.DataFrame) -> np.ndarray:
    """``sim`` or ``rig`` per row from the lift results' ``runner`` (``""`` when unknown)."""
    if "runner" not in joined.columns:
        return np.full(len(joined), "", dtype=object)
    return joined["runner"].map(lambda r: SOURCES.get(str(r), "")).to_numpy(dtype=object)


def build_index_table(
    coefficients: pd.DataFrame,
    lift_results: pd.DataFrame,
    *,
    allow_unconverged: bool = False,
    allow_flagged: bool = False,
) -> pd.DataFrame:
    """Join coefficients and lift results on ``object_id`` into an index table.

    Args:
        coefficients: one row per object with ``object_id``, ``deformability_n_per_cm`` (N/cm),
            ``damping_ns_per_cm`` (N·s/cm), and optionally ``weight_n`` / ``friction_mu``.
        lift_results: one row per object with ``object_id``, ``lift_force_n`` (N), ``converged``
            and optionally ``weight_n``, ``friction_mu``, ``f_w_n``. ``weight_n`` and
            ``friction_mu`` must be present on at least one side; when on both they must agree.
        allow_unconverged: keep objects whose search did not converge (``converged`` False),
            as long as they have a finite lifting force (an upper bound that did lift).
        allow_flagged: keep objects whose coefficients are physically impossible (D ≤ 0, λ < 0,
            not finite; ``characterize --allow-flagged`` writes them); their ``quality`` says
            so. Impossible lifting forces (:func:`impossible_rows`) are refused even then.

    The table's ``quality`` column is the coefficients' ``quality`` (``ok`` or the flags; ``ok``
    when the coefficients have none), with ``impossible_coefficients`` added to a row kept by
    ``allow_flagged``.

    Returns:
        The index table, columns :data:`INDEX_COLUMNS` and ``source`` (``sim`` or ``rig``, from
        the lift results' ``runner``: rig rows are what ``adapt`` corrects a model with), one
        row per object, sorted by ``object_id``; floats are float64 and ``converged`` is bool.

    Raises:
        SchemaError: a required column is missing.
        InputDataError: an object listed twice on one side or missing on the other side, an
            unconverged object (unless ``allow_unconverged``), an impossible row
            (:func:`impossible_rows`; coefficients only unless ``allow_flagged``), or a weight /
            friction that differs between the sides. The message names the offending ids (up
            to a few, then "and N more").
    """
    _require_columns(coefficients, COEFFICIENT_COLUMNS, "the coefficients")
    _require_columns(lift_results, LIFT_COLUMNS, "the lift results")
    coef = coefficients.copy()
    lift = lift_results.copy()
    coef["object_id"] = coef["object_id"].astype(str)
    lift["object_id"] = lift["object_id"].astype(str)
    _duplicates(coef, "the coefficients")
    _duplicates(lift, "the lift results")

    coef_ids, lift_ids = set(coef["object_id"]), set(lift["object_id"])
    no_lift = sorted(coef_ids - lift_ids)
    no_coef = sorted(lift_ids - coef_ids)
    if no_lift or no_coef:
        parts = []
        if no_lift:
            parts.append(f"{len(no_lift)} object(s) have no lift result: {format_ids(no_lift)}")
        if no_coef:
            parts.append(f"{len(no_coef)} object(s) have no coefficients: {format_ids(no_coef)}")
        raise InputDataError("; ".join(parts))

    joined = coef.merge(lift, on="object_id", how="inner", suffixes=("__coef", "__lift"))
    # Suffixes are only applied to clashing names; give every optional column a suffixed alias.
    for name in ("weight_n", "friction_mu", "f_w_n"):
        if name in joined.columns:
            side = "__lift" if name in lift.columns else "__coef"
            joined[f"{name}{side}"] = joined[name]

    converged = joined["converged"]
    if converged.isna().any():
        ids = joined["object_id"][converged.isna()]
        raise InputDataError(f"converged is missing for {format_ids(ids)}")
    converged = converged.astype(bool)
    if not allow_unconverged and not converged.all():
        ids = sorted(joined["object_id"][~converged])
        raise InputDataError(
            f"{len(ids)} object(s) did not converge: {format_ids(ids)} "
            "(use --allow-unconverged to keep them)"
        )

    weight = _pick("weight_n", lift, coef, joined).astype(float)
    mu = _pick("friction_mu", lift, coef, joined).astype(float)
    if "f_w_n" in lift.columns or "f_w_n" in coef.columns:
        f_w = _pick("f_w_n", lift, coef, joined).astype(float)
    else:
        f_w = rigid_grip_force_n(weight, mu)

    table = pd.DataFrame(
        {
            "object_id": joined["object_id"].astype(str),
            "weight_n": weight.to_numpy(dtype=np.float64),
            "deformability_n_per_cm": joined["deformability_n_per_cm"].to_numpy(dtype=np.float64),
            "damping_ns_per_cm": joined["damping_ns_per_cm"].to_numpy(dtype=np.float64),
            "lift_force_n": joined["lift_force_n"].to_numpy(dtype=np.float64),
            "friction_mu": mu.to_numpy(dtype=np.float64),
            "f_w_n": f_w.to_numpy(dtype=np.float64),
            "converged": converged.to_numpy(dtype=bool),
        },
        columns=list(INDEX_COLUMNS),
    )
    table["source"] = _sources(joined)
    quality = (
        joined["quality"].astype("string").fillna("ok").to_numpy(dtype=object)
        if "quality" in joined.columns
        else np.full(len(table), "ok", dtype=object)
    )
    table = table.sort_values("object_id", kind="stable")  # the problems name ids in order
    quality = quality[table.index.to_numpy()]
    table = table.reset_index(drop=True)
    refuse_impossible_rows(table, "the lift results", coefficients=False)
    coefficient_rows = table.drop(columns=["lift_force_n"])
    problems = impossible_rows(coefficient_rows)
    if problems and not allow_flagged:
        raise InputDataError(
            f"impossible rows in the coefficients: {'; '.join(problems)} "
            "(use --allow-flagged to keep them, flagged)"
        )
    if problems:
        bad = np.zeros(len(table), dtype=bool)
        d = table["deformability_n_per_cm"].to_numpy(dtype=np.float64)
        lam = table["damping_ns_per_cm"].to_numpy(dtype=np.float64)
        with np.errstate(invalid="ignore"):
            bad |= ~np.isfinite(d) | (d <= 0) | ~np.isfinite(lam)
            bad |= lam < -NEGATIVE_DAMPING_TOLERANCE_NS_PER_CM
        for i in np.flatnonzero(bad):
            flags = [f for f in str(quality[i]).split(",") if f and f != "ok"]
            quality[i] = ",".join([*flags, "impossible_coefficients"])
    table[QUALITY_COLUMN] = pd.array(quality, dtype="string")
    return table


#: The fewest entries a lookup or an interpolation accepts: a standardized distance divides by
#: the spread over the table, and one entry has none (every answer would be that entry).
MIN_LOOKUP_ROWS = 2


def validate_index_table(table: pd.DataFrame, *, min_rows: int = 1) -> None:
    """Check that ``table`` has the lookup columns and at least ``min_rows`` rows of finite values.

    Raises:
        SchemaError: a column of :data:`LOOKUP_KEYS` or ``lift_force_n`` is missing.
        InputDataError: the table has fewer than ``min_rows`` rows (or none), or a lookup key is
            not finite somewhere.
    """
    _require_columns(table, ("object_id", *LOOKUP_KEYS, "lift_force_n"), "the index table")
    if len(table) == 0:
        raise InputDataError("the index table has no rows")
    if len(table) < min_rows:
        raise InputDataError(
            f"the index table has {len(table)} row(s); a lookup needs at least {min_rows} "
            "(distances are standardized by the spread over the table)"
        )
    for col in LOOKUP_KEYS:
        bad = ~np.isfinite(table[col].to_numpy(dtype=float))
        if bad.any():
            raise InputDataError(
                f"{col} is not a finite number for {format_ids(table['object_id'][bad])}"
            )
    flagged = _flagged(table)
    refuse_impossible_rows(table[~flagged], "the index table")
    refuse_impossible_rows(table[flagged], "the index table", coefficients=False)


def _flagged(table: pd.DataFrame) -> np.ndarray:
    """Rows kept with impossible coefficients by ``table --allow-flagged`` (their quality)."""
    if QUALITY_COLUMN not in table.columns:
        return np.zeros(len(table), dtype=bool)
    quality = table[QUALITY_COLUMN].astype("string").fillna("")
    return quality.str.contains("impossible_coefficients", regex=False).to_numpy(dtype=bool)


def keys_without_spread(table: pd.DataFrame) -> list[str]:
    """The :data:`LOOKUP_KEYS` that are constant over ``table``: compared in their own units."""
    values = table[list(LOOKUP_KEYS)].to_numpy(dtype=np.float64)
    std = values.std(axis=0, ddof=0)
    return [k for k, s in zip(LOOKUP_KEYS, std, strict=True) if not (np.isfinite(s) and s > 0)]


def standard_scales(table: pd.DataFrame, keys: Iterable[str] = LOOKUP_KEYS) -> np.ndarray:
    """Per-key scale of the standardized distance: the population std, or 1 if it is 0.

    Returns:
        ``[len(keys)]`` float64 scales, in the units of each key.
    """
    values = table[list(keys)].to_numpy(dtype=np.float64)
    std = values.std(axis=0, ddof=0)
    return np.where(np.isfinite(std) & (std > 0), std, 1.0)


def standardized_distances(
    reference: pd.DataFrame, queries: np.ndarray, scales: np.ndarray | None = None
) -> np.ndarray:
    """Distances between query points and every reference row, in standardized units.

    Args:
        reference: rows with the :data:`LOOKUP_KEYS` columns, ``[m]`` rows.
        queries: ``[n, 3]`` points in the order of :data:`LOOKUP_KEYS`, paper units.
        scales: ``[3]`` per-key scales; default :func:`standard_scales` of ``reference``.

    Returns:
        ``[n, m]`` Euclidean distances of the standardized differences.
    """
    ref = reference[list(LOOKUP_KEYS)].to_numpy(dtype=np.float64)
    sc = standard_scales(reference) if scales is None else np.asarray(scales, dtype=np.float64)
    q = np.atleast_2d(np.asarray(queries, dtype=np.float64))
    diff = (q[:, None, :] - ref[None, :, :]) / sc
    return np.sqrt(np.sum(diff * diff, axis=-1))


def _query(
    weight_n: float | None,
    deformability_n_per_cm: float | None,
    damping_ns_per_cm: float | None,
) -> np.ndarray:
    values = {
        "weight_n": weight_n,
        "deformability_n_per_cm": deformability_n_per_cm,
        "damping_ns_per_cm": damping_ns_per_cm,
    }
    missing = [k for k, v in values.items() if v is None]
    if missing:
        raise UsageError(
            f"lookup is missing {', '.join(missing)}; expected keys: {', '.join(LOOKUP_KEYS)}"
        )
    out = np.array([float(v) for v in values.values()])  # type: ignore[arg-type]
    if not np.isfinite(out).all():
        bad = [k for k, v in zip(values, out, strict=True) if not math.isfinite(v)]
        raise UsageError(f"lookup value of {', '.join(bad)} is not a finite number")
    return out


@dataclass(frozen=True)
class LookupResult:
    """The nearest index-table entry to a query.

    Attributes:
        row: the entry, column name -> value (all :data:`INDEX_COLUMNS` the table has).
        distance: distance to the query in standardized units (see the module docstring).
    """

    row: dict[str, object]
    distance: float


def lookup(
    index_table: pd.DataFrame,
    *,
    weight_n: float | None = None,
    deformability_n_per_cm: float | None = None,
    damping_ns_per_cm: float | None = None,
) -> LookupResult:
    """The nearest entry of ``index_table`` to (W, D, λ), and its standardized distance.

    Ties go to the first row in table order.

    Args:
        index_table: an index table (at least the :data:`LOOKUP_KEYS` and ``lift_force_n``).
        weight_n: W, N. deformability_n_per_cm: D, N/cm. damping_ns_per_cm: λ, N·s/cm.
            All three are required.

    Raises:
        UsageError: a key is missing (the message names it and the expected keys) or not finite.
        SchemaError / InputDataError: see :func:`validate_index_table`; a table of fewer than
            :data:`MIN_LOOKUP_ROWS` entries is refused.

    Example:
        >>> t = pd.DataFrame({"object_id": ["A", "B"], "weight_n": [20.0, 40.0],
        ...     "deformability_n_per_cm": [30.0, 50.0], "damping_ns_per_cm": [0.0, 10.0],
        ...     "lift_force_n": [30.0, 60.0]})
        >>> r = lookup(t, weight_n=39.0, deformability_n_per_cm=49.0, damping_ns_per_cm=9.0)
        >>> r.row["object_id"], round(r.distance, 3)
        ('B', 0.245)
    """
    q = _query(weight_n, deformability_n_per_cm, damping_ns_per_cm)
    validate_index_table(index_table, min_rows=MIN_LOOKUP_ROWS)
    dist = standardized_distances(index_table, q)[0]
    i = int(np.argmin(dist))
    row = {k: _plain(v) for k, v in index_table.iloc[i].to_dict().items()}
    return LookupResult(row=row, distance=float(dist[i]))


@dataclass(frozen=True)
class InterpolationResult:
    """An inverse-distance weighted estimate of the lifting force.

    Attributes:
        lift_force_n: the weighted mean of the neighbours' ``lift_force_n``, N.
        object_ids: the ``k`` neighbours, nearest first.
        distances: their standardized distances, ``[k]``.
        weights: their normalised weights, ``[k]``, summing to 1.
    """

    lift_force_n: float
    object_ids: tuple[str, ...]
    distances: tuple[float, ...]
    weights: tuple[float, ...]


def interpolate(
    index_table: pd.DataFrame,
    *,
    weight_n: float | None = None,
    deformability_n_per_cm: float | None = None,
    damping_ns_per_cm: float | None = None,
    k: int = 4,
    power: float = 2.0,
) -> InterpolationResult:
    """Inverse-distance weighting (Shepard) of the ``k`` nearest entries' lifting forces.

    Each neighbour ``i`` gets weight ``1 / d_i**power`` (standardized distances), normalised to
    sum 1. A query that coincides with an entry (``d = 0``) returns that entry's force exactly
    (shared equally among coinciding entries). ``k`` is capped at the table's size.

    Raises:
        UsageError: a key is missing or not finite, ``k < 1`` or ``power <= 0``.
        SchemaError / InputDataError: as :func:`lookup`.
    """
    if k < 1:
        raise UsageError(f"k must be >= 1, got {k}")
    if not power > 0:
        raise UsageError(f"power must be > 0, got {power}")
    q = _query(weight_n, deformability_n_per_cm, damping_ns_per_cm)
    validate_index_table(index_table, min_rows=MIN_LOOKUP_ROWS)
    dist = standardized_distances(index_table, q)[0]
    order = np.argsort(dist, kind="stable")[: min(k, len(dist))]
    d = dist[order]
    w = (d == 0).astype(float) if (d == 0).any() else 1.0 / d**power
    w = w / w.sum()
    forces = index_table["lift_force_n"].to_numpy(dtype=np.float64)[order]
    return InterpolationResult(
        lift_force_n=float(np.dot(w, forces)),
        object_ids=tuple(str(x) for x in index_table["object_id"].to_numpy()[order]),
        distances=tuple(float(x) for x in d),
        weights=tuple(float(x) for x in w),
    )


def parse_lookup(text: str) -> dict[str, float]:
    """Parse ``"weight_n=40,deformability_n_per_cm=41.5,damping_ns_per_cm=0.2"``.

    Returns:
        key -> value for exactly the :data:`LOOKUP_KEYS`.

    Raises:
        UsageError: a malformed item, an unknown, repeated or missing key (the message names it
            and the expected keys), or a value that is not a finite number.
    """
    expected = ", ".join(LOOKUP_KEYS)
    out: dict[str, float] = {}
    for item in (s.strip() for s in text.split(",")):
        if not item:
            continue
        key, sep, value = item.partition("=")
        key = key.strip()
        if not sep:
            raise UsageError(f"lookup item {item!r} is not key=value; expected keys: {expected}")
        if key not in LOOKUP_KEYS:
            raise UsageError(f"unknown lookup key {key!r}; expected keys: {expected}")
        if key in out:
            raise UsageError(f"lookup key {key!r} given twice")
        try:
            out[key] = float(value)
        except ValueError:
            raise UsageError(f"lookup value of {key} is not a number: {value.strip()!r}") from None
        if not math.isfinite(out[key]):
            raise UsageError(f"lookup value of {key} is not a finite number")
    missing = [k for k in LOOKUP_KEYS if k not in out]
    if missing:
        raise UsageError(f"lookup is missing {', '.join(missing)}; expected keys: {expected}")
    return out


def lookup_mapping(index_table: pd.DataFrame, query: Mapping[str, float]) -> LookupResult:
    """:func:`lookup` with the keys in a mapping (e.g. from :func:`parse_lookup`)."""
    unknown = [k for k in query if k not in LOOKUP_KEYS]
    if unknown:
        raise UsageError(
            f"unknown lookup key {unknown[0]!r}; expected keys: {', '.join(LOOKUP_KEYS)}"
        )
    return lookup(
        index_table,
        weight_n=query.get("weight_n"),
        deformability_n_per_cm=query.get("deformability_n_per_cm"),
        damping_ns_per_cm=query.get("damping_ns_per_cm"),
    )


def _plain(value: object) -> object:
    """numpy scalars -> Python scalars, so a row dict is JSON friendly."""
    return value.item() if isinstance(value, np.generic) else value


def flagged_rows(index_table: pd.DataFrame) -> int:
    """Rows of an index table that a model learns from or is scored on although flagged: a
    :data:`QUALITY_COLUMN` other than ``ok`` (kept by ``table --allow-flagged``) or an
    unconverged search (kept by ``table --allow-unconverged``)."""
    flagged = pd.Series(False, index=index_table.index)
    if "converged" in index_table:
        flagged |= index_table["converged"].eq(False)
    if QUALITY_COLUMN in index_table:
        flagged |= index_table[QUALITY_COLUMN].fillna("ok").ne("ok")
    return int(flagged.sum())
