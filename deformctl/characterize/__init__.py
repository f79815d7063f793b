"""Deformability D and damping λ from squeeze logs: the paper's Kelvin model and the material laws
real objects follow.

A squeeze is fitted with a material law (:mod:`~deformctl.characterize.laws`: Kelvin–Voigt
``f = F0 + D d + λ ḋ``, Hunt–Crossley ``f = F0 + k dⁿ + λ dⁿ ḋ`` or a standard linear solid),
chosen by BIC with ``auto``; D is the secant stiffness at a stated operating force. The package:

* :mod:`~deformctl.characterize.laws`, :mod:`~deformctl.characterize.materials`: the laws and
  their bounded window fit with a lag; :mod:`~deformctl.characterize.objectfit`: one object's fit
  end to end; :mod:`~deformctl.characterize.stiffness`: operating force, loading slopes, speeds,
  hysteresis; :mod:`~deformctl.characterize.columns`: the table's material columns;
  :mod:`~deformctl.characterize.material_options`: ``--model`` and ``--at-force-n``;
  :mod:`~deformctl.characterize.plot`: one PNG per object (recordings of each law with known
  truth are test generators: :mod:`deformctl.testing.synthetic`);
* :mod:`~deformctl.characterize.fit`: the estimators, :func:`fit_lsq` (one object's bounded
  least-squares fit of a law) and :func:`fit_paper` (the paper's ratios), and
  :func:`characterize` (a table of many objects);
* :mod:`~deformctl.characterize.coefficients`: one object's result, :class:`CoefficientFit`, and
  the table's columns;
* :mod:`~deformctl.characterize.quality`: the quality flags and the policy applied before a table
  is written;
* :mod:`deformctl.squeeze`, below both stages (not in this package): the phases, the rupture
  cut, the smoothing window (:func:`default_window_s`, re-exported here) and the recording flags
  that ``measure`` and ``characterize`` share;
* :mod:`~deformctl.characterize.models`: the exact Kelvin–Voigt compression under a
  piecewise-linear force (ground truth for the examples; synthetic squeezes with known D and λ
  are in :mod:`deformctl.testing.kelvin_voigt`);
* :mod:`~deformctl.characterize.options`: the options the command builds and the stage takes
  (:class:`FitOptions`, :class:`QualityPolicy`), checked when built;
* :mod:`~deformctl.characterize.stage`: the ``characterize`` stage over squeeze logs, dataset
  directories and sweeps.

The public names of the estimators, models and stage are re-exported here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from deformctl.lazy import lazy_face

# ruff: noqa: F401 - the imports below are the public names (deformctl.lazy.lazy_face)
if TYPE_CHECKING:  # for type checkers; at run time each loads on first use
    from deformctl.characterize.arrays import (
        ARRAYS_SOURCE,
        CoefficientsWarning,
        characterize_arrays,
    )
    from deformctl.characterize.coefficients import (
        COEFFICIENT_COLUMNS,
        CoefficientFit,
    )
    from deformctl.characterize.fit import (
        DEFAULT_MIN_COMPRESSION_FRAC,
        DEFAULT_MIN_RATE_FRAC,
        DEFAULT_POLYORDER,
        UNIFORM_DT_RTOL,
        characterize,
        damping_excitation,
        fit_lsq,
        fit_paper,
    )
    from deformctl.characterize.material_options import (
        DEFAULT_MATERIALS,
        MODEL_CHOICES,
        MODELS,
        MaterialOptions,
        check_at_force_n,
        default_lag,
    )
    from deformctl.characterize.models import kelvin_voigt_piecewise_linear
    from deformctl.characterize.objectfit import (
        ObjectFit,
        fit_object,
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
    from deformctl.characterize.prepare import (
        MIN_SAMPLES,
        NO_COMPRESSION_M,
        NO_COMPRESSION_NOISE_MULT,
        validate_squeeze,
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
    from deformctl.squeeze.window import (
        DEFAULT_WINDOW_RATE_HZ,
        DEFAULT_WINDOW_S,
        default_window_s,
    )

#: Importing this package imports none of the modules above, so a module that needs one of them
#: (the command line's options) does not pay for the others (pandas, pyarrow, numba, MCAP).
__getattr__, __dir__ = lazy_face(globals())
