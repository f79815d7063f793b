"""The population's sizes and default friction, apart from :mod:`deformctl.population` (which
draws catalogs with numpy and pandas) so that ``deformctl population --help`` and ``deformctl
train --help`` state them without importing either."""

from __future__ import annotations

#: The paper's population size and split (section V.A).
PAPER_POPULATION_SIZE = 73
PAPER_TRAIN_SIZE = 40

#: Default friction coefficient of a population (constant: the network has no friction input).
DEFAULT_FRICTION_MU = 0.5
