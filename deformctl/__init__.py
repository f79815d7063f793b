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
* ``table``: :func:`build_index_table`; ``train``: :func:`train_model` (the paper's 3-2-1
  network, 40 training rows, seed 0); ``predict``: :func:`load_predictor` (a model file or the
  bundled ``grip``), :func:`read_prediction_inputs` and :func:`predict_objects`; ``inspect``:
  :func:`describe`.

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
from deformctl.lazy import lazy_exports

if TYPE_CHECKING:  # pragma: no cover - read on first use (module __getattr__)
    __version__: str

#: Each library call exported here → the module that defines it.
_API: dict[str, str] = {
    "make_population": "deformctl.population",
    "paper_objects": "deformctl.population",
    "simulate_squeezes": "deformctl.measure.sim",
    "read_recording": "deformctl.measure.stage",
    "measure_images": "deformctl.measure.images",
    "BagSource": "deformctl.measure.options",
    "CsvOptions": "deformctl.measure.csv.options",
    "CsvDialect": "deformctl.measure.csv.options",
    "Segmentation": "deformctl.measure.options",
    "SqueezeProtocol": "deformctl.measure.options",
    "ScaleReference": "deformctl.measure.options",
    "ObjectMask": "deformctl.measure.options",
    "MeasuredObject": "deformctl.catalog",
    "read_and_characterize": "deformctl.characterize.stage",
    "FitOptions": "deformctl.characterize.options",
    "QualityPolicy": "deformctl.characterize.options",
    "MaterialOptions": "deformctl.characterize.material_options",
    "lift_catalog": "deformctl.lift.stage",
    "sim_runner_factory": "deformctl.lift.runners.sim",
    "rig_runner_factory": "deformctl.lift.runners.rig",
    "SearchOptions": "deformctl.lift.options",
    "SimOptions": "deformctl.presets",
    "sim_preset": "deformctl.presets",
    "build_index_table": "deformctl.table",
    "train_model": "deformctl.train",
    "load_predictor": "deformctl.predict",
    "predict_objects": "deformctl.predict",
    "read_prediction_inputs": "deformctl.predict",
    "describe": "deformctl.artifacts",
    "read_catalog": "deformctl.artifacts",
    "read_table": "deformctl.artifacts",
    "read_squeeze_log": "deformctl.artifacts",
    "read_lift_log": "deformctl.artifacts",
}

__all__ = ["DeformctlError", "__version__", *sorted(_API)]


_api_getattr, _api_dir = lazy_exports(globals(), _API)


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
