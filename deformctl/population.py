"""Seeded object catalogs: the paper's population and a small golden population for CI.

A *catalog* is the input of ``measure`` and ``lift``: one row per object, in the paper's units at
the edge (cm, N, N/cm, N·s/cm). Its columns, in order, are :data:`CATALOG_COLUMNS`:

==================================  ======  ====================================================
column                              unit    meaning
==================================  ======  ====================================================
``object_id``                       --      unique id, ``<prefix><index>`` zero padded
``size_x_cm``                       cm      box size along the squeeze axis
``size_y_cm``                       cm      box size across the palms
``size_z_cm``                       cm      box height (the lift moves the palms by half of it)
``weight_n``                        N       weight W
``friction_mu``                     --      Coulomb friction coefficient palm/object
``material_stiffness_n_per_cm``     N/cm    the object's true squeeze stiffness (deformability D)
``material_damping_ns_per_cm``      N·s/cm  the object's true squeeze damping (λ)
==================================  ======  ====================================================

The paper (section V.A) trains its network on 73 simulated objects, 40 for training and 33 for
testing, with W about 20-60 N, D about 30-50 N/cm and λ 0-13 N·s/cm (its Table III). The paper's
network has no friction input, so by default every object of a population shares one friction
coefficient: a per-object μ would add variance to L_f that W, D and λ cannot explain. Pass a
``(low, high)`` range to ``friction_mu`` to sample it anyway.

Example:
    >>> cat = make_population(73, seed=0)
    >>> len(cat), cat["object_id"].iloc[0], cat["object_id"].iloc[-1]
    (73, 'P00', 'P72')
    >>> bool(cat["weight_n"].between(20, 60).all())
    True
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pandas as pd

from deformctl.catalog import (
    ARM_COLUMN,
    CATALOG_COLUMNS,
    EXPONENT_COLUMN,
    KELVIN_VOIGT_LAW_VALUES,
    MATERIAL_COLUMNS,
    RELAXATION_COLUMN,
    SIZE_COLUMNS,
)
from deformctl.errors import UsageError
from deformctl.population_options import (
    DEFAULT_FRICTION_MU,
    DEFAULT_GRIP_LAW_MIX,
    GRIP_LAWS,
    PAPER_POPULATION_SIZE,
)
from deformctl.quantities import (
    DAMPING_NS_PER_CM,
    FRICTION_MU,
    SIZE_CM,
    STIFFNESS_EXPONENT,
    STIFFNESS_N_PER_CM,
    WEIGHT_N,
)

#: The largest population one call draws: a catalog of 10^7 objects is 0.7 GB in memory
#: (:data:`BYTES_PER_OBJECT`, measured on 10^5 objects) and about 1 GB of CSV; more is a typo.
MAX_POPULATION_SIZE = 10_000_000
#: Memory per object of a drawn catalog, bytes (``DataFrame.memory_usage(deep=True)`` / n).
BYTES_PER_OBJECT = 70


def check_population_size(n: object, what: str = "population size") -> int:
    """``n`` as a population size: an integer in [1, :data:`MAX_POPULATION_SIZE`].

    Raises:
        UsageError: it is not; ``what`` names it (``-n`` from the CLI), a size above the bound
            with its memory estimate (exit 2).
    """
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
        raise UsageError(f"{what} must be an integer >= 1, got {n!r}")
    if n > MAX_POPULATION_SIZE:
        gib = int(n) * BYTES_PER_OBJECT / (1 << 30)
        raise UsageError(
            f"{what} {int(n)} is above the bound of {MAX_POPULATION_SIZE} objects (it would need "
            f"about {gib:.3g} GiB of memory at {BYTES_PER_OBJECT} bytes per object)"
        )
    return int(n)


Range = tuple[float, float]


def make_population(
    n: int = PAPER_POPULATION_SIZE,
    *,
    seed: int = 0,
    weight_n: Range = (20.0, 60.0),
    deformability_n_per_cm: Range = (30.0, 50.0),
    damping_ns_per_cm: Range = (0.0, 13.0),
    friction_mu: float | Range = DEFAULT_FRICTION_MU,
    size_x_cm: Range = (10.0, 20.0),
    size_y_cm: Range = (10.0, 20.0),
    size_z_cm: Range = (8.0, 20.0),
    id_prefix: str = "P",
) -> pd.DataFrame:
    """Sample a catalog of ``n`` box-shaped objects, uniformly and independently within ranges.

    Every attribute is drawn from ``numpy.random.default_rng(seed)`` in a fixed order (weight,
    deformability, damping, friction, sizes x, y, z), so the same arguments give the same catalog
    on every machine. The defaults are the paper's population (section V.A, Table III); the sizes
    are a few to 20 cm like the paper's Table I objects.

    Args:
        n: number of objects (>= 1); the paper's 73 (:data:`PAPER_POPULATION_SIZE`) by default.
        seed: seed of the generator (default 0, as ``deformctl population``).
        weight_n: range of the weight W, N.
        deformability_n_per_cm: range of D, N/cm, written to ``material_stiffness_n_per_cm``.
        damping_ns_per_cm: range of λ, N·s/cm, written to ``material_damping_ns_per_cm``.
        friction_mu: one μ for every object (default 0.5), or a ``(low, high)`` range to sample.
        size_x_cm, size_y_cm, size_z_cm: ranges of the box sizes, cm.
        Each end of each range is within its quantity's bounds (:mod:`deformctl.quantities`, the
        catalog's: a catalog written here is one every command reads).
        id_prefix: prefix of the object ids; ids are ``prefix`` + zero-padded index.

    Returns:
        The catalog, ``n`` rows, columns :data:`CATALOG_COLUMNS` (floats are float64).

    Raises:
        UsageError: ``n`` < 1, or a range that is empty, reversed, non-finite or out of bounds.
    """
    n = check_population_size(n)
    w = WEIGHT_N.check_range(weight_n)
    d = STIFFNESS_N_PER_CM.check_range(deformability_n_per_cm)
    lam = DAMPING_NS_PER_CM.check_range(damping_ns_per_cm)
    if isinstance(friction_mu, tuple | list):
        mu: Range = FRICTION_MU.check_range(friction_mu)
    else:
        mu = FRICTION_MU.check_range((friction_mu, friction_mu))
    sizes = [
        SIZE_CM.check_range(rng_, label=name)
        for name, rng_ in zip(SIZE_COLUMNS, (size_x_cm, size_y_cm, size_z_cm), strict=True)
    ]

    rng = np.random.default_rng(seed)

    def draw(bounds: Range) -> np.ndarray:
        return rng.uniform(bounds[0], bounds[1], size=n)

    weight = draw(w)
    stiffness = draw(d)
    damping = draw(lam)
    mu_values = draw(mu) if mu[0] != mu[1] else np.full(n, mu[0])
    sx, sy, sz = (draw(b) for b in sizes)

    width = max(2, len(str(n - 1)))
    ids = [f"{id_prefix}{i:0{width}d}" for i in range(n)]
    values = (ids, sx, sy, sz, weight, mu_values, stiffness, damping)  # CATALOG_COLUMNS order
    return pd.DataFrame(dict(zip(CATALOG_COLUMNS, values, strict=True)))


def paper_population(seed: int = 0) -> pd.DataFrame:
    """The paper's population: :data:`PAPER_POPULATION_SIZE` (73) objects with the default ranges.

    The first :data:`PAPER_TRAIN_SIZE` (40) rows are not special: ``train`` draws its own seeded
    40/33 split.
    """
    return make_population(PAPER_POPULATION_SIZE, seed=seed)


#: The golden population (CI dataset regression): 8 fixed objects spanning the paper's ranges.
#: Written out literally (not sampled) so that a change of the sampler never moves the golden
#: numbers. Corners and the centre of the (W, D, λ) box, plus two low-friction / small objects.
_GOLDEN_ROWS: tuple[tuple[str, float, float, float, float, float, float, float], ...] = (
    # object_id, x cm, y cm, z cm, W N, mu, D N/cm, λ N·s/cm
    ("G0", 12.0, 12.0, 10.0, 20.0, 0.5, 30.0, 0.0),
    ("G1", 15.0, 14.0, 12.0, 60.0, 0.5, 30.0, 13.0),
    ("G2", 14.0, 16.0, 11.0, 20.0, 0.5, 50.0, 13.0),
    ("G3", 18.0, 18.0, 15.0, 60.0, 0.5, 50.0, 0.0),
    ("G4", 15.0, 15.0, 12.0, 40.0, 0.5, 40.0, 6.5),
    ("G5", 11.0, 13.0, 9.0, 30.0, 0.5, 35.0, 3.0),
    ("G6", 16.0, 12.0, 14.0, 50.0, 0.4, 45.0, 10.0),
    ("G7", 10.0, 10.0, 8.0, 25.0, 0.7, 32.0, 1.0),
)


def golden_population() -> pd.DataFrame:
    """The fixed 8-object golden population used by the CI dataset regression.

    Returns:
        The catalog, 8 rows, columns :data:`CATALOG_COLUMNS`; identical on every call.
    """
    return pd.DataFrame(
        [list(row) for row in _GOLDEN_ROWS],
        columns=list(CATALOG_COLUMNS),
    ).astype(dict.fromkeys(CATALOG_COLUMNS[1:], "float64"))


def paper_objects() -> pd.DataFrame:
    """The seed paper's four Table I objects A–D (sponge, cotton, sand, water), as bundled.

    Read from the package data ``deformctl.datasets`` (``datasets/paper/objects.csv`` in a
    checkout), so it works from an installed wheel; the material values are Table II's D and λ.

    Returns:
        The catalog, 4 rows, with the file's extra columns (``name``, ``interior``).
    """
    from deformctl.artifacts import read_catalog
    from deformctl.resources import dataset_path

    return read_catalog(dataset_path("paper", "objects.csv"))


#: The bundled grip model's ranges (``make model``, ``population --grip``): what robots meet,
#: wider than the paper's population in every attribute and with a friction range.
GRIP_WEIGHT_N: Range = (0.5, 80.0)
GRIP_DEFORMABILITY_N_PER_CM: Range = (5.0, 60.0)
GRIP_DAMPING_NS_PER_CM: Range = (0.0, 15.0)
GRIP_FRICTION_MU: Range = (0.2, 1.0)
#: λ is drawn log-uniformly shifted by this much (N·s/cm): (λ + λ0) is log-uniform on
#: [λ0, 15 + λ0], so λ = 0 is reachable and each decade of λ above λ0 gets a similar share.
GRIP_DAMPING_SHIFT_NS_PER_CM = 0.01
#: The grippability rule: an object whose compression at F_w, F_w / D, exceeds this fraction of
#: its size along the squeeze axis cannot be gripped (the palms would squeeze it flat before it
#: lifts; L_f is up to about 2 F_w, so the compression at L_f is then up to half its width).
GRIP_MAX_STRAIN_AT_F_W = 0.25


def grip_strain_at_f_w(catalog: pd.DataFrame) -> np.ndarray:
    """``[n]`` compression at F_w = W / (2 μ) over the squeeze-axis size: F_w / (D · size_x).

    D is the catalog's ``material_stiffness_n_per_cm`` (N/cm), size_x ``size_x_cm``.
    """
    from deformctl.physics import rigid_grip_force_n

    f_w = rigid_grip_force_n(
        catalog["weight_n"].to_numpy(dtype=np.float64),
        catalog["friction_mu"].to_numpy(dtype=np.float64),
    )
    d = catalog[MATERIAL_COLUMNS[0]].to_numpy(dtype=np.float64)
    return np.asarray(f_w / (d * catalog[SIZE_COLUMNS[0]].to_numpy(dtype=np.float64)))


#: The Hunt–Crossley objects' stiffness exponent n, uniform: from linear to the stiffest law a
#: soft object shows (:data:`deformctl.quantities.STIFFNESS_EXPONENT`, ``characterize``'s bounds).
#: Their D and λ are the grip ranges' at F_w (the secant stiffness and equivalent damping there).
GRIP_HC_EXPONENT: Range = (STIFFNESS_EXPONENT.low, STIFFNESS_EXPONENT.high)
#: The standard linear solids' arm spring over their relaxed spring, k2 / D, log-uniform: from a
#: quarter to three times (the solid stiffens 1.25-4 times at rates fast against 1/τ).
GRIP_SLS_ARM_RATIO: Range = (0.25, 3.0)
#: The standard linear solids' relaxation time τ, s, log-uniform: what ``measure --sim``'s
#: default squeezes (0.25 s ramp, 1 s hold) let ``characterize --model sls`` recover within 3 %
#: (below about 0.2 s its fit window cannot resolve τ; above about 1.5 s the 1 s hold cannot tell
#: k2 from D; ``make sls-check``). Their D is the grip range's (the relaxed spring) and λ is 0
#: (the Zener solid itself, what ``--model sls`` fits).
GRIP_SLS_RELAXATION_TIME_S: Range = (0.25, 1.0)


def parse_law_mix(text: str, *, label: str = "--laws") -> dict[str, float]:
    """A law mix ``kv=1,hc=1,sls=1`` (weights, any scale; a law alone means weight 1) as shares
    that sum to 1, in :data:`GRIP_LAWS` order, laws of weight 0 left out.

    Raises:
        UsageError: an unknown law, a weight that is not a finite number >= 0, a law given twice,
            or no weight above 0; naming ``label`` and the known laws (exit 2).
    """
    weights: dict[str, float] = {}
    known = ", ".join(GRIP_LAWS)
    for part in str(text).split(","):
        name, _, value = part.strip().partition("=")
        name = name.strip()
        if name not in GRIP_LAWS:
            raise UsageError(f"{label}: unknown law {name!r} in {text!r} (known: {known})")
        if name in weights:
            raise UsageError(f"{label}: law {name!r} given twice in {text!r}")
        try:
            weight = float(value) if value.strip() else 1.0
        except ValueError:
            weight = math.nan
        if not (math.isfinite(weight) and weight >= 0):
            raise UsageError(f"{label}: the weight of {name} must be a number >= 0, got {value!r}")
        weights[name] = weight
    total = sum(weights.values())
    if not total > 0:
        raise UsageError(f"{label}: no law has a weight above 0 in {text!r} (known: {known})")
    return {law: weights[law] / total for law in GRIP_LAWS if weights.get(law, 0.0) > 0}


def grip_law_spec(laws: str | dict[str, float] = DEFAULT_GRIP_LAW_MIX) -> dict[str, object]:
    """The grip population's law mix and every range, JSON-safe (plain floats, lists), for a
    model's metadata or ``train --note``: ``{"mix": {law: share}, "common": {column: [low,
    high, draw]}, "laws": {law: {column: [low, high, draw]}}}`` (draw: ``log-uniform``,
    ``uniform``, ``log-uniform-shifted`` for λ, ``fixed``), only the laws of the mix.
    """
    mix = parse_law_mix(laws) if isinstance(laws, str) else parse_law_mix(_mix_text(laws))

    def span(bounds: Range, draw: str) -> list[object]:
        return [float(bounds[0]), float(bounds[1]), draw]

    d = span(GRIP_DEFORMABILITY_N_PER_CM, "log-uniform")
    lam = span(GRIP_DAMPING_NS_PER_CM, f"log-uniform-shifted {GRIP_DAMPING_SHIFT_NS_PER_CM:g}")
    per_law: dict[str, dict[str, list[object]]] = {
        "kv": {MATERIAL_COLUMNS[0]: d, MATERIAL_COLUMNS[1]: lam},
        "hc": {
            MATERIAL_COLUMNS[0]: d,
            MATERIAL_COLUMNS[1]: lam,
            EXPONENT_COLUMN: span(GRIP_HC_EXPONENT, "uniform"),
        },
        "sls": {
            MATERIAL_COLUMNS[0]: d,
            MATERIAL_COLUMNS[1]: span((0.0, 0.0), "fixed"),
            "arm_ratio_k2_over_d": span(GRIP_SLS_ARM_RATIO, "log-uniform"),
            RELAXATION_COLUMN: span(GRIP_SLS_RELAXATION_TIME_S, "log-uniform"),
        },
    }
    return {
        "mix": {law: float(share) for law, share in mix.items()},
        "common": {
            "weight_n": span(GRIP_WEIGHT_N, "log-uniform"),
            "friction_mu": span(GRIP_FRICTION_MU, "uniform"),
            **{
                column: span(bounds, "uniform")
                for column, bounds in zip(
                    SIZE_COLUMNS, ((10.0, 20.0), (10.0, 20.0), (8.0, 20.0)), strict=True
                )
            },
            "max_strain_at_f_w": float(GRIP_MAX_STRAIN_AT_F_W),
        },
        "laws": {law: per_law[law] for law in mix},
    }


def _mix_text(mix: dict[str, float]) -> str:
    return ",".join(f"{law}={weight!r}" for law, weight in mix.items())


def catalog_laws(catalog: pd.DataFrame) -> np.ndarray:
    """``[n]`` each object's material law, ``kv``, ``hc`` or ``sls``: Hunt–Crossley when its
    ``material_stiffness_exponent`` is above 1, a standard linear solid when its
    ``material_arm_stiffness_n_per_cm`` is above 0 (absent columns: Kelvin–Voigt)."""
    n = len(catalog)

    def column(name: str, absent: float) -> np.ndarray:
        if name not in catalog.columns:
            return np.full(n, absent)
        return np.asarray(pd.to_numeric(catalog[name], errors="coerce").fillna(absent))

    laws = np.full(n, "kv", dtype=object)
    kv = KELVIN_VOIGT_LAW_VALUES
    laws[column(EXPONENT_COLUMN, kv[EXPONENT_COLUMN]) > 1.0] = "hc"
    laws[column(ARM_COLUMN, kv[ARM_COLUMN]) > 0.0] = "sls"
    return laws


def grip_population(
    n: int, *, seed: int, id_prefix: str = "P", laws: str = DEFAULT_GRIP_LAW_MIX
) -> pd.DataFrame:
    """The bundled grip model's population: ``n`` grippable objects over the grip ranges.

    Drawn from ``numpy.random.default_rng(seed)`` in batches of ``n`` candidates (each batch
    in a fixed order: W, D, λ, μ, sizes x, y, z; then, unless the mix is Kelvin–Voigt alone,
    the law, n, k2 / D and τ), keeping those that can be gripped
    (:data:`GRIP_MAX_STRAIN_AT_F_W`), until ``n`` are kept; ids are numbered in the order kept.
    The law:

    * W log-uniform on :data:`GRIP_WEIGHT_N` (0.5-80 N), D log-uniform on
      :data:`GRIP_DEFORMABILITY_N_PER_CM` (5-60 N/cm): each decade counts alike, so light and
      soft objects are not crowded out by the heavy ones;
    * λ with (λ + 0.01) log-uniform on [0.01, 15.01] N·s/cm (:data:`GRIP_DAMPING_NS_PER_CM`);
    * μ uniform on :data:`GRIP_FRICTION_MU` (0.2-1.0);
    * sizes as :func:`make_population`'s defaults (x, y 10-20 cm, z 8-20 cm);
    * the material law by ``laws`` (:func:`parse_law_mix`; default Kelvin–Voigt alone, the
      catalog of before, bit for bit): Hunt–Crossley objects take n uniform on
      :data:`GRIP_HC_EXPONENT` (their D and λ stated at F_w), standard linear solids k2 / D
      log-uniform on :data:`GRIP_SLS_ARM_RATIO`, τ log-uniform on
      :data:`GRIP_SLS_RELAXATION_TIME_S` and λ = 0. A mix with another law than Kelvin–Voigt
      adds the columns ``material_stiffness_exponent`` (1 but for Hunt–Crossley),
      ``material_arm_stiffness_n_per_cm`` (0 but for the standard linear solid) and
      ``material_relaxation_time_s`` (empty but for it); :func:`grip_law_spec` states it all.

    Raises:
        UsageError: ``n`` < 1, or a bad ``laws``.
    """
    n = check_population_size(n)
    mix = parse_law_mix(laws)
    mixed = set(mix) != {"kv"}
    rng = np.random.default_rng(seed)
    shift = GRIP_DAMPING_SHIFT_NS_PER_CM

    def log_uniform(bounds: Range, size: int) -> np.ndarray:
        return np.exp(rng.uniform(math.log(bounds[0]), math.log(bounds[1]), size=size))

    kept: list[pd.DataFrame] = []
    count = 0
    while count < n:
        weight = log_uniform(GRIP_WEIGHT_N, n)
        stiffness = log_uniform(GRIP_DEFORMABILITY_N_PER_CM, n)
        damping = log_uniform((shift, GRIP_DAMPING_NS_PER_CM[1] + shift), n) - shift
        damping = np.clip(damping, *GRIP_DAMPING_NS_PER_CM)
        mu = rng.uniform(*GRIP_FRICTION_MU, size=n)
        sx, sy, sz = (
            rng.uniform(lo, hi, size=n) for lo, hi in ((10.0, 20.0),) * 2 + ((8.0, 20.0),)
        )
        batch = pd.DataFrame(
            dict(
                zip(
                    CATALOG_COLUMNS,
                    ([""] * n, sx, sy, sz, weight, mu, stiffness, damping),
                    strict=True,
                )
            )
        )
        if mixed:
            _draw_laws(batch, mix, rng, log_uniform)
        batch = batch[grip_strain_at_f_w(batch) <= GRIP_MAX_STRAIN_AT_F_W]
        kept.append(batch)
        count += len(batch)
    out = pd.concat(kept, ignore_index=True).iloc[:n].reset_index(drop=True)
    width = max(2, len(str(n - 1)))
    out["object_id"] = [f"{id_prefix}{i:0{width}d}" for i in range(n)]
    return out


def _draw_laws(
    batch: pd.DataFrame,
    mix: dict[str, float],
    rng: np.random.Generator,
    log_uniform: Callable[[Range, int], np.ndarray],
) -> None:
    """Draw each candidate's law and its parameters into ``batch`` (see :func:`grip_population`)."""
    n = len(batch)
    names = list(mix)
    law = np.asarray(names, dtype=object)[rng.choice(len(names), size=n, p=list(mix.values()))]
    exponent = rng.uniform(*GRIP_HC_EXPONENT, size=n)
    ratio = log_uniform(GRIP_SLS_ARM_RATIO, n)
    tau = log_uniform(GRIP_SLS_RELAXATION_TIME_S, n)
    hc, sls = law == "hc", law == "sls"
    d = batch[MATERIAL_COLUMNS[0]].to_numpy(dtype=np.float64)
    batch[MATERIAL_COLUMNS[1]] = np.where(sls, 0.0, batch[MATERIAL_COLUMNS[1]])
    kv = KELVIN_VOIGT_LAW_VALUES
    batch[EXPONENT_COLUMN] = np.where(hc, exponent, kv[EXPONENT_COLUMN])
    batch[ARM_COLUMN] = np.where(sls, ratio * d, kv[ARM_COLUMN])
    batch[RELAXATION_COLUMN] = np.where(sls, tau, kv[RELAXATION_COLUMN])
