"""``characterize --plot DIR``: one PNG per object, read back.

Each PNG must have the documented size and four non-blank panels: the force–compression panel
holds the samples (grey) and every law's fit in its colour, the time panel the force (red) and
the compression (purple), the residual panel every law's colour, the rate-free panel the chosen
law's. The paths are printed on stderr; a --plot that is a file is exit 2 with nothing written.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.colors import to_rgb
from matplotlib.image import imread
from typer.testing import CliRunner

from deformctl.artifacts import write_squeeze_log
from deformctl.characterize.plot import COLOURS, PIXELS
from deformctl.cli import app
from deformctl.testing.synthetic import synthetic_law_squeeze

from ._truth import TRUTH

runner = CliRunner()


def _has(panel: np.ndarray, colour: str | tuple[float, float, float], *, min_px: int = 30) -> bool:
    """At least ``min_px`` pixels of ``colour`` (within 0.04 per channel) in ``panel``."""
    rgb = np.asarray(to_rgb(colour))
    close = np.all(np.abs(panel[..., :3] - rgb) < 0.04, axis=-1)
    return int(close.sum()) >= min_px


def _log(path: Path) -> Path:
    squeezes = [  # one squeeze each, at 100 Hz: seconds, not tens
        synthetic_law_squeeze("hc", TRUTH["hc"], seed=i, rate_hz=100.0, object_id=oid)
        for i, oid in enumerate(("gel/a", "gel-b"))
    ]
    objects = [{"object_id": oid, "weight_n": 1.0} for oid in ("gel/a", "gel-b")]
    write_squeeze_log(path, objects, squeezes, provenance=None)
    return path


def test_one_png_per_object_with_four_drawn_panels(tmp_path: Path) -> None:
    log, out, plots = _log(tmp_path / "log.mcap"), tmp_path / "c.parquet", tmp_path / "plots"
    res = runner.invoke(app, ["characterize", str(log), "-o", str(out), "--plot", str(plots)])
    assert res.exit_code == 0, res.stderr
    printed = [
        ln.removeprefix("plot: ") for ln in res.stderr.splitlines() if ln.startswith("plot: ")
    ]
    assert sorted(Path(p).name for p in printed) == ["gel-b.png", "gel_a.png"]
    assert sorted(p.name for p in plots.iterdir()) == ["gel-b.png", "gel_a.png"]
    for path in printed:
        img = imread(path)
        assert img.shape[:2] == (PIXELS[1], PIXELS[0])
        h, w = img.shape[0] // 2, img.shape[1] // 2
        fd, t, r, el = img[:h, :w], img[:h, w:], img[h:, :w], img[h:, w:]
        assert _has(fd, (0.65, 0.65, 0.65))  # the samples
        for colour in COLOURS.values():  # every law's fit and residuals
            assert _has(fd, colour), colour
            assert _has(r, colour), colour
        assert _has(t, "tab:red")
        assert _has(t, "tab:purple")
        assert _has(el, COLOURS["hc"])  # the law chosen for a Hunt-Crossley object
        assert not _has(el, COLOURS["kv"])


def test_a_blank_panel_is_told_apart() -> None:
    # the check above can fail: a white panel has no pixel of any colour
    blank = np.ones((450, 600, 4))
    assert not any(_has(blank, c) for c in (*COLOURS.values(), "tab:red", (0.65, 0.65, 0.65)))


def test_plot_into_a_file_is_a_usage_error(tmp_path: Path) -> None:
    log, out = _log(tmp_path / "log.mcap"), tmp_path / "c.parquet"
    (tmp_path / "file").write_text("x", encoding="utf-8")
    res = runner.invoke(
        app, ["characterize", str(log), "-o", str(out), "--plot", str(tmp_path / "file")]
    )
    assert res.exit_code == 2
    assert res.stderr.startswith("error: ")
    assert len(res.stderr.strip().splitlines()) == 1
    assert not out.exists()
