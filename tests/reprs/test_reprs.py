"""deformctl.reprs: a result holding arrays, tables and long lists prints on one short line."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from deformctl.reprs import MAX_ITEMS, MAX_TEXT, short, short_repr


class _Shown:
    def __init__(self, text: str) -> None:
        self.text = text

    def __repr__(self) -> str:
        return self.text


@dataclass
class _Inner:
    __repr__ = short_repr
    samples: Any
    label: str = "x"


@dataclass
class _Result:
    __repr__ = short_repr
    table: Any
    attempts: list[Any]
    inner: _Inner
    secret: Any = field(default=None, repr=False)


def test_each_kind_of_value_is_short() -> None:
    assert short(1 / 3) == "0.333333"
    assert short(True) == "True"
    assert short(None) == "None"
    assert short(12) == "12"
    assert short(np.zeros((3753, 2))) == "array[3753 x 2]"
    assert short(np.float64(2.5)) == "2.5"
    assert short(pd.DataFrame(np.zeros((73, 22)))) == "DataFrame[73 x 22]"
    assert short(list(range(24))) == "[24 items]"
    assert short((1, "a")) == "(1, 'a')"
    assert short({"a": 1.0}) == "{'a': 1}"
    assert short({k: k for k in "abcd"}) == "{4 keys}"
    cut = short("z" * 500)
    assert len(cut) == MAX_TEXT + 2
    assert cut.endswith("...'")
    assert short(object()).startswith("<object object at 0x")  # a short repr stays
    assert short(_Shown("x" * (MAX_TEXT + 1))) == "_Shown(...)"  # a long one does not
    assert short(_Shown("a\nb")) == "_Shown(...)"  # nor a multi-line one
    assert short(list(range(MAX_ITEMS))) == "[0, 1, 2]"  # up to MAX_ITEMS: item by item
    assert short(list(range(MAX_ITEMS + 1))) == "[4 items]"


def test_a_result_with_big_fields_prints_on_one_short_line() -> None:
    big = np.arange(1_000_000, dtype=np.float64)
    inner = _Inner(big, label="A")
    result = _Result(pd.DataFrame({"f": big}), [inner] * 50, inner, secret=big)
    text = repr(result)
    assert text == (
        "_Result(table=DataFrame[1000000 x 1], attempts=[50 items], "
        "inner=_Inner(samples=array[1000000], label='A'))"
    )
    in_a_list = _Result(None, [inner], inner)  # a result inside a sequence: by its class only
    assert repr(in_a_list) == (
        "_Result(table=None, attempts=[_Inner(...)], "
        "inner=_Inner(samples=array[1000000], label='A'))"
    )


def test_a_series_is_a_series_and_nesting_stops_one_level_down() -> None:
    # a pandas Series has a dtype, as an array does: it still shows as a Series
    assert short(pd.Series(np.zeros(5))) == "Series[5]"
    # a dataclass in a field shows its fields; one in those shows by its class only, however
    # deep the chain (a dataclass directly in a dataclass used to restart the count)
    deep = _Result(None, [], _Inner(_Inner(_Inner(1.0))))
    assert (
        repr(deep)
        == "_Result(table=None, attempts=[], inner=_Inner(samples=_Inner(...), label='x'))"
    )
