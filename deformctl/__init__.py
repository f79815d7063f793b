"""deformctl: learn the minimum force that lifts a deformable object without slip.

The library calls a notebook needs, one per command, each with the command's defaults (imported
when first used, so ``import deformctl`` stays light; ``tests/test_api.py`` checks the defaults
against the command line's):

* ``population``: :func:`make_population` (73 objects, seed 0), :func:`paper_objects`;
* ``measure --sim``: :func:`simulate_squeezes` (a :class:`SqueezeProtocol`; the ``paper``
  preset's simulator settings);
* ``measure --bag`` / ``--csv``: :func:`read_recording` with a :class:`BagSource` or a
  :class:`CsvOptions` (with its :class:`CsvDialect`) and a :class:`Segmentation`; the object
  is a :class:`MeasuredObject`;
* ``measure --images``: :func:`measure_images` (a :class:`ScaleReference`, an
  :class:`ObjectMask`);
* ``characterize``: :func:`read_and_characterize` (:class:`FitOptions` with its
  :class:`MaterialOptions`, :class:`QualityPolicy`; the preload is fitted for rig recordings and
  the law chosen by BIC, as the command does);
* ``lift``: :func:`lift_catalog` with :func:`sim_runner_factory` (the ``paper`` preset;
  :class:`SimOptions` changes it) or :func:`rig_runner_factory`, and a :class:`SearchOptions`;
* ``table``: :func:`build_index_table`; ``train``: :func:`train_model` (a
  :class:`TrainOptions`: the paper's 3-2-1 network, 40 training rows, seed 0); ``predict``:
  :func:`load_predictor` (a model file or the bundled ``grip``), :func:`read_prediction_inputs`
  and :func:`predict_objects`; ``inspect``: :func:`describe`.

Files: :func:`read_catalog`, :func:`read_table`, :func:`read_squeeze_log`,
:func:`read_lift_log`. The packages, by pipeline stage: :mod:`~deformctl.population`,
:mod:`deformctl.measure`, :mod:`deformctl.characterize`, :mod:`deformctl.lift`,
:mod:`~deformctl.table`, :mod:`~deformctl.train`, with :mod:`deformctl.vision` for OpenCV
measurements; below them :mod:`deformctl.parallel`, :mod:`deformctl.artifacts`,
:mod:`~deformctl.catalog`, :mod:`~deformctl.presets`, :mod:`deformctl.sim` and the shared
:mod:`~deformctl.quantities` (every quantity's one rule), :mod:`~deformctl.series` and
:mod:`~deformctl.errors`; :mod:`deformctl.cli` is the ``deformctl`` command, a thin layer over
them. ``docs/development.md`` says what each package owns.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from deformctl.errors import DeformctlError
from deformctl.lazy import lazy_face

if TYPE_CHECKING:  # pragma: no cover - read on first use (module __getattr__)
    __version__: str

# ruff: noqa: F401 - the imports below are the library calls (deformctl.lazy.lazy_face)
if TYPE_CHECKING:  # for type checkers; at run time each loads on first use
    from deformctl.artifacts import (
        describe,
        read_catalog,
        read_lift_log,
        read_squeeze_log,
        read_table,
    )
    from deformctl.catalog import MeasuredObject
    from deformctl.characterize.material_options import MaterialOptions
    from deformctl.characterize.options import FitOptions, QualityPolicy
    from deformctl.characterize.stage import read_and_characterize
    from deformctl.lift.options import SearchOptions
    from deformctl.lift.runners.rig import rig_runner_factory
    from deformctl.lift.runners.sim import sim_runner_factory
    from deformctl.lift.stage import lift_catalog
    from deformctl.measure.csv.options import CsvDialect, CsvOptions
    from deformctl.measure.images import measure_images
    from deformctl.measure.options import (
        BagSource,
        ObjectMask,
        ScaleReference,
        Segmentation,
        SqueezeProtocol,
    )
    from deformctl.measure.sim import simulate_squeezes
    from deformctl.measure.stage import read_recording
    from deformctl.model import TrainOptions
    from deformctl.population import make_population, paper_objects
    from deformctl.predict import load_predictor, predict_objects, read_prediction_inputs
    from deformctl.presets import SimOptions, sim_preset
    from deformctl.table import build_index_table
    from deformctl.train import train_model

_api_getattr, _api_dir = lazy_face(globals(), first=("DeformctlError", "__version__"))


def __getattr__(name: str) -> Any:
    """The library call ``name``, imported on first use (``__version__`` too: reading the
    installed distribution's metadata costs a good part of a one-object ``predict``'s start)."""
    if name == "__version__":
        from deformctl.version import version_string

        globals()[name] = value = version_string()
        return value
    return _api_getattr(name)


def __dir__() -> list[str]:
    return sorted({*_api_dir(), "__version__"})
