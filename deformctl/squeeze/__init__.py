"""What ``measure`` and ``characterize`` both know about a squeeze, below both stages.

* :mod:`~deformctl.squeeze.phase`: the phases a squeeze is reduced to (``--phase``);
* :mod:`~deformctl.squeeze.rupture`: where a squeeze stops being a Kelvin–Voigt squeeze
  (rupture, relaxation, the loading and unloading phases' cut);
* :mod:`~deformctl.squeeze.window`: the smoothing window a log's sample rate calls for;
* :mod:`~deformctl.squeeze.flags`: the recording's flags, which ``measure`` raises and
  ``characterize`` carries into ``quality``.

``measure`` cuts squeezes with these and ``characterize`` judges them with the same rules, so
neither stage imports the other. Importing this package imports none of its modules (the phase,
window and flag modules are light; :mod:`.rupture` brings numpy).
"""
