"""Shared fixtures: catalog rows, a catalog file, synthetic recordings and a small lattice.

* :func:`catalog_row`: a 10 cm cube of 1 N with μ 0.5 and material values (D 10 N/cm, λ 1
  N·s/cm), inside every bound; :func:`sponge_row`: the paper's sponge (Table I, object A).
  Each test gets its own copy.
* :func:`write_catalog`: writes rows (dicts with the catalog columns) as a catalog CSV.
* :func:`kv_squeeze`: a synthetic Kelvin–Voigt squeeze with known D = 20 N/cm, λ = 1 N·s/cm
  (1 % force noise, 0.05 mm position noise, seed 1); :func:`kv_csv`: the same squeeze written as a
  testing machine's CSV export (time s, force N, compression mm, names with their units).
* :func:`small_lattice`: the simulator's lattice of a 10 x 7 x 5 cm box at 2.5 cm spacing
  (5 x 4 x 3 particles), built once per session; treat it as read-only.
* :func:`dask_cluster`: a Dask scheduler and two workers, each its own process, on 127.0.0.1
  (``tests/_helpers/dask_cluster.py``), stopped after the test.
* :func:`wheel_file`, :func:`fresh_venv`, :func:`warm_venv`: the wheel of the source tree, a
  fresh venv with it installed, and that venv after ``deformctl warmup``, each made once per
  session, shared by the xdist workers (``tests/_helpers/wheel.py``).

Hypothesis draws its examples from a fixed seed (``derandomize``) and keeps no example database,
so every run of ``make test`` tries the same cases on every machine: a fuzz test that finds a bug
finds it on the first run, not on one CI run in fifty. To explore new cases locally, run
``pytest --hypothesis-profile explore`` (random seeds, examples remembered in ``.hypothesis/``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pytest
from hypothesis import settings

from tests._helpers.dask_cluster import dask_cluster  # noqa: F401 - a shared fixture
from tests._helpers.wheel import fresh_venv, warm_venv, wheel_file  # noqa: F401 - shared fixtures

#: the markers of the long tests, which a developer's inner loop can skip with
#: ``pytest -m "not slow and not e2e and not docs"`` (``make test`` and CI run them all)
LONG_MARKERS = ("slow", "e2e", "docs")


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Tests marked ``slow``, ``e2e`` or ``docs`` run first (stable order otherwise): ``make
    test``'s two xdist workers then share the long ones from the start instead of one worker
    finishing a 100 s test alone at the end. Every worker sorts the same collection the same
    way, as xdist requires."""
    items.sort(key=lambda item: not any(item.get_closest_marker(m) for m in LONG_MARKERS))


settings.register_profile("deterministic", derandomize=True, database=None)
settings.register_profile("explore", derandomize=False)
settings.load_profile("deterministic")

if TYPE_CHECKING:
    from deformctl.series import SqueezeSeries
    from deformctl.sim.lattice import Lattice

#: The known truth of :func:`kv_squeeze`.
KV_D_N_PER_CM = 20.0
KV_LAMBDA_NS_PER_CM = 1.0

_CUBE = {
    "object_id": "A",
    "size_x_cm": 10.0,
    "size_y_cm": 10.0,
    "size_z_cm": 10.0,
    "weight_n": 1.0,
    "friction_mu": 0.5,
    "material_stiffness_n_per_cm": 10.0,
    "material_damping_ns_per_cm": 1.0,
}
_SPONGE = {
    "object_id": "sponge",
    "size_x_cm": 17.8,
    "size_y_cm": 19.1,
    "size_z_cm": 9.2,
    "weight_n": 0.7,
    "friction_mu": 0.5,
    "material_stiffness_n_per_cm": 49.18,
    "material_damping_ns_per_cm": 6.47,
}


@pytest.fixture
def catalog_row() -> dict[str, Any]:
    """A 10 cm cube with material values, inside every catalog bound (a fresh copy)."""
    return dict(_CUBE)


@pytest.fixture
def sponge_row() -> dict[str, Any]:
    """The paper's sponge (Table I, object A), a fresh copy."""
    return dict(_SPONGE)


@pytest.fixture
def write_catalog() -> Callable[[Path, Sequence[Mapping[str, Any]]], Path]:
    """``write(path, rows)``: the rows as a catalog CSV (the first row's columns), its path."""

    def write(path: Path, rows: Sequence[Mapping[str, Any]]) -> Path:
        header = list(rows[0])
        lines = [",".join(header)] + [",".join(str(r[c]) for c in header) for r in rows]
        path.write_text("\n".join(lines) + "\n")
        return path

    return write


@pytest.fixture
def kv_squeeze() -> SqueezeSeries:
    """A synthetic Kelvin–Voigt squeeze, D = 20 N/cm, λ = 1 N·s/cm (noisy, seed 1)."""
    from deformctl.testing.kelvin_voigt import synthetic_kelvin_voigt_squeeze

    return synthetic_kelvin_voigt_squeeze(KV_D_N_PER_CM, KV_LAMBDA_NS_PER_CM, seed=1)


@pytest.fixture
def kv_csv(tmp_path: Path, kv_squeeze: SqueezeSeries) -> Path:
    """:func:`kv_squeeze` as a CSV export: ``Time (s),Load (N),Compression (mm)``."""
    path = tmp_path / "kv.csv"
    rows = np.column_stack([kv_squeeze.time_s, kv_squeeze.force_n, 1e3 * kv_squeeze.compression_m])
    lines = ["Time (s),Load (N),Compression (mm)"]
    lines += [f"{t:.6f},{f:.6f},{d:.6f}" for t, f, d in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="session")
def small_lattice() -> Lattice:
    """A 10 x 7 x 5 cm box at 2.5 cm spacing: 5 x 4 x 3 particles (read-only)."""
    from deformctl.sim.lattice import build_lattice

    return build_lattice((0.1, 0.07, 0.05), 0.025)
