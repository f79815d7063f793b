"""The CSV source of ``measure``: testing-machine and gripper exports (``measure csv``).

One module per step; importing the package imports none of them:

* :mod:`~deformctl.measure.csv.options`: :class:`CsvOptions` and :class:`CsvDialect`, what the
  command builds from its flags and the library takes;
* :mod:`~deformctl.measure.csv.table`: the text of an export (encoding, delimiter, decimal mark,
  preamble, header, units row) and its numbers;
* :mod:`~deformctl.measure.csv.columns`: which column is the time, the force and the position,
  with their units;
* :mod:`~deformctl.measure.csv.reader`: one export read into a
  :class:`~deformctl.measure.recording.Recording` (the source of
  :func:`deformctl.measure.stage.read_recording`);
* :mod:`~deformctl.measure.csv.batch`: many files per call (a folder, a glob, a list), one object
  each, into one squeeze log or a dataset directory;
* :mod:`~deformctl.measure.csv.dry_run`: what ``measure csv --dry-run`` reports, nothing written.
"""
