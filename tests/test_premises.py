"""Guaranteed for MEMS units too (issue 23): the estimate is linearised at the exact-model fit, every
a-priori bound is a stated premise, and the printed bounds contain the truth whenever the premises
hold, on every built-in stand, without becoming vacuous."""
import json

import numpy as np
import pytest

from conftest import write_csv
from garant.verify import models
from garant.verify.cli import main
from garant.verify.io.positions import Positions
from garant.verify.workflows.estimate import estimate
from garant.verify.workflows.premises import premises

G = 9.81
SIGMA = 1e-5
#: A MEMS-size block (issue 23, item 0): scale errors to 2e-2, misalignments to 1e-2 rad, biases to 0.1 g.
MEMS = {"scale": 2e-2, "misalignment": 1e-2, "bias": 0.1}


def truth(mod, rng, block=MEMS, vertex=False):
    """Physical errors: the block's of the given size, the stand's, mounting's and Delta_g/g within the
    bounds the premises state (uniform inside, or at a vertex of the box: where worst cases live)."""
    prem = premises(mod, SIGMA, G)
    draw = (lambda b: b * rng.choice([-1.0, 1.0])) if vertex else (lambda b: rng.uniform(-b, b))
    p = np.zeros(len(mod.PARAMETER_NAMES))
    for k, (name, kind) in enumerate(zip(mod.PARAMETER_NAMES, prem.kinds)):
        if kind == "block":
            p[k] = draw(block["scale"] if name[-1] == name[-2] else block["misalignment"])
        elif kind == "bias":
            p[k] = draw(block["bias"])
        else:
            p[k] = draw(prem.bounds[k])
    return p


def grid(mod):
    """The 30 x 45 degree grid on two angles (issue 23), 45 degrees on three, 30 on one (all mountings)."""
    names, mounts = models.layout(mod)
    steps = {1: 30, 2: None, 3: 90}[len(names)]
    if len(names) == 2:
        axes = [np.arange(0, 360, 30.0), np.arange(0, 360, 45.0)]
    else:
        axes = [np.arange(0, 360, steps)] * len(names)
    P = np.array(np.meshgrid(*axes, indexing="ij")).reshape(len(names), -1).T
    m = None
    if len(mounts) > 1:
        m = np.repeat(np.arange(len(mounts)), len(P))
        P = np.tile(P, (len(mounts), 1))
    return P, m


def readings(mod, P, m, p, noise):
    kw = {"mount": m} if m is not None else {}
    return mod.readings(*np.deg2rad(P).T, p, G, **kw).T + G * noise


def run(mod, P, m, f):
    r = estimate(mod, Positions("mems", P, f, m), SIGMA, G)
    if not r["consistent"]:
        return r, None, None
    return r, np.array(list(r["q"].values())), np.array(list(r["guaranteed_error"].values()))


@pytest.mark.parametrize("name", ["two-axis", "single-axis", "three-axis"])
def test_mems_unit_bounds_contain_the_truth_and_stay_useful(name):
    # Monte Carlo and adversarial: truths at box vertices, noise at +-sigma with the signs of an
    # estimator's weights (its worst case). 0 truths outside a printed bound with a verdict of consistent;
    # every bound within 3x of the same run with block errors of 1e-4 (not vacuous). Before issue 23 the
    # two-axis MEMS case printed bounds the truth exceeded by 1.3-1.75x (linearised at zero errors).
    mod = models.load(name)
    P, m = grid(mod)
    rng = np.random.default_rng(23)
    small = {"scale": 1e-4, "misalignment": 1e-4, "bias": 1e-4}
    for trial in range(3):
        p = truth(mod, rng, vertex=trial > 0)
        noise = rng.choice([-1.0, 1.0], (len(P), 3)) * SIGMA
        r, q, e = run(mod, P, m, readings(mod, P, m, p, noise))
        assert r["consistent"], (name, trial)
        if trial == 2:                                  # the estimator's own worst noise for its largest bound
            nu = int(np.argmax(e))
            W = _weights(mod, P, m, readings(mod, P, m, p, 0 * noise), nu)
            r, q, e = run(mod, P, m, readings(mod, P, m, p, SIGMA * np.sign(W).reshape(-1, 3)))
            assert r["consistent"]
        assert np.all(np.abs(q - mod.PHYSICAL_TO_Q @ p) <= e), (name, trial)
        # Not vacuous: beyond what the premises themselves leave open (q's linear definition against the
        # unit's nonlinear invariance: about |Gamma| times the a-priori bound of the unseparable
        # parameters, which no estimator can remove), within 3x of a block 200 times smaller.
        parts = r["remainder_parts"]
        premised = np.array([parts["unseparable"][n] + parts["absorbed_into_q"][n] for n in mod.Q_NAMES])
        _, _, e_small = run(mod, P, m, readings(mod, P, m, truth(mod, rng, small), noise))
        assert np.all(e - premised <= 3 * e_small), (name, trial, ((e - premised) / e_small).max())


