"""A production line in one command: many logs in one process, every core, a guaranteed pass
or fail against the unit's specification, one bad log a row of the summary."""
import json

import numpy as np

import pytest

from garant.verify.cli import main
from conftest import REAL, needs_real, flat

SPEC = """[limits]
scale = 0.01
misalignment = 0.01
bias = 0.05

[bound_limits]
scale = 0.005
"""


@pytest.mark.slow
@needs_real
def test_a_batch_calibrates_each_log_judges_it_and_reports_a_bad_one_on_its_line(tmp_path, capsys):
    logs = [str(REAL / f"repeat_session{k}_acc.txt") for k in (2, 3, 4)]
    (tmp_path / "bad.txt").write_text("not a log\n")
    (tmp_path / "spec.toml").write_text(SPEC)
    outs = {}
    for jobs in ("1", "2"):
        code = main(["calibrate-norm", *logs, str(tmp_path / "bad.txt"), "--g", "9.81", "--out", str(tmp_path / jobs),
                     "--spec", str(tmp_path / "spec.toml"), "--jobs", jobs])
        assert code == 5                                    # one log could not be judged: the bad one
        outs[jobs] = {p.name: p.read_bytes() for p in (tmp_path / jobs).iterdir() if p.suffix in (".json", ".csv")}
    assert outs["1"] == outs["2"] and len(outs["1"]) == 4     # three calibrations and the summary, whatever --jobs
    out = flat(capsys.readouterr().out)
    assert "bad.txt: error, retest (not calibrated: " in out
    assert "4 logs: 3 calibrated, 0 refuted their noise bound, 1 could not be calibrated" in out
    rows = (tmp_path / "1" / "summary.csv").read_text().splitlines()
    assert rows[0].startswith("log,status,verdict,reason") and len(rows) == 5
    assert rows[1].endswith(",repeat_session2_acc.json") and rows[4].endswith(",")   # whose file is which
    # session 3's lambda2 is bounded less tightly than the 0.005 the spec allows its bound: not a guaranteed pass
    assert ",consistent,undecided,lambda2's guaranteed error " in rows[2] and " above 0.005," in rows[2]
    assert "0 fail, 1 undecided, 1 retest" in out
    cal = json.loads((tmp_path / "1" / "repeat_session2_acc.json").read_text())
    assert cal["format"] == "garant-calibration-1" and cal["kind"] == "norm"
    # the page: each unit's verdict in its colour and a link to its calibration file; the limits and every
    # parameter in a stated unit (summary.csv keeps the same in SI for programs)
    page = (tmp_path / "1" / "index.html").read_text()
    assert '<td class="v-pass">' in page and '<td class="v-retest">' in page and '<td class="v-undecided">' in page
    assert '<a href="repeat_session2_acc.json">' in page and 'href="bad.json"' not in page
    assert "<th>lambda1 (ppm)</th>" in page and "<th>alpha (mrad)</th>" in page and "<th>eps1/g (mg)</th>" in page
    assert "<td>scale</td><td>lambda1, lambda2, lambda3</td><td>10000 ppm</td><td>5000 ppm</td>" in page   # SPEC
    assert " ± " in page


def test_a_specification_is_checked_and_single_log_outputs_are_refused_in_a_batch(tmp_path, capsys):
    (tmp_path / "spec.toml").write_text("[limits]\nscale = 2\n")
    (tmp_path / "a.txt").write_text("x\n")
    assert main(["calibrate-norm", str(tmp_path / "a.txt"), str(tmp_path / "a.txt"), "--out", str(tmp_path / "o"),
                 "--spec", str(tmp_path / "spec.toml")]) == 2
    assert "[limits] scale = 2 must be a number > 0 and < 1" in capsys.readouterr().err
    assert main(["calibrate-norm", str(tmp_path / "a.txt"), str(tmp_path / "a.txt"), "--out", str(tmp_path / "o"),
                 "--save", str(tmp_path / "c.json")]) == 2
    assert "--save concerns one log" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["calibrate-norm", str(tmp_path / "a.txt"), "--jobs", "0"])


