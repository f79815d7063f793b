"""The simulation model: settings, lattice + palms + table assembled for the implicit integrator.

**Integrator.** Linearised backward Euler with the tangent frozen at the rest configuration::

    (M + dt C + dt^2 K) dv = dt (f(x, v) + f_ext - dt K v) + J^T Lambda

with ``f`` the exact nonlinear element force and ``K``, ``C`` the lattice stiffness and damping
matrices at rest (``C`` from the element dampers ``c_e`` as ``K`` from the springs ``k_e``, see
:mod:`deformctl.sim.lattice`). With the linear springs this is backward Euler, stable for any
stiffness, damping and step; with the geometrically exact springs (default) it is one Newton
iteration of it. ``A`` never changes, so its solver is built once per model, and nothing dense of
size ``N x N`` is built. The model's memory is estimated from the particle counts before anything
is built and refused above ``SimSettings.memory_budget_gib``. ``integrator="bdf2"`` is linearised
BDF2 (second order, the same single solve with ``h = 2 dt / 3``).

**Solver** (``SimSettings.solver``, ``"auto"`` by default): **direct** up to ``direct_max_dofs``
DOFs, ``A = L D L^T`` in nested-dissection order (:mod:`deformctl.sim.solver`), contacts from
exact columns ``A^-1 e_d``; **iterative** above, CG preconditioned by one geometric-multigrid
V-cycle (:mod:`deformctl.sim.multigrid`, :mod:`deformctl.sim.stencil`), warm-started from the
last steps' velocity changes, with contacts as fixed DOFs. The step's row loops visit only the
rows that can act (``ROW_MARGIN_FRACTION``) and a table row predicted to release is released
first (``PREDICT_RELEASE``).

The step (``dt = 1 ms``) is chosen for accuracy, not stability: it resolves the lift profile's
50 ms jerk ramps. Contacts are velocity-level constraints (:mod:`deformctl.sim.step`) with
Coulomb friction that sticks exactly inside the cone. Each palm is rigid and flat; its face
layer is bonded to it along x and moves as one rigid patch along z, sticking or sliding.

The measurements behind each choice (solver crossover, fill, CG iterations, step and lattice
convergence) are in docs/performance.md; the ``paper`` preset's model options
(``palm_layer="surface"``, ``shear_damping_ratio``, ``min_shear_retardation_s``, BDF2) in
docs/explanation/presets.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Literal

import numpy as np
import scipy.sparse

from deformctl.arraytypes import FloatArray, IntArray
from deformctl.errors import UsageError
from deformctl.quantities import (
    ALPHA_CM,
    CG_TOLERANCE_M_S,
    DT_S,
    GRIP_RAMP_S,
    GRIP_SETTLE_S,
    MAX_SQUEEZE_STRAIN,
    MEMORY_BUDGET_GIB,
    MIN_SHEAR_RETARDATION_S,
    PALM_MASS_KG,
    PARTICLES_PER_SIDE,
    SHEAR_DAMPING_RATIO,
    TABLE_MU,
)
from deformctl.sim.hunt_crossley import hc_law, spec_elements
from deformctl.sim.lattice import (
    Lattice,
    build_lattice,
    lattice_factor,
    palm_dof_map,
    particles_per_axis,
    reduced_stiffness,
)
from deformctl.sim.multigrid import Hierarchy, build_hierarchy
from deformctl.sim.objects import ObjectSpec
from deformctl.sim.sls import implicit_damping, maxwell_arms, unloaded
from deformctl.sim.solver import LDLFactor, estimate_factor_entries, ldl_columns
from deformctl.sim.statics import resting_state, unit_squeeze_stiffness_n_per_m
from deformctl.sim.stencil import build_stencil
from deformctl.sim.step import (
    N_REC,
    Body,
    Contacts,
    DirectSolver,
    Drive,
    ElementRuns,
    HuntCrossley,
    IterativeSolver,
    Maxwell,
    Palms,
    element_runs,
    integrate,
    integrate_iterative,
    with_scratch,
)
from deformctl.units import CM, GRAVITY_M_S2

#: velocity changes the iterative solver's warm start combines
#: (:func:`deformctl.sim.step.iterative._warm_start`).
#: CG iterations per solve, one lift attempt of the 10 cm cube at 8^3 / 16^3 / 21^3: linear
#: extrapolation of two 1.24 / 1.97 / 2.47; least squares over 2: 0.63 / 1.06 / 1.47; over 3:
#: 0.51 / 0.93 / 1.23; over 4: 0.47 / 0.88 / 1.16, over 6: 0.43 / - / 1.06 (3 is the fastest:
#: each kept vector costs two passes over the DOFs per step). Since the coarse levels also fix
#: what the fine level fixes (fewer iterations), at 16^3 per step: over 3 0.64, over 4 0.61,
#: over 5 0.59, over 8 0.54 (a scratch variant of the warm start; still not worth the passes)
WARM_HISTORY = 3  # step.iterative._warm_start takes at most 3
#: the error a carried product ``A dv`` may have, as a fraction of the CG tolerance, before the
#: iterative solver forms it again (:func:`deformctl.sim.step.iterative.integrate_iterative`):
#: CG's stopping test then holds for the true residual within 1 %.
PRODUCT_CARRY_FRACTION = 0.01
#: the gap, as a fraction of the lattice's shortest element, beyond which the iterative solver's
#: row loops leave out an inactive table or palm-plane row until the lattice moves
#: (:func:`deformctl.sim.step.contact._choose_rows`; results do not depend on it). Half an
#: element keeps the bottom layer's table rows (and any palm-plane row a squeeze brings that
#: close) and leaves out the rest; it is chosen again after 0.2 element of motion.
ROW_MARGIN_FRACTION = 0.5
#: the iterative solver releases a table row before a step's first round when its impulse,
#: extrapolated from the last two steps, is not positive
#: (:func:`deformctl.sim.step.iterative.integrate_iterative`): fewer rounds while the support
#: peels off the table, the same solution up to the CG tolerance
PREDICT_RELEASE = True

#: Bytes each simulated step keeps: the record row (``N_REC`` doubles), the commanded force
#: and palm velocity, and the series built from them (about three copies).
STEP_BYTES = 8 * (N_REC + 2) * 3
#: Bytes a scene frame keeps per particle: the copied position (3 doubles) and, for a surface
#: particle, its JSON sphere in the log writer's messages (about 200 bytes).
SCENE_FRAME_BYTES_PER_PARTICLE = 24 + 200


@dataclass(frozen=True)
class SimSettings:
    """Numerical settings of the simulator (defaults from the convergence study, see bench/).

    Attributes:
        alpha_cm: lattice spacing alpha, cm. ``None`` (default) picks
            ``alpha = longest side / (particles_per_side - 1)``, i.e. 5 particles along the
            longest side: the squeeze stiffness is calibrated exactly for any alpha, and halving
            alpha changes the lifting force by a few % while costing ~10x.
        dt_s: time step, s (:data:`~deformctl.quantities.DT_S`: 10 µs to 50 ms). 1 ms: halving it
            changes the lifting force < 2 %.
        particles_per_side: particles along the longest side when ``alpha_cm`` is None.
        nonlinear_springs: geometrically exact springs (True) or linear small-strain springs.
        palm_mass_kg: mass of each palm, kg (0: the felt force equals the commanded force).
        table_mu: friction coefficient of the table (0: frictionless table, the default, so the
            squeeze stiffness measured on the table is the object's own D).
        grip_ramp_s: time to ramp the grip force from 0 before a lift, s.
        grip_settle_s: time at full grip force before the palms start to rise, s.
        max_squeeze_strain: compression (fraction of the width between the palms) at which the
            object is fully densified: the palms stop there (a unilateral constraint) and any
            further force goes into the dense core. The catalog D is a small-strain stiffness;
            without this, a paper-range grip (e.g. W = 60 N, mu = 0.2 needs > 150 N per palm on
            D = 5 N/cm) would squeeze the lattice through itself.
        pgs_iterations: maximum projected Gauss–Seidel sweeps per step (an exact active-set
            solve follows).
        pgs_tolerance_m_s: PGS stopping tolerance on the constraint velocity, m/s.
        solver: ``"direct"`` (sparse factor), ``"iterative"`` (multigrid-preconditioned CG) or
            ``"auto"`` (default: direct up to ``direct_max_dofs`` DOFs, iterative above).
        direct_max_dofs: the ``"auto"`` threshold, DOFs.
        cg_tolerance_m_s: CG stopping tolerance of the iterative solver: RMS residual impulse per
            DOF over the particle mass, m/s. 2e-7 (tests/sim/test_cg_tolerance.py, against
            2e-9): a lift's centre-of-mass path within 8.3e-10 m (11^3 cube) and the paper
            preset's slip within 2.1e-5 relative; a free damped lattice's energy never rises (it
            does from 1e-6 on, tests/sim/test_free_and_rest.py). With the stencil V-cycle, 3e-7
            left the paper preset's slip 1.3e-4 from the tight solve (the test asks for 1e-4);
            2e-7 costs 4-9 % more CG iterations (8^3 0.50 -> 0.54, 16^3 0.89 -> 0.96 per solve,
            the population's lattices 0.55 -> 0.57).
        cg_max_iterations: CG iteration limit per solve.
        memory_budget_gib: refuse a model whose estimated memory (:func:`memory_estimate_bytes`,
            made before anything is built) exceeds this, GiB.
        integrator: ``"euler"`` (linearised backward Euler, first order, strongly dissipative) or
            ``"bdf2"`` (linearised second-order BDF, same cost per step; see the module docs).
        palm_layer: ``"particle"``: the x faces are particle layers of equal mass riding with the
            palms; ``"surface"``: they are massless palm surfaces, the interior layers at slab
            centres (:func:`deformctl.sim.lattice.build_lattice`).
        shear_damping_ratio: r in (0, 1]: the lattice dampers are ``r`` times
            stiffness-proportional (``c_e = k_e r lambda / D``), and the rest of the squeeze
            damping, ``(1 - r) lambda``, acts across the gripped width (a damper between the two
            palm x DOFs). The squeeze test still measures lambda; the shear (hanging) modes see
            only ``r lambda / D``. 1 (default): every damper in the lattice.
        min_shear_retardation_s: a floor on the lattice dampers' retardation time, s
            (``c_e = k_e (r lambda / D + this)``): the smallest internal friction of a real
            material, so that an undamped object (lambda = 0) does not ring forever in its
            lattice-scale modes. The width damper is reduced by ``D`` times this (not below 0).
    """

    alpha_cm: float | None = None
    dt_s: float = 1e-3
    particles_per_side: int = 5
    nonlinear_springs: bool = True
    palm_mass_kg: float = 0.0
    table_mu: float = 0.0
    grip_ramp_s: float = 0.1
    grip_settle_s: float = 0.1
    max_squeeze_strain: float = 0.5
    pgs_iterations: int = 60
    pgs_tolerance_m_s: float = 1e-13
    solver: Literal["auto", "direct", "iterative"] = "auto"
    direct_max_dofs: int = 32
    cg_tolerance_m_s: float = 2e-7
    cg_max_iterations: int = 100
    memory_budget_gib: float = 2.0
    integrator: Literal["euler", "bdf2"] = "euler"
    palm_layer: Literal["particle", "surface"] = "particle"
    shear_damping_ratio: float = 1.0
    min_shear_retardation_s: float = 0.0

    def __post_init__(self) -> None:
        ALPHA_CM.check_optional(self.alpha_cm)
        DT_S.check(self.dt_s)
        MAX_SQUEEZE_STRAIN.check(self.max_squeeze_strain)
        MEMORY_BUDGET_GIB.check(self.memory_budget_gib)
        if self.solver not in ("auto", "direct", "iterative"):
            raise UsageError(f"solver must be auto, direct or iterative, got {self.solver!r}")
        CG_TOLERANCE_M_S.check(self.cg_tolerance_m_s)
        PARTICLES_PER_SIDE.check(self.particles_per_side)
        if self.integrator not in ("euler", "bdf2"):
            raise UsageError(f"integrator must be euler or bdf2, got {self.integrator!r}")
        if self.palm_layer not in ("particle", "surface"):
            raise UsageError(f"palm_layer must be particle or surface, got {self.palm_layer!r}")
        SHEAR_DAMPING_RATIO.check(self.shear_damping_ratio)
        MIN_SHEAR_RETARDATION_S.check(self.min_shear_retardation_s)
        PALM_MASS_KG.check(self.palm_mass_kg)
        TABLE_MU.check(self.table_mu)
        GRIP_RAMP_S.check(self.grip_ramp_s)
        GRIP_SETTLE_S.check(self.grip_settle_s)

    @property
    def implicit_step_s(self) -> float:
        """The implicit step h of the update ``(M + h C + h^2 K) dv = h f``: dt (Euler), 2 dt/3
        (BDF2), s."""
        return 2.0 * self.dt_s / 3.0 if self.integrator == "bdf2" else self.dt_s

    def alpha_m(self, spec: ObjectSpec) -> float:
        """The lattice spacing used for ``spec``, m."""
        if self.alpha_cm is not None:
            return self.alpha_cm * CM
        return max(spec.size_m) / (self.particles_per_side - 1)


@dataclass(frozen=True, eq=False)
class Model:
    """A lattice with its palms/table configuration, ready for :func:`run_model`.

    Attributes:
        lattice: rest geometry.
        base_x: reference positions, m, ``[n, 3]`` (rest, or resting on the table under gravity).
        dof_of: DOF of each coordinate, ``[3 n]``; n_dof: DOF count.
        palm_x_dof, palm_z_dof: palm DOFs (``-1`` when free), ``[2]``; palm_x0: palm x, m, ``[2]``.
        particle_mass_kg: mean particle mass, kg (the iterative solver's tolerance scale);
        particle_masses_kg: mass of each particle, kg, ``[n]`` (0 on palm surfaces);
        dof_mass_kg: ``[n_dof]``.
        width_damping_ns_per_m: the damper across the gripped width, N·s/m (0 when free).
        stiffness_n_per_m, damping_ns_per_m: element constants, ``[m]``; retardation_s: their
            ratio, s (every element's ``damping = retardation_s * stiffness``).
        factor: sparse ``L D L^T`` of the implicit matrix ``A = M + dt C + dt^2 K``.
        contact_cols: ``A^-1 e_d`` for the DOFs of the rows that are live in most steps (palm
            DOFs, bottom layer), 1/kg, ``[n_cols, n_dof]``; col_of_dof: column of each DOF or -1.
        row_dof, row_dof2, row_particle, row_type, row_link: contact rows
            (see :mod:`deformctl.sim.step`);
        bottom_particles, bottom_row: table contact map (every particle).
        gravity_m_s2: gravity along -z (0 when off).
        law: the Hunt–Crossley elements (:func:`deformctl.sim.hunt_crossley.hc_law`); arm: the
            Maxwell arms (:mod:`deformctl.sim.sls`; their implicit share is in the damping).
        runs: the elements as the linear Kelvin loop reads them (:mod:`deformctl.sim.step.runs`).
    """

    spec: ObjectSpec
    settings: SimSettings
    lattice: Lattice
    base_x: FloatArray
    dof_of: IntArray
    n_dof: int
    palm_x_dof: IntArray
    palm_z_dof: IntArray
    palm_x0: FloatArray
    palm_stop_m: FloatArray
    particle_mass_kg: float
    particle_masses_kg: FloatArray
    width_damping_ns_per_m: float
    dof_mass_kg: FloatArray
    stiffness_n_per_m: FloatArray
    damping_ns_per_m: FloatArray
    retardation_s: float
    factor: LDLFactor | None
    contact_cols: FloatArray
    col_of_dof: IntArray
    hierarchy: Hierarchy | None
    solver_stats: IntArray
    row_dof: IntArray
    row_dof2: IntArray
    row_particle: IntArray
    row_type: IntArray
    row_link: IntArray
    bottom_particles: IntArray
    bottom_row: IntArray
    gravity_m_s2: float
    law: HuntCrossley
    arm: Maxwell
    runs: ElementRuns


@lru_cache(maxsize=16)
def _lattice_and_scale(
    size_m: tuple[float, float, float], alpha_m: float, palm_surface: bool = False
) -> tuple[Lattice, float]:
    lattice = build_lattice(size_m, alpha_m, palm_surface=palm_surface)
    return lattice, unit_squeeze_stiffness_n_per_m(lattice)


GIB = 1024**3


def memory_estimate_bytes(spec: ObjectSpec, settings: SimSettings) -> float:
    """Estimated peak memory of building and running the model of ``spec``, bytes.

    Made from the particle counts alone (nothing is built). Direct solver: the sparse factor
    (``nnz(L)`` from :func:`deformctl.sim.solver.estimate_factor_entries`, 12 bytes per entry,
    three times over for SuperLU's working copy of ``L`` and ``U`` while factorising) and the
    precomputed contact columns (palm and bottom-layer DOFs, ``n_dof`` doubles each). Iterative
    solver: the multigrid levels (about 30 matrix entries of 12 bytes per DOF, twice over for the
    calibration's own hierarchy). Both: the element arrays and their assembly (about 2 kB per
    element) and 50 MB of fixed overhead. ``bench/bench_sim.py`` prints it beside the measured
    peak of the 21^3 run.
    """
    nx, ny, nz = particles_per_axis(spec.size_m, settings.alpha_m(spec))
    n = float(nx) * float(ny) * float(nz)
    n_dof = 3.0 * n
    n_elements = 9.0 * n
    common = 2000.0 * n_elements + 50e6
    gripped_dofs = n_dof - 4.0 * float(ny) * float(nz) + 4.0
    direct = (
        gripped_dofs <= settings.direct_max_dofs
        if settings.solver == "auto"
        else (settings.solver == "direct")
    )
    if not direct:
        return common + 2.0 * 30.0 * 12.0 * n_dof + 400.0 * n_dof
    entries = float(estimate_factor_entries(int(min(n_dof, 1e15))))
    factor = 3.0 * 12.0 * entries + 64.0 * n_dof
    n_cols = float(nx * ny) * (3.0 if settings.table_mu > 0 else 1.0) + 4.0
    columns = 8.0 * n_cols * n_dof
    return factor + columns + common


def uses_iterative_solver(settings: SimSettings, n_dof: int) -> bool:
    """Whether a model of ``n_dof`` DOFs runs the iterative solver under ``settings``."""
    if settings.solver == "auto":
        return n_dof > settings.direct_max_dofs
    return settings.solver == "iterative"


@dataclass(frozen=True)
class RunPlan:
    """One object's simulated run, worked out once before anything is built: what the
    memory-budget check judges and the run uses (:func:`plan_run`).

    Attributes:
        spec: the simulator's object.
        particles: the lattice's particle count.
        steps: the run's steps (a whole number as a float: an absurd duration is refused, not
            an overflow).
        memory_bytes: the estimated peak memory of the model, its steps and its scene frames.
        frame_every: a scene frame every this many steps (0: none).
    """

    spec: ObjectSpec
    particles: int
    steps: float
    memory_bytes: float
    frame_every: int = 0


def _check_model(spec: ObjectSpec, settings: SimSettings, model_bytes: float) -> int:
    """The particle count of ``spec``'s lattice, when its model (``model_bytes``) fits."""
    alpha_m = settings.alpha_m(spec)
    n_particles = math.prod(particles_per_axis(spec.size_m, alpha_m))
    if model_bytes > settings.memory_budget_gib * GIB:
        raise UsageError(
            f"object {spec.object_id!r}: alpha {alpha_m / CM:.3g} cm gives {n_particles:,} "
            f"particles, an estimated {model_bytes / GIB:.3g} GiB, above the memory budget of "
            f"{settings.memory_budget_gib:g} GiB; use a larger alpha_cm (or raise the budget)"
        )
    return n_particles


def plan_run(
    spec: ObjectSpec, settings: SimSettings, n_steps: float, what: str, frame_every: int = 0
) -> RunPlan:
    """The :class:`RunPlan` of a run of ``n_steps`` steps, when its model, recorded steps and
    scene frames (one every ``frame_every`` steps; 0: none) fit ``settings.memory_budget_gib``.

    Made before the model is built or any step allocated (``n_steps`` comes from the protocol's
    durations and ``dt_s``; the estimate is a float, so an absurd duration does not overflow).

    Raises:
        UsageError: one line naming the steps, the estimate and the budget (exit 2); a model
            too large by itself: one line naming its particle count instead.
    """
    model = memory_estimate_bytes(spec, settings)
    n_particles = _check_model(spec, settings, model)
    estimate = model + float(n_steps) * STEP_BYTES
    if frame_every > 0:
        frames = float(n_steps) / frame_every + 2.0
        estimate += frames * float(n_particles) * SCENE_FRAME_BYTES_PER_PARTICLE
    if not estimate <= settings.memory_budget_gib * GIB:  # also refuses inf / nan
        raise UsageError(
            f"object {spec.object_id!r}: a {what} of {float(n_steps):.3g} steps of "
            f"{settings.dt_s:g} s needs an estimated {estimate / GIB:.3g} GiB, above the memory "
            f"budget of {settings.memory_budget_gib:g} GiB; use a larger --dt-s or shorter "
            "durations, or raise --memory-budget-gib"
        )
    return RunPlan(spec, n_particles, float(n_steps), estimate, frame_every)


def element_constants(
    spec: ObjectSpec, settings: SimSettings, reference_m: float | None = None
) -> tuple[Lattice, FloatArray, FloatArray]:
    """Lattice and calibrated element stiffness (N/m) and damping (N·s/m; arms too), ``[m]``
    (its size within the budget: the run's :class:`RunPlan` judged it before)."""
    if spec.hunt_crossley:  # the tangent and damping at the reference strain
        el = spec_elements(spec, settings, reference_m)
        return el.lattice, el.tangent_n_per_m, el.damping_ns_per_m
    alpha_m = settings.alpha_m(spec)
    lattice, unit_d = _lattice_and_scale(spec.size_m, alpha_m, settings.palm_layer == "surface")
    stiffness = lattice.unit_stiffness * (spec.stiffness_n_per_m / unit_d)
    damping = stiffness * element_retardation_s(spec, settings)
    if spec.standard_linear_solid:
        damping = damping + implicit_damping(spec, stiffness, settings.implicit_step_s)
    return lattice, stiffness, damping


def element_retardation_s(spec: ObjectSpec, settings: SimSettings) -> float:
    """The lattice elements' damping over stiffness, s: every element's damper is this times its
    spring (:func:`element_constants`; the step kernels form the dampers from it). A Hunt–Crossley
    object's linear dampers are the floor alone (:mod:`deformctl.sim.hunt_crossley`)."""
    if spec.hunt_crossley:
        return settings.min_shear_retardation_s
    retardation = spec.damping_ns_per_m / spec.stiffness_n_per_m
    if settings.shear_damping_ratio != 1.0 or settings.min_shear_retardation_s > 0.0:
        retardation = settings.shear_damping_ratio * retardation + settings.min_shear_retardation_s
    return retardation


def width_damping_ns_per_m(
    spec: ObjectSpec, settings: SimSettings, ref: float | None = None
) -> float:
    """The damper across the gripped width, N·s/m: the squeeze damping the lattice does not carry,
    ``max(0, lambda - D (r lambda / D + min_shear_retardation_s))``; for a Hunt–Crossley object
    ``(1 - r) lambda`` at the operating compression, scaled by the step with the compression."""
    if spec.hunt_crossley:
        return spec_elements(spec, settings, ref).width_damping_ns_per_m
    lattice_part = (
        settings.shear_damping_ratio * spec.damping_ns_per_m
        + settings.min_shear_retardation_s * spec.stiffness_n_per_m
    )
    return max(0.0, spec.damping_ns_per_m - lattice_part)


def build_model(
    spec: ObjectSpec,
    settings: SimSettings,
    *,
    gripped: bool,
    gravity: bool = True,
    table: bool = True,
    resting: bool = True,
    lift_m: float = 0.0,
    reference_m: float | None = None,
) -> Model:
    """Assemble (and cache) the model of ``spec``: one cached model per set of values, however
    the call spells them (a default left out or passed explicitly is the same model).

    Args:
        gripped: palms bonded to the x faces (squeeze, lift) or a free object.
        gravity: gravity on (``GRAVITY_M_S2`` along -z) or off.
        table: table contact at z = 0 on the bottom layer.
        resting: start from the static rest shape on the table under gravity (else undeformed).
        lift_m: start height of the bottom layer above the table, m.
        reference_m: a Hunt–Crossley object's implicit step's compression (None: d_op).
    """
    return _build_model(spec, settings, gripped, gravity, table, resting, lift_m, reference_m)


def clear_model_cache() -> None:
    """Forget every cached model (:func:`build_model`)."""
    _build_model.cache_clear()


@lru_cache(maxsize=8)
def _build_model(
    spec: ObjectSpec,
    settings: SimSettings,
    gripped: bool,
    gravity: bool,
    table: bool,
    resting: bool,
    lift_m: float,
    reference_m: float | None,
) -> Model:
    lattice, stiffness, damping = element_constants(spec, settings, reference_m)
    n, law = lattice.n_particles, hc_law(spec, settings, reference_m)
    masses = np.ones(n)
    if settings.palm_layer == "surface" and lattice.shape[0] >= 3:
        masses[lattice.face_mask(0) | lattice.face_mask(1)] = 0.0
    masses *= spec.mass_kg / masses.sum()
    g = GRAVITY_M_S2 if gravity else 0.0
    if resting and gravity:
        base_x, law = resting_state(lattice, stiffness, masses * g, law)
    else:
        base_x = lattice.positions_m.copy()
    base_x[:, 2] += lift_m
    dof_of, n_dof, palm_x, palm_z = palm_dof_map(lattice, gripped)
    dof_mass: FloatArray = np.bincount(
        dof_of, weights=np.repeat(masses, 3), minlength=n_dof
    ).astype(np.float64)
    palm_x0 = np.zeros(2)
    if gripped:
        dof_mass[palm_x] += settings.palm_mass_kg
        palm_x0[0] = base_x[lattice.face_mask(0), 0].min()
        palm_x0[1] = base_x[lattice.face_mask(1), 0].max()
    h = settings.implicit_step_s
    # A = M + h C + h^2 K, C assembled from the element dampers as K from the springs
    # (both are sums of element terms with the same pattern: assembled in one pass)
    a = reduced_stiffness(lattice, h * h * stiffness + h * damping, dof_of, n_dof)
    a = (a + scipy.sparse.diags(dof_mass, format="csr")).tocsr()
    width_c = width_damping_ns_per_m(spec, settings, reference_m) if gripped else 0.0
    if width_c > 0.0:
        pl, pr = int(palm_x[0]), int(palm_x[1])
        width = h * width_c * np.array([1.0, -1.0, -1.0, 1.0])
        ij = ([pl, pl, pr, pr], [pl, pr, pl, pr])
        a = (a + scipy.sparse.coo_matrix((width, ij), shape=(n_dof, n_dof)).tocsr()).tocsr()
    palm_dofs = np.concatenate([palm_x, palm_z])
    iterative = uses_iterative_solver(settings, n_dof)
    factor = None if iterative else lattice_factor(lattice, a, dof_of, n_dof, last=palm_dofs)
    hierarchy = None
    if iterative:
        stencil = build_stencil(
            lattice, h * h * stiffness + h * damping, masses, dof_of, n_dof, palm_x, palm_z
        )
        hierarchy = build_hierarchy(lattice.shape, gripped, a, stencil=stencil)

    row_dof: list[int] = []
    row_dof2: list[int] = []
    row_type: list[int] = []
    row_link: list[int] = []
    row_particle: list[int] = []
    # every particle can touch the table (rows are skipped while far and receding)
    bottom = np.arange(n, dtype=np.int64) if table else np.zeros(0, dtype=np.int64)
    on_bottom = lattice.bottom_mask()
    bottom_row = np.zeros(bottom.size, dtype=np.int64)
    row_of_dof: dict[int, int] = {}
    for b, p in enumerate(bottom):
        d = int(dof_of[3 * p + 2])
        if d not in row_of_dof:
            row_of_dof[d] = len(row_dof)
            row_dof.append(d)
            row_type.append(0)
            row_link.append(-1)
        bottom_row[b] = row_of_dof[d]
    if table and settings.table_mu > 0:
        seen: set[int] = set()
        for b, p in enumerate(bottom):
            if not on_bottom[p]:
                continue
            for axis in (0, 1):
                d = int(dof_of[3 * p + axis])
                if d in seen or d in palm_x:
                    continue
                seen.add(d)
                row_dof.append(d)
                row_type.append(2)
                row_link.append(int(bottom_row[b]))
    palm_stop = np.zeros(2)
    if gripped:
        for side in (0, 1):
            row_dof.append(int(palm_z[side]))
            row_type.append(1)
            row_link.append(-1)
        centre = 0.5 * (palm_x0[0] + palm_x0[1])
        half_dense = 0.5 * (palm_x0[1] - palm_x0[0]) * (1.0 - settings.max_squeeze_strain)
        palm_stop[:] = (centre - half_dense, centre + half_dense)
        for side in (0, 1):
            row_dof.append(int(palm_x[side]))
            row_type.append(3 + side)
            row_link.append(-1)
        # no particle may pass through a palm plane
        row_dof2 += [-1] * (len(row_dof) - len(row_dof2))
        row_particle += [-1] * (len(row_dof) - len(row_particle))
        nx = lattice.shape[0]
        if nx >= 3:
            interior = (lattice.grid_index[:, 0] > 0) & (lattice.grid_index[:, 0] < nx - 1)
            for side in (0, 1):
                for p in np.flatnonzero(interior):
                    xd = int(dof_of[3 * p])
                    row_dof.append(xd if side == 0 else int(palm_x[1]))
                    row_dof2.append(int(palm_x[0]) if side == 0 else xd)
                    row_type.append(5 + side)
                    row_link.append(-1)
                    row_particle.append(int(p))
    row_dof2 += [-1] * (len(row_dof) - len(row_dof2))
    row_particle += [-1] * (len(row_dof) - len(row_particle))
    # contact columns for the rows live in most steps: palms, bottom layer (and its friction)
    col_dofs: list[int] = [int(d) for d in palm_dofs if d >= 0]
    if table:
        for p in np.flatnonzero(on_bottom):
            col_dofs.append(int(dof_of[3 * p + 2]))
            if settings.table_mu > 0:
                col_dofs += [int(dof_of[3 * p]), int(dof_of[3 * p + 1])]
    col_dof_arr = np.unique(np.asarray(col_dofs, dtype=np.int64))
    if factor is None:  # the iterative solver fixes contact DOFs instead
        col_dof_arr = col_dof_arr[:0]
    contact_cols = np.empty((col_dof_arr.size, n_dof))
    if factor is not None:
        ldl_columns(factor, col_dof_arr, contact_cols)
    col_of_dof = np.full(n_dof, -1, dtype=np.int64)
    col_of_dof[col_dof_arr] = np.arange(col_dof_arr.size)
    return Model(
        spec=spec,
        settings=settings,
        lattice=lattice,
        base_x=base_x,
        dof_of=dof_of,
        n_dof=n_dof,
        palm_x_dof=palm_x,
        palm_z_dof=palm_z,
        palm_x0=palm_x0,
        palm_stop_m=palm_stop,
        particle_mass_kg=spec.mass_kg / n,
        particle_masses_kg=masses,
        width_damping_ns_per_m=width_c,
        dof_mass_kg=dof_mass,
        stiffness_n_per_m=stiffness,
        damping_ns_per_m=damping,
        retardation_s=element_retardation_s(spec, settings),
        factor=factor,
        contact_cols=contact_cols,
        col_of_dof=col_of_dof,
        hierarchy=hierarchy,
        solver_stats=np.zeros(6, dtype=np.int64),
        row_dof=np.asarray(row_dof, dtype=np.int64),
        row_dof2=np.asarray(row_dof2, dtype=np.int64),
        row_particle=np.asarray(row_particle, dtype=np.int64),
        row_type=np.asarray(row_type, dtype=np.int64),
        row_link=np.asarray(row_link, dtype=np.int64),
        bottom_particles=bottom.astype(np.int64),
        bottom_row=bottom_row,
        gravity_m_s2=g,
        law=law,
        arm=maxwell_arms(spec, stiffness),
        runs=element_runs(lattice.edges, lattice.rest_length_m, lattice.direction, stiffness),
    )


def run_model(
    model: Model,
    force_cmd_n: FloatArray,
    palm_vz_m_s: FloatArray,
    *,
    gravity_scale: FloatArray | None = None,
    stop_slip_m: float | None = None,
    stop_from_step: int = 0,
    q: FloatArray | None = None,
    v: FloatArray | None = None,
    frame_every: int = 0,
    frames: FloatArray | None = None,
    arm: Maxwell | None = None,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Integrate ``len(force_cmd_n) - 1`` steps.

    The run starts from rest history: with BDF2 the state before the first step is taken equal to
    the start state (exact for a body at rest; see :mod:`deformctl.sim.step`).

    Args:
        force_cmd_n: commanded normal force per palm at each step end, N, ``[n_steps + 1]``
            (index 0 is the initial time).
        palm_vz_m_s: palm vertical velocity, m/s, ``[n_steps + 1]``.
        gravity_scale: the fraction of the model's gravity acting at each step end, ``[n_steps +
            1]`` (1 throughout by default). A support that carries part of every particle's
            weight is modelled this way (see :func:`deformctl.sim.protocols.lift_attempt`).
        stop_slip_m: stop early once the mean palm slip accumulated since the step before
            ``stop_from_step`` exceeds this, m (None: run every step).
        q, v: initial DOF displacement (m) and velocity (m/s), ``[n_dof]``; zero by default.
        frame_every, frames: copy the particle positions into ``frames`` (m, ``[n_frames, n,
            3]``, see :func:`deformctl.sim.scene.frame_buffer`) after steps 0, ``frame_every``,
            2 ``frame_every``... (0: no copies; what is simulated does not depend on it).
        arm: the Maxwell arms to run with, updated in place (default: the model's, unloaded).

    Returns:
        final q, final v and the record matrix ``[n_run, N_REC]`` (``n_run`` is
        ``n_steps`` unless the run stopped early).
    """
    s = model.settings
    n_steps = int(force_cmd_n.shape[0]) - 1
    q0 = np.zeros(model.n_dof) if q is None else np.asarray(q, dtype=np.float64)
    v0 = np.zeros(model.n_dof) if v is None else np.asarray(v, dtype=np.float64)
    lat = model.lattice
    body = Body(
        model.base_x, model.dof_of, model.particle_masses_kg, lat.edges, lat.rest_length_m,
        lat.direction, model.stiffness_n_per_m, model.retardation_s, s.nonlinear_springs,
        model.law, unloaded(model.arm) if arm is None else arm,
        with_scratch(model.runs, lat.n_particles),
    )  # fmt: skip
    palms = Palms(
        model.palm_x_dof, model.palm_z_dof, model.palm_x0, model.palm_stop_m, s.palm_mass_kg,
        model.width_damping_ns_per_m,
    )  # fmt: skip
    contacts = Contacts(
        model.row_dof, model.row_dof2, model.row_type, model.row_link, model.row_particle,
        model.bottom_particles, model.bottom_row, model.spec.friction_mu, s.table_mu,
    )  # fmt: skip
    drive = Drive(
        np.ascontiguousarray(force_cmd_n, dtype=np.float64),
        np.ascontiguousarray(palm_vz_m_s, dtype=np.float64),
        np.ones(n_steps + 1)
        if gravity_scale is None
        else np.ascontiguousarray(gravity_scale, dtype=np.float64),
        model.gravity_m_s2,
        s.dt_s,
        n_steps,
        s.integrator == "bdf2",
        -1.0 if stop_slip_m is None else float(stop_slip_m),
        int(stop_from_step),
        int(frame_every) if frames is not None else 0,
        np.zeros((0, model.lattice.n_particles, 3)) if frames is None else frames,
    )
    if model.hierarchy is not None:
        tol = s.cg_tolerance_m_s * model.particle_mass_kg * math.sqrt(model.n_dof)
        iterative = IterativeSolver(
            model.hierarchy.kernel_args(),
            tol,
            s.cg_max_iterations,
            WARM_HISTORY,
            PRODUCT_CARRY_FRACTION * tol,
            ROW_MARGIN_FRACTION * float(model.lattice.rest_length_m.min()),
            PREDICT_RELEASE,
            model.solver_stats,
        )
        return integrate_iterative(body, palms, contacts, drive, iterative, q0, v0)
    assert model.factor is not None
    direct = DirectSolver(
        model.factor, model.contact_cols, model.col_of_dof, s.pgs_iterations, s.pgs_tolerance_m_s
    )
    return integrate(body, palms, contacts, drive, direct, q0, v0)


def positions_m(model: Model, q: FloatArray) -> FloatArray:
    """Particle positions for DOF displacements ``q``, m, ``[n, 3]``."""
    return np.asarray(model.base_x + q[model.dof_of].reshape(-1, 3))
