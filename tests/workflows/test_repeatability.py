"""The MIMU4444BT stream, means files, the fixture stand and `garant repeatability`.

Real data: ../shared/data/real/mimu4444bt (Carlsson, Skog, Jalden, IEEE Sensors J. 21(6), 2021; MIT),
read in place; in CI it must be present."""
import json
import os

import numpy as np
import pytest

from garant.verify import models
from garant.verify.cli import main
from garant.verify.errors import DataError
from garant.verify.io import means, mimu
from garant.verify.io.recordings import Still
from garant.verify.workflows import repeatability as rp
from conftest import REAL, ROOT, flat

MIMU = REAL / "mimu4444bt"
needs_real = pytest.mark.skipif(not MIMU.is_dir() and not os.environ.get("CI"), reason="mimu4444bt not present")
G = 9.80665
COUNT = G / 2048
PHI = (1 + 5 ** 0.5) / 2
#: The 20 dodecahedron vertices (the fixture's nominal directions, the data's README).
DODECA = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
                  + [p for s1 in (-1, 1) for s2 in (-1, 1) for p in ([0, s1 * PHI, s2 / PHI], [s2 / PHI, 0, s1 * PHI],
                                                                     [s1 * PHI, s2 / PHI, 0])]) / 3 ** 0.5


def _packet(counter, stamp, acc):
    """One packet as the README states it: acc (8, 3) counts, gyro zero, checksum of the bytes before."""
    body = bytearray([0xAA]) + counter.to_bytes(3, "big") + (stamp % (1 << 32)).to_bytes(4, "big")
    for a in acc:
        body += b"".join(int(v).to_bytes(2, "big", signed=True) for v in (*a, 0, 0, 0))
    return bytes(body + (sum(body) % 65536).to_bytes(2, "big"))


def test_mimu_stream_checksum_axis_map_and_time(tmp_path):
    acc = np.arange(24).reshape(8, 3) * 7 - 80                         # distinct counts, some negative
    stamps = [(1 << 32) - 2_048_000 + k * 1_024_000 for k in range(5)]  # wraps after the second packet
    packets = [_packet(256 * k, s, acc + k) for k, s in enumerate(stamps)]
    bad = bytearray(packets[2])
    bad[20] ^= 0xFF                                                    # fails its checksum: dropped
    data = b"\x01\xaa\x02" + packets[0] + packets[1] + bytes(bad) + packets[3] + packets[4]
    path = tmp_path / "data.bin"
    path.write_bytes(data)
    t, f, step, skipped, jumps = mimu.read(str(path), 1)
    assert skipped == 3 + mimu.PACKET and jumps == 0                    # a wrap and a gap are no jump
    assert np.allclose(t, [0, 1 / 62.5, 3 / 62.5, 4 / 62.5])           # time across the wrap, the gap kept
    assert np.allclose(f / step, acc[0] + np.array([0, 1, 3, 4])[:, None])
    _, f2, _, _, _ = mimu.read(str(path), 2)                              # a bottom IMU: x' = -y, y' = -x, z' = -z
    raw = acc[1] + np.array([0, 1, 3, 4])[:, None]
    assert np.allclose(f2 / step, np.column_stack([-raw[:, 1], -raw[:, 0], -raw[:, 2]]))


def test_mimu_time_stamps_that_reset_or_go_back_are_counted_and_said(tmp_path, capsys):
    # Stamps going back every packet, or reset to 0 mid-stream, were accepted without a word.
    acc = np.arange(24).reshape(8, 3) * 7 - 80
    for stamps, want in (([5_000_000 + k * 1_024_000 for k in range(3)] + [k * 1_024_000 for k in range(3)], 1),
                         ([9_000_000 - (k % 2) * 1_024_000 for k in range(6)], 3)):
        path = tmp_path / "data.bin"
        path.write_bytes(b"".join(_packet(256 * k, s, acc) for k, s in enumerate(stamps)))
        t, _, _, _, jumps = mimu.read(str(path), 1)
        assert jumps == want and np.allclose(t, np.arange(6) / mimu.RATE_HZ)
    from garant.verify.io import recordings
    path.write_bytes(b"".join(_packet(256 * k, (k % 60) * 1_024_000, acc) for k in range(120)))   # a reset
    assert "1 time stamp(s) repeat, go back or jump (a reset?)" in recordings.read_log(str(path), "mimu", imu=1).note
    path.write_bytes(b"".join(_packet(256 * k, 9_000_000 - k * 1_024_000, acc) for k in range(6)))
    with pytest.raises(DataError, match="the time stamps do not advance"):      # back at every packet
        mimu.read(str(path), 1)


