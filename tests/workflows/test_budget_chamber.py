"""garant budget of a two-axis stand's file over temperature (estimate --thermal-degree on a chamber session), over
every attitude and temperature of its range; each figure against the truth of a simulated unit and a lower bound of
the set's largest computed independently (test_budget.py's helpers; test_sample_set.py `lower_jacobian`)."""
import json

import numpy as np
import pytest

from garant.verify.cli import main
from garant.verify.io import calibration, schemas
from test_budget import _ascend_tilt, _between, _directions, _largest, _largest_norm_at, _tilt_at, _truth_inside

G = 9.81


@pytest.mark.slow
def test_a_two_axis_file_over_temperature_is_budgeted_over_its_range(tmp_path):
    # A chamber session's file (two-axis, --thermal-degree 1: every Gamma_ij and bias_i linear in T) was refused
    # ("not budgeted yet"). Its figures are LPs at the Bernstein control points of the error's polynomial in T over
    # the set, M(T) about the range's middle and the rest outward (workflows/budget.py lower_thermal_figures): the
    # unit's own errors at 1,000 random attitudes and temperatures of the range within every figure (in the frame
    # the data define), and each figure within 1.25x of a lower bound of the set's largest (the file's correction of
    # a unit q differentiated here, HiGHS's LP, at a grid's attitudes and the range's ends, the tilt's by a local
    # ascent from the grid's best). Red with the drift left out of the Models (the control point at t0 alone): the
    # per-axis figures 0.47-0.84x that lower bound (the truth check alone passes: this unit's own errors are small).
    from test_sample_set import lower_jacobian
    from garant.verify import models
    truth = {"kappa": 2e-5, "epsilon": -1.5e-5, "theta1": 3e-3, "theta2": -2e-3, "Gamma11": 1.2e-2, "Gamma22": -8e-3,
             "Gamma33": 5e-3, "Gamma21": 4e-3, "Gamma31": -3e-3, "Gamma32": 2e-3, "bias1": 0.05, "bias2": -0.03,
             "bias3": 0.02, "bias1_T1": 1e-3, "bias2_T1": -1e-3, "bias3_T1": 1e-3, "Gamma11_T1": 1e-4,
             "Gamma22_T1": -1e-4, "Gamma33_T1": 1e-4, "Gamma21_T1": 2e-5}
    mod = models.thermal("two-axis", 1, 20)
    p = np.array([truth.get(n, 0.0) for n in mod.PARAMETER_NAMES])
    P1 = np.array([(a, b) for a in range(0, 360, 90) for b in range(0, 360, 90)], float)
    temps = (-20.0, 20.0, 60.0)
    P, T = np.tile(P1, (len(temps), 1)), np.repeat(temps, len(P1))
    rng = np.random.default_rng(8)
    f = mod.readings(*np.deg2rad(P).T, p, G, temp_c=T).T + G * 1e-4 * rng.uniform(-1, 1, (len(P), 3))
    data = tmp_path / "chamber.csv"
    np.savetxt(data, np.column_stack([P, f, T]), delimiter=",", header="alpha_deg,beta_deg,f1,f2,f3,temp_c",
               comments="", fmt="%.17g")
    cal_path, out = tmp_path / "c.json", tmp_path / "b.json"
    assert main(["estimate", "--model", "two-axis", str(data), "--sigma", "1e-4", "--g", str(G), "--thermal-degree",
                 "1", "--save", str(cal_path), "--json", str(tmp_path / "r.json")]) == 0
    assert main(["budget", str(cal_path), "--json", str(out)]) == 0
    res = json.loads(out.read_text())
    schemas.validate(res, "budget", str(out))
    assert res["temperature_range_c"] == [-20.0, 60.0]
    cal = calibration.read(cal_path)

    def block(k=""):
        return (np.array([[truth.get(f"Gamma{i}{j}{k}", 0.0) for j in (1, 2, 3)] for i in (1, 2, 3)]),
                np.array([truth.get(f"bias{i}{k}", 0.0) for i in (1, 2, 3)]))
    (G0, b0), (G1, b1) = block(), block("_T1")
    EG0 = np.eye(3) + G0
    R0 = np.linalg.solve(np.linalg.cholesky(EG0 @ EG0.T), EG0)     # block axes -> the frame the data define
    m = rng.normal(size=(1000, 3))
    m /= np.linalg.norm(m, axis=1)[:, None]
    Ts = rng.uniform(-20.0, 60.0, 1000)
    Gf, bf, _ = calibration.thermal_gamma(cal, Ts)
    e = np.array([np.linalg.solve(np.eye(3) + Gf[i], (np.eye(3) + G0 + tau * G1) @ (R0.T @ (G * m[i])) + G * (
        b0 + tau * b1) - bf[i]) - G * m[i] for i, tau in enumerate(Ts - 20.0)])
    _truth_inside(res, e, m)
    st, definitions = cal["information_set"], json.loads((tmp_path / "r.json").read_text())["definitions"]
    q_m = np.asarray(st["estimate"])
    axis, norm, tilt = np.zeros(3), 0.0, 0.0
    for t in (-20.0, 60.0):                            # (degree 1: each unit's error is affine in T, largest at an end)
        M_t, b_t = np.linalg.inv(np.eye(3) + calibration.thermal_gamma(cal, [t])[0][0]), \
            calibration.thermal_gamma(cal, [t])[1][0]

        def at(n, M_t=M_t, b_t=b_t, t=t):
            C = lower_jacobian(st, definitions, np.linalg.solve(M_t, G * n) + b_t, t - 20.0)
            return -C @ q_m, C
        got = _largest(cal, at, np.vstack([_directions(2), res["worst_attitude"]]))
        axis, tilt = np.maximum(axis, got[0]), max(tilt, got[2])
        norm = max(norm, got[1], _largest_norm_at(cal, at, np.array(res["worst_attitude"])))
        # the tilt's worst case between the grid's attitudes: a local ascent from the grid's best at this end
        start = max(_directions(2), key=lambda n: _tilt_at(cal, at, n))
        tilt = max(tilt, _ascend_tilt(cal, at, start))
    _between(res, axis, norm, tilt)
