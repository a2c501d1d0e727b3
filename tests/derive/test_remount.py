"""Other mountings, (25)-(29) of 000: derived substitutions, round trips, and recovery from data."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from garant.generated import two_axis_remount as rm
from conftest import write_csv, fast_first
from garant.derive.derivation import derive
from garant.derive.remount import mountings, substitution_holds
from garant.derive.builtin import TWO_AXIS_MODEL
from garant.verify.io.positions import read_positions
from garant.verify.papers import physics_000
from garant.verify.workflows import mounting
from garant.verify.workflows.estimate import estimate

NAMES = sorted(rm.MOUNTS)
STAND = ("kappa", "epsilon", "Delta_alpha", "Delta_beta", "alpha_star", "Delta_g")


def test_24_proper_mountings():
    Qs = mountings()
    assert len(Qs) == 24 and set(Qs) == set(rm.MOUNTS)
    assert len({tuple(np.array(Q, int).ravel()) for Q in Qs.values()}) == 24


@pytest.mark.slow
def test_substitutions_26_27_hold_for_every_mounting():
    d = derive(TWO_AXIS_MODEL)
    assert all(substitution_holds(d, Q) for Q in mountings().values())


def test_unseen_part_is_E_dg_minus_N_dbeta():
    # (29) of 000: E Delta_g/g - Q N Q^-1 Delta_beta, N = [[0,-1,0],[1,0,0],[0,0,0]].
    np.testing.assert_array_equal(rm.D_DELTA_G, np.eye(3))
    np.testing.assert_array_equal(rm.D_DELTA_BETA, -np.array([[0, -1, 0], [1, 0, 0], [0, 0, 0]]))


@settings(max_examples=40, deadline=None)
@given(st.sampled_from(NAMES))
def test_Q_is_a_proper_rotation(name):
    Q = rm.MOUNTS[name]
    np.testing.assert_array_equal(Q.T @ Q, np.eye(3))
    assert round(np.linalg.det(Q)) == 1
    axis = {"x": 0, "y": 1, "z": 2}
    for i in range(3):
        sign, ax = name[2 * i], name[2 * i + 1]
        assert Q[i, axis[ax]] == (1 if sign == "+" else -1)


def independent_readings(P_deg, stand, Q, Gamma, bias, theta_k, g=1.0):
    """Readings (N, 3) from the paper's chain written directly in numpy (no derive/, no generated/)."""
    return g * np.array([physics_000.readings_over_g(a, b, stand, Q, Gamma, bias, theta_k)
                         for a, b in np.deg2rad(np.asarray(P_deg, float))])


@settings(max_examples=40, deadline=None)
@given(st.sampled_from(NAMES), st.sampled_from(["lower", "symmetric"]), st.integers(0, 10**6))
def test_recovery_round_trip(mod, name, gamma, seed):
    # (28)-(29) of 000: readings simulated by the paper's chain, q by least squares with the generated
    # H on the quarter grid, then the recovery: exact up to the second order of errors of size 1e-6.
    rng = np.random.default_rng(seed)
    size, Q = 1e-6, rm.MOUNTS[name]
    stand = dict(zip(STAND, rng.uniform(-size, size, 6)))
    Gamma = rng.uniform(-size, size, (3, 3))
    Gamma = np.tril(Gamma) if gamma == "lower" else (Gamma + Gamma.T) / 2
    bias, theta_k = rng.uniform(-size, size, 3), rng.uniform(-size, size, 3)
    P = np.array([(a, b) for a in (0, 90, 180, 270) for b in (0, 90, 180, 270)], float)
    f = independent_readings(P, stand, Q, Gamma, bias, theta_k)
    z = np.concatenate([physics_000.residual_table_axes(a, b, fk, Q) for (a, b), fk in zip(np.deg2rad(P), f)])
    A = np.transpose(mod.H(*np.deg2rad(P).T), (1, 2, 0)).reshape(15, -1)
    q = np.linalg.lstsq(A.T, z, rcond=None)[0]
    got = rm.recovery_matrix(name, gamma) @ q + rm.neglected(name, stand["Delta_g"], stand["Delta_beta"], gamma)
    want = np.concatenate([[stand["kappa"], stand["Delta_alpha"] + stand["alpha_star"], stand["epsilon"]],
                           bias, Gamma.ravel(), theta_k])
    np.testing.assert_allclose(got, want, atol=1e-4 * size)


