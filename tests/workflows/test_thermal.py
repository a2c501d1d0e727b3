"""Calibration over temperature: each q a polynomial in T, one guaranteed bound over the whole range, and
ArduPilot's thermal parameters out."""
import json

import numpy as np
import pytest

from garant.verify import models
from garant.verify.cli import main
from garant.verify.workflows import thermal
from conftest import flat

SIGMA, G = 1e-4, 9.81
TEMPS = (-20.0, 0.0, 20.0, 40.0, 60.0)
#: A MEMS-size unit: 1.2 % scale, 50 mg bias, biases 1 mg/C and scale factors 100 ppm/C, both quadratic in T.
MEMS = {"kappa": 2e-5, "epsilon": -1.5e-5, "theta1": 3e-3, "theta2": -2e-3,
        "Gamma11": 1.2e-2, "Gamma22": -8e-3, "Gamma33": 5e-3, "Gamma21": 4e-3, "Gamma31": -3e-3, "Gamma32": 2e-3,
        "bias1": 0.05, "bias2": -0.03, "bias3": 0.02,
        "bias1_T1": 1e-3, "bias2_T1": -1e-3, "bias3_T1": 1e-3, "bias1_T2": 1e-5, "bias2_T2": -1e-5, "bias3_T2": 1e-5,
        "Gamma11_T1": 1e-4, "Gamma22_T1": -1e-4, "Gamma33_T1": 1e-4,
        "Gamma11_T2": 1e-6, "Gamma22_T2": 1e-6, "Gamma33_T2": -1e-6}


def _write(path, P, f, T):
    rows = ["alpha_deg,beta_deg,f1,f2,f3,temp_c"] + [",".join(repr(float(x)) for x in (*p, *ff, t))
                                                     for p, ff, t in zip(P, f, T)]
    path.write_text("\n".join(rows) + "\n")
    return path