@needs_real
@pytest.mark.slow
def test_apply_corrects_each_log_by_its_own_calibration_from_the_batch_folder(tmp_path, capsys):
    """`apply DIR LOG... --out OUT`: each log takes DIR/<its name>.json, the file is byte for byte the one-log
    command's, and a log without a calibration is said on its line (exit status 1) while the others go on.
    Red if a log took another unit's calibration (the two sessions' files would then differ from the one-log
    runs), or if the missing one stopped the batch."""
    logs = [str(REAL / f"repeat_session{k}_acc.txt") for k in (2, 4)]
    assert main(["calibrate-norm", *logs, "--g", "9.81744", "--out", str(tmp_path / "cal"), "--jobs", "1"]) == 0
    (tmp_path / "stranger.txt").write_text((REAL / "repeat_session3_acc.txt").read_text())
    code = main(["apply", str(tmp_path / "cal"), *logs, str(tmp_path / "stranger.txt"), "--out", str(tmp_path / "out")])
    out = flat(capsys.readouterr().out)
    # one status, the count printed: the count as the exit status was 1 here (1 means "a check failed"), and would
    # have been 2 or 3 (bad input, refuted) with more failures
    assert code == 2 and "stranger.txt: not corrected: no calibration " in out
    assert "3 logs: 2 corrected into " in out and ", 1 failed" in out
    for log in logs:
        stem = log.rsplit("/", 1)[1][:-4]
        assert main(["apply", str(tmp_path / "cal" / f"{stem}.json"), log, "-o", str(tmp_path / f"{stem}.csv")]) == 0
        assert (tmp_path / "out" / f"{stem}.csv").read_bytes() == (tmp_path / f"{stem}.csv").read_bytes()
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["repeat_session2_acc.csv",
                                                                    "repeat_session4_acc.csv"]


def test_apply_says_which_output_several_logs_need(tmp_path, capsys):
    """Several logs with -o (one file for many), or a folder of calibrations for one log with -o: one line, exit 2."""
    (tmp_path / "c.json").write_text("{}")
    (tmp_path / "a.txt").write_text("0 0 0 9.8\n")
    assert main(["apply", str(tmp_path / "c.json"), str(tmp_path / "a.txt"), str(tmp_path / "a.txt"),
                 "-o", str(tmp_path / "o.csv")]) == 2
    assert "several logs: give --out DIR" in capsys.readouterr().err
    assert main(["apply", str(tmp_path), str(tmp_path / "a.txt"), "-o", str(tmp_path / "o.csv")]) == 2
    assert "is a folder: a batch's calibrations apply to several logs with --out DIR" in capsys.readouterr().err
    assert not (tmp_path / "o.csv").exists()


@needs_real
def test_a_recording_that_proves_nothing_is_retest_not_fail(tmp_path, capsys):
    """A log that could not be calibrated (session 1: one still interval) and a log whose noise bound the data
    refute (session 2 under --delta-sigma 1e-4; it supports 3.3e-4) prove nothing of the unit: each is
    retest with its reason, counted apart, and the batch exits 5 (some log not judged), never a fail that
    would scrap a good unit. Red if either is called fail, or the exit status is a count of units."""
    (tmp_path / "spec.toml").write_text(SPEC)
    logs = [str(REAL / f"repeat_session{k}_acc.txt") for k in (1, 2)]
    code = main(["calibrate-norm", *logs, "--g", "9.81", "--delta-sigma", "1e-4", "--out", str(tmp_path / "o"),
                 "--spec", str(tmp_path / "spec.toml"), "--jobs", "1"])
    out = flat(capsys.readouterr().out)
    assert code == 5
    assert "repeat_session1_acc.txt: error, retest (not calibrated: " in out
    assert "repeat_session2_acc.txt: refuted, retest (the log refutes its noise bound at still interval(s) 1, " in out
    assert "0 pass (guaranteed), 0 fail, 0 undecided, 2 retest" in out
    rows = (tmp_path / "o" / "summary.csv").read_text().splitlines()
    assert [r.split(",")[2] for r in rows[1:]] == ["retest", "retest"]
    assert "2 retest" in (tmp_path / "o" / "index.html").read_text()


