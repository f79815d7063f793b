"""Helpers of the command-line tests: the synthetic index example, one-line errors, an index table.

:func:`load_example` loads ``examples/synthetic_index.py`` (the paper's population with a
closed-form lifting force); :func:`write_index` writes its index table; :func:`_error` checks
that a failed run printed one ``error:`` line with the expected exit code.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType

import pandas as pd
from click.testing import Result

from deformctl.artifacts import Provenance, write_table
from deformctl.table import build_index_table

ROOT = Path(__file__).resolve().parents[2]
N_OBJECTS = 30


def load_example() -> ModuleType:
    """``examples/synthetic_index.py`` as a module."""
    spec = importlib.util.spec_from_file_location(
        "synthetic_index", ROOT / "examples" / "synthetic_index.py"
    )
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _error(result: Result, code: int) -> str:
    """The one stderr line of a failed run (asserts exit code, one line, no traceback)."""
    assert result.exit_code == code, (result.exit_code, result.stdout, result.stderr)
    assert isinstance(result.exception, SystemExit)
    err = result.stderr
    assert err.startswith("error: "), err
    assert err.count("\n") == 1, err
    return err.strip()


def write_index(path: Path, n: int = N_OBJECTS, seed: int = 0) -> pd.DataFrame:
    """Write the synthetic index table of ``n`` objects to ``path``; return it."""
    _, coefficients, lift = load_example().synthetic_tables(n, seed)
    index = build_index_table(coefficients, lift)
    write_table(index, path, "index_table", provenance=Provenance.from_invocation(argv=["t"]))
    return index
