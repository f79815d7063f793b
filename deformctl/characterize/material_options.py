"""The material options of ``characterize``, checked once: :class:`MaterialOptions`.

The command builds one from ``--model`` and ``--at-force-n``; the stage
(:func:`deformctl.characterize.read_and_characterize`), the sweep task and the estimators take
it. Which lag is fitted is chosen per object from where its log came from
(:func:`default_lag`), as the preload is.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

from deformctl.errors import UsageError
from deformctl.quantities import AT_FORCE_N
from deformctl.squeeze.flags import LAG_ESTIMATED, LAG_GIVEN

Model = Literal["kv", "hc", "sls", "exp"]
#: The laws (:mod:`deformctl.characterize.laws`), Kelvin–Voigt first: ``auto`` keeps it unless
#: another law's extra parameters are identified and decisively better
#: (:func:`deformctl.characterize.materials.choose`).
MODELS: tuple[Model, ...] = ("kv", "hc", "sls", "exp")
#: ``characterize --model`` choices.
MODEL_CHOICES: tuple[str, ...] = (*MODELS, "auto")


def check_model(model: object) -> str:
    """``model`` when it names a law or ``auto``.

    Raises:
        UsageError: anything else (exit 2).
    """
    if model not in MODEL_CHOICES:
        raise UsageError(f"--model must be one of {', '.join(MODEL_CHOICES)}, got {model!r}")
    return str(model)


#: The ``source`` a squeeze log's object row carries when ``measure`` read a rig recording (and
#: that of arrays given to :func:`deformctl.characterize.arrays.characterize_arrays`).
RIG_SOURCES = ("ros2_bag", "csv", "arrays")


def check_at_force_n(value: object) -> float | None:
    """``--at-force-n`` when it is None or a finite force > 0, N (its rule:
    :data:`deformctl.quantities.AT_FORCE_N`).

    Raises:
        UsageError: anything else (exit 2).
    """
    return AT_FORCE_N.check_optional(value)


@dataclass(frozen=True)
class MaterialOptions:
    """Which material law is fitted and where its deformability is stated.

    Attributes:
        model: ``kv``, ``hc``, ``sls``, ``exp``, or ``auto`` (all four, chosen by
            :func:`deformctl.characterize.materials.choose`).
        at_force_n: the operating force D is the secant stiffness at, N; None: F_w = W/(2μ)
            when the log knows the object's weight and friction, else its median loading force.
            Above an object's peak force it is an error (exit 2).

    Raises:
        UsageError: an unknown model or a force that is not > 0 (exit 2).
    """

    model: str = "auto"
    at_force_n: float | None = None

    def __post_init__(self) -> None:
        check_model(self.model)
        object.__setattr__(self, "at_force_n", check_at_force_n(self.at_force_n))

    def as_dict(self) -> dict[str, Any]:
        """The options, for provenance."""
        return {"model": self.model, "at_force_n": self.at_force_n}


#: The command's defaults.
DEFAULT_MATERIALS = MaterialOptions()


def default_lag(obj: Mapping[str, object] | None) -> float | None:
    """The lag of an object whose log does not choose one: 0 when ``measure`` took a given lag
    out of the force (``force_lag_source`` ``given``: ``--lag-s SECONDS``, the rig's latency;
    none is left), else fitted (None) for rig recordings, 0 for simulated squeezes (the
    simulator's force and position share one clock), 0 for logs that do not say where they came
    from."""
    if obj is not None and obj.get("force_lag_source") == LAG_GIVEN:
        return 0.0
    source = None if obj is None else obj.get("source")
    return None if source in RIG_SOURCES else 0.0


def lag_estimated(obj: Mapping[str, object] | None) -> bool:
    """Whether ``measure`` shifted the object's force by a lag it estimated (``--lag-s auto``,
    ``force_lag_source`` ``auto``): the estimate is the latency less λ/D, so the shift takes λ
    with it and the fit withholds λ (:func:`deformctl.characterize.objectfit.fit_object`)."""
    return obj is not None and obj.get("force_lag_source") == LAG_ESTIMATED


__all__ = [
    "DEFAULT_MATERIALS",
    "MODEL_CHOICES",
    "MaterialOptions",
    "check_at_force_n",
    "default_lag",
    "lag_estimated",
]
