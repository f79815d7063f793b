"""The sparse implicit solve reproduces the former dense path (dense ``A^-1``, before the
sparse solvers): the factor solves like a dense inverse, and squeeze D/lambda and L_f at 5^3 and 8^3
particles match values recorded from the dense path."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse

from deformctl.characterize import characterize
from deformctl.sim import ObjectSpec, SimSettings, f_w_n, lift_attempt, squeeze_many
from deformctl.sim.engine import build_model
from deformctl.sim.lattice import reduced_stiffness

CUBE = ObjectSpec("cube", (10.0, 10.0, 10.0), 5.0, 0.5, 30.0, 1.0)
SPONGE = ObjectSpec("sponge", (17.8, 19.1, 9.2), 0.7, 0.5, 49.18, 6.47)

# (D N/cm, lambda N·s/cm, L_f N) recorded with the dense path: 3 squeezes at 1 % strain
# (ramp 0.25 s, hold 1 s, characterize lsq) and L_f bisected to 1e-4 from [F_w, 1.6 F_w].
DENSE = {
    ("cube", 5): (30.403815240296055, 1.031140741739261, 6.0220947265625),
    ("sponge", 5): (49.32492976665686, 6.536853908308658, 0.8356079101562499),
    ("cube", 8): (30.440187165309464, 1.0331725421568112, 6.0330810546875),
    ("sponge", 8): (49.23213872217354, 6.524653296258682, 0.8356079101562499),
}


# λ with the material-law estimator (lsq in integral form, D as the secant at the
# operating force), on the sparse path whose D and L_f still match the dense values above within
# 8e-5 and the bisection: the estimator moved λ by -0.54 % on the cube and -0.15 % on the sponge
# (the golden objects moved by the same order). The solver is what this file checks; λ against the
# dense path's own number would test the old estimator instead.
LAMBDA_ISSUE_33 = {
    ("cube", 5): 1.025583811530476,
    ("sponge", 5): 6.5273391327305115,
    ("cube", 8): 1.0276383991502152,
    ("sponge", 8): 6.515148456500074,
}


def _system_matrix(spec: ObjectSpec, settings: SimSettings) -> np.ndarray:
    model = build_model(spec, settings, gripped=True)
    lat = model.lattice
    dt = settings.dt_s
    k = reduced_stiffness(lat, model.stiffness_n_per_m, model.dof_of, model.n_dof)
    c = reduced_stiffness(lat, model.damping_ns_per_m, model.dof_of, model.n_dof)
    a = dt * dt * k + dt * c + scipy.sparse.diags(model.dof_mass_kg)
    return np.asarray(a.toarray())


def test_factor_and_contact_columns_equal_the_dense_inverse() -> None:
    settings = SimSettings(solver="direct")
    model = build_model(CUBE, settings, gripped=True)
    a_inv = np.linalg.inv(_system_matrix(CUBE, settings))
    rng = np.random.default_rng(0)
    b = rng.normal(size=model.n_dof)
    assert np.allclose(
        model.factor.solve(b), a_inv @ b, rtol=1e-11, atol=1e-14 * np.abs(a_inv).max()
    )
    dofs = np.flatnonzero(model.col_of_dof >= 0)
    assert dofs.size > 4  # palms and the bottom layer
    cols = model.contact_cols[model.col_of_dof[dofs]]
    assert np.allclose(cols, a_inv[:, dofs].T, rtol=1e-11, atol=1e-14 * np.abs(a_inv).max())


def _lift_force_n(spec: ObjectSpec, settings: SimSettings) -> float:
    lo, hi = f_w_n(spec), 1.6 * f_w_n(spec)
    assert not lift_attempt(spec, lo, settings=settings).lifted
    assert lift_attempt(spec, hi, settings=settings).lifted
    while hi - lo > 1e-4 * hi:
        mid = 0.5 * (lo + hi)
        if lift_attempt(spec, mid, settings=settings).lifted:
            hi = mid
        else:
            lo = mid
    return hi


@pytest.mark.slow
@pytest.mark.parametrize(("name", "n"), list(DENSE))
def test_squeeze_coefficients_and_lifting_force_match_the_dense_path(name: str, n: int) -> None:
    spec = CUBE if name == "cube" else SPONGE
    settings = SimSettings(particles_per_side=n)
    peak = spec.stiffness_n_per_m * 0.01 * spec.size_m[0]
    runs = squeeze_many(spec, 3, peak_force_n=peak, settings=settings, ramp_s=0.25, hold_s=1.0)
    coeffs = characterize({spec.object_id: runs})
    d_ref, _, lf_ref = DENSE[(name, n)]
    lam_ref = LAMBDA_ISSUE_33[(name, n)]
    assert float(coeffs.deformability_n_per_cm[0]) == pytest.approx(d_ref, rel=0.005)
    assert float(coeffs.damping_ns_per_cm[0]) == pytest.approx(lam_ref, rel=0.005)
    assert _lift_force_n(spec, settings) == pytest.approx(lf_ref, rel=0.005)
