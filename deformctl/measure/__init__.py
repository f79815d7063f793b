"""Squeeze logs from real rigs (ROS 2 MCAP bags, CSV exports) and the simulator; catalog rows from
images.

One module per source, each a reader the ``measure`` command calls:

* :mod:`~deformctl.measure.ros2_bag`: a ROS 2 bag (``measure bag``);
* :mod:`~deformctl.measure.csv`: a CSV export (``measure csv``), a package: the text of an
  export in :mod:`~deformctl.measure.csv.table`, its columns and units in
  :mod:`~deformctl.measure.csv.columns`, its options in :mod:`~deformctl.measure.csv.options`,
  the reader in :mod:`~deformctl.measure.csv.reader` and many files per call in
  :mod:`~deformctl.measure.csv.batch`;
* :mod:`~deformctl.measure.sim`: :func:`simulate_squeezes` (``measure sim``), squeezing
  catalog objects in :mod:`deformctl.sim`;
* :mod:`~deformctl.measure.images`: :func:`~deformctl.measure.images.measure_images`
  (``measure images``), an object-catalog row from a top and a side image (OpenCV, imported
  when used).

The options the command builds and the library takes are in :mod:`~deformctl.measure.options`
(:class:`BagSource`, :class:`Segmentation`, :class:`SqueezeProtocol`; a CSV's
:class:`CsvOptions` are in :mod:`~deformctl.measure.csv.options`). One door reads a recording
of either source: :func:`read_recording` (path, the source's options, the object, the
segmentation). It returns a :class:`Recording` (:mod:`~deformctl.measure.recording`: the
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

from deformctl.lazy import lazy_face

# ruff: noqa: F401 - the imports below are the public names (deformctl.lazy.lazy_face)
if TYPE_CHECKING:  # for type checkers; at run time each loads on first use
    from deformctl.measure.csv.batch import (
        CSV_MEASURE_SCHEMA,
        CsvBatchResult,
        CsvFile,
        CsvFileTask,
        csv_objects,
        measure_csv_files,
        measure_csv_sweep,
        read_objects_from,
    )
    from deformctl.measure.csv.options import (
        DEFAULT_CSV_MEMORY_BUDGET_GIB,
        CsvDialect,
        CsvOptions,
    )
    from deformctl.measure.csv.reader import (
        ABSOLUTE_TIME_MIN_S,
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
        read_recording,
        recording_log,
        sim_provenance,
        simulate_catalog_file,
        simulate_catalog_sweep,
    )

#: Importing this package imports none of the modules above, so a module that needs one of them
#: (the command line's options) does not pay for the others (pandas, pyarrow, numba, MCAP).
__getattr__, __dir__ = lazy_face(globals())
