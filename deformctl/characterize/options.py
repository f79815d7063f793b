"""The options of ``characterize``, checked once: :class:`FitOptions` (with its
:class:`~deformctl.characterize.material_options.MaterialOptions`) and :class:`QualityPolicy`.

The command builds them from its flags; the stage
(:func:`deformctl.characterize.read_and_characterize`,
:func:`~deformctl.characterize.characterize_file`), the sweep task
(:class:`~deformctl.characterize.CharacterizeTask`) and the estimators' checks take them. The
window's rule is :data:`deformctl.quantities.WINDOW_S`, the operating force's
:data:`deformctl.quantities.AT_FORCE_N`, the law's :func:`deformctl.characterize.laws.check_model`;
the method's and the preload's are here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

from deformctl.characterize.material_options import DEFAULT_MATERIALS, MaterialOptions
from deformctl.characterize.quality import check_policy
from deformctl.errors import UsageError
from deformctl.quantities import WINDOW_S

Method = Literal["lsq", "paper"]
METHODS: tuple[str, ...] = ("lsq", "paper")
Preload = Literal["fit", "zero"]
PRELOADS: tuple[str, ...] = ("fit", "zero")


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


def check_paper_options(method: str, preload: object) -> None:
    """The paper estimator fits no preload.

    Raises:
        UsageError: ``method="paper"`` with ``preload="fit"`` (exit 2).
    """
    if method == "paper" and preload == "fit":
        raise UsageError("the paper estimator has no preload; use --method lsq")


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
        materials: lsq: the material law (``--model``) and the operating force D is stated at
            (``--at-force-n``), :class:`~deformctl.characterize.material_options.MaterialOptions`.

    Raises:
        UsageError: an unknown method or preload, a window outside its rule, a preload with the
            paper method, or materials that are not a ``MaterialOptions`` (exit 2;
            the law and the force are checked when the ``MaterialOptions`` is built).
    """

    method: Method = "lsq"
    window_s: float | None = None
    preload: Preload | None = None
    materials: MaterialOptions = DEFAULT_MATERIALS

    def __post_init__(self) -> None:
        check_method(self.method)
        if not isinstance(self.materials, MaterialOptions):
            raise UsageError(
                f"materials must be a MaterialOptions (--model, --at-force-n), got "
                f"{self.materials!r}"
            )
        WINDOW_S.check_optional(self.window_s)
        if self.preload is not None:
            check_preload(self.preload)
        check_paper_options(self.method, self.preload)

    def as_dict(self) -> dict[str, Any]:
        """The options as given, for provenance and a sweep's fingerprint (``*_option``: None
        means per object; ``model`` and ``at_force_n`` from :attr:`materials`)."""
        return {
            "method": self.method,
            "window_s_option": self.window_s,
            "preload_option": self.preload,
            **self.materials.as_dict(),
        }


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
