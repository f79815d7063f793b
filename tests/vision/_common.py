"""What the size and slip tests of deformctl.vision share: the rendering cameras' focal length
and the one-line error check."""

from __future__ import annotations

import pytest

FOCAL_PX = 900.0


def _one_line(err: pytest.ExceptionInfo[BaseException]) -> str:
    text = str(err.value)
    assert "\n" not in text
    return text
