"""The test suite, a package so that every test module has a unique dotted name.

Tests mirror the source: ``tests/<package>/test_<module>.py`` tests
``deformctl/<package>/<module>.py``, and the tests of a top-level module ``deformctl/<name>.py``
live in ``tests/<name>/``. Shared fixtures are in ``tests/conftest.py``, shared helpers in
``tests/_helpers/``; ``tests/test_layout.py`` checks the rule.
"""
