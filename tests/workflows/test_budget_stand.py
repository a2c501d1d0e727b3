"""garant budget of stand files (000): the block's calibration over its set (three-axis), a two-axis file in the frame
the data define (its q's set, the LQ split's rest outward), constant and over temperature; each figure against the
truth of a simulated unit and against a lower bound of the largest the information set allows, computed here
independently (test_budget.py's helpers: the error's derivative by finite differences, HiGHS's LP over the set)."""
import json

import numpy as np
import pytest

from garant.verify.cli import main
from garant.verify.io import calibration
from test_budget import _truth_inside, _within_1_25x

G = 9.81


def _stand_error(cal):
    """e(n, z) = M ((E + Gamma) g n + g beta - b) - g n of a stand file for the block (Gamma, beta) at the set's
    block columns: (off, C) with e = off + C z, by differences (exactly affine)."""
    st, g, M, b = cal["information_set"], cal["g"], cal["M"], cal["b"]
    cols = np.asarray(st["block_columns"])
    P = len(st["estimate"])

    def e(n, z):
        p = z[cols]
        return M @ ((np.eye(3) + p[:9].reshape(3, 3)) @ (g * n) + g * p[9:] - b) - g * n

    def at(n):
        off = e(n, np.zeros(P))
        return off, np.column_stack([(e(n, 1e-3 * np.eye(P)[j]) - off) / 1e-3 for j in range(P)])
    return at


@pytest.mark.slow
def test_a_stand_file_s_budget_holds_the_truth_and_sits_within_1_25x_of_the_sets_largest(tmp_path):
    # The same figures for a three-axis stand's calibration (the block over its set, 000, 39 columns): the unit's
    # own errors at 1,000 attitudes within them, each within 1.25x of the largest the set allows at a grid's
    # attitudes (LPs here). Red with every other row that can bind left out of the LPs (support.essential: per axis
    # 1.45x).
    from garant.verify import models
    from garant.verify.solve import plans
    mod = models.load("three-axis")
    names, _ = models.layout(mod)
    rng = np.random.default_rng(5)
    p = np.array([rng.uniform(-2e-3, 2e-3) if k in ("block", "bias") else 0.0 for k in mod.PARAMETER_KINDS])
    P = plans.grid(mod)[0]
    f = mod.readings(*np.deg2rad(P).T, p, G).T + G * 1e-4 * rng.uniform(-1, 1, (len(P), 3))
    data = tmp_path / "d.csv"
    data.write_text(",".join([f"{a}_deg" for a in names] + ["f1", "f2", "f3"]) + "\n" + "\n".join(
        ",".join(map(repr, map(float, [*P[k], *f[k]]))) for k in range(len(P))) + "\n")
    cal_path, out = tmp_path / "c.json", tmp_path / "b.json"
    assert main(["estimate", "--model", "three-axis", str(data), "--sigma", "1e-4", "--g", str(G),
                 "--save", str(cal_path)]) == 0
    assert main(["budget", str(cal_path), "--json", str(out)]) == 0
    res = json.loads(out.read_text())
    cal = calibration.read(cal_path)
    names_p = list(mod.PARAMETER_NAMES)
    Gam = np.array([[p[names_p.index(f"Gamma{i}{j}")] for j in (1, 2, 3)] for i in (1, 2, 3)])
    beta = np.array([p[names_p.index(f"bias{i}")] for i in (1, 2, 3)])
    m = rng.normal(size=(1000, 3))
    m /= np.linalg.norm(m, axis=1)[:, None]
    e = ((np.eye(3) + Gam) @ (G * m.T)).T + G * beta - cal["b"]
    e = e @ cal["M"].T - G * m
    _truth_inside(res, e, m)
    _within_1_25x(res, cal, _stand_error(cal))
