"""Norm-side discovery carried through: `calibrate-norm --diagnose` names the effect a static log needs and the
command that adds it; `--effect` calibrates the extended norm relation (2.2) of 001 with every bound over its
information set, the truth inside each; the file it saves takes the effect out of each sample in `garant apply`."""
import json

import numpy as np
import pytest

from garant.generated import norm as N
from garant.verify.cli import main
from garant.verify.io import schemas
from garant.verify.workflows import jobs
from conftest import G_REAL, REAL, ROOT, needs_real, flat, command_line, fast_first
from test_diagnose_norm import EFFECTS, G, _warm_up, static_log

#: The hidden effects' parameters as the generator of test_diagnose_norm.py adds them (over g, the units of the
#: generated module's EFFECT_UNITS), in the order of N.EFFECTS[name].
TRUE = {
    "bias_drift": [3e-6, -2e-6, 2e-6],
    "scale_quadratic": [2e-3, -2e-3, 1.5e-3],
    "cross_coupling": [2e-3, 0.0, 0.0, 2e-3, -2e-3, 0.0],     # C_12, C_13, C_21, C_23, C_31, C_32
    "scale_asymmetry": [1.5e-3, -1e-3, 1e-3],
    "bias_temperature": [2e-5, -2e-5, 1.5e-5],
}


def _truth(seed=0):
    """The 9 parameters of (1.3) of 001 the generator draws first (lambda, misalignments, biases over g)."""
    return np.random.default_rng(seed).uniform(-2e-3, 2e-3, 9)


