"""The grip model per material law: what a coefficients row's law adds to (W, D, λ, μ).

A coefficients row states its material law in its ``model`` column (:data:`KNOWN_LAWS`) and that
law's parameters in its own columns. The grip model takes them in a dimensionless form
(measured in docs/explanation/model.md, ``python -m deformctl.repro.grip_study_laws``):

* ``kv`` (Kelvin–Voigt): nothing more; the bundled network of ``[log10 ω_n, log10(ζ + ζ_0)]``
  (:mod:`deformctl.grip.groups`) exactly as before;
* ``hc`` (Hunt–Crossley): the exponent ``n`` (column ``hc_exponent``) and the object's shape,
  a network of ``[log10 ω_n, log10(ζ + ζ_0), n, log10 μ, log10 ε_W, log10(L_y / L_x),
  log10(L_z / L_x)]`` (D and λ are the row's, stated at F_w; μ, which only scales F_w for
  Kelvin–Voigt, moves a stiffening object's ratio by 2.7 %). ``ε_W = W / (D L_x)`` is the strain
  a force equal to the weight causes along the squeeze axis x (``size_x_cm``), and ``L_y / L_x``,
  ``L_z / L_x`` (z up) the aspect ratios: a stiffening lattice is soft where it is not
  compressed, so how far the jaws pre-strain it sets how it holds its own weight (the
  shape inputs halve the held-out error, docs/explanation/model.md). A network trained
  before the shape inputs (the first four only) is still read;
* ``sls`` (standard linear solid): the arm's stiffness over the relaxed one ``k2 / D`` and the
  relaxation time in units of the object's own time scale ``τ ω_n``, a network of
  ``[log10 ω_n, log10(k2 / D), log10(τ ω_n)]`` (its damping λ = k2 τ is then fixed by them).

Each law has its own network, training ranges and calibration scores (group-conditional split
conformal: a bound for an ``hc`` row is calibrated on ``hc`` rows only, so it holds within the
group, :mod:`deformctl.grip.conformal`). A model file states them in its metadata under
``laws`` (:data:`LAW_MIX_KEY`); a file without it (written before) knows Kelvin–Voigt only.

Numpy only (the predictor's side); training is :mod:`deformctl.grip.lawtrain`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from deformctl.catalog import SIZE_COLUMNS
from deformctl.errors import InputDataError
from deformctl.grip.groups import group_values

__all__ = [
    "KNOWN_LAWS",
    "LAW_COLUMN",
    "LAW_FEATURES",
    "LAW_MIX_KEY",
    "LAW_PARAMETERS",
    "LAW_PARAMETER_COLUMNS",
    "OPTIONAL_PARAMETER_COLUMNS",
    "SHAPE_PARAMETERS",
    "law_features",
    "law_groups",
    "law_parameter_values",
    "network_parameters",
    "read_laws",
    "recognised_laws",
    "unknown_law_line",
]

#: The coefficients table's column that states the row's law.
LAW_COLUMN = "model"
#: The laws the grip model knows, in order (kv first: the model file's main network).
KNOWN_LAWS: tuple[str, ...] = ("kv", "hc", "sls")
#: Where a model file's metadata states its law mix, ranges, networks and scores.
LAW_MIX_KEY = "laws"
#: Each law's physically meaningful parameters the model sees (beyond W, D, λ, μ), in order
#: (for ``hc`` also the object's shape: ``weight_strain`` = W / (D L_x), ``aspect_y_x`` and
#: ``aspect_z_x``).
LAW_PARAMETERS: dict[str, tuple[str, ...]] = {
    "kv": (),
    "hc": ("stiffness_exponent", "weight_strain", "aspect_y_x", "aspect_z_x"),
    "sls": ("arm_stiffness_ratio", "relaxation_time_omega_n"),
}
#: The coefficients columns each law's parameters are computed from.
LAW_PARAMETER_COLUMNS: dict[str, tuple[str, ...]] = {
    "kv": (),
    "hc": ("hc_exponent", *SIZE_COLUMNS),
    "sls": ("sls_stiffness_n_per_cm", "sls_arm_stiffness_n_per_cm", "sls_relaxation_time_s"),
}

#: Parameter columns a row may lack: its parameters are then unknown (NaN) and predicted at the
#: most cautious value of the training range, flagged; a missing law column is refused.
OPTIONAL_PARAMETER_COLUMNS: frozenset[str] = frozenset(SIZE_COLUMNS)
#: The parameters of :data:`LAW_PARAMETERS` that describe the object's shape, not its material
#: (unknown when the row has no size: flagged ``shape_assumed``).
SHAPE_PARAMETERS: frozenset[str] = frozenset({"weight_strain", "aspect_y_x", "aspect_z_x"})
#: Each law network's inputs, in order (:func:`law_groups`' columns).
LAW_FEATURES: dict[str, tuple[str, ...]] = {
    "hc": (
        "log10_natural_frequency_rad_s",
        "log10_damping_ratio_shifted",
        "stiffness_exponent",
        "log10_friction_mu",
        "log10_weight_strain",
        "log10_aspect_y_x",
        "log10_aspect_z_x",
    ),
    "sls": (
        "log10_natural_frequency_rad_s",
        "log10_arm_stiffness_ratio",
        "log10_relaxation_time_omega_n",
    ),
}
#: Input lists of law networks written before, still read (a network states its own list).
EARLIER_LAW_FEATURES: dict[str, tuple[tuple[str, ...], ...]] = {
    "hc": (LAW_FEATURES["hc"][:4],),
}
#: The law parameter each network input is computed from (inputs of W, D, λ, μ alone: none).
FEATURE_PARAMETER: dict[str, str] = {
    "stiffness_exponent": "stiffness_exponent",
    "log10_weight_strain": "weight_strain",
    "log10_aspect_y_x": "aspect_y_x",
    "log10_aspect_z_x": "aspect_z_x",
    "log10_arm_stiffness_ratio": "arm_stiffness_ratio",
    "log10_relaxation_time_omega_n": "relaxation_time_omega_n",
}


#: The laws ``characterize`` fits that the grip model has no network for (the grip package sits
#: below ``characterize``, so the list is stated here; tests/grip/test_laws.py checks it against
#: :data:`deformctl.characterize.laws.PARAMETERS`).
OTHER_CHARACTERIZE_LAWS: tuple[str, ...] = ("exp",)


def recognised_laws() -> tuple[str, ...]:
    """Every law a coefficients row may state: the grip model's (:data:`KNOWN_LAWS`) and any
    other law ``characterize`` fits (a row of such a law is "another law's row": predicted by
    the Kelvin–Voigt network, bound not guaranteed)."""
    return (*KNOWN_LAWS, *OTHER_CHARACTERIZE_LAWS)


def unknown_law_line(value: object, ids: str) -> str:
    """The one line for a ``model`` value the grip model does not know."""
    return (
        f"column {LAW_COLUMN!r} is {value!r} for {ids}; the known laws are "
        f"{', '.join(recognised_laws())} (a blank cell: characterize could not tell)"
    )


def read_laws(values: Sequence[Any], names: Sequence[str]) -> np.ndarray:
    """``[n]`` law per row (``""`` where blank: the law is unknown) from a ``model`` column.

    Raises:
        InputDataError: a value that is not a known law nor blank (one line naming the column
            and the known laws; exit 65).
    """
    out = []
    bad: list[str] = []
    first: object = None
    known = recognised_laws()
    for value, name in zip(values, names, strict=True):
        blank = value is None or (isinstance(value, float) and math.isnan(value))
        text = "" if blank else str(value).strip().lower()
        if text and text not in known:
            bad.append(str(name))
            first = value if first is None else first
        out.append(text)
    if bad:
        shown = ", ".join(bad[:5]) + (f" and {len(bad) - 5} more" if len(bad) > 5 else "")
        raise InputDataError(unknown_law_line(first, shown))
    return np.asarray(out, dtype=object)


def law_parameter_values(
    law: str, columns: Mapping[str, Any], weight_n: Any, deformability_n_per_cm: Any
) -> dict[str, np.ndarray]:
    """The law's parameters (:data:`LAW_PARAMETERS`) from its coefficients columns, ``[n]``
    arrays (NaN where a column is NaN, e.g. SLS's arm when damping is not identifiable)."""
    if law == "kv":
        return {}
    if law == "hc":
        n = np.asarray(columns["hc_exponent"], dtype=np.float64)
        nan = np.full(n.shape, np.nan)
        lx, ly, lz = (np.asarray(columns.get(c, nan), dtype=np.float64) for c in SIZE_COLUMNS)
        D = np.asarray(deformability_n_per_cm, dtype=np.float64)
        with np.errstate(divide="ignore", invalid="ignore"):
            return {
                "stiffness_exponent": n,
                "weight_strain": np.asarray(weight_n, dtype=np.float64) / (D * lx),
                "aspect_y_x": ly / lx,
                "aspect_z_x": lz / lx,
            }
    k1 = np.asarray(columns["sls_stiffness_n_per_cm"], dtype=np.float64)
    k2 = np.asarray(columns["sls_arm_stiffness_n_per_cm"], dtype=np.float64)
    tau = np.asarray(columns["sls_relaxation_time_s"], dtype=np.float64)
    omega, _ = group_values(weight_n, deformability_n_per_cm, np.zeros_like(k1))
    with np.errstate(divide="ignore", invalid="ignore"):
        return {"arm_stiffness_ratio": k2 / k1, "relaxation_time_omega_n": tau * omega}


def sls_damping_ns_per_cm(D: Any, omega: Any, ratio: Any, tau_omega: Any) -> np.ndarray:
    """λ = k2 τ of a standard linear solid from ``k2 / D`` and ``τ ω_n`` (N·s/cm)."""
    return np.asarray(ratio * np.asarray(D) * np.asarray(tau_omega) / np.asarray(omega))


def law_groups(
    law: str,
    W: np.ndarray,
    D: np.ndarray,
    lam: np.ndarray,
    mu: np.ndarray,
    params: Mapping[str, np.ndarray],
    zeta_shift: float,
    features: Sequence[str] | None = None,
) -> np.ndarray:
    """``[n, k]`` network inputs of a non-KV law (module doc): the columns ``features`` names
    (default: the law's, :data:`LAW_FEATURES`; a network written before states its own)."""
    if law not in LAW_FEATURES:
        raise ValueError(f"no law network for {law!r}")
    omega, zeta = group_values(W, D, lam)
    names = LAW_FEATURES[law] if features is None else tuple(features)
    columns = {
        "log10_natural_frequency_rad_s": lambda: np.log10(omega),
        "log10_damping_ratio_shifted": lambda: np.log10(zeta + zeta_shift),
        "log10_friction_mu": lambda: np.log10(np.broadcast_to(mu, omega.shape)),
    }
    out = []
    for name in names:
        if name in columns:
            out.append(columns[name]())
        elif name.startswith("log10_"):
            out.append(np.log10(params[FEATURE_PARAMETER[name]]))
        else:
            out.append(np.asarray(params[FEATURE_PARAMETER[name]], dtype=np.float64))
    return np.column_stack(out)


def law_features(law: str) -> tuple[str, ...]:
    """The names of the law network's inputs (:func:`law_groups`' columns)."""
    return LAW_FEATURES[law]


def network_parameters(features: Sequence[str]) -> tuple[str, ...]:
    """The law parameters a network with inputs ``features`` uses, in order."""
    return tuple(FEATURE_PARAMETER[f] for f in features if f in FEATURE_PARAMETER)


#: A law network's entries a summary leaves out (arrays, ids).
_BULK = ("weights", "biases", "scaler_mean", "scaler_scale", "conformal_scores", "check_points",
         "split")  # fmt: skip


def law_summary(metadata: Mapping[str, Any]) -> dict[str, Any] | None:
    """The ``laws`` section of a model file's metadata without its arrays (``inspect``), or
    None for a file without a law mix (it knows Kelvin–Voigt objects only)."""
    section = metadata.get(LAW_MIX_KEY)
    if not isinstance(section, Mapping):
        return None
    out = {k: v for k, v in section.items() if k != "models"}
    models = section.get("models")
    out["models"] = {
        str(law): {k: v for k, v in m.items() if k not in _BULK}
        for law, m in (models.items() if isinstance(models, Mapping) else ())
        if isinstance(m, Mapping)
    }
    return out


def law_summary_lines(summary: Mapping[str, Any] | None) -> list[str]:
    """``inspect``'s lines of :func:`law_summary`: the mix, each law's ranges and figures."""
    if summary is None:
        return ["material laws: no law mix stated (Kelvin–Voigt objects only)"]
    try:
        return _summary_lines(summary)
    except (AttributeError, KeyError, TypeError, ValueError, IndexError):
        return ["material laws: the model's law section is malformed"]


def _summary_lines(summary: Mapping[str, Any]) -> list[str]:
    mix = summary.get("mix") or {}
    lines = [
        "material law mix: "
        + ", ".join(
            f"{law} {m['rows']} rows ({100 * m['fraction']:.0f} %)" for law, m in mix.items()
        )
    ]
    if summary.get("population"):
        lines.append(f"  population law spec: {summary['population']}")
    models = summary.get("models") or {}
    for law, ranges in (summary.get("ranges") or {}).items():
        lines.append(f"  {law} training range:")
        lines += [f"    {k:<26} {v[0]:.6g} .. {v[1]:.6g}" for k, v in ranges.items()]
        m = models.get(law)
        if m:
            lines.append(f"    {law} network: {network_line(m)}")
    return lines


def network_line(m: Mapping[str, Any]) -> str:
    """A law network's rows and test figures in one line (``inspect``, ``train --laws``); a
    network with no test rows (every row trained or calibrated) says where its test is."""
    rows = f"{m.get('n_train')} train / {m.get('n_calibration')} calibration / "
    if not m.get("n_test"):
        fresh = "python -m deformctl.repro.grip_model report"
        return f"{rows}0 test rows (tested on fresh objects: {fresh})"
    conf = (m.get("conformal") or {}).get("0.9") or {}
    return (
        f"{rows}{m.get('n_test')} test rows; test median rel. error "
        f"{_pct(m.get('test_median_rel_error'))}, max {_pct(m.get('test_max_rel_error'))}; "
        f"P = 0.9 coverage {_pct(conf.get('coverage'))}, mean margin "
        f"{_pct(conf.get('mean_margin'))}"
    )


def _pct(value: Any) -> str:
    return "n/a" if value is None else f"{100.0 * float(value):.2f} %"
