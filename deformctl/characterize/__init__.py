"""Deformability D and damping λ from squeeze logs (the paper's Kelvin model, section III.B).

A squeeze is modelled as one Kelvin–Voigt element between the palms, ``f = D · d + λ · d'``
(:mod:`~deformctl.characterize.fit` says how it is fitted). The package:

* :mod:`~deformctl.characterize.fit`: the estimators, :func:`fit_lsq` (the default, one joint
  least-squares fit with robust standard errors) and :func:`fit_paper` (the paper's ratios), and
  :func:`characterize` (a table of many objects);
* :mod:`~deformctl.characterize.coefficients`: one object's result, :class:`CoefficientFit`, and
  the table's columns;
* :mod:`~deformctl.characterize.quality`: the quality flags and the policy applied before a table
  is written;
* :mod:`~deformctl.characterize.rupture`: where a squeeze stops being a Kelvin–Voigt squeeze
  (rupture, the loading and unloading phases), used by ``measure`` too;
* :mod:`~deformctl.characterize.models`: the exact Kelvin–Voigt response and synthetic squeezes
  with known D and λ (ground truth for tests and examples);
* :mod:`~deformctl.characterize.options`: the options the command builds and the stage takes
  (:class:`FitOptions`, :class:`QualityPolicy`), checked when built;
* :mod:`~deformctl.characterize.stage`: the ``characterize`` stage over squeeze logs, dataset
  directories and sweeps.

The public names of the estimators, models and stage are re-exported here.
"""

from __future__ import annotations

from deformctl.characterize.coefficients import (
    COEFFICIENT_COLUMNS,
    CoefficientFit,
)
from deformctl.characterize.fit import (
    COLLINEAR_COND,
    DEFAULT_MIN_COMPRESSION_FRAC,
    DEFAULT_MIN_RATE_FRAC,
    DEFAULT_POLYORDER,
    DEFAULT_WINDOW_RATE_HZ,
    DEFAULT_WINDOW_S,
    MIN_SAMPLES,
    NO_COMPRESSION_M,
    NO_COMPRESSION_NOISE_MULT,
    UNIFORM_DT_RTOL,
    characterize,
    damping_excitation,
    default_window_s,
    fit_lsq,
    fit_paper,
    validate_squeeze,
)
from deformctl.characterize.models import (
    Profile,
    kelvin_voigt_piecewise_linear,
    kelvin_voigt_response,
    synthetic_kelvin_voigt_squeeze,
)
from deformctl.characterize.options import (
    DEFAULT_FIT,
    DEFAULT_POLICY,
    METHODS,
    PRELOADS,
    FitOptions,
    Method,
    Preload,
    QualityPolicy,
    check_method,
    check_paper_options,
    check_preload,
)
from deformctl.characterize.stage import (
    RIG_SOURCES,
    CharacterizeTask,
    LogCoefficients,
    characterize_dir,
    characterize_file,
    characterize_items,
    characterize_sweep,
    default_preload,
    read_and_characterize,
    squeeze_log_parts,
    sweep_warnings,
)

__all__ = [
    "COEFFICIENT_COLUMNS",
    "COLLINEAR_COND",
    "DEFAULT_FIT",
    "DEFAULT_MIN_COMPRESSION_FRAC",
    "DEFAULT_MIN_RATE_FRAC",
    "DEFAULT_POLICY",
    "DEFAULT_POLYORDER",
    "DEFAULT_WINDOW_RATE_HZ",
    "DEFAULT_WINDOW_S",
    "METHODS",
    "MIN_SAMPLES",
    "NO_COMPRESSION_M",
    "NO_COMPRESSION_NOISE_MULT",
    "PRELOADS",
    "RIG_SOURCES",
    "UNIFORM_DT_RTOL",
    "CharacterizeTask",
    "CoefficientFit",
    "FitOptions",
    "LogCoefficients",
    "Method",
    "Preload",
    "Profile",
    "QualityPolicy",
    "characterize",
    "characterize_dir",
    "characterize_file",
    "characterize_items",
    "characterize_sweep",
    "check_method",
    "check_paper_options",
    "check_preload",
    "damping_excitation",
    "default_preload",
    "default_window_s",
    "fit_lsq",
    "fit_paper",
    "kelvin_voigt_piecewise_linear",
    "kelvin_voigt_response",
    "read_and_characterize",
    "squeeze_log_parts",
    "sweep_warnings",
    "synthetic_kelvin_voigt_squeeze",
    "validate_squeeze",
]