def _weights(mod, P, m, f, nu):
    """The weights of q_nu's estimator on these readings (z = f/g - u): by linearity, the response of
    the estimate to a unit change of each reading is the estimator itself, which we read off the LP."""
    from garant.verify.solve import lp
    from garant.verify.workflows import estimate as workflow, guarantee
    pos = Positions("mems", P, f, m)
    z = workflow.residuals_table_axes(mod, pos, G, np.eye(3)).reshape(-1)
    A = lp.measurement_matrix(mod, np.deg2rad(P), m)
    lin = guarantee.linearise(mod, pos, z, A, premises(mod, SIGMA, G))
    return lp.primal(lin.A)[0].T[nu]


def test_the_mems_case_of_the_issue_through_the_command(tmp_path):
    # Item 0 of issue 23 as a user runs it: `garant estimate --g 9.81` on a MEMS block, stand errors of
    # 2e-5 rad, the 30x45 grid, noise at +-sigma: exit 0, every q inside its bound, the premises in the
    # JSON (the noise bound and its source, each a-priori bound and its source, the statement).
    mod = models.load("two-axis")
    P, _ = grid(mod)
    rng = np.random.default_rng(0)
    p = truth(mod, rng)
    p[[mod.PARAMETER_NAMES.index(n) for n in ("kappa", "epsilon", "Delta_alpha", "Delta_beta", "alpha_star")]] = \
        rng.uniform(-2e-5, 2e-5, 5)
    p[mod.PARAMETER_NAMES.index("Delta_g")] = 0.0
    data = write_csv(tmp_path / "d.csv", P, readings(mod, P, None, p, rng.choice([-1, 1], (len(P), 3)) * SIGMA))
    out = tmp_path / "e.json"
    assert main(["estimate", "--model", "two-axis", str(data), "--sigma", "1e-5", "--g", "9.81",
                 "--json", str(out)]) == 0
    d = json.loads(out.read_text())
    q = np.array([d["q"][n] for n in mod.Q_NAMES])
    e = np.array([d["guaranteed_error"][n] for n in mod.Q_NAMES])
    assert np.all(np.abs(q - mod.PHYSICAL_TO_Q @ p) <= e) and e.max() < 3e-4
    prem = d["premises"]
    assert prem["sigma"] == 1e-5 and prem["sigma_source"] == "--sigma"
    assert prem["g_uncertainty"] == 1e-5 and "local --g" in prem["g_source"]
    assert prem["a_priori"]["theta2"] == {"kind": "mounting", "bound": 5e-3, "source": "stand description"}
    assert prem["a_priori"]["Gamma11"]["source"] == "default for a block error"
    assert prem["statement"].startswith("the bounds hold if every residual component of (5) is within sigma")


