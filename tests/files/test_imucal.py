"""imucal's users: its Ferraris session straight in, its calibration file out, and imucal's own
calibration of the same session inside garant's bounds. imucal is installed by the test extra."""
import json

import numpy as np
import pytest

from garant.verify.cli import main
from conftest import DATA

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
