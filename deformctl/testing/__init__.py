"""Test generators that ship with the package: seeded synthetic recordings with known truth.

:mod:`deformctl.testing.synthetic` makes a squeeze of each material law, a rupture with back-off
and a relaxation; :mod:`deformctl.testing.kelvin_voigt` a Kelvin–Voigt squeeze with known D and
λ from the exact response to a force profile.

:mod:`deformctl.testing.shapes` draws seeded recordings of every shape real squeeze recordings
take (falling stretches, buckling, fruit collapse, relaxation, latency, logging gaps) and writes
them as the exports instruments write (preambles, two-row headers, CRLF/CR line ends, text
columns, GBK headers); ``python -m deformctl.testing.shapes check`` runs them through
``measure --csv`` and ``characterize`` and counts internal errors and confidently wrong rows.
:mod:`deformctl.testing.fruit` draws force-controlled fruit squeezes to collapse (with yield,
back-off, slip and sensor lag) and the shapes that are not rupture, each with its true onset
force; ``python -m deformctl.testing.fruit check`` measures the rupture detector on them.
"""
