"""The NumPy array types the package annotates with, named once for every module."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
UIntArray = NDArray[np.uint64]
Int32Array = NDArray[np.int32]
BoolArray = NDArray[np.bool_]