def test_a_unit_outside_its_premises_is_named_and_inside_them_is_sound(tmp_path, capsys):
    # Item 1 of issue 23: scale errors and Delta_g of 5e-3, no noise, sigma 1e-6. With a local --g the
    # premise |Delta_g/g| <= 1e-5 is false: the output states it as an assumption (or the data refute it).
    # With --g-uncertainty 6e-3 the premise holds and every q is inside its bound.
    mod = models.load("two-axis")
    P, _ = grid(mod)
    p = np.zeros(len(mod.PARAMETER_NAMES))
    for n in ("Gamma11", "Gamma22", "Gamma33", "Delta_g"):
        p[mod.PARAMETER_NAMES.index(n)] = 5e-3
    data = write_csv(tmp_path / "d.csv", P, readings(mod, P, None, p, 0.0))
    out = tmp_path / "e.json"
    code = main(["estimate", "--model", "two-axis", str(data), "--sigma", "1e-6", "--g", "9.81", "--json", str(out)])
    text = capsys.readouterr().out
    assert code in (0, 3) and "|Delta_g/g| <= 1e-05" in text
    assert main(["estimate", "--model", "two-axis", str(data), "--sigma", "1e-6", "--g", "9.81",
                 "--g-uncertainty", "6e-3", "--json", str(out)]) == 0
    d = json.loads(out.read_text())
    q = np.array([d["q"][n] for n in mod.Q_NAMES])
    e = np.array([d["guaranteed_error"][n] for n in mod.Q_NAMES])
    assert np.all(np.abs(q - mod.PHYSICAL_TO_Q @ p) <= e)


def test_relinearised_h_at_zero_errors_is_h_of_000():
    # The Jacobian of the exact model by the complex step, at zero errors, in the q coordinates: H of (3)
    # of 000 itself, exactly (a wrong coordinate map or step turns it red).
    from garant.verify.solve import taylor
    from garant.verify.workflows import guarantee
    mod = models.load("two-axis")
    P, _ = grid(mod)
    L, _, _ = guarantee.coordinates(mod, premises(mod, SIGMA, G).bounds)
    _, J = taylor.jacobian(mod, np.deg2rad(P).T, L, np.zeros(L.shape[0]))
    H = np.moveaxis(mod.H(*np.deg2rad(P).T), 2, 0)
    assert np.abs(J[:, :, :15] - H).max() <= 1e-15 and np.abs(J[:, :, 15:]).max() <= 1e-15
    assert np.array_equal(np.asarray(mod.PHYSICAL_TO_Q, float) @ L, np.eye(21)[:15])


PLAN10 = np.array([[0, 0], [0, 180], [180, 90], [180, 270], [90, 90], [270, 90], [90, 270], [90, 180], [270, 180],
                   [90, 0]], float)   # the starred rows of Table 2 of 000


def test_a_minimal_plan_says_which_estimators_it_cannot_check(tmp_path, capsys):
    # Item 6 of issue 23: on the 10-position plan of 000, offsets of 10 sigma shaped like q3's estimator are
    # fitted exactly, so the verdict passes and q3 misses its bound: the output must say that
    # those bounds rest on sigma. The 96-position grid has redundancy along every estimator: no such line.
    mod = models.load("two-axis")
    rng = np.random.default_rng(5)
    p = truth(mod, rng, {"scale": 1e-4, "misalignment": 1e-4, "bias": 1e-4})
    sigma = 1e-6
    z0 = readings(mod, PLAN10, None, p, 0.0)
    W = _weights(mod, PLAN10, None, z0, 2)
    offset = 10 * sigma * W.reshape(-1, 3) / np.abs(W).max()
    data = write_csv(tmp_path / "d.csv", PLAN10, z0 + G * offset)
    out = tmp_path / "e.json"
    assert main(["estimate", "--model", "two-axis", str(data), "--sigma", "1e-6", "--json", str(out)]) == 0
    d = json.loads(out.read_text())
    assert abs(d["q"]["q3"] - (mod.PHYSICAL_TO_Q @ p)[2]) > 1.5 * d["guaranteed_error"]["q3"]   # missed
    assert any("estimators of q3" in w and "rest on sigma" in w for w in d["warnings"])
    assert "note: noise shaped like the estimators of q3" in capsys.readouterr().out
    P, _ = grid(mod)
    r = estimate(mod, Positions("grid", P, readings(mod, P, None, p, 0.0)), sigma, G)
    assert not any("rest on sigma" in w for w in r["warnings"])