def test_mimu_stream_errors(tmp_path):
    p = tmp_path / "x.bin"
    p.write_bytes(b"\xaa" * 500)
    with pytest.raises(DataError, match="no packet with a valid checksum"):
        mimu.read(str(p), 1)
    with pytest.raises(DataError, match="IMUs 1 to 8"):
        mimu.read(str(p), 9)
    assert main(["calibrate-norm", str(p), "--format", "mimu"]) == 2        # no --imu: one line, exit 2


def _runs(changes, seed=0, scale=None):
    """Means of 20 fixture positions for each run: raw = (I + P) g u + b_run + noise within the noise rule."""
    rng = np.random.default_rng(seed)
    P = np.array([[2e-3, 0, 0], [1e-3, -3e-3, 0], [-2e-3, 1.5e-3, 4e-3]])
    b = np.array([0.2, -0.1, 0.3])
    out = []
    for r, db in enumerate(changes):
        Pr = P + (np.diag(scale[r]) if scale is not None else 0)
        stills = []
        for u in DODECA:
            raw = (np.eye(3) + Pr) @ (G * u) + b + db + rng.uniform(-1e-3, 1e-3, 3)
            stills.append(Still(float(30 * len(stills)), float(30 * len(stills) + 20), raw,
                                np.full(3, 0.035 / np.sqrt(1250)), 1250))
        out.append(means.Run(f"run{r + 1}", stills, DODECA, COUNT))
    return out


@pytest.mark.slow
@pytest.mark.parametrize("name, changes, scale", [
    ("none", [np.zeros(3)] * 4, None),
    ("bias_turn_on", [np.zeros(3), [0, 0, 0.03], [0.02, 0, 0.05], [0.02, -0.02, 0.06]], None),
    ("scale_turn_on", [np.zeros(3)] * 4, [np.zeros(3), [4e-3, 0, 0], [4e-3, 0, -5e-3], [0, 3e-3, -5e-3]]),
])
def test_repeatability_names_the_effect_that_was_planted(name, changes, scale):
    res = rp.run(models.load("norm"), _runs([np.asarray(c, float) for c in changes], scale=scale), G)
    assert res["named_effect"] == name
    assert not res["unexplained"]
    if name == "bias_turn_on":                                   # the planted change, within the joint fit
        ch = next(x for x in res["effects"] if x["effect"] == name)["changes"]["run 3 - run 1"]
        assert abs(ch["eps3/g"] - 0.05 / G) < 5e-4 and abs(ch["eps1/g"] - 0.02 / G) < 5e-4
    if name != "none":                                           # the runs disagree beyond their own bounds
        assert res["coverage_per_run_bounds"] < 1


def test_per_run_bound_contains_the_truth():
    """The printed estimate is the LP estimator's (its bound holds), not the minimax fit's."""
    res = rp.run(models.load("norm"), _runs([np.zeros(3)] * 3, seed=4), G)
    truth = {"lambda1": 2e-3, "lambda2": -3e-3, "lambda3": 4e-3, "alpha": 1e-3, "beta": -2e-3, "gamma": 1.5e-3,
             "eps1/g": 0.2 / G, "eps2/g": -0.1 / G, "eps3/g": 0.3 / G}
    for r in res["runs"]:
        for k, v in truth.items():
            assert abs(r["parameters"][k] - v) <= r["guaranteed_error"][k], (r["run"], k)


def test_means_file_errors(tmp_path):
    p = tmp_path / "m.csv"
    p.write_text("exp,imu,f_x,f_y,f_z,std_x,std_y,std_z\n1,1,0,0,9.8,0.03,0.03,0.03\n")
    with pytest.raises(DataError, match="missing column.*n_samples"):
        means.read(str(p), 1)
    p.write_text("exp,imu,f_x,f_y,f_z,std_x,std_y,std_z,n_samples\n1,1,0,0,x,0.03,0.03,0.03,100\n")
    with pytest.raises(DataError, match="line 2: column f_z: 'x' is not a number"):
        means.read(str(p), 1)
    with pytest.raises(DataError, match="choose one with --imu"):
        means.read(str(p))
    assert main(["repeatability", str(p), "--imu", "1", "--json", str(tmp_path / "o.json")]) == 2
    assert not (tmp_path / "o.json").exists()