@needs_real
@pytest.mark.slow
def test_a_log_in_raw_counts_is_judged_against_its_nominal_sensitivity(tmp_path, capsys):
    """The Xsens log in raw counts had no verdict at all (always undecided). With [nominal] sensitivity and
    offset in the spec, its parameters relative to the nominal are judged: the same unit's log converted to
    m/s^2 by that nominal (a = (raw - offset) g / S) is calibrated on its own, and each interval of the two
    has its centre within a fifth of the smaller bound (the same readings, two information sets: the noise rules
    differ by half a count). A spec without [nominal] still says how to get a verdict."""
    from garant.verify.workflows import batch, jobs
    src = REAL / "imu_tk_xsens_acc.txt"
    S, off = 4096.0, 32768.0
    (tmp_path / "spec.toml").write_text("[limits]\nscale = 0.01\nmisalignment = 0.03\nbias = 0.2\n"
                                        f"[nominal]\nsensitivity = {S:g}\noffset = {off:g}\n")
    code = main(["calibrate-norm", str(src), "--g", "9.81", "--out", str(tmp_path / "o"),
                 "--spec", str(tmp_path / "spec.toml")])
    out = flat(capsys.readouterr().out)
    d = np.loadtxt(src)
    d[:, 1:] = (d[:, 1:] - off) * 9.81 / S
    np.savetxt(tmp_path / "si.txt", d, fmt="%.10e")
    counts = jobs.calibrate_norm(str(src), g=9.81)
    si = jobs.calibrate_norm(str(tmp_path / "si.txt"), g=9.81)
    pars, errs = batch.nominal_parameters(counts["raw_axes_counts"], [S] * 3, [off] * 3)
    for name, v in pars.items():
        w, e = si["parameters"][name], si["guaranteed_error"][name]
        assert abs(v - w) <= 0.2 * min(errs[name], e), name
    # the verdict the converted log's own intervals give: a scale wholly beyond 0.01 fails the unit (exit 4)
    beyond = [n for n in ("lambda1", "lambda2", "lambda3")
              if abs(si["parameters"][n]) - si["guaranteed_error"][n] > 0.01]
    assert beyond and code == 4 and f"imu_tk_xsens_acc.txt: consistent, fail ({beyond[0]} " in out
    (tmp_path / "bare.toml").write_text("[limits]\nscale = 0.01\n")
    assert main(["calibrate-norm", str(src), "--g", "9.81", "--out", str(tmp_path / "b"),
                 "--spec", str(tmp_path / "bare.toml")]) == 0
    assert "undecided (a log in raw counts: its parameters are relative to the raw axes; give the nominal " \
           "sensitivity (counts per g) as [nominal] sensitivity in the spec)" in flat(capsys.readouterr().out)


def test_batch_files_never_share_a_name_and_the_summary_is_csv(tmp_path, capsys):
    """Logs a/u.txt, b/u.txt, c/u_2.txt gave stems u, u_2, u_2: the third unit's file overwrote the second's.
    Each unit now has its own file, named in its summary row; a log name with a line break stays one cell."""
    from garant.verify.workflows import batch
    assert batch.stems(["a/u.txt", "b/u.txt", "c/u_2.txt"]) == ["u", "u_3", "u_2"]
    assert len(set(batch.stems(["u", "u", "u_2", "u_3", "u"]))) == 5
    from garant.verify.cli.calibrate_norm import _csv_text
    import csv
    import io
    text = _csv_text([["log", "verdict"], ["a\nb.txt", "pass"], ['q"uote,', "fail"]])
    assert list(csv.reader(io.StringIO(text))) == [["log", "verdict"], ["a\nb.txt", "pass"], ['q"uote,', "fail"]]
