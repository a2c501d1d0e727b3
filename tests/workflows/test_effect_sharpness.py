"""Effect bounds at the information set's range: every catalogue effect's parameters, calibrated through the
extended norm relation (2.2) of 001,
against the range of the same parameters over the linearised set computed here independently (scipy's linprog);
and the bound of the effects' term per interval and axis (norm_information.effect_reach) against its own LP."""
import numpy as np
import pytest

from garant.generated import norm as N
from garant.verify.bench.outputs import warm_up_log
from garant.verify.workflows import jobs, norm_thermal
from garant.verify.workflows.stills import still_intervals
from test_diagnose_norm import EFFECTS, G, static_log

#: The effects a warm-up log (biases drifting with the temperature) needs beside the one under test.
BESIDE = "bias_temperature"
#: Effects of the temperature's rate: a warm-up alone cannot tell them from the bias's temperature coefficient
#: (dT/dt = (50 C - T) / 300 s), a log that heats and cools can.
RATE = {"temperature_lag"}


def _independent_range(res, log, names):
    """Half the range of each effect parameter over {x : |s_k - H(n_k)^T q - c_k^T theta| <= bound_k}: the
    intervals' fitted directions n_k, their residuals s_k at the fit and their printed bounds (noise bound and
    proven remainder, units of g), each column c_kj = n_k^T phi_j(n_k, t_k, T_k) of the generated basis at the
    interval's mid-time from the effects' reference, its mean temperature and rate (first order of (2.2) of 001)."""
    from scipy.optimize import linprog
    data = jobs.read_log(str(log))
    stills, _ = still_intervals(data)
    temps, rates = (np.asarray(v, float) for v in norm_thermal.of_intervals(data, stills))
    pi = res["per_interval"]
    assert len(pi) == len(stills)
    n = np.array([r["direction"] for r in pi]).T
    s = np.array([r["residual_after_ms2"] for r in pi]) / G
    bound = np.array([r["bound"] for r in pi])
    t = np.array([0.5 * (st.start + st.stop) for st in stills]) - res["effect_reference"]["time_s"]
    T = temps - res["effect_reference"]["temp_c"] + 20.0
    A = np.vstack([N.H(n)[:9]] + [np.einsum("ik,jik->jk", n, N.effect_basis(x, n, t, T, rates)) for x in names])
    rows, rhs = np.hstack([A, -A]).T, np.r_[s + bound, bound - s]       # -bound <= s - A^T x <= bound
    half = []
    for j in range(9, len(A)):
        e = np.eye(len(A))[j]
        top, bottom = (linprog(c, A_ub=rows, b_ub=rhs, bounds=(None, None), method="highs").fun for c in (-e, e))
        half.append(0.5 * (-top - bottom))
    return np.array(half)


@pytest.fixture(scope="module")
def warm(tmp_path_factory):
    """The 36-direction warm-up log, made once for the module."""
    return warm_up_log(tmp_path_factory.mktemp("warm") / "warm.csv")


@pytest.fixture(scope="module")
def heat_cool(tmp_path_factory):
    """The 36-direction log heating to 50 C and cooling back, made once for the module."""
    return warm_up_log(tmp_path_factory.mktemp("cool") / "cool.csv", cool=True)


@pytest.mark.slow
@pytest.mark.parametrize("effect", N.EFFECTS)
def test_every_effects_bound_is_within_a_tenth_of_the_sets_range(tmp_path, warm, heat_cool, effect):
    # Static logs with the effect hidden (test_diagnose_norm's generator) for the effects it makes, a 36-direction
    # warm-up (biases drifting with T, 20 -> 50 C) for the temperature ones with bias_temperature beside, and for
    # temperature_lag the same unit heating to 50 C and cooling back: every printed bound within 1.1x of the
    # independent range (measured 0.9998-1.001x; the lag's 0.9999997-1.0000005x). Red for a bound not the set's
    # range: the LP estimator's a-priori bound taken where it is larger is 1.19x on one of scale_temperature_3's
    # parameters (checked).
    if effect in EFFECTS:
        log, names = static_log(tmp_path / "log.csv", effect), [effect]
    else:
        log = heat_cool if effect in RATE else warm
        names = [BESIDE] + ([effect] if effect != BESIDE else [])
    res = jobs.calibrate_norm(str(log), g=G, effects=",".join(names)).to_dict()
    assert res["consistent"]
    printed = np.array([v["guaranteed_error"] for x in names for v in res["effects"][x]["parameters"].values()])
    ratio = printed / _independent_range(res, log, names)
    assert np.all(ratio <= 1.1) and np.all(ratio >= 0.99), ratio


def test_the_effects_term_is_bounded_for_each_interval_and_axis_as_its_own():
    # norm_information.effect_reach: the largest |Phi(p_k)[i, :] theta'| over the set, per axis i and interval k,
    # against scipy's LP for that very (i, k). Its LPs are solved axis by axis (row i K + k) and were read back as
    # if interval by interval (3 k + i): each interval's bound of the effects' term was another's (red so).
    from types import SimpleNamespace

    from scipy.optimize import linprog

    from garant.verify.workflows.norm_information import effect_reach
    rng = np.random.default_rng(8)
    P, K = 2, 12
    A = rng.normal(size=(9 + P, K))
    x0 = rng.uniform(-0.1, 0.1, 9 + P)
    bound = np.full(K, 0.05)
    s = A.T @ x0 + rng.uniform(-0.04, 0.04, K)
    ext = SimpleNamespace(phi=rng.normal(size=(P, 3, K)) * np.arange(1, K + 1))     # each interval its own size
    got = effect_reach(A, s, bound, np.ones(9 + P), ext)
    rows, rhs = np.hstack([A, -A]).T, np.r_[s + bound, bound - s]
    for i in range(3):
        for k in range(K):
            c = np.r_[np.zeros(9), ext.phi[:, i, k]]
            ends = [linprog(sign * c, A_ub=rows, b_ub=rhs, bounds=[(-1, 1)] * (9 + P), method="highs").fun
                    for sign in (1.0, -1.0)]
            want = max(abs(ends[0]), abs(ends[1]))
            assert want <= got[i, k] <= want * (1 + 1e-6) + 1e-12, (i, k, got[i, k], want)
