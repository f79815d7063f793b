"""Test generators that ship with the package: synthetic recordings with known truth.

:mod:`deformctl.testing.shapes` draws seeded recordings of every shape real squeeze recordings
take (falling stretches, buckling, fruit collapse, relaxation, latency, logging gaps) and writes
them as the exports instruments write (preambles, two-row headers, CRLF/CR line ends, text
columns, GBK headers); ``python -m deformctl.testing.shapes check`` runs them through
``measure --csv`` and ``characterize`` and counts internal errors and confidently wrong rows.
"""
