"""The array types are named once: deformctl/arraytypes.py, and no other module restates them."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

import deformctl
from deformctl import arraytypes

PACKAGE = Path(deformctl.__file__).resolve().parent


def test_the_types_are_numpys_arrays_of_their_dtype() -> None:
    assert arraytypes.FloatArray == NDArray[np.float64]
    assert arraytypes.IntArray == NDArray[np.int64]
    assert arraytypes.Int32Array == NDArray[np.int32]
    assert arraytypes.BoolArray == NDArray[np.bool_]


def test_no_other_module_defines_an_array_type() -> None:
    restated = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.name == "arraytypes.py" and path.parent == PACKAGE:
            continue
        for node in ast.parse(path.read_text()).body:
            value = node.value if isinstance(node, ast.Assign | ast.AnnAssign) else None
            # an alias of one NDArray (a union with other types is a type of its own)
            if isinstance(value, ast.Subscript) and ast.unparse(value.value).endswith("NDArray"):
                restated.append(f"{path.relative_to(PACKAGE)}:{node.lineno}")
    assert not restated, f"array types defined outside deformctl/arraytypes.py: {restated}"
