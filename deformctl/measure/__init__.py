"""Squeeze logs from real rigs (ROS 2 MCAP bags, CSV exports) and the simulator; catalog rows from
images.

One module per source, each a reader the ``measure`` command calls:

* :mod:`~deformctl.measure.ros2_bag`: :func:`read_ros2_bag` (``--bag``);
* :mod:`~deformctl.measure.csv`: :func:`read_csv_export` (``--csv``), with the text of an
  export in :mod:`~deformctl.measure.csv_table`, its columns and units in
  :mod:`~deformctl.measure.csv_columns`, its options in :mod:`~deformctl.measure.csv_options`
  and many files per call in :mod:`~deformctl.measure.csv_batch`;
* :mod:`~deformctl.measure.sim`: :func:`simulate_squeezes` (``--sim``), squeezing catalog objects
  in :mod:`deformctl.sim`;
* :mod:`~deformctl.measure.images`: :func:`~deformctl.measure.images.measure_images`
  (``--images``), an object-catalog row from a top and a side image (OpenCV, imported when used).

The options the command builds and the library takes are in :mod:`~deformctl.measure.options`
(:class:`BagSource`, :class:`Segmentation`, :class:`SqueezeProtocol`; a CSV's
:class:`CsvOptions` are in :mod:`~deformctl.measure.csv_options`; the
readers :func:`read_bag` and :func:`read_csv` take them, :func:`read_ros2_bag` and
:func:`read_csv_export` build them from keyword arguments). Both recording readers return a
:class:`Recording` (:mod:`~deformctl.measure.recording`: the
squeezes in SI, the source sample rates and the ruptures; the compression from a position signal),
cut into squeezes by :mod:`~deformctl.measure.segment` (segmentation, rupture and phase cuts).
:mod:`~deformctl.measure.stage` writes the squeeze logs: :func:`recording_log` for a recording,
:func:`simulate_catalog_file` for a catalog and, at scale, :class:`SimulateCatalogTask` (the sweep
task of one object) and :func:`simulate_catalog_sweep` (a dataset directory).

A recording's defects (a logging gap, a coarse force, a force that lags the position) are
reported, not fitted over (:mod:`~deformctl.measure.defects`). Every reader checks the
recording's plausibility (:mod:`deformctl.plausibility`: a sample rate,
peak force, peak compression, force axis or compression sign that a unit, axis or sign mistake
explains is refused with the likely fix), and every squeeze is cut at a rupture and reduced to the
``phase`` asked for (:mod:`deformctl.squeeze.rupture`); the :class:`Recording` carries the
ruptures, which the log stores with the object (:meth:`Recording.log_fields`).

The public names of the readers and the stage are re-exported here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from deformctl.lazy import lazy_exports

if TYPE_CHECKING:  # the names below, for type checkers; at run time they load on first use
    from deformctl.measure.csv import (
        ABSOLUTE_TIME_MIN_S,
        read_csv,
        read_csv_export,
        squeeze_from_csv,
    )
    from deformctl.measure.csv_batch import (
        CSV_MEASURE_SCHEMA,
        CsvBatchResult,
        CsvFile,
        CsvFileTask,
        csv_objects,
        measure_csv_files,
        measure_csv_sweep,
        read_objects_from,
    )
    from deformctl.measure.csv_options import (
        DEFAULT_CSV_MEMORY_BUDGET_GIB,
        CsvDialect,
        CsvOptions,
    )
    from deformctl.measure.images import (
        ImagesResult,
        measure_images,
    )
    from deformctl.measure.options import (
        DEFAULT_FORCE_THRESHOLD_FRAC,
        DEFAULT_MIN_GAP_S,
        DEFAULT_MIN_SQUEEZE_S,
        DEFAULT_SEGMENTATION,
        DEFAULT_SIM_HOLD_S,
        DEFAULT_SIM_RAMP_S,
        DEFAULT_SIM_SQUEEZES,
        DEFAULT_SQUEEZE_PROTOCOL,
        DEFAULT_SQUEEZE_STRAIN,
        INCREASES_WHEN,
        Axis,
        BagSource,
        CompressionZero,
        IncreasesWhen,
        PositionIs,
        Segmentation,
        SqueezeProtocol,
    )
    from deformctl.measure.recording import (
        Recording,
    )
    from deformctl.measure.ros2_bag import (
        JOINT_STATE_TYPE,
        POSE_TYPE,
        WRENCH_TYPE,
        read_bag,
        read_ros2_bag,
        squeeze_from_ros2_bag,
    )
    from deformctl.measure.segment import (
        segment_squeezes,
    )
    from deformctl.measure.sim import (
        SqueezeProgress,
        default_peak_force_n,
        simulate_squeezes,
    )
    from deformctl.measure.stage import (
        LOG_SAMPLE_BYTES,
        MEASURE_SCHEMA,
        SimulateCatalogTask,
        recording_log,
        sim_provenance,
        simulate_catalog_file,
        simulate_catalog_sweep,
    )

#: Public name -> the submodule that defines it. Importing this package imports none of them, so
#: a module that needs one of them (the command line's options) does not pay for the others
#: (pandas, pyarrow, numba, the MCAP readers).
_EXPORTS: dict[str, str] = {
    "ABSOLUTE_TIME_MIN_S": "deformctl.measure.csv",
    "read_csv": "deformctl.measure.csv",
    "read_csv_export": "deformctl.measure.csv",
    "squeeze_from_csv": "deformctl.measure.csv",
    "CSV_MEASURE_SCHEMA": "deformctl.measure.csv_batch",
    "CsvBatchResult": "deformctl.measure.csv_batch",
    "CsvFile": "deformctl.measure.csv_batch",
    "CsvFileTask": "deformctl.measure.csv_batch",
    "csv_objects": "deformctl.measure.csv_batch",
    "measure_csv_files": "deformctl.measure.csv_batch",
    "measure_csv_sweep": "deformctl.measure.csv_batch",
    "read_objects_from": "deformctl.measure.csv_batch",
    "DEFAULT_CSV_MEMORY_BUDGET_GIB": "deformctl.measure.csv_options",
    "CsvDialect": "deformctl.measure.csv_options",
    "CsvOptions": "deformctl.measure.csv_options",
    "ImagesResult": "deformctl.measure.images",
    "measure_images": "deformctl.measure.images",
    "DEFAULT_FORCE_THRESHOLD_FRAC": "deformctl.measure.options",
    "DEFAULT_MIN_GAP_S": "deformctl.measure.options",
    "DEFAULT_MIN_SQUEEZE_S": "deformctl.measure.options",
    "DEFAULT_SEGMENTATION": "deformctl.measure.options",
    "DEFAULT_SIM_HOLD_S": "deformctl.measure.options",
    "DEFAULT_SIM_RAMP_S": "deformctl.measure.options",
    "DEFAULT_SIM_SQUEEZES": "deformctl.measure.options",
    "DEFAULT_SQUEEZE_PROTOCOL": "deformctl.measure.options",
    "DEFAULT_SQUEEZE_STRAIN": "deformctl.measure.options",
    "INCREASES_WHEN": "deformctl.measure.options",
    "Axis": "deformctl.measure.options",
    "BagSource": "deformctl.measure.options",
    "CompressionZero": "deformctl.measure.options",
    "IncreasesWhen": "deformctl.measure.options",
    "PositionIs": "deformctl.measure.options",
    "Segmentation": "deformctl.measure.options",
    "SqueezeProtocol": "deformctl.measure.options",
    "Recording": "deformctl.measure.recording",
    "JOINT_STATE_TYPE": "deformctl.measure.ros2_bag",
    "POSE_TYPE": "deformctl.measure.ros2_bag",
    "WRENCH_TYPE": "deformctl.measure.ros2_bag",
    "read_bag": "deformctl.measure.ros2_bag",
    "read_ros2_bag": "deformctl.measure.ros2_bag",
    "squeeze_from_ros2_bag": "deformctl.measure.ros2_bag",
    "segment_squeezes": "deformctl.measure.segment",
    "SqueezeProgress": "deformctl.measure.sim",
    "default_peak_force_n": "deformctl.measure.sim",
    "simulate_squeezes": "deformctl.measure.sim",
    "LOG_SAMPLE_BYTES": "deformctl.measure.stage",
    "MEASURE_SCHEMA": "deformctl.measure.stage",
    "SimulateCatalogTask": "deformctl.measure.stage",
    "recording_log": "deformctl.measure.stage",
    "sim_provenance": "deformctl.measure.stage",
    "simulate_catalog_file": "deformctl.measure.stage",
    "simulate_catalog_sweep": "deformctl.measure.stage",
}


__getattr__, __dir__ = lazy_exports(globals(), _EXPORTS)


__all__ = [
    "ABSOLUTE_TIME_MIN_S",
    "CSV_MEASURE_SCHEMA",
    "DEFAULT_CSV_MEMORY_BUDGET_GIB",
    "DEFAULT_FORCE_THRESHOLD_FRAC",
    "DEFAULT_MIN_GAP_S",
    "DEFAULT_MIN_SQUEEZE_S",
    "DEFAULT_SEGMENTATION",
    "DEFAULT_SIM_HOLD_S",
    "DEFAULT_SIM_RAMP_S",
    "DEFAULT_SIM_SQUEEZES",
    "DEFAULT_SQUEEZE_PROTOCOL",
    "DEFAULT_SQUEEZE_STRAIN",
    "INCREASES_WHEN",
    "JOINT_STATE_TYPE",
    "LOG_SAMPLE_BYTES",
    "MEASURE_SCHEMA",
    "POSE_TYPE",
    "WRENCH_TYPE",
    "Axis",
    "BagSource",
    "CompressionZero",
    "CsvBatchResult",
    "CsvDialect",
    "CsvFile",
    "CsvFileTask",
    "CsvOptions",
    "ImagesResult",
    "IncreasesWhen",
    "PositionIs",
    "Recording",
    "Segmentation",
    "SimulateCatalogTask",
    "SqueezeProgress",
    "SqueezeProtocol",
    "csv_objects",
    "default_peak_force_n",
    "measure_csv_files",
    "measure_csv_sweep",
    "measure_images",
    "read_bag",
    "read_csv",
    "read_csv_export",
    "read_objects_from",
    "read_ros2_bag",
    "recording_log",
    "segment_squeezes",
    "sim_provenance",
    "simulate_catalog_file",
    "simulate_catalog_sweep",
    "simulate_squeezes",
    "squeeze_from_csv",
    "squeeze_from_ros2_bag",
]
