"""garant verify: the LP optimum, the published closed forms, the plans (000, sections 3-4)."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from garant.derive import published
from garant.verify.papers import stand_000
from garant.verify.solve import exact, lp, plans


@pytest.mark.parametrize("group", [stand_000.closed_forms, stand_000.continuum_optimum, stand_000.grid_lp,
                                   stand_000.plan_checks, stand_000.additivity])
def test_every_check_passes(mod, group):
    rows = list(group(mod))
    assert rows and all(r.passed for r in rows), [r for r in rows if not r.passed]


def test_published_estimators_exact(mod):
    # Section 4.3 of 000: each closed form is unbiased and has guaranteed error sigma, exactly.
    for nu, name in enumerate(mod.Q_NAMES):
        terms = exact.terms_from_published(published.ESTIMATORS_000[name])
        assert exact.unbiased_image(mod.H, terms) == [int(i == nu) for i in range(15)]
        assert exact.l1(terms) == 1


def test_a_wrong_estimator_is_caught(mod):
    terms = exact.terms_from_published(published.ESTIMATORS_000["q3"])
    w, p, pos = terms[0]
    terms[0] = (-w, p, pos)
    assert exact.unbiased_image(mod.H, terms) != [int(i == 2) for i in range(15)]


def test_plan_search(mod):
    # 000, section 4.3: fewer than 10 positions cannot be optimal; "at least 64" plans of 10.
    r = plans.search(mod, np.array(plans.QUARTER_DEG, float))
    assert r.min_positions == 10
    assert len(r.optimal_plans) == 64          # exact count on the quarter-turn grid
    starred = tuple(sorted(plans.QUARTER_DEG.index(p) for p in published.PLAN_000))
    assert starred in r.optimal_plans


@pytest.mark.slow
def test_primal_dual_chebyshev_agree_on_a_coarse_grid(mod):
    g = np.deg2rad(np.arange(0, 360, 45))
    A = lp.measurement_matrix(mod.H, np.array([(x, y) for x in g for y in g]))
    Phi, primal = lp.primal(A)
    _, dual = lp.dual(A)
    L, Y = lp.chebyshev(A)
    np.testing.assert_allclose(L, np.abs(A.T @ Y).max(axis=0), atol=1e-10)     # Y attains L
    np.testing.assert_allclose(L, _chebyshev_as_stated(A), atol=1e-8)          # (12) as cvxpy states it
    np.testing.assert_allclose(primal, 1, atol=1e-8)
    np.testing.assert_allclose(dual, 1, atol=1e-8)
    np.testing.assert_allclose(1 / L, 1, atol=1e-8)
    np.testing.assert_allclose(A @ Phi, np.eye(15), atol=1e-8)


def _chebyshev_as_stated(A):
    """(12) of 000 written as the paper states it, all nu at once: min sum t_nu subject to diag(Y) = 1,
    |A^T Y| <= t (cvxpy): the reference lp.chebyshev's per-nu HiGHS fit is compared with."""
    import cvxpy as cp
    m = A.shape[0]
    Y, t = cp.Variable((m, m)), cp.Variable(m)
    cons = [cp.diag(Y) == 1, cp.abs(A.T @ Y) <= cp.reshape(t, (1, m), order="C")]
    lp.optimal(cp.Problem(cp.Minimize(cp.sum(t)), cons), "Chebyshev polynomial (12)")
    return t.value


def test_nine_positions_of_the_starred_plan_are_not_optimal(mod):
    A_full = published.PLAN_000
    for drop in range(10):
        pos = np.deg2rad(np.array([p for k, p in enumerate(A_full) if k != drop], float))
        A = lp.measurement_matrix(mod.H, pos)
        if lp.unidentifiable(A):
            continue
        _, err = lp.primal(A)
        assert err.max() > 1 + 1e-6


@settings(max_examples=25, deadline=None)
@given(st.floats(0, 2 * np.pi), st.floats(0, 2 * np.pi))
def test_H_is_within_its_proven_bound(mod, alpha, beta):
    assert np.all(np.abs(mod.H(alpha, beta)) <= mod.H_SUP + 1e-15)


def test_generated_estimators_are_unbiased_on_their_plan(mod):
    P = np.deg2rad(mod.PLAN_DEG.astype(float))
    Hp = mod.H(P[:, 0], P[:, 1])                 # (3, 15, S)
    np.testing.assert_allclose(np.einsum("nsp,pms->nm", mod.PSI, Hp), np.eye(15), atol=1e-15)
    np.testing.assert_array_equal(np.abs(mod.PSI).sum(axis=(1, 2)), 1)
