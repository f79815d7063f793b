"""Helpers of the model-file tests: a small seeded training table and a saved model.

:func:`_table` is 30 objects with a smooth known L_f; :func:`_metadata` the metadata ``train``
stores with a model; :func:`_model` trains on the table and saves the model (or a model file whose
metadata is the JSON text given, to test the reader's limits).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import skops.io as sio

from deformctl.artifacts.model import MODEL_FORMAT, save_model
from deformctl.model import TrainOptions
from deformctl.train import FEATURES, TrainResult, train_model


def _table(n: int = 30) -> pd.DataFrame:
    rng = np.random.default_rng(4)
    w = rng.uniform(20, 60, n)
    d = rng.uniform(30, 50, n)
    lam = rng.uniform(0, 13, n)
    return pd.DataFrame(
        {
            "object_id": [f"M{i:02d}" for i in range(n)],
            "weight_n": w,
            "deformability_n_per_cm": d,
            "damping_ns_per_cm": lam,
            "lift_force_n": w * (1 + 0.5 * w / d * np.exp(-lam / 5)),
            "f_w_n": w,
        }
    )


def _metadata(result: TrainResult) -> dict[str, object]:
    return {
        "seed": result.metrics["seed"],
        "features": list(FEATURES),
        "training_range": result.metrics["training_range"],
        "metrics": {"test": result.metrics["model"]["test"]},
    }


def _model(path: Path, metadata_json: str | None = None) -> Path:
    trained = train_model(_table(), TrainOptions(train_size=20, seed=1, restarts=1))
    if metadata_json is None:
        return save_model(path, trained.model, metadata=_metadata(trained), force=True)
    payload = {"format": MODEL_FORMAT, "metadata_json": metadata_json, "model": trained.model}
    sio.dump(payload, path)
    return path
