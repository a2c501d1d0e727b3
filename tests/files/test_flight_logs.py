"""Flight controllers' own logs: PX4 ULog and ArduPilot DataFlash read as the stacks wrote them (the real logs of
shared/data/real/flight, README there), and a hand-turned warm-up written into a real ULog calibrated into the file
PX4 loads, in the slot the vehicle's own parameters give the sensor."""
import json
import sys

import numpy as np
import pytest

from garant.verify.cli import main
from garant.verify.errors import DataError
from garant.verify.io import flight, recordings
from conftest import REAL, ROOT, flat, needs_real, fast_first

FLIGHT = REAL / "flight"
G = 9.81


def test_ardupilots_board_orientations_are_its_own_matrices():
    # The 16 matrices ArduPilot's own rotation test holds (libraries/AP_Math/examples/rotations: MATRIX_ROTATION_*,
    # rows a, b, c; the test checks v.rotate(r) == m * v) against flight.ap_rotation's Rz(yaw) Ry(pitch) Rx(roll) of
    # the enum's angles. Red with the product in another order (Rx Ry Rz: YAW_45 after ROLL_180 differs).
    h = 0.70710678
    theirs = {0: (1, 0, 0, 0, 1, 0, 0, 0, 1), 1: (h, -h, 0, h, h, 0, 0, 0, 1), 2: (0, -1, 0, 1, 0, 0, 0, 0, 1),
              3: (-h, -h, 0, h, -h, 0, 0, 0, 1), 4: (-1, 0, 0, 0, -1, 0, 0, 0, 1), 5: (-h, h, 0, -h, -h, 0, 0, 0, 1),
              6: (0, 1, 0, -1, 0, 0, 0, 0, 1), 7: (h, h, 0, -h, h, 0, 0, 0, 1), 8: (1, 0, 0, 0, -1, 0, 0, 0, -1),
              9: (h, h, 0, h, -h, 0, 0, 0, -1), 10: (0, 1, 0, 1, 0, 0, 0, 0, -1), 11: (-h, h, 0, h, h, 0, 0, 0, -1),
              12: (-1, 0, 0, 0, 1, 0, 0, 0, -1), 13: (-h, -h, 0, -h, h, 0, 0, 0, -1),
              14: (0, -1, 0, -1, 0, 0, 0, 0, -1), 15: (h, -h, 0, -h, -h, 0, 0, 0, -1)}
    for code, m in theirs.items():
        np.testing.assert_allclose(flight.ap_rotation(code), np.reshape(m, (3, 3)), atol=1e-8, err_msg=str(code))
    for code in range(len(flight.AP_ROTATIONS)):
        R = flight.ap_rotation(code)
        assert np.allclose(R @ R.T, np.eye(3)) and np.isclose(np.linalg.det(R), 1.0)


def test_ardupilots_thermal_correction_is_undone_too_and_what_cannot_be_is_one_line():
    # With INS_TCAL2_ENABLE 1 ArduPilot also corrects accelerometer 1 for temperature before its offsets
    # (AP_InertialSensor_tempcal.cpp, TCal::correct_sensor: v = raw - P(T) + P(T_cal), T and T_cal held within
    # [TMIN, TMAX], P(x) = (c1 + (c2 + c3 x) x) x 1e-6, x = T - 35 C): forward here on what the reader returns gives
    # the logged values back, past TMAX too. Red with the polynomial's sign flipped in the reader.
    rng = np.random.default_rng(0)
    raw = rng.normal(0, 5, (50, 3))
    T = np.linspace(10, 70, 50)
    c = {(p, a): rng.uniform(-3e3, 3e3) for p in (1, 2, 3) for a in "XYZ"}
    params = {"INS_TCAL2_ENABLE": 1, "INS_TCAL2_TMIN": 15.0, "INS_TCAL2_TMAX": 60.0, "INS_ACC2_CALTEMP": 25.0,
              "AHRS_ORIENTATION": 2, **{f"INS_TCAL2_ACC{p}_{a}": v for (p, a), v in c.items()},
              **{f"INS_ACC2OFFS_{a}": o for a, o in zip("XYZ", (0.1, -0.2, 0.3))},
              **{f"INS_ACC2SCAL_{a}": s for a, s in zip("XYZ", (1.01, 0.99, 1.02))}}
    C = np.array([[c[p, a] for a in "XYZ"] for p in (1, 2, 3)])

    def P(t):
        x = (np.clip(t, 15.0, 60.0) - 35.0)[:, None]
        return (C[0] + (C[1] + C[2] * x) * x) * x * 1e-6
    v = raw - P(T) + P(np.full(50, 25.0))
    logged = ((v - [0.1, -0.2, 0.3]) * [1.01, 0.99, 1.02]) @ np.array([[0, -1.0, 0], [1.0, 0, 0], [0, 0, 1.0]]).T
    got, said = flight.ardupilot_raw(logged, T, params, 1, "log.bin")
    np.testing.assert_allclose(got, raw, rtol=0, atol=1e-12)
    assert "INS_TCAL2_* about INS_ACC2_CALTEMP 25 C" in said and "AHRS_ORIENTATION 2" in said
    with pytest.raises(DataError, match="holds no temperature of accelerometer 1"):
        flight.ardupilot_raw(logged, None, params, 1, "log.bin")
    with pytest.raises(DataError, match="AHRS_ORIENTATION 101 .a custom or irregular board rotation. cannot be undone"):
        flight.ardupilot_raw(logged, T, {**params, "AHRS_ORIENTATION": 101}, 1, "log.bin")