@needs_real
def test_raw_stream_agrees_with_the_published_means():
    """The reader against the means extracted independently (the data's README): run 1 is exp_1."""
    t, f, step, _, jumps = mimu.read(str(MIMU / "raw" / "exp_1" / "data.bin"), 3)
    assert jumps == 0                                  # the real stream's stamps advance
    assert abs(step - COUNT) < 1e-12 and 590 < t[-1] < 610
    rows = [line.split(",") for line in open(MIMU / "static_positions_runs1-5.csv") if line.startswith("1,")]
    for r in [r for r in rows if r[10] == "3"][:5]:
        a, b = int(r[7]), int(r[8])
        assert np.allclose(f[a:b].mean(axis=0), [float(v) for v in r[11:14]], atol=2e-3)


@pytest.mark.slow
@needs_real
def test_repeatability_on_mimu4444bt_runs_1_to_5(tmp_path):
    """The target figures: with the envelope >= 95 % of comparisons inside, every exceedance of
    the per-run bounds explained by the named effect."""
    out = tmp_path / "rep.json"
    code = main(["repeatability", str(MIMU / "static_positions_runs1-5.csv"), "--imu", "all", "--g", str(G),
                 "--count", str(COUNT), "--rate", "62.5", "--json", str(out)])
    assert code == 0
    res = json.loads(out.read_text())
    assert len(res) == 8
    pairs = [x["inside"] for r in res.values() for x in r["envelope_judged"]["pairs"]]
    loo = [x["inside"] for r in res.values() for x in r["envelope_judged"]["leave_one_out"]]
    assert np.mean(pairs) >= 0.95 and np.mean(loo) >= 0.95
    assert all(not r["unexplained"] for r in res.values())
    assert {r["named_effect"] for r in res.values()} == {"bias_turn_on"}


@pytest.mark.slow
@needs_real
def test_fixture_stand_with_known_directions(capsys):
    """The fixture stand (docs/stands/icosahedral_fixture.toml) estimated from the means file: the data
    refute a fixture known to 1e-3 g, support it at 0.02 g, and its bias agrees with the norm relation's."""
    args = ["estimate", "--model", str(ROOT / "docs" / "stands" / "icosahedral_fixture.toml"),
            str(MIMU / "static_positions_runs1-5.csv"),
            "--imu", "1", "--run", "1", "--g", str(G)]
    assert main(args + ["--sigma", "0.001"]) == 3
    capsys.readouterr()
    assert main(args + ["--sigma", "0.02"]) == 0
    row = next(line for line in capsys.readouterr().out.splitlines() if line.startswith("q12"))
    est, err = float(row.split()[2]), float(row.split()[3])
    norm = rp.run(models.load("norm"), means.read(str(MIMU / "static_positions_runs1-5.csv"), 1, quantum=COUNT)[:2], G)
    a, e = norm["runs"][0]["parameters"]["eps3/g"], norm["runs"][0]["guaranteed_error"]["eps3/g"]
    assert abs(est - a) <= err + e and err > 10 * e


@pytest.mark.slow
@needs_real
def test_calibrate_norm_every_imu_of_the_stream(tmp_path):
    out = tmp_path / "all.json"
    assert main(["calibrate-norm", str(MIMU / "raw" / "exp_2" / "data.bin"), "--imu", "all", "--g", str(G),
                 "--json", str(out)]) == 0
    res = json.loads(out.read_text())
    assert list(res) == [f"IMU {k}" for k in range(1, 9)] and all(r["consistent"] for r in res.values())
    assert main(["calibrate-norm", str(MIMU / "raw" / "exp_2" / "data.bin"), "--imu", "all",
                 "--save", str(tmp_path / "c.json")]) == 2
    assert not (tmp_path / "c.json").exists()


@pytest.mark.slow
@needs_real
def test_the_published_repeatability_tables_are_what_the_command_writes(tmp_path, monkeypatch):
    """docs/repeatability_mimu4444bt.md is the output of the command it names: rerun it and compare."""
    monkeypatch.chdir(ROOT)
    doc = ROOT / "docs" / "repeatability_mimu4444bt.md"
    lines = doc.read_text().splitlines()
    command = lines[lines.index("```sh") + 1].split()
    assert command[:2] == ["garant", "repeatability"]
    out = tmp_path / "rep.md"
    args = command[1:]
    args[args.index("--markdown") + 1] = str(out)
    assert main(args) == 0
    assert out.read_text().replace(str(out), "docs/repeatability_mimu4444bt.md") == doc.read_text()


