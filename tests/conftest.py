"""Shared test set-up.

Hypothesis draws its examples from a fixed seed (``derandomize``) and keeps no example database,
so every run of ``make test`` tries the same cases on every machine: a fuzz test that finds a bug
finds it on the first run, not on one CI run in fifty. To explore new cases locally, run
``pytest --hypothesis-profile explore`` (random seeds, examples remembered in ``.hypothesis/``).
"""

from __future__ import annotations

from hypothesis import settings

settings.register_profile("deterministic", derandomize=True, database=None)
settings.register_profile("explore", derandomize=False)
settings.load_profile("deterministic")
