"""imucal's users: its Ferraris session straight in, its calibration file out, and imucal's own
calibration of the same session inside garant's bounds. imucal is installed by the test extra."""
import json

import numpy as np
import pytest

from garant.verify.cli import main
from conftest import DATA, flat

IMUCAL = DATA / "imucal"
SESSION, SECTIONS = IMUCAL / "example_ferraris_session.csv", IMUCAL / "example_ferraris_session_list.json"
imucal = pytest.importorskip("imucal")
pd = pytest.importorskip("pandas")


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    """garant's six-face calibration of imucal's example session (102.4 Hz, m/s^2), as files."""
    folder = tmp_path_factory.mktemp("imucal")
    argv = ["estimate", "--model", "six-face", str(SESSION), "--format", "imucal", "--sections", str(SECTIONS),
            "--sigma", "1e-2", "--save", str(folder / "g.json"), "--export-imucal", str(folder / "i.json")]
    assert main(argv) == 0
    return folder


def test_imucals_own_calibration_lies_inside_garants_bounds(calibrated):
    # The session, read with no conversion; imucal's Ferraris calibration of it (K_a R_a, b_a) is
    # garant's block model f = (E + Gamma) a + bias with E + Gamma = K_a R_a: every entry within the bound.
    from imucal import FerrarisCalibration, ferraris_regions_from_section_list
    df = pd.read_csv(SESSION, header=0, index_col=0)
    info = FerrarisCalibration().compute(ferraris_regions_from_section_list(df, pd.read_json(SECTIONS).T), 102.4,
                                         "m/s^2", "deg/s")
    g = json.loads((calibrated / "g.json").read_text())
    gamma_imucal = np.asarray(info.K_a) @ np.asarray(info.R_a) - np.eye(3)
    gamma_garant = np.linalg.inv(np.asarray(g["M"])) - np.eye(3)
    # the bound of Gamma entrywise: garant's file bounds M (E + Gamma) - E, |Gamma - G| <= |E + G| B to first order
    bound = np.abs(np.eye(3) + gamma_garant) @ np.asarray(g["bound_matrix"]) * 1.01
    assert np.all(np.abs(gamma_imucal - gamma_garant) <= bound)
    assert np.all(np.abs(np.asarray(info.b_a) - np.asarray(g["b"])) <= np.asarray(g["bound_bias"]))


@pytest.mark.slow
def test_the_imucal_export_loads_in_imucal_and_corrects_as_garant_apply(calibrated, tmp_path, capsys):
    # --export-imucal writes imucal's FerrarisCalibrationInfo; imucal's load_calibration_info reads
    # it and its calibrate_df gives `garant apply`'s output.
    from imucal.management import load_calibration_info
    info = load_calibration_info(calibrated / "i.json")
    assert "gyroscope NOT calibrated" in info.comment and "bound_bias" in info.comment
    df = pd.read_csv(SESSION, header=0, index_col=0)
    ours = info.calibrate_df(df, "m/s^2", "deg/s")[["acc_x", "acc_y", "acc_z"]].to_numpy()
    log = tmp_path / "log.csv"
    np.savetxt(log, np.column_stack([np.arange(len(df)) / 102.4, df[["acc_x", "acc_y", "acc_z"]].to_numpy()]),
               delimiter=",", header="time_s,x,y,z", comments="")
    assert main(["apply", str(calibrated / "g.json"), str(log), "-o", str(tmp_path / "a.csv")]) == 0
    theirs = np.loadtxt(tmp_path / "a.csv", delimiter=",", skiprows=1)[:, 1:4]
    assert np.abs(ours - theirs).max() < 1e-5                         # the CSV's 8 significant digits


def test_an_annotated_session_in_counts_is_refused_by_estimate_in_a_line(tmp_path, capsys):
    # imucal's annotated session (a part column, raw counts): read by label, and refused by estimate with
    # what to do instead, in one line.
    assert main(["estimate", "--model", "six-face", str(IMUCAL / "annotated_session.csv"), "--format", "imucal",
                 "--sigma", "1e-2"]) == 2
    err = capsys.readouterr().err
    # the faces' median norm, from the file by pandas: raw counts, far from g
    df = pd.read_csv(IMUCAL / "annotated_session.csv")
    faces = df[df["part"].isin(["x_p", "x_a", "y_p", "y_a", "z_p", "z_a"])].groupby("part")[["acc_x", "acc_y", "acc_z"]]
    norm = np.median(np.linalg.norm(faces.mean().to_numpy(), axis=1))
    assert err.count("\n") == 1 and f"the six faces read {norm:.4g} in the file's unit, not about g" in err


