"""``deformctl population``: a seeded catalog of simulated objects within stated ranges."""

from __future__ import annotations

import typer

from deformctl.cli._common import translate_errors
from deformctl.cli._options import Force
from deformctl.errors import UsageError
from deformctl.population_options import (
    DEFAULT_FRICTION_MU,
    DEFAULT_GRIP_LAW_MIX,
    EQUAL_GRIP_LAW_MIX,
    PAPER_POPULATION_SIZE,
)

#: The columns whose ranges are options (``--weight-n`` for ``weight_n``, ...).
RANGE_COLUMNS = ("weight_n", "deformability_n_per_cm", "damping_ns_per_cm", "friction_mu")


def parse_range(option: str, text: str) -> tuple[float, float]:
    """Parse ``LOW,HIGH`` (or a single number meaning LOW = HIGH) into a pair of floats."""
    parts = [p.strip() for p in text.split(",")]
    if len(parts) == 1:
        parts = parts * 2
    try:
        low, high = (float(p) for p in parts)
    except ValueError:
        raise UsageError(f"{option} takes LOW,HIGH or one number, got {text!r}") from None
    return (low, high)


@translate_errors
def population(
    output: str = typer.Option(
        ..., "-o", "--output", metavar="catalog.csv", help="Catalog to write (.csv or Parquet)."
    ),
    n: int = typer.Option(PAPER_POPULATION_SIZE, "-n", "--n", help="Number of objects."),
    seed: int = typer.Option(0, "--seed", help="Seed of the random draws.", min=0),
    weight_n: str = typer.Option("20,60", "--weight-n", metavar="LOW,HIGH", help="W range, N."),
    deformability_n_per_cm: str = typer.Option(
        "30,50", "--deformability-n-per-cm", metavar="LOW,HIGH", help="D range, N/cm."
    ),
    damping_ns_per_cm: str = typer.Option(
        "0,13", "--damping-ns-per-cm", metavar="LOW,HIGH", help="λ range, N·s/cm."
    ),
    friction_mu: str = typer.Option(
        str(DEFAULT_FRICTION_MU),
        "--friction-mu",
        metavar="MU|LOW,HIGH",
        help="One μ for every object, or a range to sample.",
    ),
    id_prefix: str = typer.Option("P", "--id-prefix", help="Prefix of the object ids."),
    golden: bool = typer.Option(
        False, "--golden", help="Write the fixed 8-object golden population (ignores the ranges)."
    ),
    paper: bool = typer.Option(
        False,
        "--paper",
        help="Write the paper's four Table I objects A-D with Table II's D and λ (the bundled "
        "datasets/paper/objects.csv; ignores the ranges).",
    ),
    grip: bool = typer.Option(
        False,
        "--grip",
        help="Write -n grippable objects of the bundled grip model's law (W 0.5-80 N and D "
        "5-60 N/cm log-uniform, λ 0-15 N·s/cm, μ 0.2-1.0; ignores the ranges).",
    ),
    laws: str = typer.Option(
        DEFAULT_GRIP_LAW_MIX,
        "--laws",
        metavar="LAW=WEIGHT,...",
        help="With --grip: the material laws' mix, weights of kv (Kelvin–Voigt), hc "
        "(Hunt–Crossley, n 1-3) and sls (standard linear solid: k2/D 0.25-3, τ 0.25-1 s, λ 0), "
        f"e.g. {EQUAL_GRIP_LAW_MIX}. The default is Kelvin–Voigt alone.",
    ),
    force: Force = False,
) -> None:
    """Write a seeded catalog of objects with W, D, λ drawn uniformly from stated ranges.

    The defaults are the paper's population: 73 objects, W 20-60 N, D 30-50 N/cm,
    λ 0-13 N·s/cm, μ = 0.5 for all (the paper's network has no friction input). The catalog
    carries the simulator's ground truth in material_stiffness_n_per_cm and
    material_damping_ns_per_cm.

    --paper writes the paper's four Table I objects instead, --golden the CI population,
    --grip the population of the bundled grip model (`make model`): W and D log-uniform, λ with
    (λ + 0.01) log-uniform, μ uniform, and only objects whose compression at F_w = W / (2 μ) is
    at most a quarter of their size along the squeeze axis (F_w / D <= 0.25 size_x). With
    --laws it also draws each object's material law (Hunt–Crossley: n uniform in [1, 3], D and
    λ stated at F_w; standard linear solid: D its relaxed spring, k2/D log-uniform in
    [0.25, 3], τ log-uniform in [0.25, 1] s, λ = 0); the catalog's provenance records the mix
    and every range.

    Example: deformctl population -n 73 --seed 0 -o population.csv
    """
    from deformctl.artifacts import Provenance, write_catalog
    from deformctl.population import (
        check_population_size,
        golden_population,
        grip_law_spec,
        grip_population,
        make_population,
        paper_objects,
    )

    check_population_size(n, "-n")  # before anything: exit 2 naming the flag
    chosen = [
        flag for flag, on in (("--golden", golden), ("--paper", paper), ("--grip", grip)) if on
    ]
    if len(chosen) > 1:
        raise UsageError(f"give one of --golden, --paper and --grip, not {' and '.join(chosen)}")
    if laws != DEFAULT_GRIP_LAW_MIX and not grip:
        raise UsageError("--laws draws the material laws of --grip's population: give --grip")
    law_spec = grip_law_spec(laws) if grip else None  # before anything: a bad mix is exit 2
    if grip:
        if n < 1:
            raise UsageError(f"-n must be >= 1, got {n}")
        catalog = grip_population(n, seed=seed, id_prefix=id_prefix, laws=laws)
    elif golden:
        catalog = golden_population()
    elif paper:
        catalog = paper_objects()
    else:
        mu_low, mu_high = parse_range("--friction-mu", friction_mu)
        try:
            catalog = make_population(
                n,
                seed=seed,
                weight_n=parse_range("--weight-n", weight_n),
                deformability_n_per_cm=parse_range(
                    "--deformability-n-per-cm", deformability_n_per_cm
                ),
                damping_ns_per_cm=parse_range("--damping-ns-per-cm", damping_ns_per_cm),
                friction_mu=mu_low if mu_low == mu_high else (mu_low, mu_high),
                id_prefix=id_prefix,
            )
        except UsageError as err:  # the library names the column: name the flag too
            column = err.message.split(" ", 1)[0]
            if column in RANGE_COLUMNS:
                err.message = f"--{column.replace('_', '-')}: {err.message}"
            raise
    provenance = Provenance.from_invocation(
        seed=None if golden or paper else seed,
        settings={
            "golden": golden,
            "paper": paper,
            "grip": grip,
            "n": len(catalog),
            **({"laws": law_spec} if law_spec is not None and laws != DEFAULT_GRIP_LAW_MIX else {}),
        },
    )
    write_catalog(catalog, output, provenance=provenance, force=force)
    typer.echo(f"wrote {len(catalog)} objects to {output}", err=True)
