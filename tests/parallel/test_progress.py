"""The sweep's progress bar: done/total, failed, rate, elapsed and ETA on a terminal; nothing
otherwise (CI logs stay clean)."""

from __future__ import annotations

import io
import sys

import pytest

from deformctl.parallel.sweep import _Progress


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_the_sweep_bar_shows_eta_on_a_terminal(monkeypatch: pytest.MonkeyPatch) -> None:
    fake = _Terminal()
    monkeypatch.setattr(sys, "stderr", fake)
    bar = _Progress(True, total=4, completed=0)
    for ok in (True, False, True):
        bar.advance(ok)
    bar.close()
    text = fake.getvalue()
    assert "3/4" in text
    assert "1 failed" in text
    assert "ETA" in text


def test_no_bar_when_stderr_is_not_a_terminal(monkeypatch: pytest.MonkeyPatch) -> None:
    plain = io.StringIO()
    monkeypatch.setattr(sys, "stderr", plain)
    bar = _Progress(True, total=4, completed=0)
    bar.advance(True)
    bar.close()
    assert plain.getvalue() == ""
