"""The bundled datasets, installed as the package data ``deformctl.datasets``.

``paper/``: the seed paper's Table I objects and its Tables II and III; ``golden/``: the CI
regression population and its expected numbers; ``examples/``: a sample ROS 2 bag and a
testing machine's CSV export (``examples/make_sample_recordings.py`` writes them). Read them with
:func:`deformctl.repro.dataset_path`, which works from a checkout and from an installed wheel.
"""