def test_the_true_effects_are_the_generators():
    # The table above against the generator's own functions: the basis of the generated module times TRUE is the
    # generator's term (red when a value or the order of the parameters is copied wrong).
    rng = np.random.default_rng(3)
    w = rng.normal(size=(3, 5))
    w /= np.linalg.norm(w, axis=0)
    for name, theta in TRUE.items():
        t = 100.0
        mine = np.einsum("j,jik->ik", theta, N.effect_basis(name, w, t, _warm_up(t)))
        theirs = np.array([EFFECTS[name](G * w[:, k], t) for k in range(5)]).T / G
        np.testing.assert_allclose(mine, theirs, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("effect", fast_first(list(TRUE)))
def test_the_named_effect_is_added_and_the_truth_lies_in_every_bound(tmp_path, effect):
    # Each log refutes the 9-parameter model; the diagnosis ends with the set whose whole calibration is consistent,
    # the hidden effect (a quadratic scale factor is named as cross-coupling to first order, and the second order
    # tells them apart: the calibration with cross-coupling is checked and not taken); with it the log calibrates,
    # and the truth lies within every bound: the scale factors, misalignments and biases (the bias at the time the
    # effect counts from, for a drift), and the effect's own parameters. Red when the diagnosis takes the
    # first-order family's first member without checking it (the quadratic log then adds cross_coupling).
    log = str(static_log(tmp_path / "log.csv", effect))
    res = jobs.calibrate_norm(log, g=G, diagnose=True).to_dict()
    assert not res["consistent"]
    d = res["diagnosis"]
    assert d["add"] == [effect], d["checked"]
    out = jobs.calibrate_norm(log, g=G, effects=effect).to_dict()
    assert out["consistent"]
    truth = _truth()
    if effect == "bias_drift":
        truth[6:9] += np.array(TRUE[effect]) * out["effect_reference"]["time_s"]
    for k, (name, value) in enumerate(out["parameters"].items()):
        assert abs(value - truth[k]) <= out["guaranteed_error"][name], (name, value, truth[k])
    pars = out["effects"][effect]["parameters"]
    for name, true in zip(N.EFFECTS[effect], TRUE[effect]):
        assert abs(pars[name]["estimate"] - true) <= pars[name]["guaranteed_error"], (name, pars[name], true)
    schemas.validate(json.loads(json.dumps(out)), "calibrate-norm", "out")
    schemas.validate(json.loads(json.dumps(out["calibration"])), "calibration", "calibration")


def test_a_log_without_an_effect_names_nothing_and_adds_nothing(tmp_path):
    d = jobs.calibrate_norm(str(static_log(tmp_path / "log.csv", "none")), g=G, diagnose=True).to_dict()["diagnosis"]
    assert d["named"] == [] and d["add"] is None and d["checked"] == {}


@pytest.mark.slow
def test_the_cross_coupling_log_is_not_said_to_be_a_quadratic_scale_factor(tmp_path):
    # The quadratic scale factor is nested in cross-coupling (n_i^3 = n_i - n_i n_j^2 - n_i n_k^2 on the sphere),
    # but a log with cross-coupling the quadratic one cannot fit (worst residual 77 noise bounds) tells them apart:
    # it is not listed as one the data cannot tell from the named effect.
    d = jobs.calibrate_norm(str(static_log(tmp_path / "log.csv", "cross_coupling")), g=G,
                            diagnose=True).to_dict()["diagnosis"]
    assert d["named"] == ["cross_coupling"] and d["equivalent"]["cross_coupling"] == []


@pytest.mark.slow
def test_the_saved_file_takes_the_effect_out_of_each_sample_within_its_bound(tmp_path, capsys):
    # Noise-free readings of the same unit (its 9 parameters and its scale asymmetry) at 2,000 random directions,
    # corrected by the file: within the per-sample bound, component by component. Red when apply leaves the
    # effect in (errors up to 1.5e-3 g, ten times the bound).
    log = static_log(tmp_path / "log.csv", "scale_asymmetry")
    cal = tmp_path / "cal.json"
    assert main(["calibrate-norm", str(log), "--g", str(G), "--effect", "scale_asymmetry", "--save", str(cal),
                 "--export-imu-tk", str(tmp_path / "tk.txt"), "--report", str(tmp_path / "rep")]) == 0
    said = capsys.readouterr().out
    assert "--export-imu-tk has no parameter for scale_asymmetry" in said
    assert "| scale_asymmetry | A_1 |" in (tmp_path / "rep" / "report.md").read_text()      # the report shows them
    rng = np.random.default_rng(7)
    m = rng.normal(size=(3, 2000))
    m /= np.linalg.norm(m, axis=0)
    params = np.concatenate([_truth(), np.zeros(7)])
    f = G * N.readings(m, params[:, None]) + np.array([EFFECTS["scale_asymmetry"](G * m[:, k], 0.0)
                                                        for k in range(m.shape[1])]).T
    t = np.arange(m.shape[1]) / 100.0
    c = jobs.apply(str(cal), np.column_stack([t, f.T]))
    err = np.abs(c.a - G * m.T)
    assert np.all(err <= c.bound), float((err / c.bound).max())
    assert (err / c.bound).max() > 0.05                 # a bound that holds, not one that is vacuous
    plain = json.loads(cal.read_text())
    del plain["effects"]
    plain["model"] = "a = M (raw - b)"
    c0 = jobs.apply(plain, np.column_stack([t, f.T]))
    assert np.any(np.abs(c0.a - G * m.T) > c0.bound)     # without the effect, the same bound fails


@needs_real
@pytest.mark.slow
def test_the_real_openaxes_log_is_named_added_and_calibrated(tmp_path, capsys):
    # The OpenAXES ADXL355 log (the recordings' g) refutes the 9-parameter model with the default noise rule; the
    # diagnosis checks the sets that fit to first order by their whole calibration and ends with the command of
    # the first that calibrates; that command is consistent, with every bound over the information set, and says
    # the worst residual before (above 1) and after (within 1) in units of each interval's noise rule, in the
    # report too. Red when the part of each interval's remainder along n is bounded by the Lipschitz norm alone
    # (then no premise box contracts: "cannot be proven from any box around the fit", no set calibrates).
    log, G = str(REAL / "openaxes_imu9.csv"), G_REAL
    out = tmp_path / "d.json"
    assert main(["calibrate-norm", log, "--sensor", "adxl355", "--g", str(G), "--diagnose", "--json", str(out)]) == 3
    said = capsys.readouterr().out
    d = json.loads(out.read_text())["diagnosis"]
    assert d["max_residual_before"] > 1 and d["add"], d["checked"]
    line = command_line(said, "add them:")
    assert line.startswith(f"add them: garant calibrate-norm {log} --sensor adxl355 --g {G}"), line
    assert line.endswith(f" --effect {','.join(d['add'])}") and "--diagnose" not in line, line
    out = tmp_path / "e.json"
    assert main(["calibrate-norm", log, "--sensor", "adxl355", "--g", str(G), "--effect", ",".join(d["add"]),
                 "--json", str(out), "--report", str(tmp_path / "rep")]) == 0
    res = json.loads(out.read_text())
    assert res["consistent"] and res["effects"] and res["guaranteed_error"]
    m = res["model_discrepancy"]
    assert m["max_residual_before"] > 1 >= m["max_residual_after"], m
    assert "without the effects (INCONSISTENT) ->" in capsys.readouterr().out
    assert "without the effects (INCONSISTENT) ->" in (tmp_path / "rep" / "report.md").read_text()
    schemas.validate(res, "calibrate-norm", "out")


def test_effect_errors_are_one_line(tmp_path, capsys):
    log = static_log(tmp_path / "log.csv", "bias_drift", temperature=False)
    for effect, said in (("warp_drive", "not an effect of the catalogue"),
                         ("alpha_encoder_harmonic", "it needs a stand's angles"),
                         ("bias_temperature", "the log has no temperature column")):
        assert main(["calibrate-norm", str(log), "--effect", effect]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and said in err[0], err
    from garant.verify.errors import DataError
    with pytest.raises(DataError, match="give names as text or a list of text"):     # the API validates as the CLI
        jobs.calibrate_norm(str(log), effects=1)
    assert main(["calibrate-norm", str(log), str(log), "--out", str(tmp_path / "o"), "--effect", "bias_drift"]) == 2
    assert "--effect concerns one log" in capsys.readouterr().err


@pytest.mark.parametrize("names", [("scale_asymmetry",), ("cross_coupling", "bias_drift"), ("scale_quadratic",)])
def test_each_intervals_remainder_with_effects_holds_at_the_vertices(names):
    # The remainder of the extended relation per interval (norm_effects.Extension.extra into
    # norm_information.remainder_per_interval) against the exact one: the truth's reading of the fit is
    # F = (E + A) m + eps/g + Phi(m) theta_t - Phi(p) theta_fit + u, p the fixed point the fit evaluates the term at,
    # at vertices of the box of the correction (base and effects, where the worst cases live), noise at its bound;
    # what is left of sigma after H'^T (q - s), the effects' columns times theta_t - theta_fit and n^T u / |F| is
    # within the bound, which is not loose by more than 10x at the worst vertex (measured: 1.5x, 2.0x and 1.5x). Red
    # when the effect's Lipschitz part (rho, |Phi(m) - Phi(p)| theta) is left out, or its part along n (the slope
    # bound at p times each coordinate's |m - p|) is taken 0.3x.
    import itertools
    from types import SimpleNamespace

    from garant.verify.workflows.norm_effects import Extension, fixed_point
    from garant.verify.workflows.norm_information import remainder_per_interval
    rng = np.random.default_rng(11)
    K = 40
    stills = [SimpleNamespace(start=10.0 * k, stop=10.0 * k + 5) for k in range(K)]
    ext = Extension(N, names, stills, None, "test")
    P = len(ext.labels)
    scale = np.array([1e-6 if u == "1/s" else 1.0 for u in ext.units])
    theta_fit = rng.uniform(-5e-3, 5e-3, P) * scale
    reach = np.r_[[5e-3] * 3, [3e-3] * 3, [2e-3] * 3, 2e-3 * scale]
    A_box = np.array([[reach[0], 0, 0], [reach[3], reach[1], 0], [reach[4], reach[5], reach[2]]])
    w = rng.normal(size=(3, K))
    w /= np.linalg.norm(w, axis=0)
    nu = np.full(K, 1e-3)
    worst = 0.0
    for signs in itertools.islice(itertools.product((-1, 1), repeat=9 + P), 0, 2 ** (9 + P), 2 ** (9 + P) // 150):
        q = np.array(signs) * reach
        A = np.array([[q[0], 0, 0], [q[3], q[1], 0], [q[4], q[5], q[2]]])
        e = q[6:9]
        u = rng.normal(size=(3, K))
        u *= nu / np.linalg.norm(u, axis=0)
        ext.theta = theta_fit + q[9:]
        f = (np.eye(3) + A) @ w + e[:, None] + ext.term(w) + u            # the reading of the fit, over g
        ext.theta = theta_fit
        F, p = fixed_point(ext, f.T)
        fn = np.linalg.norm(F, axis=1)
        n = F.T / fn
        ext.at(p, n)
        sigma = (fn ** 2 - 1) / (2 * fn ** 2)
        H = N.H(n)[:9]
        H[6:9] /= fn
        Pm = 0.5 * A.T @ A + A @ A
        shift = np.r_[np.diag(Pm) + 0.5 * e @ e, Pm[0, 1] + Pm[1, 0], Pm[0, 2] + Pm[2, 0], Pm[1, 2] + Pm[2, 1],
                      A.T @ e + A @ e]
        left = np.abs(sigma - H.T @ (q[:9] - shift) - ext.columns(n).T @ q[9:] / fn - np.einsum("ik,ik->k", n, u) / fn)
        bound, shift_bound = remainder_per_interval(F, A_box, reach[6:9], nu, ext.extra(reach[9:], A_box, reach[6:9],
                                                                                         nu))
        assert np.all(np.abs(shift) <= shift_bound)
        assert np.all(left <= bound), (left / bound).max()
        worst = max(worst, (left / bound).max())
    assert worst > 0.1, worst


@pytest.mark.slow
def test_a_warm_up_calibrates_over_temperature_and_the_flight_stacks_files_remove_the_drift(tmp_path, capsys):
    # A unit turned through 36 still orientations while it warms from 20 C (to 43 C), its biases drifting 2e-5 g/C
    # (bias_temperature of the generator): `calibrate-norm --thermal-degree 1` is consistent; each axis's raw bias,
    # scale factor (Gamma_ii) and misalignment over the logged range lie within their one bound of the truth at 60
    # temperatures of it. The files it writes, applied as ArduPilot's and PX4's C++ does (test_thermal.py
    # re-implements both, as cited there) to the truth's readings of one direction across the range, leave at most
    # 10 % of the drift. Red on the slope's sign, or the constant not re-expanded about t0 (the bias at 20 C written
    # for the one at t0).
    from test_thermal import _ardupilot, _px4
    log = static_log(tmp_path / "warm.csv", "bias_temperature", still_s=10.0)
    out = tmp_path / "r.json"
    assert main(["calibrate-norm", str(log), "--g", str(G), "--thermal-degree", "1", "--json", str(out),
                 "--export-ardupilot", str(tmp_path / "t.parm"), "--export-px4", str(tmp_path / "t.params"),
                 "--px4-device-id", "42", "--save", str(tmp_path / "cal.json")]) == 0
    said = capsys.readouterr().out
    assert "over temperature (the IMU's, the log's temp_c)" in said
    res = json.loads(out.read_text())
    assert res["consistent"]
    th = res["thermal"]
    lo, hi = th["range_c"]
    assert lo < 21 and hi > 42
    # the saved file, applied to the unit's noise-free readings at 500 directions and temperatures of the range:
    # each within its per-sample bound
    rng = np.random.default_rng(5)
    m = rng.normal(size=(3, 500))
    m /= np.linalg.norm(m, axis=0)
    temp = rng.uniform(lo, hi, 500)
    f = G * N.readings(m, np.r_[_truth(), np.zeros(7)]) + G * np.outer(TRUE["bias_temperature"], temp - 20)
    log2 = tmp_path / "apply.csv"
    np.savetxt(log2, np.column_stack([np.arange(500) / 100, f.T, temp]), delimiter=",", comments="", fmt="%.12g",
               header="time_s,ax,ay,az,temp_c")
    c = jobs.apply(str(tmp_path / "cal.json"), str(log2))
    assert np.all(np.abs(c.a - G * m.T) <= c.bound), float((np.abs(c.a - G * m.T) / c.bound).max())
    truth = _truth()
    T = np.linspace(lo, hi, 60)
    for i in range(3):
        c, true = th["q"][f"bias{i + 1}"], truth[6 + i] + TRUE["bias_temperature"][i] * (T - 20)
        assert np.abs(c[0] + c[1] * (T - th["t0_c"]) - true).max() <= th["bound"][f"bias{i + 1}"]
        for name, true in ((f"scale{i + 1}", truth[i]), ("alpha beta gamma".split()[i], truth[3 + i])):
            c = th["q"][name]
            assert np.abs(c[0] + c[1] * (T - th["t0_c"]) - true).max() <= th["bound"][name], name
    m = np.array([0.6, -0.48, 0.64])
    m /= np.linalg.norm(m)
    raw = np.array([G * N.readings(m, np.concatenate([truth, np.zeros(7)])) + G * np.array(TRUE["bias_temperature"])
                    * (t - 20) for t in T])
    drift = np.abs(raw - raw[0]).max()
    for got in (_ardupilot((tmp_path / "t.parm").read_text())[0](raw, T),
                _px4((tmp_path / "t.params").read_text(), 42)[0](raw, T)):
        left = np.abs(got - got[len(T) // 2]).max()
        assert left <= 0.1 * drift, (left, drift)
    for argv, said in ((["--thermal-degree", "4"], "give the degree of the polynomials in T, 1, 2 or 3"),
                       (["--export-px4", str(tmp_path / "x.params")], "--export-px4 needs --thermal-degree D")):
        assert main(["calibrate-norm", str(log), *argv]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and said in err, err
    no_temp = static_log(tmp_path / "cold.csv", "none", temperature=False)
    assert main(["calibrate-norm", str(no_temp), "--thermal-degree", "1"]) == 2
    assert "--thermal-degree needs each sample's temperature" in capsys.readouterr().err


@pytest.mark.slow
def test_a_still_only_warm_up_gives_each_axis_drift_and_names_what_it_cannot_separate(tmp_path, capsys):
    # ArduPilot's procedure: the board still, level, while it heats 20 -> 48 C over 20 min, each axis's reading
    # drifting by g x (2e-5, -2e-5, 1.5e-5) per C, noise within 2e-4 m/s^2. `calibrate-norm --thermal-degree 1` cuts
    # the one still interval where the temperature moves and bounds each axis's slope over the information set:
    # the truth within each bound; it says that one orientation cannot separate a bias drift from a scale drift
    # times the axis's share of g, and refuses to write a calibration from it. Red when the still interval is not
    # cut where the temperature moves (one piece at one mean temperature: no slope, refused).
    rng = np.random.default_rng(1)
    t = np.arange(0, 1200, 0.01)
    T = 20 + 30 * (1 - np.exp(-t / 400))
    m = np.array([0.02, -0.03, 1.0]) / np.linalg.norm([0.02, -0.03, 1.0])
    slope = G * np.array([2e-5, -2e-5, 1.5e-5])
    raw = (G * m * (1 + np.array([2e-3, -1e-3, 3e-3])) + np.array([0.05, -0.02, 0.03]) + slope * (T[:, None] - 20)
           + rng.uniform(-2e-4, 2e-4, (len(t), 3)))
    log = tmp_path / "still.csv"
    np.savetxt(log, np.column_stack([t, raw, T]), delimiter=",", header="time_s,ax,ay,az,temp_c", comments="",
               fmt="%.9g")
    out = tmp_path / "s.json"
    assert main(["calibrate-norm", str(log), "--g", str(G), "--thermal-degree", "1", "--json", str(out)]) == 0
    said = flat(capsys.readouterr().out)
    assert "one orientation" in said and "cannot separate a bias drift from a scale-factor drift" in said
    res = json.loads(out.read_text())
    assert res["intervals"] > 20 and res["range_c"][1] - res["range_c"][0] > 25
    for i, axis in enumerate("xyz"):
        d = res["drift"][axis]
        assert abs(d["slope"] - slope[i]) <= d["slope_bound"] < 0.1 * abs(slope[i]), (axis, d)
    assert main(["calibrate-norm", str(log), "--thermal-degree", "1", "--save", str(tmp_path / "c.json")]) == 2
    assert "a still-only warm-up gives each axis's drift" in capsys.readouterr().err
    assert not (tmp_path / "c.json").exists()


def _lagging_warm_up(path, tau=8.0, seed=0, noise=1e-4, rate=100, still_s=5.0, move_s=2.0, directions=144):
    """A log whose sensor's temperature lags the logged one (first order, time constant tau s) through a heat-cool
    cycle (20 -> 50 -> 20 C over the log), its biases 5e-5 g/C of the sensor's temperature: (path, the 9
    parameters, the coefficients)."""
    rng = np.random.default_rng(seed)
    truth, coef = rng.uniform(-2e-3, 2e-3, 9), np.array([5e-5, -5e-5, 4e-5])
    dirs = rng.normal(size=(directions, 3))
    period = directions * (still_s + move_s)
    t = np.arange(int(period * rate)) / rate
    T = 35 - 15 * np.cos(2 * np.pi * t / period)
    Ts = np.empty(len(t))
    Ts[0] = T[0]
    for k in range(1, len(t)):                     # dTs/dt = (T - Ts) / tau
        Ts[k] = Ts[k - 1] + (T[k - 1] - Ts[k - 1]) / (tau * rate)
    rows, k = [], 0
    for m in dirs / np.linalg.norm(dirs, axis=1, keepdims=True):
        for _ in range(int(still_s * rate)):
            f = (G * N.readings(m, np.r_[truth, np.zeros(7)]) + G * coef * (Ts[k] - 20)
                 + G * rng.uniform(-noise, noise, 3))
            rows.append([t[k], *f, T[k]])
            k += 1
        for _ in range(int(move_s * rate)):
            rows.append([t[k], *(G * rng.normal(size=3)), T[k]])
            k += 1
    np.savetxt(path, np.array(rows), delimiter=",", comments="", fmt="%.10g", header="time_s,ax,ay,az,temp_c")
    return path, truth, coef


@pytest.mark.slow
def test_a_sensor_lagging_the_logged_temperature_is_named_and_calibrated(tmp_path):
    # Through a heat-cool cycle the sensor's temperature lags the logged one by tau = 8 s, so the same logged
    # temperature gives another bias heating than cooling: a temperature coefficient alone leaves 2.4 noise bounds
    # (the 9-parameter model 60); --diagnose names bias_temperature with temperature_lag (worst 0.29), whose
    # calibration is consistent with the truth in every bound: T_i, and L_i = -tau T_i to first order in the lag.
    # On a warm-up whose rate follows its temperature (an exponential approach: test_diagnose_norm.py's logs) the
    # two span one space, and bias_temperature is named with temperature_lag listed as equivalent. Red when the
    # temperature's rate is not read per interval (the lag's columns are then 0: nothing fits).
    log, truth, coef = _lagging_warm_up(tmp_path / "cycle.csv")
    d = jobs.calibrate_norm(str(log), g=G, diagnose=True).to_dict()["diagnosis"]
    assert d["scores"][0]["bias_temperature"] > 1 and d["named"] == ["bias_temperature", "temperature_lag"], d
    assert d["add"] == ["bias_temperature", "temperature_lag"]
    out = jobs.calibrate_norm(str(log), g=G, effects="bias_temperature,temperature_lag").to_dict()
    assert out["consistent"]
    pars = {**out["effects"]["bias_temperature"]["parameters"], **out["effects"]["temperature_lag"]["parameters"]}
    for i in range(3):
        for name, true in ((f"T_{i + 1}", coef[i]), (f"L_{i + 1}", -8.0 * coef[i])):
            assert abs(pars[name]["estimate"] - true) <= pars[name]["guaranteed_error"], (name, pars[name], true)
    d = jobs.calibrate_norm(str(static_log(tmp_path / "warm.csv", "bias_temperature")), g=G,
                            diagnose=True).to_dict()["diagnosis"]
    assert d["named"] == ["bias_temperature"] and d["equivalent"] == {"bias_temperature": ["temperature_lag"]}


@pytest.mark.slow
def test_a_warm_up_with_a_curved_drift_calibrates_with_degree_2(tmp_path, monkeypatch, capsys):
    # The biases drift as 2e-5 g/C plus 1e-6 g/C^2 of (T - 20 C) through a warm-up from 20 to 43 C: degree 1
    # leaves the data refuted (the curvature is 5e-4 g over the range); `--thermal-degree 2` is consistent and each
    # axis's raw bias lies within its one bound of the truth at 60 temperatures of the range (Bernstein control
    # points of each piece, norm_thermal.block); PX4's correction from its file leaves under 10 % of the drift.
    # Red when degree 1 is taken as consistent (the first command exits 3), or without the effects' temperature
    # counted from the middle of the range (counted from 20 C no premise box contracts: exit 2).
    from test_thermal import _px4
    curve = np.array([1e-6, -1e-6, 8e-7])
    monkeypatch.setitem(EFFECTS, "curved", lambda w, t: G * (np.array(TRUE["bias_temperature"]) * (_warm_up(t) - 20)
                                                             + curve * (_warm_up(t) - 20) ** 2))
    log = static_log(tmp_path / "warm.csv", "curved", still_s=10.0)
    assert main(["calibrate-norm", str(log), "--g", str(G), "--thermal-degree", "1"]) == 3
    out = tmp_path / "r.json"
    assert main(["calibrate-norm", str(log), "--g", str(G), "--thermal-degree", "2", "--json", str(out),
                 "--export-px4", str(tmp_path / "t.params"), "--px4-device-id", "7"]) == 0
    th = json.loads(out.read_text())["thermal"]
    assert th["degree"] == 2
    lo, hi = th["range_c"]
    T = np.linspace(lo, hi, 60)
    truth = _truth()
    for i in range(3):
        c = th["q"][f"bias{i + 1}"]
        true = truth[6 + i] + TRUE["bias_temperature"][i] * (T - 20) + curve[i] * (T - 20) ** 2
        est = c[0] + c[1] * (T - th["t0_c"]) + c[2] * (T - th["t0_c"]) ** 2
        assert np.abs(est - true).max() <= th["bound"][f"bias{i + 1}"], i
    m = np.array([0.6, -0.48, 0.64]) / np.linalg.norm([0.6, -0.48, 0.64])
    raw = np.array([G * N.readings(m, np.r_[truth, np.zeros(7)]) + G * (np.array(TRUE["bias_temperature"]) * (t - 20)
                                                                         + curve * (t - 20) ** 2) for t in T])
    got = _px4((tmp_path / "t.params").read_text(), 7)[0](raw, T)
    assert np.abs(got - got[30]).max() <= 0.1 * np.abs(raw - raw[30]).max()


def test_the_calibration_schema_names_every_effect_the_norm_relation_carries():
    # A calibration with an effect the schema did not list was refused on --save (misalignment_temperature);
    # the schema's list is the generated module's.
    schema = json.loads((ROOT / "docs" / "schemas" / "calibration.schema.json").read_text())
    names = schema["properties"]["effects"]["properties"]["names"]
    assert names["items"]["enum"] == list(N.EFFECTS) and names["maxItems"] == len(N.EFFECTS)
    count = sum(len(p) for p in N.EFFECTS.values())
    assert all(schema["properties"]["effects"]["properties"][k]["maxItems"] == count for k in ("theta", "bound"))


@needs_real
@pytest.mark.slow
def test_every_key_of_calibrate_norms_json_is_in_its_schema(tmp_path):
    # 24 keys of calibrate-norm's JSON (directions_gain, duration_s, format, ...) were in no schema: every key of
    # real runs (plain, --diagnose, --effect, --thermal-degree 1, a still-only warm-up, six faces with --bound) is now
    # a property of docs/schemas/calibrate-norm.schema.json, with its meaning.
    schema = json.loads((ROOT / "docs" / "schemas" / "calibrate-norm.schema.json").read_text())
    log = str(REAL / "repeat_session2_acc.txt")
    warm = str(static_log(tmp_path / "warm.csv", "bias_temperature"))
    rng = np.random.default_rng(1)
    t = np.arange(0, 600, 0.01)
    T = 20 + 30 * (1 - np.exp(-t / 300))
    still = tmp_path / "still.csv"
    np.savetxt(still, np.column_stack([t, np.array([0.1, 0.2, G])[None, :] + 2e-4 * (T[:, None] - 20)
                                       + rng.uniform(-2e-4, 2e-4, (len(t), 3)), T]), delimiter=",",
               header="time_s,ax,ay,az,temp_c", comments="", fmt="%.9g")
    faces = str(ROOT / "tests" / "data" / "imucal" / "example_ferraris_session.csv")
    runs = [jobs.calibrate_norm(log), jobs.calibrate_norm(log, diagnose=True),
            jobs.calibrate_norm(warm, g=G, effects="bias_temperature"),
            jobs.calibrate_norm(warm, g=G, thermal_degree=1),
            jobs.calibrate_norm(str(still), g=G, thermal_degree=1),
            jobs.calibrate_norm(faces, format="imucal", rate=102.4, bound={"alpha": 1e-2, "beta": 1e-2, "gamma": 1e-2})]
    keys = set().union(*(r.to_dict() for r in runs))
    assert keys - set(schema["properties"]) == set()
    import jsonschema                                     # and every value as the schema states it, nothing else
    for r in runs:
        check = jsonschema.Draft202012Validator(schema)
        assert [(list(e.absolute_path), e.message[:200]) for e in check.iter_errors(r.to_dict())] == []
    assert all(schema["properties"][k].get("description") or k in schema["required"] for k in keys)
