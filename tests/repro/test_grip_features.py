"""The input-set study of the law networks (``python -m deformctl.repro.grip_features``) on a
synthetic population whose Hunt–Crossley L_f depends on the shape by a known law
(tests/grip/_synthetic.py: +10 % per decade of L_z / L_x)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from deformctl.repro.grip_features import INPUT_SETS, cross_validated_errors, main
from tests.grip._synthetic import law_index


def test_the_shape_inputs_learn_the_shape_law_the_earlier_inputs_cannot() -> None:
    rows = law_index(240, seed=21, noise=0.005, laws="hc=1")
    sets = INPUT_SETS["hc"]
    before = np.abs(cross_validated_errors("hc", rows, sets["without the shape (before)"], 4, 0))
    today = np.abs(cross_validated_errors("hc", rows, sets["with the shape (today)"], 4, 0))
    assert before.shape == today.shape == (240,)
    # the known shape term spans about +-4 %: without the shape the held-out error is that spread
    assert np.median(before) > 0.01
    assert np.median(today) < 0.6 * np.median(before)


def test_bad_arguments_are_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main([str(tmp_path), "--folds", "1"]) == 2
    assert main([str(tmp_path)]) == 66
    err = capsys.readouterr().err
    assert err.count("error:") == 2
    assert "no training run" in err