def _session(tmp_path, truth, noise):
    """The two-axis stand's quarter turns (16 positions) at each chamber temperature, the readings of the thermal model
    (degree 2 about 20 C) with `noise(P, T)` (units of g, within +-SIGMA) added."""
    mod = models.thermal("two-axis", 2, 20)
    P = np.array([(a, b) for a in range(0, 360, 90) for b in range(0, 360, 90)] * len(TEMPS), float)
    T = np.repeat(TEMPS, len(P) // len(TEMPS))
    p = [truth.get(n, 0.0) for n in mod.PARAMETER_NAMES]
    f = mod.readings(*np.deg2rad(P).T, p, G, temp_c=T).T + G * noise(P, T)
    return mod, _write(tmp_path / "chamber.csv", P, f, T)


NOISES = {
    "uniform": lambda P, T: np.random.default_rng(5).uniform(-SIGMA, SIGMA, (len(P), 3)),
    "tilting": lambda P, T: SIGMA * np.sign(T - 20.0 + 1e-9)[:, None] * np.ones((1, 3)),       # pushes the slope
    "bending": lambda P, T: SIGMA * np.sign((T - 20.0) ** 2 - 800.0)[:, None] * np.ones((1, 3)),   # the curvature
}


def _estimated(folder, truth, *options):
    """A chamber session of `truth` (uniform noise) and `estimate --thermal-degree 2 --json r.json` on it, with
    `options` (paths inside `folder`): (module, data path, the result's JSON)."""
    mod, data = _session(folder, truth, NOISES["uniform"])
    assert main(["estimate", "--model", "two-axis", str(data), "--sigma", str(SIGMA), "--g", str(G),
                 "--thermal-degree", "2", "--json", str(folder / "r.json"), *[str(folder / o) if "." in o else o
                                                                             for o in options]]) == 0
    return mod, data, json.loads((folder / "r.json").read_text())


@pytest.fixture(scope="module")
def mems(tmp_path_factory):
    """The MEMS unit's session estimated once, its calibration saved (cal.json)."""
    folder = tmp_path_factory.mktemp("mems")
    return (folder,) + _estimated(folder, MEMS, "--save", "cal.json")


@pytest.fixture(scope="module")
def biases_drift(tmp_path_factory):
    """A unit whose biases alone drift with T (quadratic), estimated once with ArduPilot's export."""
    folder = tmp_path_factory.mktemp("biases")
    truth = {k: v for k, v in MEMS.items() if not k.startswith("Gamma") or "_T" not in k}
    return (folder, truth) + _estimated(folder, truth, "--export-ardupilot", "tcal.parm")


@pytest.mark.slow
@pytest.mark.parametrize("signs, noise", [(1, "uniform"), (-1, "tilting"), (1, "bending"), (-1, "bending")])
def test_the_bound_over_the_range_holds_at_every_temperature_of_it(tmp_path, noise, signs):
    """A MEMS-size unit at the extremes of its thermal coefficients (both signs) and noise at +-sigma that
    tilts or bends the polynomial: |q(T) - q_hat(T)| within the printed bound at every T of [-20, 60] C (401
    temperatures, the chamber's five among them), for every q with a thermal part. Red if the bound were that
    of q at T0 alone (the estimate's own guaranteed error); and it stays within 1.5x of the worst chamber
    temperature's own bound (red with the range in one piece instead of 8: PIECES = 1 gives 1.8x)."""
    truth = {k: (signs * v if "_T" in k else v) for k, v in MEMS.items()}
    mod, data = _session(tmp_path, truth, NOISES[noise])
    assert main(["estimate", "--model", "two-axis", str(data), "--sigma", str(SIGMA), "--g", str(G),
                 "--thermal-degree", "2", "--json", str(tmp_path / "r.json")]) == 0
    res = json.loads((tmp_path / "r.json").read_text())
    th = res["thermal"]
    assert th["t0_c"] == 20 and th["range_c"] == [-20.0, 60.0] and th["degree"] == 2
    q_true = models.q_of(mod, [truth.get(n, 0.0) for n in mod.PARAMETER_NAMES])
    taus = np.linspace(-40.0, 40.0, 401)
    polys = thermal.polynomials(mod, 2)
    assert set(polys) == set(th["q"]) and len(polys) == 12            # every block q has its polynomial
    for name, xs in polys.items():
        true = sum(tk * (xs[k] @ q_true) for k, tk in enumerate((taus ** 0, taus, taus ** 2)))
        est = sum(c * taus ** k for k, c in enumerate(th["q"][name]))
        worst = np.abs(true - est).max()
        assert worst <= th["bound"][name], (name, worst, th["bound"][name])
        at = [r["bound"] for r in th["at_temperature"][name]]
        assert th["bound"][name] <= 1.5 * max(at)        # close to the worst chamber's: the hull of 8 pieces is tight
        assert th["bound"][name] < 5e-4                                  # and it says something
    assert th["bound"]["q7"] > res["guaranteed_error"]["q7"]             # T0's own bound would not hold at the ends


@pytest.mark.slow
def test_too_few_temperatures_for_the_degree_are_refused_naming_what_is_missing(tmp_path, capsys):
    """Two chamber temperatures cannot identify a quadratic: one line naming them and what to add, exit 2."""
    mod = models.thermal("two-axis", 1, 20)
    P = np.array([(a, b) for a in range(0, 360, 45) for b in range(0, 360, 90)] * 2, float)
    T = np.repeat([0.0, 40.0], len(P) // 2)
    f = mod.readings(*np.deg2rad(P).T, [0.0] * len(mod.PARAMETER_NAMES), G, temp_c=T).T
    data = _write(tmp_path / "two.csv", P, f, T)
    assert main(["estimate", "--model", "two-axis", str(data), "--sigma", "1e-4", "--thermal-degree", "2"]) == 2
    err = capsys.readouterr().err
    assert "2 distinct temperature(s) (0, 40 C) cannot identify a polynomial of degree 2 in T (it needs 3)" in err
    assert main(["estimate", "--model", "two-axis", str(data), "--sigma", "1e-4", "--thermal-degree", "1"]) == 0


def _ardupilot(parm, imu=1):
    """ArduPilot's correction as its C++ applies it (libraries/AP_InertialSensor/AP_InertialSensor_tempcal.cpp,
    TCal::correct_sensor and polynomial_eval; AP_InertialSensor_Backend.cpp, _rotate_and_correct_accel): T and
    T_cal = INS_ACCn_CALTEMP held within [TMIN, TMAX], P(x) = (c1 + (c2 + c3 x) x) x 1e-6 with x = T - 35 C (no
    constant), v = raw - P(T - 35) + P(T_cal - 35), then a = (v - INS_ACCOFFS) * INS_ACCSCAL, per axis."""
    values = dict(line.split() for line in parm.splitlines() if line and not line.startswith("#"))
    n = "" if imu == 1 else str(imu)
    tmin, tmax = float(values[f"INS_TCAL{imu}_TMIN"]), float(values[f"INS_TCAL{imu}_TMAX"])
    c = np.array([[float(values[f"INS_TCAL{imu}_ACC{p}_{a}"]) for a in "XYZ"] for p in (1, 2, 3)])
    t_cal = float(values[f"INS_ACC{imu}_CALTEMP"])
    offs = np.array([float(values[f"INS_ACC{n}OFFS_{a}"]) for a in "XYZ"])
    scal = np.array([float(values[f"INS_ACC{n}SCAL_{a}"]) for a in "XYZ"])

    def P(x):
        return (c[0] + (c[1] + c[2] * x[:, None]) * x[:, None]) * x[:, None] * 1e-6

    def correct(raw, T):
        T, tc = np.clip(T, tmin, tmax), np.clip(np.full(len(T), t_cal), tmin, tmax)
        return (raw - P(T - 35.0) + P(tc - 35.0) - offs) * scal
    return correct, values


@pytest.mark.slow
def test_the_ardupilot_parameters_correct_the_readings_as_ardupilot_applies_them(biases_drift):
    """A unit whose biases alone drift with T (quadratic): ArduPilot's own correction with the file as loaded (its
    INS_ACC1_CALTEMP, offsets and scales included) takes each reading to what its calibration at T0 = 20 C gives
    there, within twice the bias bound over the range plus twice the noise, leaving well under 10 % of the drift;
    the offsets and scales are the bias and 1 / (1 + scale) at T0 within their bounds. Red on a sign, the 1e6
    scaling, the re-expansion about 35 C missing (the quadratic term moves the linear coefficient by 2 x 1e-5 x
    15 C = 0.3 mg/C between 20 and 35 C: 12 mg over the range), or CALTEMP left out (ArduPilot then takes -300 C,
    held at TMIN: the correction is off by P(TMIN) - P(T0))."""
    folder, truth, mod, data, res = biases_drift
    text = (folder / "tcal.parm").read_text()
    assert "INS_TCAL1_ENABLE 1\nINS_TCAL1_TMIN -20.0\nINS_TCAL1_TMAX 60.0\n" in text
    correct, values = _ardupilot(text)
    assert float(values["INS_ACC1_CALTEMP"]) == 20.0
    bound = G * max(res["thermal"]["bound"][q] for q in ("q7", "q11", "q15"))
    rows = np.loadtxt(data, delimiter=",", skiprows=1)
    raw, T = rows[:, 2:5], rows[:, 5]
    corrected = correct(raw, T)
    at20 = np.tile(corrected[T == 20.0], (len(TEMPS), 1))
    miss = np.abs(corrected - at20).max()
    drift = np.abs(raw - np.tile(raw[T == 20.0], (len(TEMPS), 1))).max()
    assert miss <= 2 * bound + 2 * G * SIGMA and miss < 0.1 * drift, (miss, bound, drift)
    assert drift > 0.5                                                   # the drift itself is 60 mg and more
    q_true = models.q_of(mod, [truth.get(n, 0.0) for n in mod.PARAMETER_NAMES])
    for i, (qb, qs) in enumerate((("q7", "q5"), ("q11", "q10"), ("q15", "q14"))):
        assert abs(float(values[f"INS_ACCOFFS_{'XYZ'[i]}"]) - G * q_true[mod.Q_NAMES.index(qb)]) <= \
            G * res["thermal"]["bound"][qb]
        assert abs(float(values[f"INS_ACCSCAL_{'XYZ'[i]}"]) - 1 / (1 + q_true[mod.Q_NAMES.index(qs)])) <= \
            1.1 * res["thermal"]["bound"][qs]


def test_thermal_outputs_need_temperature_and_a_calibration_file_is_refused_with_it(tmp_path, capsys):
    """--export-ardupilot or --thermal-plot without --thermal-degree, or --export-imu-tk with it: one line, exit 2."""
    data = tmp_path / "d.csv"
    data.write_text("alpha_deg,beta_deg,f1,f2,f3,temp_c\n0,0,0,0,9.81,20\n")
    assert main(["estimate", "--model", "two-axis", str(data), "--sigma", "1e-4", "--export-ardupilot",
                 str(tmp_path / "t.parm")]) == 2
    assert "--export-ardupilot needs --thermal-degree D" in capsys.readouterr().err
    assert main(["estimate", "--model", "two-axis", str(data), "--sigma", "1e-4", "--thermal-degree", "1",
                 "--export-imu-tk", str(tmp_path / "c.txt")]) == 2
    assert "--export-imu-tk: that file holds no polynomial in T" in capsys.readouterr().err
    assert not list(tmp_path.glob("t.parm")) and not list(tmp_path.glob("c.txt"))


@pytest.mark.slow
def test_simulate_runs_the_plan_at_each_chamber_temperature(tmp_path):
    """`simulate --temperatures` repeats the plan at each temperature with temp_c set, and the truth's thermal
    coefficients are what estimate --thermal-degree finds (within its bounds)."""
    (tmp_path / "t.json").write_text(json.dumps(MEMS))
    assert main(["simulate", "--model", "two-axis", "--plan", "quarter16", "--temperatures=-20,0,20,40,60",
                 "--truth", str(tmp_path / "t.json"), "--sigma", str(SIGMA), "--seed", "3",
                 "-o", str(tmp_path / "d.csv")]) == 0
    rows = np.loadtxt(tmp_path / "d.csv", delimiter=",", skiprows=1)
    assert sorted(set(rows[:, -1])) == list(TEMPS) and len(rows) == 5 * 16
    assert main(["estimate", "--model", "two-axis", str(tmp_path / "d.csv"), "--sigma", str(SIGMA), "--g", "9.81",
                 "--thermal-degree", "2", "--json", str(tmp_path / "r.json")]) == 0
    th = json.loads((tmp_path / "r.json").read_text())["thermal"]
    for q, truth in (("q7", (0.05, 1e-3, 1e-5)), ("q11", (-0.03, -1e-3, -1e-5))):
        worst = max(abs(sum(c * t ** k for k, c in enumerate(th["q"][q]))
                        - sum(c * t ** k for k, c in enumerate(truth))) for t in np.linspace(-40, 40, 81))
        assert worst <= th["bound"][q]


@pytest.mark.slow
def test_plan_gives_the_fewest_positions_per_temperature_that_identify_every_coefficient(tmp_path, capsys):
    """`plan --temperatures`: 3 positions per temperature at five temperatures identify the 39 q of the quadratic
    thermal two-axis model, proven fewest by counting (2 x 3 readings x 5 temperatures = 30 < 39); estimate on
    readings there identifies every q and holds the truth, and without any one of the positions it cannot.
    Red if the plan missed a coefficient, or if a position of it were idle."""
    assert main(["plan", "--model", "two-axis", "--temperatures=-20,0,20,40,60", "-o", str(tmp_path / "p.csv"),
                 "--json", str(tmp_path / "p.json")]) == 0
    out = capsys.readouterr().out
    assert "3 position(s) per temperature identify every q" in out and "the fewest, proven" in out
    d = json.loads((tmp_path / "p.json").read_text())
    assert d["per_temperature"] == d["lower_bound"] == 3 and d["proven_fewest"]
    rows = np.loadtxt(tmp_path / "p.csv", delimiter=",", skiprows=1)
    assert max(np.bincount(np.searchsorted(TEMPS, rows[:, 2]))) == 3 and len(set(rows[:, 2])) == 5
    mod = models.thermal("two-axis", 2, 20)
    p = [MEMS.get(n, 0.0) for n in mod.PARAMETER_NAMES]
    f = mod.readings(*np.deg2rad(rows[:, :2]).T, p, G, temp_c=rows[:, 2]).T
    _write(tmp_path / "d.csv", rows[:, :2], f, rows[:, 2])
    assert main(["estimate", "--model", "two-axis", str(tmp_path / "d.csv"), "--sigma", str(SIGMA), "--g", str(G),
                 "--thermal-degree", "2", "--json", str(tmp_path / "r.json")]) == 0
    res = json.loads((tmp_path / "r.json").read_text())
    q_true = models.q_of(mod, p)
    q, e = (np.array([res[k][n] for n in mod.Q_NAMES]) for k in ("q", "guaranteed_error"))
    assert np.all(np.abs(q - q_true) <= e)
    for drop in range(len(rows)):
        keep = np.arange(len(rows)) != drop
        _write(tmp_path / "d.csv", rows[keep, :2], f[keep], rows[keep, 2])
        assert main(["estimate", "--model", "two-axis", str(tmp_path / "d.csv"), "--sigma", str(SIGMA),
                     "--thermal-degree", "2"]) == 2
        assert "cannot identify" in capsys.readouterr().err


def _px4(params, device_id):
    """PX4's correction as its C++ applies it (src/modules/temperature_compensation/TemperatureCompensation.cpp:
    set_sensor_id maps the sensor to the slot j whose TC_Aj_ID is its device id, none when no slot has it;
    calc_thermal_offsets_3D holds T within [TMIN, TMAX], d = T - TREF, offset = X0 + X1 d + X2 d^2 + X3 d^3;
    src/lib/sensor_calibration/Accelerometer.hpp, Correct: (data - thermal_offset - offset) * scale, the offset and
    scale CAL_ACCn_xOFF, xSCALE of the calibration slot whose CAL_ACCn_ID is the device id), per axis."""
    values = {line.split("\t")[2]: float(line.split("\t")[3]) for line in params.splitlines()
              if line and not line.startswith("#")}
    slot = next((j for j in range(4) if values.get(f"TC_A{j}_ID") == device_id), None)
    cal = next((j for j in range(4) if values.get(f"CAL_ACC{j}_ID") == device_id), None)
    offset = np.array([values[f"CAL_ACC{cal}_{a}OFF"] for a in "XYZ"]) if cal is not None else np.zeros(3)
    scale = np.array([values[f"CAL_ACC{cal}_{a}SCALE"] for a in "XYZ"]) if cal is not None else np.ones(3)

    def correct(raw, T):
        if slot is None:                                  # set_sensor_id found no slot: no thermal offset
            return (raw - offset) * scale
        a = f"TC_A{slot}"
        d = np.clip(T, values[f"{a}_TMIN"], values[f"{a}_TMAX"]) - values[f"{a}_TREF"]
        thermal = np.column_stack([values[f"{a}_X0_{i}"] + values[f"{a}_X1_{i}"] * d + values[f"{a}_X2_{i}"] * d ** 2
                                   + values[f"{a}_X3_{i}"] * d ** 3 for i in range(3)])
        return (raw - thermal - offset) * scale
    return correct, values


@pytest.mark.slow
def test_the_px4_parameters_correct_the_readings_as_px4_applies_them(biases_drift, tmp_path, capsys):
    """A unit whose biases alone drift with T: PX4's own correction with the file as loaded (slot 3, device id
    1310988) takes each reading to its value at TREF within twice the bias bound plus twice the noise, leaving
    well under 10 % of the drift; the file carries TC_A3_ID and no SCL, X0 = 0 (relative to TREF, as PX4's own
    script writes it), and CAL_ACC3_xOFF, xSCALE are the bias and 1 / (1 + scale) at TREF within their bounds.
    Another sensor's id finds no slot (PX4 leaves its drift). Without --px4-device-id: refused in one line before
    any work, nothing written. Red on a missing TC_A3_ID (no slot: the whole drift stays), X0 holding the bias
    (an xOFF then subtracts it twice), a sign, or the polynomial about the wrong TREF."""
    folder, truth, mod, data, res = biases_drift
    out = tmp_path / "tc.params"
    argv = ["estimate", "--model", "two-axis", str(data), "--sigma", str(SIGMA), "--g", str(G), "--thermal-degree", "2",
            "--export-px4", str(out), "--px4-instance", "3"]
    assert main(argv) == 2 and not out.exists()
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--export-px4 needs --px4-device-id N" in err
    assert main(argv + ["--px4-device-id", "1310988"]) == 0
    text = out.read_text()
    assert "SCL" not in text
    correct, values = _px4(text, 1310988)
    assert values["TC_A_ENABLE"] == 1 and values["TC_A3_ID"] == 1310988 and values["CAL_ACC3_ID"] == 1310988
    assert values["TC_A3_TREF"] == 20 and values["TC_A3_TMAX"] == 60
    assert all(values[f"TC_A3_X0_{i}"] == 0 for i in range(3))
    rows = np.loadtxt(data, delimiter=",", skiprows=1)
    raw, T = rows[:, 2:5], rows[:, 5]
    got = correct(raw, T)
    at_ref = np.tile(got[T == 20.0], (len(TEMPS), 1))
    bound = G * max(res["thermal"]["bound"][q] for q in ("q7", "q11", "q15"))
    drift = np.abs(raw - np.tile(raw[T == 20.0], (len(TEMPS), 1))).max()
    miss = np.abs(got - at_ref).max()
    assert miss <= 1.02 * (2 * bound + 2 * G * SIGMA) and miss < 0.1 * drift, (miss, bound, drift)
    q_true = models.q_of(mod, [truth.get(n, 0.0) for n in mod.PARAMETER_NAMES])
    for i, (qb, qs) in enumerate((("q7", "q5"), ("q11", "q10"), ("q15", "q14"))):     # Gamma_ii - Delta_g
        assert abs(values[f"CAL_ACC3_{'XYZ'[i]}OFF"] - G * q_true[mod.Q_NAMES.index(qb)]) <= \
            G * res["thermal"]["bound"][qb]
        assert abs(values[f"CAL_ACC3_{'XYZ'[i]}SCALE"] - 1 / (1 + q_true[mod.Q_NAMES.index(qs)])) <= \
            1.1 * res["thermal"]["bound"][qs]
    other = _px4(text, 1310996)[0](raw, T)
    assert np.abs(other - np.tile(other[T == 20.0], (len(TEMPS), 1))).max() > 0.5 * drift


@pytest.mark.slow
@pytest.mark.parametrize("degree", [1, 2])
def test_a_chamber_session_that_refutes_a_constant_model_is_told_the_degree_it_needs(tmp_path, degree):
    """diagnose's thermal step (workflows/thermal.degree_needed, on estimate --thermal-degree D): a unit whose
    biases and scale factors are linear in T needs degree 1, one with a quadratic part degree 2 (degree 1 is
    then refuted by the data). Red if a degree were taken as consistent without its verdict, or the scan
    stopped at the first degree."""
    from garant.verify.workflows import jobs
    truth = {k: v for k, v in MEMS.items() if degree == 2 or not k.endswith("_T2")}
    _, data = _session(tmp_path, truth, NOISES["uniform"])
    positions = jobs.positions_of(models.load("two-axis"), str(data))
    levels = thermal.chamber_levels(positions)
    assert levels == list(TEMPS)
    found = thermal.degree_needed(levels, lambda d: jobs.estimate("two-axis", str(data), SIGMA, g=G, thermal_degree=d))
    assert found["needed"] == degree
    assert [t["consistent"] for t in found["tried"]] == [False] * (degree - 1) + [True]


def _lower_turn(truth):
    """The turn from the block's axes into the frame the data define (the lower-triangular frame of (29) of 000):
    with E + Gamma(t0) = L0 R0 R^T... the unit's E + Gamma at t0 is L0 R', L0 lower-triangular with a positive
    diagonal (the Cholesky factor of (E + Gamma)(E + Gamma)^T), so a sample's specific force in that frame is
    L0^-1 (E + Gamma) times its specific force in the block's axes."""
    EG = np.eye(3) + np.array([[truth.get(f"Gamma{i}{j}", 0.0) for j in (1, 2, 3)] for i in (1, 2, 3)])
    L0 = np.linalg.cholesky(EG @ EG.T)
    return np.linalg.solve(L0, EG)


@pytest.mark.slow
def test_apply_corrects_each_sample_at_its_own_temperature_within_its_bound(tmp_path, capsys, mems):
    """`estimate --thermal-degree 2 --save` holds the block at T0 and its polynomial in T; `apply` on a log with a
    temp_c column corrects each sample at its own temperature: every component within its per-sample bound of
    the true specific force (the readings of a block without errors), at 2,000 random positions and
    temperatures of the range. Red if apply took the calibration at T0 for every sample (the biases drift by
    up to 40 mg, 8x the bound). A sample beyond the range, or a log without temperatures, is refused in one
    line."""
    folder, mod, _, _ = mems
    cal = folder / "cal.json"
    assert json.loads(cal.read_text())["thermal"]["range_c"] == [-20.0, 60.0]
    rng = np.random.default_rng(1)
    n = 2000
    angles, T = rng.uniform(0, 360, (n, 2)), rng.uniform(-20, 60, n)
    p = [MEMS.get(k, 0.0) for k in mod.PARAMETER_NAMES]
    ideal = [0.0 if k.startswith(("Gamma", "bias")) else v for k, v in zip(mod.PARAMETER_NAMES, p)]
    f = mod.readings(*np.deg2rad(angles).T, p, G, temp_c=T).T          # the bound is the calibration's, not the noise's
    a_block = mod.readings(*np.deg2rad(angles).T, ideal, G, temp_c=T).T
    a_true = a_block @ _lower_turn(MEMS).T
    log = tmp_path / "log.csv"
    np.savetxt(log, np.column_stack([np.arange(n) * 0.01, f, T]), delimiter=",", header="time_s,ax,ay,az,temp_c",
               comments="", fmt="%.12g")
    assert main(["apply", str(cal), str(log), "-o", str(tmp_path / "c.csv")]) == 0
    out = np.loadtxt(tmp_path / "c.csv", delimiter=",", skiprows=1)
    assert np.all(np.abs(out[:, 1:4] - a_true) <= out[:, 4:7])
    assert np.abs(f - a_true).max() > 8 * out[:, 4:7].max()             # uncorrected, far outside
    T[7] = 61.0
    np.savetxt(log, np.column_stack([np.arange(n) * 0.01, f, T]), delimiter=",", header="time_s,ax,ay,az,temp_c",
               comments="", fmt="%.12g")
    capsys.readouterr()
    assert main(["apply", str(cal), str(log), "-o", str(tmp_path / "c2.csv")]) == 0       # dropped and counted
    assert f"{n - 1} samples corrected by" in flat(capsys.readouterr().out) and len(np.loadtxt(
        tmp_path / "c2.csv", delimiter=",", skiprows=1)) == n - 1
    (tmp_path / "c2.csv").unlink()
    assert main(["apply", str(cal), str(log), "-o", str(tmp_path / "c2.csv"), "--outside", "refuse"]) == 2
    assert "1 sample(s) at temperatures outside the calibrated range [-20, 60] C (the first, sample 8" in \
        capsys.readouterr().err
    np.savetxt(log, np.column_stack([np.arange(n) * 0.01, f]), delimiter=",", header="time_s,ax,ay,az",
               comments="", fmt="%.12g")
    assert main(["apply", str(cal), str(log), "-o", str(tmp_path / "c2.csv")]) == 2
    assert "the calibration holds a temperature polynomial; the log needs each sample's temperature" in \
        capsys.readouterr().err
    assert not (tmp_path / "c2.csv").exists()


@pytest.mark.slow
def test_the_thermal_file_is_in_the_frame_the_data_define_as_sharp_as_the_constant_one(tmp_path, mems):
    """The thermal file is written in the frame the data define (lower-triangular at t0, as the constant file),
    so no mounting premise lands in it: at t0 its per-sample bounds are within 3x of those of the constant file
    made from the same unit's readings at t0 alone (measured 1.53x median, 2.16x largest), and so are its
    off-diagonal bounds. Red on the block's own axes (the mounting's a-priori bound, 5e-3, in every
    off-diagonal entry: 48x)."""
    from garant.verify.io import calibration
    folder, mod, data, _ = mems
    rows = np.loadtxt(data, delimiter=",", skiprows=1)
    at_t0 = rows[rows[:, 5] == 20.0]
    assert len(at_t0) == 16
    np.savetxt(tmp_path / "t0.csv", at_t0[:, :5], delimiter=",", header="alpha_deg,beta_deg,f1,f2,f3", comments="",
               fmt="%.17g")
    assert main(["estimate", "--model", "two-axis", str(tmp_path / "t0.csv"), "--sigma", str(SIGMA), "--g", str(G),
                 "--save", str(tmp_path / "c0.json")]) == 0
    thermal_cal, constant = calibration.read(folder / "cal.json"), calibration.read(tmp_path / "c0.json")
    th = thermal_cal["thermal"]
    assert th["frame"] == "lower" and np.all(np.triu(np.linalg.inv(thermal_cal["M"]), 1) == 0)
    ratio = _t0_ratio(mod, MEMS, thermal_cal, constant, np.random.default_rng(3))
    assert ratio.max() <= 2.0 and np.median(ratio) < 1.0, (ratio.max(), np.median(ratio))
    piece = np.searchsorted(th["pieces_c"], 20.0, side="right") - 1
    lower = np.tril_indices(3, -1)
    assert np.all(th["bound_Gamma"][piece][lower] <= 3 * constant["bound_matrix"][lower])


def _t0_ratio(mod, truth, thermal_cal, constant, rng, n=500):
    """The thermal file's per-sample bound (over its set: `garant apply`'s) over the constant file's, at n random
    attitudes of the unit `truth` at t0 = 20 C."""
    from garant.verify.io import calibration
    from garant.verify.workflows import sample_set
    angles = rng.uniform(0, 360, (n, 2))
    p = [truth.get(k, 0.0) for k in mod.PARAMETER_NAMES]
    T = np.full(n, 20.0)
    f = mod.readings(*np.deg2rad(angles).T, p, G, temp_c=T).T
    return sample_set.apply_thermal(thermal_cal, f, T)[1] / calibration.apply(constant, f)[1]


@pytest.mark.slow
def test_the_thermal_file_is_within_twice_the_constant_file_on_random_chamber_units(tmp_path):
    """Issue 74's target for the stand's thermal file: on 5 random units of the chamber example's kind (scale factors
    to 1.2 %, misalignments to 4e-3, biases to 50 mg, drifts to 100 ppm/C and 1 mg/C with quadratic parts, the
    mounting to 3e-3 rad; the 45 x 90 degree grid at -20, 0, 20, 40, 60 C, noise uniform within sigma), each
    sample's bound at t0 within 2x that of the constant file made from the t0 readings alone, at 300 random
    attitudes (measured: largest 0.67-1.03x). Red without the mounting absorbed into the thermal model's Gamma'
    (derive/model.py `absorbed` refusing the thermal effect: largest 1.7-3.0x; the mounting's a-priori bound then
    stays in each Gamma q as its unseparable part, whatever the readings)."""
    from garant.verify.io import calibration
    mod = models.thermal("two-axis", 2, 20)
    P1 = np.array([(a, b) for a in range(0, 360, 45) for b in range(0, 360, 90)], float)
    P, T = np.tile(P1, (len(TEMPS), 1)), np.repeat(TEMPS, len(P1))
    worst = []
    for seed in range(5):
        rng = np.random.default_rng(seed)
        truth = {n: rng.uniform(-3e-3, 3e-3) for n in ("theta1", "theta2", "theta3")}
        truth.update(kappa=rng.uniform(-2e-5, 2e-5), epsilon=rng.uniform(-2e-5, 2e-5))
        for i in (1, 2, 3):
            truth.update({f"Gamma{i}{j}": rng.uniform(-4e-3, 4e-3) for j in range(1, i)})
            truth.update({f"Gamma{i}{i}": rng.uniform(-1.2e-2, 1.2e-2), f"bias{i}": rng.uniform(-0.05, 0.05),
                          f"bias{i}_T1": rng.uniform(-1e-3, 1e-3), f"bias{i}_T2": rng.uniform(-1e-5, 1e-5),
                          f"Gamma{i}{i}_T1": rng.uniform(-1e-4, 1e-4), f"Gamma{i}{i}_T2": rng.uniform(-1e-6, 1e-6)})
        p = [truth.get(n, 0.0) for n in mod.PARAMETER_NAMES]
        f = mod.readings(*np.deg2rad(P).T, p, G, temp_c=T).T + G * rng.uniform(-SIGMA, SIGMA, (len(P), 3))
        _write(tmp_path / "chamber.csv", P, f, T)
        np.savetxt(tmp_path / "t0.csv", np.column_stack([P, f])[T == 20.0], delimiter=",", comments="", fmt="%.17g",
                   header="alpha_deg,beta_deg,f1,f2,f3")
        for data, extra, out in (("chamber.csv", ["--thermal-degree", "2"], "cal.json"), ("t0.csv", [], "c0.json")):
            assert main(["estimate", "--model", "two-axis", str(tmp_path / data), "--sigma", str(SIGMA), "--g", str(G),
                         *extra, "--save", str(tmp_path / out)]) == 0
        ratio = _t0_ratio(mod, truth, calibration.read(tmp_path / "cal.json"),
                          calibration.read(tmp_path / "c0.json"), rng, 300)
        worst.append(ratio.max())
    assert max(worst) <= 2.0, worst


@pytest.mark.slow
def test_the_thermal_file_bounds_each_sample_by_the_sup_over_its_set(mems):
    """apply's per-sample bound of the thermal file against the largest error its information set allows at that
    sample and temperature, computed here independently (test_sample_set.py `lower_jacobian`: the exact correction
    of a unit q at T differentiated by central differences; `_set_sup`: HiGHS's LP over the set); the error of g
    (|s - 1| <= u = 1e-5 with --g) adds u |a_k|. Within 1.25x of it and never below, at 40 random attitudes and
    temperatures of the range (measured 1.001-1.014x). Red with the rest of each entry (rest_Gamma) left out of the
    bound: 0.75x."""
    from test_sample_set import _set_sup, lower_jacobian
    from garant.verify.io import calibration
    from garant.verify.workflows import sample_set
    folder, mod, _, res = mems
    cal = calibration.read(folder / "cal.json")
    st = cal["information_set"]
    rng = np.random.default_rng(4)
    n = 40
    angles, T = rng.uniform(0, 360, (n, 2)), rng.uniform(-20, 60, n)
    p = [MEMS.get(k, 0.0) for k in mod.PARAMETER_NAMES]
    f = mod.readings(*np.deg2rad(angles).T, p, G, temp_c=T).T
    a, bound = sample_set.apply_thermal(cal, f, T)
    ratio = np.array([[bound[i, k] / (_set_sup(st, jac[k]) + 1e-5 * abs(a[i, k])) for k in range(3)]
                      for i, jac in enumerate(lower_jacobian(st, res["definitions"], f[i], T[i] - 20.0)
                                              for i in range(n))])
    assert ratio.min() >= 1 - 1e-6 and ratio.max() <= 1.25, (ratio.min(), ratio.max())


@pytest.mark.parametrize("mount", ["+y+z+x", "-x-y+z"])
@pytest.mark.slow
def test_a_unit_in_another_mounting_is_calibrated_over_temperature(tmp_path, mount):
    """`--mount` with `--thermal-degree`: the block mounted by Q reads Q times the readings of the unit with
    Gamma' = Q^T Gamma Q, bias' = Q^T bias and theta' = Q^T theta ((26)-(27) of 000, at every T); its file, in
    the block's axes and the frame the data define, corrects the block's own readings at 1,000 random
    positions and temperatures within each per-sample bound. Red when the mounting is ignored (the file would
    be the equivalent unit's) or refused."""
    from garant.verify.io import calibration
    from garant.verify.workflows import sample_set
    rm = models.load_remount("two-axis")
    Q = np.asarray(rm.MOUNTS[mount], float)
    mod = models.thermal("two-axis", 2, 20)

    def equivalent(truth):
        out = dict(truth)
        for suffix in ("", "_T1", "_T2"):
            Gm = np.array([[truth.get(f"Gamma{i}{j}{suffix}", 0.0) for j in (1, 2, 3)] for i in (1, 2, 3)])
            b = np.array([truth.get(f"bias{i}{suffix}", 0.0) for i in (1, 2, 3)])
            Gm, b = Q.T @ Gm @ Q, Q.T @ b
            out.update({f"Gamma{i + 1}{j + 1}{suffix}": Gm[i, j] for i in range(3) for j in range(3)})
            out.update({f"bias{i + 1}{suffix}": b[i] for i in range(3)})
        th = Q.T @ np.array([truth.get(f"theta{i}", 0.0) for i in (1, 2, 3)])
        out.update({f"theta{i + 1}": th[i] for i in range(3)})
        return [out.get(n, 0.0) for n in mod.PARAMETER_NAMES]

    def block(angles, T, truth):
        return (Q @ mod.readings(*np.deg2rad(angles).T, equivalent(truth), G, temp_c=T)).T
    P = np.array([(a, b) for a in range(0, 360, 90) for b in range(0, 360, 90)] * len(TEMPS), float)
    T = np.repeat(TEMPS, 16)
    f = block(P, T, MEMS) + G * np.random.default_rng(5).uniform(-SIGMA, SIGMA, (len(P), 3))
    data = _write(tmp_path / "chamber.csv", P, f, T)
    assert main(["estimate", "--model", "two-axis", str(data), "--sigma", str(SIGMA), "--g", str(G),
                 "--thermal-degree", "2", f"--mount={mount}", "--save", str(tmp_path / "cal.json")]) == 0
    cal = calibration.read(tmp_path / "cal.json")
    rng = np.random.default_rng(2)
    angles, T = rng.uniform(0, 360, (1000, 2)), rng.uniform(-20, 60, 1000)
    ideal = {k: v for k, v in MEMS.items() if not k.startswith(("Gamma", "bias"))}
    a, bound = sample_set.apply_thermal(cal, block(angles, T, MEMS), T)
    truth = block(angles, T, ideal) @ _lower_turn(MEMS).T
    assert np.all(np.abs(a - truth) <= bound) and bound.max() < 1e-2


@pytest.mark.slow
def test_the_api_takes_a_temperature_degree_as_the_command_does(mems):
    """garant.estimate(..., thermal_degree=2) gives the command's `thermal` (the same job); a degree that is not a
    whole number 1 to 3 (True, 4, "2") is refused naming the argument (verify/options.py `degree`). The old name
    `temperature=` (the degree, not a temperature) is taken for a release, with a DeprecationWarning."""
    import garant
    from garant.verify.errors import DataError
    _, _, data, command = mems
    res = garant.estimate("two-axis", str(data), SIGMA, g=G, thermal_degree=2)
    assert res.to_dict()["thermal"] == command["thermal"]
    with pytest.warns(DeprecationWarning, match="thermal_degree"):
        old = garant.estimate("two-axis", str(data), SIGMA, g=G, temperature=2)
    assert old.to_dict()["thermal"] == command["thermal"]
    for bad in (True, 4, "2"):
        with pytest.raises(DataError, match="thermal_degree") as e:
            garant.estimate("two-axis", str(data), SIGMA, thermal_degree=bad)
        assert e.value.param == "thermal_degree"
