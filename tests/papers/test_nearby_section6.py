"""Positions that miss their target ((20)-(24) of 000) and ignoring the stand (section 6 of 000)."""
import numpy as np
import pytest

from garant.generated import two_axis_remount as rm
from garant.verify.papers import section6, stand_000
from garant.verify.workflows import nearby


@pytest.mark.parametrize("miss", [0.01, 0.5, 2.0])
def test_estimator_23_is_unbiased_and_near_sigma(mod, miss):
    rng = np.random.default_rng(0)
    P = np.asarray(mod.PLAN_DEG, float) + rng.uniform(-miss, miss, (10, 2))
    r = nearby.compare(mod, P)
    assert r["unbiased_23"] < 1e-12                       # (24): Psi~ H^T = E
    assert np.all(r["error_lp"] <= r["error_23"] + 1e-9)  # the LP is the optimum on these positions
    assert np.all(r["error_23"] < 1 + 0.1 * miss)          # close to the optimum sigma of the exact plan
    assert np.abs(r["bias_of_exact"]).max() > 0            # reusing D: biased, guaranteed error infinite


def test_exact_plan_gives_back_D(mod):
    r = nearby.compare(mod, mod.PLAN_DEG)
    np.testing.assert_allclose(r["error_23"], 1, atol=1e-12)
    assert np.abs(r["bias_of_exact"]).max() < 1e-12


def test_match_plan_permuted_and_wrapped(mod):
    P = np.asarray(mod.PLAN_DEG, float)[::-1] + 0.3
    P[P[:, 0] < 1, 0] += 360                                # 0 written as 360.3
    order, miss = nearby.match_plan(P[:, 0], P[:, 1], mod.PLAN_DEG)
    assert miss == pytest.approx(0.3) and sorted(order) == list(range(10))
    assert nearby.match_plan(P[:9, 0], P[:9, 1], mod.PLAN_DEG) is None


def test_section6_some_biased_some_not(mod):
    rows = section6.analyse(mod, [0, 1, 2])
    by = {r.name: r for r in rows}
    assert by["q5"].biased == 0 and by["q4"].biased > 0
    assert by["q4"].example == "-epsilon"
    assert all(r.error_full == r.error_reduced == 1 for r in rows)
    assert section6.per_accelerometer(mod, [0, 1, 2]) == {
        1: ["q4", "q5", "q6", "q7"], 2: ["q8", "q9", "q10", "q11"], 3: ["q12", "q13", "q14", "q15"]}


@pytest.mark.parametrize("group", [stand_000.remount_round_trip, stand_000.ignoring_the_stand])
def test_remount_and_stand_blind_checks_pass(mod, group):
    rows = list(group(mod, rm))
    assert rows and all(r.passed for r in rows)


def test_realised_plan_checks_pass(mod):
    assert all(r.passed for r in stand_000.realised_plan(mod))