@needs_real
@pytest.mark.slow
def test_apply_reads_one_imu_of_a_mimu_stream(tmp_path, capsys):
    # `garant apply cal.json data.bin --format mimu --imu 3 -o x.csv` said "unrecognized arguments".
    # The calibration of IMU 3 applied to IMU 3's samples: every sample corrected, |a| near g when still.
    log, cal, out = MIMU / "raw" / "exp_1" / "data.bin", tmp_path / "c.json", tmp_path / "x.csv"
    tk, kalibr = tmp_path / "c.calib", tmp_path / "imu.yaml"
    assert main(["calibrate-norm", str(log), "--format", "mimu", "--imu", "3", "--save", str(cal),
                 "--export-imu-tk", str(tk), "--export-kalibr", str(kalibr)]) == 0
    assert "accelerometer_noise_density" in kalibr.read_text()
    from garant.verify.io import calibration
    M, _ = calibration.read_imu_tk(tk)             # imu_tk's form of the same calibration: the same |a|
    X = np.random.default_rng(1).normal(size=(3, 20)) * 2048
    np.testing.assert_allclose(np.linalg.norm(M @ X, axis=0),
                               np.linalg.norm(np.asarray(calibration.read(cal)["M"]) @ X, axis=0), rtol=1e-12)
    assert main(["apply", str(cal), str(log), "--format", "mimu", "--imu", "3", "-o", str(out)]) == 0
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    assert data.shape[1] == 7 and np.median(np.linalg.norm(data[:, 1:4], axis=1)) == pytest.approx(9.81, rel=0.01)
    assert main(["apply", str(cal), str(log), "--format", "mimu", "-o", str(tmp_path / "y.csv")]) == 2
    assert "choose one with --imu K" in capsys.readouterr().err


@needs_real
def test_a_refused_run_is_left_out_and_the_others_compared(tmp_path, capsys):
    # One unusable log (session 1 has one still interval) aborted the whole comparison. Now it is
    # said in one line and left out; sessions 2-4 are compared.
    real = MIMU.parent
    logs = [str(real / f"repeat_session{i}_acc.txt") for i in (1, 2, 3, 4)]
    out = tmp_path / "r.json"
    assert main(["repeatability", *logs, "--g", "9.81744", "--json", str(out)]) == 0
    text = flat(capsys.readouterr().out)            # a longer checkout path wraps the line before the file name
    assert text.count("left out:") == 1 and "repeat_session1_acc.txt: found only 1 still interval" in text
    res = json.loads(out.read_text())
    assert [x["log"] for x in res["refused_runs"]] == [logs[0]] and len(res["runs"]) == 3 and "envelope" in res
    assert main(["repeatability", logs[0], logs[1], "--g", "9.81744"]) == 2      # one usable run is not enough
    assert "at least two usable runs" in capsys.readouterr().err


@needs_real
def test_the_fixture_ends_in_a_calibration_that_holds_on_another_run(tmp_path, capsys):
    # The icosahedral fixture (a means file with known directions) could not save a calibration.
    # Now run 1 of IMU 1 gives one (sigma 0.02, as above), exported to imu_tk too; applied to run 2's
    # means, each corrected reading's norm is g within apply's bound (the per-sample bound plus the run's
    # own noise, 0.02 g).
    from garant.verify.io import calibration
    cal, tk = tmp_path / "c.json", tmp_path / "c.calib"
    assert main(["estimate", "--model", str(ROOT / "docs" / "stands" / "icosahedral_fixture.toml"),
                 str(MIMU / "static_positions_runs1-5.csv"), "--imu", "1", "--run", "1", "--g", str(G),
                 "--sigma", "0.02", "--save", str(cal), "--export-imu-tk", str(tk)]) == 0
    run2 = means.read(str(MIMU / "static_positions_runs1-5.csv"), 1)[1]
    a, bound = calibration.apply(calibration.read(cal), np.array([st.mean for st in run2.stills]))
    assert np.all(np.abs(np.linalg.norm(a, axis=1) - G) <= np.linalg.norm(bound, axis=1) + 0.02 * G)
    M, b = calibration.read_imu_tk(tk)
    np.testing.assert_allclose(M, calibration.read(cal)["M"], rtol=1e-12)


@needs_real
def test_three_runs_say_which_judgement_needs_a_fourth_and_name_each_run_by_its_file(capsys):
    # With 3 runs the pairs' envelope said "n/a (needs 3 or 4 runs)" and the runs were numbers only.
    logs = [str(REAL / f"repeat_session{k}_acc.txt") for k in (2, 3, 4)]
    main(["repeatability", *logs, "--g", "9.81744"])
    out = flat(capsys.readouterr().out)
    assert "run pairs n/a (needs at least 4 runs)" in out and "needs 3 or 4" not in out
    assert "each run against the envelope of the others n/a" not in out
    assert all(f"{k} {log}" in out for k, log in enumerate(logs, 1))
