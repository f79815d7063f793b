"""The options of ``characterize``, checked once: :class:`FitOptions` and :class:`QualityPolicy`.

The command builds them from its flags; the stage
(:func:`deformctl.characterize.read_and_characterize`,
:func:`~deformctl.characterize.characterize_file`), the sweep task
(:class:`~deformctl.characterize.CharacterizeTask`) and the estimators' checks take them. The
window's rule is :data:`deformctl.quantities.WINDOW_S`; the method's and the preload's are here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

from deformctl.characterize.quality import check_policy
from deformctl.errors import UsageError
from deformctl.quantities import WINDOW_S

Method = Literal["lsq", "paper"]
METHODS: tuple[str, ...] = ("lsq", "paper")
Preload = Literal["fit", "zero"]
PRELOADS: tuple[str, ...] = ("fit", "zero")
#: The material models ``characterize --model`` selects by name. ``kv``: Kelvin–Voigt,
#: ``f = D d + λ d'`` (``+ F0`` with a preload), fitted by ``fit_lsq`` or ``fit_paper``.
MODELS: tuple[str, ...] = ("kv",)
DEFAULT_MODEL = "kv"


def check_method(method: object) -> Method:
    """``method`` when it is ``lsq`` or ``paper``.

    Raises:
        UsageError: another method (exit 2).
    """
    if method not in METHODS:
        raise UsageError(f"--method must be lsq or paper, got {method!r}")
    return method  # type: ignore[return-value]


def check_preload(preload: object) -> Preload:
    """``preload`` when it is ``fit`` or ``zero``.

    Raises:
        UsageError: another value (exit 2).
    """
    if preload not in PRELOADS:
        raise UsageError(f"--preload must be fit or zero, got {preload!r}")
    return preload  # type: ignore[return-value]


def check_model(model: object) -> str:
    """``model`` when it names a model of :data:`MODELS`.

    Raises:
        UsageError: an unknown model (exit 2).
    """
    if model not in MODELS:
        raise UsageError(f"--model must be one of {', '.join(MODELS)}, got {model!r}")
    return str(model)


def check_paper_options(method: str, preload: object, constrain_damping: bool) -> None:
    """The paper estimator fits neither a preload nor a damping bound.

    Raises:
        UsageError: ``method="paper"`` with ``preload="fit"`` or ``constrain_damping`` (exit 2).
    """
    if method == "paper" and (preload == "fit" or constrain_damping):
        raise UsageError("the paper estimator has no preload or damping bound; use --method lsq")


@dataclass(frozen=True)
class FitOptions:
    """How each object is fitted.

    Attributes:
        method: ``lsq`` (the joint least-squares fit, the default) or ``paper`` (the paper's
            per-sample ratios).
        window_s: the Savitzky–Golay window, s; None: per object from the position sample rate
            its log stores (:func:`deformctl.characterize.default_window_s`).
        preload: lsq: ``fit`` (an intercept F0) or ``zero`` for every object; None: per object,
            ``fit`` for a rig recording, ``zero`` for a simulated squeeze
            (:func:`deformctl.characterize.default_preload`).
        constrain_damping: lsq: fit with λ >= 0.
        model: the material model (:data:`MODELS`; ``kv``, Kelvin–Voigt).

    Raises:
        UsageError: an unknown method, preload or model, a window outside its rule, or a preload or
            damping bound with the paper method (exit 2).
    """

    method: Method = "lsq"
    window_s: float | None = None
    preload: Preload | None = None
    constrain_damping: bool = False
    model: str = DEFAULT_MODEL

    def __post_init__(self) -> None:
        check_method(self.method)
        check_model(self.model)
        WINDOW_S.check_optional(self.window_s)
        if self.preload is not None:
            check_preload(self.preload)
        check_paper_options(self.method, self.preload, self.constrain_damping)

    def as_dict(self) -> dict[str, Any]:
        """The options as given, for provenance (``*_option``: None means per object).

        ``model`` only when it is not the default, so that directories written before it
        existed stay resumable (their fingerprints hold these settings).
        """
        out: dict[str, Any] = {
            "method": self.method,
            "window_s_option": self.window_s,
            "preload_option": self.preload,
            "constrain_damping": self.constrain_damping,
        }
        if self.model != DEFAULT_MODEL:
            out["model"] = self.model
        return out


@dataclass(frozen=True)
class QualityPolicy:
    """What happens to flagged objects (:mod:`deformctl.characterize.quality`).

    Attributes:
        strict: any flag is an error (exit 65, nothing written).
        allow_flagged: write objects with negative D (flagged) instead of refusing them.

    Raises:
        UsageError: both (exit 2).
    """

    strict: bool = False
    allow_flagged: bool = False

    def __post_init__(self) -> None:
        check_policy(self.strict, self.allow_flagged)

    def as_dict(self) -> dict[str, Any]:
        """The policy, for provenance."""
        return {"strict": self.strict, "allow_flagged": self.allow_flagged}


#: The command's defaults, for signatures.
DEFAULT_FIT = FitOptions()
DEFAULT_POLICY = QualityPolicy()
