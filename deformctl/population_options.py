"""The population's sizes and default friction, apart from :mod:`deformctl.population` (which
draws catalogs with numpy and pandas) so that ``deformctl population --help`` and ``deformctl
train --help`` state them without importing either."""

from __future__ import annotations

#: The paper's population size and split (section V.A).
PAPER_POPULATION_SIZE = 73
PAPER_TRAIN_SIZE = 40

#: Default friction coefficient of a population (constant: the network has no friction input).
DEFAULT_FRICTION_MU = 0.5

#: The material laws ``population --grip`` draws (``--laws``): Kelvin–Voigt, Hunt–Crossley and the
#: standard linear solid (Zener), as ``characterize --model`` names them.
GRIP_LAWS = ("kv", "hc", "sls")
#: ``population --grip``'s default mix: Kelvin–Voigt objects only (the bundled model's
#: population, bit for bit as before the laws were drawn).
DEFAULT_GRIP_LAW_MIX = "kv=1"
#: The mix of the three laws in equal shares (``--laws kv=1,hc=1,sls=1``).
EQUAL_GRIP_LAW_MIX = "kv=1,hc=1,sls=1"
