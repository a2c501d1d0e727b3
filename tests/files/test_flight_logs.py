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
from conftest import REAL, ROOT, flat, needs_real

FLIGHT = REAL / "flight"
G = 9.81


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
    # checked against pymavlink's messages read here directly.
    from pymavlink import DFReader
    reader = DFReader.DFReader_binary(str(FLIGHT / "test.BIN"), zero_time_base=True)
    theirs = {"IMU": [], "IMU2": []}
    while (m := reader.recv_match(type=["IMU", "IMU2"])) is not None:
        theirs[m.get_type()].append((m.AccX, m.T))
    for k, kind in enumerate(("IMU", "IMU2")):
        t, raw, temp, meta = flight.read_dataflash(FLIGHT / "test.BIN", k)
        assert len(t) == len(theirs[kind]) == 45
        np.testing.assert_array_equal(raw[:, 0], [a for a, _ in theirs[kind]])
        np.testing.assert_array_equal(temp, [T for _, T in theirs[kind]])
    assert meta["instances"] == {0: 1246730, 1: 1442826} and meta["stack"] == "ardupilot"
    assert recordings.guess_format(FLIGHT / "test.BIN") == "dataflash"
    assert main(["calibrate-norm", str(FLIGHT / "test.BIN"), "--imu", "1"]) == 2
    assert "only 45 samples" in capsys.readouterr().err


def _warm_ulog(tmp_path, parameters=None, instance=0):
    """A hand-turned warm-up (garant simulate --model norm) written into sample_log_small.ulg's sensor_accel
    instance `instance` (its device id kept), with the vehicle's parameters at start changed by `parameters`."""
    from pyulog import ULog
    from garant.verify.workflows import simulate_log
    t, raw, T, truth = simulate_log.simulate("random:48", {"bias_temperature": np.array([2e-5, -2e-5, 1.5e-5])}, 1e-3,
                                             seed=1, profile="warmup:20,45,200", size=1e-2, still_s=6)
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
    assert not names(project["dependencies"]) & {"pyulog", "pymavlink"}
    assert names(project["optional-dependencies"]["flight"]) == {"pyulog", "pymavlink"}