@needs_real
def test_the_real_px4_log_is_read_instance_by_instance_with_its_device_ids_and_temperatures(capsys):
    # shared/data/real/flight/README.md: sensor_accel instances 0-2, device ids 2424842, 3670050, 2621474, 6 samples
    # each, and the vehicle's CAL_ACC0..2_ID. Checked against pyulog read here directly.
    from pyulog import ULog
    log = ULog(str(FLIGHT / "sample_log_small.ulg"), ["sensor_accel"])
    for d in log.data_list:
        t, raw, temp, meta = flight.read_ulog(FLIGHT / "sample_log_small.ulg", d.multi_id)
        assert meta["device_id"] == int(d.data["device_id"][0]) and len(t) == len(d.data["x"]) == 6
        np.testing.assert_array_equal(raw[:, 2], d.data["z"])
        np.testing.assert_array_equal(temp, d.data["temperature"])
    assert meta["instances"] == {0: 2424842, 1: 3670050, 2: 2621474}
    assert {meta["parameters"][f"CAL_ACC{k}_ID"] for k in range(3)} == {2424842, 3670050, 2621474}
    assert flight.read_ulog(FLIGHT / "sample_log_small.ulg", 3670050)[3]["instance"] == 1      # by device id
    # the other log logs temperature 0 (a sensor without one): no temperature, not 0 C
    assert flight.read_ulog(FLIGHT / "sample_logging_tagged_and_default_params.ulg", 0)[2] is None
    assert main(["calibrate-norm", str(FLIGHT / "sample_log_small.ulg")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "3 accelerometers in this PX4 log: 0 (device id 2424842)" in err
    assert main(["calibrate-norm", str(FLIGHT / "sample_log_small.ulg"), "--imu", "2424842"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "only 6 samples; a static calibration needs a long recording" in err


@needs_real
def test_the_real_ardupilot_log_is_read_with_its_imus_and_temperatures(capsys):
    # test.BIN: IMU and IMU2, 45 messages each (TimeUS, AccX..AccZ m/s^2, T C), INS_ACC_ID and INS_ACC2_ID in PARM;
    # checked against pymavlink's messages read here directly. ArduPilot logs the reading corrected
    # (AP_InertialSensor_Backend.cpp, _rotate_and_correct_accel: a = (raw - INS_ACCOFFS) * INS_ACCSCAL per axis, then
    # a.rotate(AHRS_ORIENTATION)); the reader undoes it, so ArduPilot's correction applied here, forward, to what it
    # read gives the logged values back. This vehicle: offsets up to 2.49 m/s^2, a scale 0.90, the board rolled 180
    # deg (AHRS_ORIENTATION 8). Red with the reader passing the logged values through (the offsets not undone).
    from pymavlink import DFReader
    reader = DFReader.DFReader_binary(str(FLIGHT / "test.BIN"), zero_time_base=True)
    theirs, params = {"IMU": [], "IMU2": []}, {}
    while (m := reader.recv_match(type=["IMU", "IMU2", "PARM"])) is not None:
        if m.get_type() == "PARM":
            params.setdefault(m.Name, m.Value)
        else:
            theirs[m.get_type()].append((m.AccX, m.AccY, m.AccZ, m.T))
    assert params["AHRS_ORIENTATION"] == 8 and abs(params["INS_ACCOFFS_Y"]) > 2
    roll_180 = np.diag([1.0, -1.0, -1.0])                 # AP_Math's examples/rotations: MATRIX_ROTATION_ROLL_180
    for k, kind in enumerate(("IMU", "IMU2")):
        t, raw, temp, meta = flight.read_dataflash(FLIGHT / "test.BIN", k)
        n = "" if k == 0 else "2"
        offs, scal = (np.array([params[f"INS_ACC{n}{w}_{a}"] for a in "XYZ"]) for w in ("OFFS", "SCAL"))
        logged = np.array(theirs[kind])
        assert len(t) == len(logged) == 45
        np.testing.assert_allclose(((raw - offs) * scal) @ roll_180.T, logged[:, :3], rtol=0, atol=1e-12)
        assert np.abs(raw - logged[:, :3]).max() > 1.0
        np.testing.assert_array_equal(temp, logged[:, 3])
        assert "ArduPilot's correction undone" in meta["undone"]
    assert meta["instances"] == {0: 1246730, 1: 1442826} and meta["stack"] == "ardupilot"
    assert recordings.guess_format(FLIGHT / "test.BIN") == "dataflash"
    assert main(["calibrate-norm", str(FLIGHT / "test.BIN"), "--imu", "1"]) == 2
    assert "only 45 samples" in capsys.readouterr().err


def _warm_ulog(tmp_path, parameters=None, instance=0, samples=None):
    """A hand-turned warm-up (garant simulate --model norm), or `samples` (t, raw, T), written into
    sample_log_small.ulg's sensor_accel instance `instance` (its device id kept), with the vehicle's parameters at
    start changed by `parameters`."""
    from pyulog import ULog
    from garant.verify.workflows import simulate_log
    t, raw, T, truth = samples + (None,) if samples else simulate_log.simulate(
        "random:48", {"bias_temperature": np.array([2e-5, -2e-5, 1.5e-5])}, 1e-3, seed=1, profile="warmup:20,45,200",
        size=1e-2, still_s=6)
    log = ULog(str(FLIGHT / "sample_log_small.ulg"))
    d = next(x for x in log.data_list if x.name == "sensor_accel" and x.multi_id == instance)
    device = int(d.data["device_id"][0])
    n, ts = len(t), (1_000_000 + t * 1e6).astype(np.uint64)
    d.data = {"timestamp": ts, "timestamp_sample": ts, "device_id": np.full(n, device, np.uint32),
              **{a: raw[:, i].astype(np.float32) for i, a in enumerate("xyz")}, "temperature": T.astype(np.float32),
              "error_count": np.zeros(n, np.uint32), **{f"clip_counter[{i}]": np.zeros(n, np.uint8) for i in range(3)}}
    log.initial_parameters.update(parameters or {})
    path = tmp_path / "warm.ulg"
    log.write_ulog(str(path))
    return path, device, truth


@needs_real
@pytest.mark.slow
def test_a_warm_up_in_a_ulog_calibrates_into_the_slot_px4_will_use(tmp_path, capsys):
    # Done when of the flight-log issue: `calibrate-norm LOG.ulg --imu 2424842 --thermal-degree 1 --export-px4
    # tc.params` without --px4-device-id puts the thermal rows in slot 0 (the vehicle's CAL_ACC0 holds 2424842),
    # TC_A0_ID = 2424842 and no other slot with that id; PX4's correction of the file (test_thermal.py's
    # re-implementation of TemperatureCompensation.cpp) leaves of the truth's drift across the range at most twice
    # garant's bound of each axis's bias (at T and at TREF), a fifth of the drift or less.
    sys.path.insert(0, str(ROOT / "tests" / "workflows"))
    from test_thermal import _px4
    path, device, truth = _warm_ulog(tmp_path)
    assert device == 2424842
    out, params = tmp_path / "r.json", tmp_path / "tc.params"
    assert main(["calibrate-norm", str(path), "--imu", str(device), "--g", str(G), "--thermal-degree", "1",
                 "--export-px4", str(params), "--json", str(out)]) == 0
    said = flat(capsys.readouterr().out)
    assert f"wrote {params} (TC_A0, CAL_ACC0, device id 2424842, the slots the log's parameters give it)" in said
    res = json.loads(out.read_text())
    assert res["flight"]["stack"] == "px4" and res["flight"]["device_id"] == device
    rows = [line.split("\t") for line in params.read_text().splitlines() if not line.startswith("#")]
    ids = {name: int(v) for _, _, name, v, _ in rows if name.startswith("TC_A") and name.endswith("_ID")}
    assert ids == {"TC_A0_ID": 2424842}
    correct, values = _px4(params.read_text(), device)
    lo, hi = res["thermal"]["range_c"]
    T = np.linspace(lo, hi, 60)
    m = np.array([0.6, -0.48, 0.64]) / np.linalg.norm([0.6, -0.48, 0.64])
    P = np.linalg.inv(np.array(truth["matrix"]))
    raw = np.array([P @ (G * m + G * np.array([2e-5, -2e-5, 1.5e-5]) * (x - 20)) + np.array(truth["bias"])
                    for x in T])
    got = correct(raw, T)
    bound = G * np.array([res["thermal"]["bound"][f"bias{i + 1}"] for i in range(3)])
    scale = np.array([values[f"CAL_ACC0_{a}SCALE"] for a in "XYZ"])       # PX4 scales the offset-corrected reading
    assert np.all(np.abs(got - got[30]).max(axis=0) <= 2 * bound * scale)
    assert np.abs(got - got[30]).max() <= 0.2 * np.abs(raw - raw[30]).max()


@needs_real
@pytest.mark.slow
def test_px4_slots_follow_the_vehicles_parameters_and_a_second_slot_with_the_id_is_cleared(tmp_path, capsys):
    # The sensor of instance 1 (3670050): where the vehicle already holds it in TC_A2 and again in TC_A3, the rows
    # go to slot 2 and TC_A3_ID is cleared (PX4 applies the first slot whose id matches); --px4-instance overrides.
    path, device, _ = _warm_ulog(tmp_path, {"TC_A2_ID": 3670050, "TC_A3_ID": 3670050}, instance=1)
    assert device == 3670050
    params = tmp_path / "tc.params"
    assert main(["calibrate-norm", str(path), "--imu", "1", "--g", str(G), "--thermal-degree", "1",
                 "--export-px4", str(params)]) == 0
    said = flat(capsys.readouterr().out)
    assert "(TC_A2, CAL_ACC1, device id 3670050, the slots the log's parameters give it; TC_A3_ID cleared" in said
    rows = {line.split("\t")[2]: line.split("\t")[3] for line in params.read_text().splitlines()
            if not line.startswith("#")}
    assert rows["TC_A2_ID"] == "3670050" and rows["TC_A3_ID"] == "0" and rows["CAL_ACC1_ID"] == "3670050"
    assert main(["calibrate-norm", str(path), "--imu", "1", "--g", str(G), "--thermal-degree", "1",
                 "--export-px4", str(params), "--px4-instance", "0"]) == 0
    assert "(TC_A0, CAL_ACC0, device id 3670050; TC_A2, TC_A3_ID cleared" in flat(capsys.readouterr().out)


def test_without_the_flight_extra_one_line_says_how_to_add_it(tmp_path, monkeypatch):
    # A ULog read where pyulog is not installed: one line naming the install, not an ImportError.
    path = tmp_path / "x.ulg"
    path.write_bytes(flight.ULOG_MAGIC + b"\x01" + b"\0" * 200)
    monkeypatch.setitem(sys.modules, "pyulog", None)
    with pytest.raises(DataError, match=r"reading this log needs pyulog \(pip install 'garant\[flight\]'\)"):
        recordings.read_log(str(path))


def test_the_base_install_has_no_flight_reader_and_the_extra_has_them():
    import tomllib
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    names = lambda reqs: {r.split(">")[0].split("=")[0].split("[")[0] for r in reqs}      # noqa: E731
    assert not names(project["dependencies"]) & {"pyulog", "pymavlink", "rosbags"}
    assert names(project["optional-dependencies"]["flight"]) == {"pyulog", "pymavlink", "rosbags"}


def _still(tmp_path, S=2e-5):
    """A still warm-up (the board level while it heats 20 -> 48 C): each axis's bias drifting by beta(T) and each
    entry of Gamma by at most S per C (here the scale factors at +-S), noise within 2e-4 m/s^2. Returns the log, the
    raw bias drift (m/s^2) as a function of T, and the orientation's gravity in the raw axes."""
    rng = np.random.default_rng(1)
    t = np.arange(0, 1200, 0.01)
    T = 20 + 30 * (1 - np.exp(-t / 400))
    w = G * np.array([0.02, -0.03, 1.0]) / np.linalg.norm([0.02, -0.03, 1.0])
    beta = lambda x: G * np.outer(x - 20, [2e-5, -2e-5, 1.5e-5])        # noqa: E731
    gamma = np.array([S, -S, S])
    raw = (w * (1 + np.array([2e-3, -1e-3, 3e-3]) + np.outer(T - 34, gamma)) + np.array([0.05, -0.02, 0.03])
           + beta(T) + rng.uniform(-2e-4, 2e-4, (len(t), 3)))
    log = tmp_path / "still.csv"
    np.savetxt(log, np.column_stack([t, raw, T]), delimiter=",", header="time_s,ax,ay,az,temp_c", comments="",
               fmt="%.9g")
    return log, beta


@pytest.mark.parametrize("S, degree", fast_first([(2e-5, 1), (None, 1), (2e-5, 2)]))
def test_a_still_warm_up_writes_the_stacks_offset_polynomials_under_the_scale_drift_premise(tmp_path, capsys, S,
                                                                                            degree):
    # PX4's and ArduPilot's own procedure (the board still while it heats) was refused any file. Now the offset
    # polynomial of each axis is written with its bound widened by a stated bound of the scale and misalignment
    # drift (--bound scale_drift, or the default 1e-4/C, printed as assumed), the vehicle's calibration at TREF left
    # alone; the stacks' own correction of the files (test_thermal.py's re-implementations of
    # AP_InertialSensor_tempcal.cpp and TemperatureCompensation.cpp, with the vehicle's offsets 0 and scales 1) takes
    # the true bias drift out within garant's bound at 60 temperatures of the range. Red without the premise's
    # widening (the truth's scale drift, 2e-5/C on 9.8 m/s^2 over 14 C, then lies outside).
    sys.path.insert(0, str(ROOT / "tests" / "workflows"))
    from test_thermal import _ardupilot, _px4
    log, beta = _still(tmp_path)
    out, parm, params = tmp_path / "r.json", tmp_path / "t.parm", tmp_path / "t.params"
    premise = ["--bound", f"scale_drift={S}"] if S else []
    assert main(["calibrate-norm", str(log), "--g", str(G), "--thermal-degree", str(degree), *premise, "--json",
                 str(out), "--export-ardupilot", str(parm), "--export-px4", str(params), "--px4-device-id", "7"]) == 0
    said = flat(capsys.readouterr().out)
    assert ("(--bound scale_drift)" if S else "assumed, a typical MEMS datasheet figure") in said
    res = json.loads(out.read_text())
    th = res["thermal"]
    bound = G * np.array([th["bound"][f"bias{i + 1}"] for i in range(3)])
    rows = lambda text: [x.split()[0] if "\t" not in x else x.split("\t")[2] for x in text.splitlines()     # noqa
                         if x and not x.startswith("#")]
    assert not [n for n in rows(parm.read_text()) if n.startswith("INS_ACC")]         # the vehicle's left alone
    assert not [n for n in rows(params.read_text()) if n.startswith("CAL_ACC")]
    assert f"drifts by at most {S or 1e-4:g} per C" in parm.read_text()
    lo, hi = th["range_c"]
    T = np.linspace(lo, hi, 60)
    vehicle = f"INS_ACC1_CALTEMP {th['t0_c']}\n" + "".join(f"INS_ACCOFFS_{a} 0\nINS_ACCSCAL_{a} 1\n" for a in "XYZ")
    ardupilot = _ardupilot(parm.read_text() + vehicle)[0]
    px4 = _px4(params.read_text() + "1\t1\tCAL_ACC0_ID\t7\t6\n"
               + "".join(f"1\t1\tCAL_ACC0_{a}OFF\t0\t9\n1\t1\tCAL_ACC0_{a}SCALE\t1\t9\n" for a in "XYZ"), 7)[0]
    for correct in (ardupilot, px4):
        left = correct(beta(T), T)                          # the bias drift alone, through the stack's correction
        left = left - correct(beta(np.array([th["t0_c"]])), np.array([th["t0_c"]]))
        assert np.all(np.abs(left) <= bound), (np.abs(left) / bound).max()
    assert main(["calibrate-norm", str(log), "--g", str(G), "--thermal-degree", "1", "--save",
                 str(tmp_path / "c.json")]) == 2
    assert "--save is refused: a still-only warm-up gives each axis's drift" in capsys.readouterr().err


def test_the_scale_drift_premise_is_refused_where_it_is_not_one(tmp_path, capsys):
    # A turned warm-up calibrates the scale's drift itself: the premise is refused there, in one line.
    log = tmp_path / "w.csv"
    assert main(["simulate", "--model", "norm", "--plan", "random:30", "--temperature-profile", "warmup:20,40,200",
                 "--effect", "bias_temperature=2e-5,-2e-5,1.5e-5", "--sigma", "2e-4", "-o", str(log)]) == 0
    capsys.readouterr()
    assert main(["calibrate-norm", str(log), "--g", str(G), "--thermal-degree", "1", "--bound",
                 "scale_drift=1e-4"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--bound scale_drift is the premise of a still warm-up" in err


@needs_real
@pytest.mark.slow
def test_a_still_warm_up_in_a_ulog_writes_the_slot_px4_will_use(tmp_path, capsys):
    # The still warm-up in a real ULog's instance 0: --export-px4 without --px4-device-id writes TC_A0 for 2424842
    # (the vehicle's CAL_ACC0) and leaves CAL_ACC0 alone.
    log, _ = _still(tmp_path)
    data = np.loadtxt(log, delimiter=",", skiprows=1)
    path, device, _ = _warm_ulog(tmp_path, samples=(data[:, 0], data[:, 1:4], data[:, 4]))
    params = tmp_path / "t.params"
    assert main(["calibrate-norm", str(path), "--imu", "0", "--g", str(G), "--thermal-degree", "1",
                 "--bound", "scale_drift=2e-5", "--export-px4", str(params)]) == 0
    assert "wrote " + str(params) + " (TC_A0, device id 2424842, the slots the log's parameters give it)" in flat(
        capsys.readouterr().out)
    names = [x.split("\t")[2] for x in params.read_text().splitlines() if x and not x.startswith("#")]
    assert "TC_A0_ID" in names and not [n for n in names if n.startswith("CAL_ACC")]


@needs_real
@pytest.mark.slow
def test_the_flight_controller_example_of_the_docs_runs_as_written(tmp_path, monkeypatch, capsys):
    # docs/thermal.md's "From your flight controller" lines, run as written in a folder holding the logs they name.
    import shlex
    text = (ROOT / "docs" / "thermal.md").read_text()
    block = text.split("<!-- flight example -->\n```sh\n", 1)[1].split("```", 1)[0]
    _warm_ulog(tmp_path)                                    # warm.ulg
    _still(tmp_path)                                        # still.csv
    monkeypatch.chdir(tmp_path)
    for line in block.strip().splitlines():
        argv = shlex.split(line)
        assert argv[0] == "garant" and main(argv[1:]) == 0, line
    said = flat(capsys.readouterr().out)
    assert "wrote tc.params (TC_A0, CAL_ACC0, device id 2424842, the slots the log's parameters give it)" in said
    assert "wrote tc.parm (IMU 1)" in said and (tmp_path / "still.params").exists()


@needs_real
@pytest.mark.slow
def test_imu_all_calibrates_each_accelerometer_of_a_ulog_and_says_which_cannot(tmp_path, capsys):
    # --imu all on the warm-up ULog: instance 0 (the warm-up) calibrates; 1 and 2 (6 samples each, as logged) are
    # each said in a line and the others go on, as a batch does; the exit status says some could not be calibrated.
    path, _, _ = _warm_ulog(tmp_path)
    out = tmp_path / "all.json"
    assert main(["calibrate-norm", str(path), "--imu", "all", "--g", str(G), "--json", str(out)]) == 2
    said = flat(capsys.readouterr().out)
    assert "== IMU 0" in said and "IMU 1: not calibrated:" in said and "IMU 2: not calibrated:" in said
    res = json.loads(out.read_text())
    assert res["IMU 0"]["consistent"] and "only 6 samples" in res["IMU 1"]["error"]


@pytest.mark.slow
def test_a_ros_bag_calibrates_as_its_csv_twin(tmp_path, capsys):
    # Kalibr's users record sensor_msgs/Imu in a bag: a hand-turned log written into a ROS 1 bag (rosbags' writer,
    # the header stamps the times) and the same samples as a csv (times and readings written to round-trip exactly)
    # give the same calibration file, every byte but its `source` (the log's own name).
    from pathlib import Path
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore
    from garant.verify.workflows import simulate_log
    t, raw, _, _ = simulate_log.simulate("random:30", {}, 2e-4, seed=4, size=1e-2, still_s=4, move_s=1, rate=50)
    store = get_typestore(Stores.ROS1_NOETIC)
    ty = store.types
    Imu, Header, Time = ty["sensor_msgs/msg/Imu"], ty["std_msgs/msg/Header"], ty["builtin_interfaces/msg/Time"]
    Vec, Quat = ty["geometry_msgs/msg/Vector3"], ty["geometry_msgs/msg/Quaternion"]
    ns = (np.round(t * 1e9).astype(np.int64) + 1_000_000_000)
    bag = Path(tmp_path / "imu.bag")
    with Writer(bag) as w:
        other = w.add_connection("/cam0/imu", Imu.__msgtype__, typestore=store)
        conn = w.add_connection("/imu0", Imu.__msgtype__, typestore=store)
        for k, (n, a) in enumerate(zip(ns, raw)):
            msg = Imu(header=Header(seq=k, stamp=Time(sec=int(n // 10**9), nanosec=int(n % 10**9)), frame_id="imu"),
                      orientation=Quat(x=0.0, y=0.0, z=0.0, w=1.0), orientation_covariance=np.zeros(9),
                      angular_velocity=Vec(x=0.0, y=0.0, z=0.0), angular_velocity_covariance=np.zeros(9),
                      linear_acceleration=Vec(x=a[0], y=a[1], z=a[2]), linear_acceleration_covariance=np.zeros(9))
            w.write(conn, int(n), store.serialize_ros1(msg, Imu.__msgtype__))
            if k < 5:
                w.write(other, int(n), store.serialize_ros1(msg, Imu.__msgtype__))
    stamps = (ns // 10**9) + (ns % 10**9) * 1e-9                 # as the reader forms them
    csv = tmp_path / "imu.csv"
    csv.write_text("time_s,ax,ay,az\n" + "".join(",".join(repr(float(v)) for v in row) + "\n"
                                                 for row in np.column_stack([stamps, raw])))
    assert main(["calibrate-norm", str(bag), "--g", str(G)]) == 2
    err = capsys.readouterr().err
    assert "2 accelerometers in this ROS bag log: 0 (topic /cam0/imu), 1 (topic /imu0)" in err
    assert main(["calibrate-norm", str(bag), "--imu", "1", "--g", str(G), "--save", str(tmp_path / "b.json")]) == 0
    assert main(["calibrate-norm", str(csv), "--g", str(G), "--save", str(tmp_path / "c.json")]) == 0
    bag_cal, csv_cal = (json.loads((tmp_path / f).read_text()) for f in ("b.json", "c.json"))
    assert bag_cal.pop("source") != csv_cal.pop("source") and bag_cal == csv_cal
    assert (tmp_path / "b.json").read_text().replace(str(bag), str(csv)) == (tmp_path / "c.json").read_text()


def test_a_flight_log_without_the_fields_it_needs_is_one_line(monkeypatch, tmp_path):
    # A sensor_accel topic without x (a damaged or foreign layout) was a KeyError; one line names the field.
    monkeypatch.setattr(flight, "_load_ulog", lambda path: ({0: {"timestamp": np.arange(3), "y": np.zeros(3),
                                                                 "z": np.zeros(3)}}, {0: 7}, {}))
    with pytest.raises(DataError, match="sensor_accel instance 0 has no field x"):
        flight.read_ulog(tmp_path / "x.ulg")