@pytest.mark.parametrize("seed", range(4))
def test_simulate_estimate_recover_within_bounds(mod, tmp_path, seed):
    rng = np.random.default_rng(seed)
    name, gamma = NAMES[rng.integers(24)], ("lower", "symmetric")[seed % 2]
    sigma, g, size = 1e-5, 9.81, 1e-4
    stand = dict(zip(STAND, rng.uniform(-size, size, 6)))
    Gamma = rng.uniform(-size, size, (3, 3))
    Gamma = np.tril(Gamma) if gamma == "lower" else (Gamma + Gamma.T) / 2
    bias, theta_k = rng.uniform(-1e-3, 1e-3, 3), rng.uniform(-size, size, 3)
    P = np.array(mod.PLAN_DEG, float) + (rng.uniform(-0.5, 0.5, (10, 2)) if seed >= 2 else 0)
    f = independent_readings(P, stand, rm.MOUNTS[name], Gamma, bias, theta_k, g)
    f += g * rng.uniform(-sigma, sigma, f.shape)
    res = estimate(mod, read_positions(write_csv(tmp_path / "d.csv", P, f)), sigma, g,
                   remount=rm, mount=name, gamma=gamma)
    assert ("(23)" in res["method"]) == (seed >= 2)
    ph, bd = res["physical"], res["physical_bound"]
    neg = dict(zip(rm.OUTPUTS, rm.neglected(name, stand["Delta_g"], stand["Delta_beta"], gamma)))
    rem = 1e-7                                   # second-order remainder, |errors| <= 1e-4
    for key, true in (("kappa", stand["kappa"]), ("epsilon", stand["epsilon"]),
                      ("dalpha_plus_astar", stand["Delta_alpha"] + stand["alpha_star"])):
        assert abs(ph[key] - true) <= bd[key] + rem
    for i in range(3):
        assert abs(ph["bias"][i] - g * bias[i]) <= bd["bias"][i] + g * rem
        assert abs(ph["theta_k"][i] - theta_k[i] + neg[f"theta_k{i + 1}"]) <= bd["theta_k"][i] + rem
        for j in range(3):
            err = ph["Gamma"][i][j] - Gamma[i, j] + neg[f"Gamma{i + 1}{j + 1}"]
            assert abs(err) <= bd["Gamma"][i][j] + rem


def test_cli_estimate_with_mount_prints_block_errors(mod, tmp_path, capsys):
    # The --mount path of `garant estimate` end to end: the table of block errors (29) of 000 is printed.
    from garant.verify.cli import main
    stand = dict(zip(STAND, [1e-4] * 6))
    f = mounting.mounted_readings(mod, rm, *np.deg2rad(np.array(mod.PLAN_DEG, float).T), stand,
                                  np.zeros((3, 3)), np.zeros(3), np.zeros(3), "+y+z+x", 9.81).T
    path = write_csv(tmp_path / "d.csv", mod.PLAN_DEG, f)
    assert main(["estimate", "--model", "two-axis", str(path), "--sigma", "1e-5", "--mount", "+y+z+x"]) == 0
    out = capsys.readouterr().out
    assert "block errors in block axes, mounting +y+z+x" in out and "theta_k3" in out


@pytest.mark.parametrize("seed", fast_first(range(3)))
def test_mems_size_block_errors_recovered_within_bounds(mod, tmp_path, seed):
    # The block's physical errors (29) of 000 from the q of an estimate in which the block absorbs the
    # mounting and Delta_g: their split into Gamma and theta_k is first order in the q of (4) taken
    # literally, which differ from the absorbed ones by about |Gamma| |theta|. The bound must carry that
    # (premised on the mounting's stated bound): MEMS-size Gamma (2e-2) and theta_k (5e-3, the two-axis
    # description's bound), noise at +-sigma. Without that term the Gamma bounds miss by about 1e-4.
    rng = np.random.default_rng(seed)
    name, gamma = NAMES[rng.integers(24)], "lower"
    sigma, g = 1e-5, 9.81
    stand = dict(zip(STAND, rng.uniform(-1e-5, 1e-5, 6)))
    Gamma = np.tril(rng.uniform(-2e-2, 2e-2, (3, 3)))
    bias, theta_k = rng.uniform(-0.05, 0.05, 3), rng.choice([-5e-3, 5e-3], 3)
    P = np.array([(a, b) for a in range(0, 360, 30) for b in range(0, 360, 45)], float)
    f = independent_readings(P, stand, rm.MOUNTS[name], Gamma, bias, theta_k, g)
    f += g * sigma * rng.choice([-1.0, 1.0], f.shape)
    res = estimate(mod, read_positions(write_csv(tmp_path / "d.csv", P, f)), sigma, g,
                   remount=rm, mount=name, gamma=gamma)
    assert res["consistent"]
    ph, bd = res["physical"], res["physical_bound"]
    neg = dict(zip(rm.OUTPUTS, rm.neglected(name, stand["Delta_g"], stand["Delta_beta"], gamma)))
    for i in range(3):
        assert abs(ph["theta_k"][i] - theta_k[i] + neg[f"theta_k{i + 1}"]) <= bd["theta_k"][i]
        for j in range(3):
            assert abs(ph["Gamma"][i][j] - Gamma[i, j] + neg[f"Gamma{i + 1}{j + 1}"]) <= bd["Gamma"][i][j]