def test_imucals_session_through_the_norm_says_what_six_faces_cannot_identify(capsys):
    # On imucal's own session (read as a log with --format imucal --rate): the norm
    # fit set a misalignment to 1.6 rad at its first step and went on to M -> 0. It stops there and says why.
    assert main(["calibrate-norm", str(SESSION), "--format", "imucal"]) == 2
    assert "give --rate HZ" in capsys.readouterr().err
    assert main(["calibrate-norm", str(SESSION), "--format", "imucal", "--rate", "102.4"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "the norm fit diverges at step 1" in err
    assert "13 still intervals in 6 distinct orientation(s), each along an axis" in err
    assert "cannot identify alpha, beta, gamma" in err and "would identify lambda1, lambda2, lambda3" in err
    assert "state bounds on alpha, beta, gamma, e.g. --bound alpha=1e-3" in err


def test_imucals_session_calibrates_scale_and_bias_with_the_misalignment_premise(tmp_path, capsys):
    # Six faces identify the scale factors and biases; the misalignments enter (2.2) of 001 only at second order
    # there, so they are a stated premise (--bound, rad), printed with the bounds and bounding them. imucal's own
    # Ferraris calibration of the session (it also turns the unit, so it sees the misalignments): its
    # non-orthogonality in garant's lower-triangular frame is within 1e-2 rad (|alpha| 6.2e-3, |beta| 6.1e-3,
    # |gamma| 3.9e-3), so that premise holds for this unit, and its scale factors and biases lie within garant's
    # bounds. With 2e-3 rad the faces refute the premise (exit 3). Red when the held misalignments are held at 0
    # instead of within the premise (the faces then refute the model: exit 3).
    from imucal import FerrarisCalibration, ferraris_regions_from_section_list
    base = ["calibrate-norm", str(SESSION), "--format", "imucal", "--rate", "102.4"]
    premise = [x for name in ("alpha", "beta", "gamma") for x in ("--bound", f"{name}=1e-2")]
    out, cal = tmp_path / "r.json", tmp_path / "c.json"
    assert main(base + premise + ["--json", str(out), "--save", str(cal)]) == 0
    said = flat(capsys.readouterr().out)
    assert "the misalignments are within |alpha| <= 0.01 rad, |beta| <= 0.01 rad, |gamma| <= 0.01 rad (--bound" in said
    res = json.loads(out.read_text())
    assert res["misalignment_premise"] == {"alpha": 1e-2, "beta": 1e-2, "gamma": 1e-2}
    assert all(res["guaranteed_error"][k] <= 1e-2 * 1.001 for k in ("alpha", "beta", "gamma"))
    assert "|alpha| <= 0.01 rad" in json.loads(cal.read_text())["premises"]
    df = pd.read_csv(SESSION, header=0, index_col=0)
    info = FerrarisCalibration().compute(ferraris_regions_from_section_list(df, pd.read_json(SECTIONS).T), 102.4,
                                         "m/s^2", "deg/s")
    G = np.asarray(info.K_a) @ np.asarray(info.R_a) - np.eye(3)
    lower = [G[1, 0] + G[0, 1], G[2, 0] + G[0, 2], G[2, 1] + G[1, 2]]        # the skew part turned away
    assert np.all(np.abs(lower) <= 1e-2) and np.max(np.abs(lower)) > 5e-3
    p, e = res["parameters"], res["guaranteed_error"]
    for i, k in enumerate(("lambda1", "lambda2", "lambda3")):
        assert abs(G[i, i] - p[k]) <= e[k], (k, G[i, i], p[k], e[k])
    for i, k in enumerate(("eps1/g", "eps2/g", "eps3/g")):
        assert abs(info.b_a[i] / res["g"] - p[k]) <= e[k], (k, info.b_a[i], p[k], e[k])
    tight = [x for name in ("alpha", "beta", "gamma") for x in ("--bound", f"{name}=2e-3")]
    assert main(base + tight) == 3
    assert main(base + ["--bound", "kappa=1e-3"]) == 2
    assert "takes bounds of the misalignments alpha, beta, gamma" in capsys.readouterr().err


@pytest.mark.slow
def test_a_dataframe_in_gives_a_calibrated_copy_out(calibrated):
    # imucal's habit, calibrate_df: a DataFrame with acc_x, acc_y, acc_z (no time: rate over
    # its index) is corrected into a copy, its other columns kept, the bounds beside.
    import garant
    df = pd.read_csv(SESSION, header=0, index_col=0)
    out = garant.apply(str(calibrated / "g.json"), df, rate=102.4)
    from imucal.management import load_calibration_info
    theirs = load_calibration_info(calibrated / "i.json").calibrate_df(df, "m/s^2", "deg/s")
    assert list(out.columns) == list(df.columns) + ["bound_x", "bound_y", "bound_z"]
    assert np.allclose(out[["acc_x", "acc_y", "acc_z"]], theirs[["acc_x", "acc_y", "acc_z"]], rtol=0, atol=1e-9)
    assert out["gyr_x"].equals(df["gyr_x"]) and (out["bound_x"] > 0).all()
    with pytest.raises(garant.DataError, match="needs rate=HZ"):
        garant.apply(str(calibrated / "g.json"), df)


def test_apply_reads_imucals_session_with_the_options_apply_has(tmp_path, capsys):
    # `apply --format imucal` asked for --rate, which apply did not have; --sensor took only lower case.
    cal = tmp_path / "c.json"
    premise = [x for name in ("alpha", "beta", "gamma") for x in ("--bound", f"{name}=1e-2")]
    assert main(["calibrate-norm", str(SESSION), "--format", "imucal", "--rate", "102.4", *premise,
                 "--save", str(cal)]) == 0
    out = tmp_path / "o.csv"
    assert main(["apply", str(cal), str(SESSION), "--format", "imucal", "-o", str(out)]) == 2
    assert "give --rate HZ" in capsys.readouterr().err
    assert main(["apply", str(cal), str(SESSION), "--format", "imucal", "--rate", "102.4", "--sensor", "ADXL355",
                 "-o", str(out)]) == 0
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    assert data.shape[1] == 7 and len(data) == len(pd.read_csv(SESSION))
