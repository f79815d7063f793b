"""The one-line error check of the measure tests."""

from __future__ import annotations

from collections.abc import Callable

import pytest


def _err(fn: Callable[[], object], cls: type[Exception], match: str) -> str:
    with pytest.raises(cls, match=match) as info:
        fn()
    msg = str(info.value)
    assert "\n" not in msg
    return msg
