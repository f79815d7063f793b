"""``python -m deformctl``."""

from deformctl.cli import main

main()