def test_smallest_supported_sigma_to_its_stated_tolerance(tmp_path):
    # Item 6: the data refute sigma = 1e-6 (noise 1e-5); the smallest sigma they support is found to the
    # stated relative tolerance: the data support it, and refute it less the tolerance.
    mod = models.load("two-axis")
    P, _ = grid(mod)
    rng = np.random.default_rng(8)
    p = truth(mod, rng, {"scale": 1e-4, "misalignment": 1e-4, "bias": 1e-4})
    f = readings(mod, P, None, p, rng.uniform(-1e-5, 1e-5, (len(P), 3)))
    r = estimate(mod, Positions("n", P, f), 1e-6, G)
    s, tol = r["sigma_min_supported"], r["sigma_min_tolerance"]
    assert not r["consistent"] and 1e-6 < s <= 1.1e-5 and tol == 0.01
    assert estimate(mod, Positions("n", P, f), s, G)["consistent"]
    assert not estimate(mod, Positions("n", P, f), s / (1 + tol) ** 2, G)["consistent"]


def test_remainder_part_per_q_against_the_worst_nonlinear_error_found():
    # Item 3 of issue 23: each q's remainder part against the worst nonlinear error of its estimate that a
    # search finds where worst cases live (vertices of the last box, single-sign flips): on the 10-position
    # plan of 000, a precision block. Every bound holds the worst found (soundness). The block combinations
    # are within 3x (they are set by the mounting's bound, which the search attains); the stand and bias
    # combinations are within 20x of 1 % of sigma times their linear factor (the interval width of the
    # Hessian over the mounting's box; before issue 23, over 4,000x): a looser bound turns this red.
    from garant.verify.solve import lp, worst
    from garant.verify.workflows import estimate as workflow, guarantee
    mod = models.load("two-axis")
    rng = np.random.default_rng(0)
    p = truth(mod, rng, {"scale": 1e-4, "misalignment": 1e-4, "bias": 1e-4})
    pos = Positions("plan", PLAN10, readings(mod, PLAN10, None, p, 0.0))
    z = workflow.residuals_table_axes(mod, pos, G, np.eye(3)).reshape(-1)
    lin = guarantee.linearise(mod, pos, z, lp.measurement_matrix(mod, np.deg2rad(PLAN10)), premises(mod, SIGMA, G))
    W, _ = workflow.choose_estimator(mod, pos, lin.A)
    v = guarantee.verdict(lin, z, SIGMA, W)
    lo, hi = v.box
    m = len(mod.Q_NAMES)
    cols = list(lin.keep) + list(range(m, lin.L.shape[1]))
    centre = np.r_[lin.q0[lin.keep], np.zeros(len(lin.T))]
    half = np.maximum(hi - centre, centre - lo)

    def nonlinear(nu, V):
        out = []
        for dv in V.T:
            full = np.r_[lin.q0, np.zeros(len(lin.T))]
            full[cols] += dv
            out.append(W[nu] @ (guarantee._z_exact(mod, pos, lin.L @ full, G) - lin.z0) - (full[nu] - lin.q0[nu]))
        return np.array(out)
    found = np.array([worst.vertex_search(lambda X, V, nu=nu: nonlinear(nu, V), np.zeros((1, 1)), half, starts=4,
                                          keep=4, ascent=0, rounds=6, seed=nu).value for nu in range(m)])
    assert np.all(found <= v.error_remainder)
    ratio = v.error_remainder / np.maximum(found, 0.01 * v.error_linear)
    lead = [mod.PARAMETER_NAMES.index(d.split()[0]) for d in mod.Q_DEFINITIONS]     # q's leading parameter
    block = np.array([mod.PARAMETER_KINDS[k] == "block" for k in lead])
    assert block.sum() == 9
    assert np.all(ratio[block] <= 3) and np.all(ratio <= 20), ratio
