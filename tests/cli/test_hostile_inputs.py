"""Hostile and malformed inputs: no code runs from a user's file, and every bad file ends
with exit status 2, exactly one line on stderr naming the file or option and the problem, no output
file, and in work bounded by counts (never the clock)."""
import json
import re
from pathlib import Path

import numpy as np
import pytest

from garant.derive.builtin import STANDS_DIR
from garant.generated import two_axis
from garant.verify.cli import main
from conftest import STANDS, flat

BASE = (STANDS_DIR / "single_axis.toml").read_text()
G = 9.81


def run(argv, capsys):
    """The command's status and its standard error's lines, less the progress lines of long work ("budget: 1024 of
    3458 attitudes ...": an estimate's --report computes its budget before the page is written). Its work is
    bounded by the code's own budgets (counts: search nodes, rows, characters), never by the clock, so no test here
    depends on the machine's speed."""
    code = main([str(a) for a in argv])
    err = [line for line in capsys.readouterr().err.strip().splitlines() if not PROGRESS.match(line)]
    return code, err


PROGRESS = re.compile(r"^[a-z-]+: \d+ of \d+ [a-z ]+ \.\.\.$")


def refused(argv, capsys, *words, outputs=()):
    code, err = run(argv, capsys)
    assert code == 2, err
    assert len(err) == 1, err
    assert err[0].startswith("garant"), err
    for w in words:
        assert w in err[0], err[0]
    for out in outputs:
        assert not Path(out).exists() or (Path(out).is_dir() and not any(Path(out).iterdir())), out
    return err[0]


# ---------------------------------------------------------------- stand descriptions (TOML)

HOSTILE_UNIT = "rad\", __import__('os').system('touch pwned'), \""


@pytest.mark.slow
def test_string_in_a_description_cannot_run_code(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    old_unit = 'unit = "rad"\nmeaning = "encoder offset (read - true)"'
    old_title = 'title = "Single-axis indexing table, block in three mountings"'
    assert old_unit in BASE and old_title in BASE
    title = 'Tri"""ple \\ quoted """'
    # a unit is one of a whitelist, so the hostile text goes where free text may: the meaning
    hostile = HOSTILE_UNIT + ' a """ b end'
    text = BASE.replace(old_unit, 'unit = "rad"\nmeaning = ' + json.dumps(hostile), 1)
    text = text.replace(old_title, f"title = {json.dumps(title)}", 1)
    (tmp_path / "s.toml").write_text(text)
    code, err = run(["derive", "s.toml", "--out", "out"], capsys)
    assert code == 0, err
    assert not (tmp_path / "pwned").exists()
    from garant.verify import models
    mod = models.load(str(tmp_path / "s.toml"))
    assert not (tmp_path / "pwned").exists()
    meanings = dict((n, m) for n, _, m in mod.PARAMETERS)
    assert meanings["Delta_phi"] == hostile                         # a string, round-tripped
    assert 'Tri"""ple \\ quoted' in mod.__doc__


@pytest.mark.parametrize("old, new, where", [
    ('detents_deg = [0, 90, 180, 270]', 'range_deg = 5', "angle[1].range_deg"),
    ('detents_deg = [0, 90, 180, 270]', 'detents_deg = 90', "angle[1].detents_deg"),
    ('mountings = ["+x+y+z", "+y+z+x", "+z+x+y"]', 'mountings = 3', "block.mountings"),
    ('preferred = ["kappa"', 'preferred = [1, "kappa"', "estimation.preferred"),
    ('[estimation]\n', '[estimation]\nplan_deg = [["a"]]\n', "estimation.plan_deg"),
    ('source = "garant example stand (docs/new_stand.md)"', "source = 5", "stand.source"),
    ('angle = "phi"', 'angle = [1]', "link[2].angle"),
    ('title = "Single-axis indexing table, block in three mountings"', 'title = "two\\nlines"', "stand.title"),
    ('name = "phi"', 'name = "lambda"', "reserved"),
    ('name = "phi"', 'name = "None"', "reserved"),
    ('unit = "rad"', f"unit = {json.dumps(HOSTILE_UNIT)}", "is not a unit the model computes in"),
    ('name = "phi"', 'name = "time_s"', "reserved"),
    ('name = "kappa"', 'name = "Gamma11"', "reserved"),
    ('detents_deg = [0, 90, 180, 270]', 'detents_deg = [1e-300, 90, 180, 270]', "to at most 6 decimals"),
    ('detents_deg = [0, 90, 180, 270]', 'detents_deg = [0, 90.0000001, 180, 270]', "to at most 6 decimals"),
    ('[[parameter]]\nname = "kappa"', '[[angle]]\nname = "phi"\n\n[[parameter]]\nname = "kappa"', "declared twice"),
    ('remount', 'remount', ""),
    # Integers of 400 digits ended in "OverflowError: int too large to convert to float"
    ('detents_deg = [0, 90, 180, 270]', 'detents_deg = [0, 90, 180, '
                                        '1111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111]', "angle[1].detents_deg"),  # noqa: E501
    ('detents_deg = [0, 90, 180, 270]', 'range_deg = [0, '
                                        '1111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111]', "angle[1].range_deg"),  # noqa: E501
    ('[estimation]\n', '[estimation]\nplan_deg = '
                       '[[1111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111]]\n', "estimation.plan_deg"),  # noqa: E501
    ('[estimation]\n', '[estimation]\nplan_deg = [[1e308]]\n', "estimation.plan_deg"),
    ('name = "phi"', 'name = "pi"', "'pi' is reserved"),
    ('axis = "y"', 'axis = [0, 1, '
                   '1111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111111]', "an axis vector needs three finite numbers"),  # noqa: E501
])
def test_bad_description_is_one_line_and_writes_nothing(tmp_path, capsys, old, new, where):
    if old == "remount":
        text = BASE + "remount = 3\n"
        where = "estimation.remount"
    else:
        assert old in BASE
        text = BASE.replace(old, new, 1)
    (tmp_path / "s.toml").write_text(text)
    refused(["derive", tmp_path / "s.toml", "--out", tmp_path / "out"], capsys, "s.toml", where,
            outputs=[tmp_path / "out"])


@pytest.mark.parametrize("make, words", [
    (lambda: BASE + "\n" + "\n".join('[[link]]\naxis = "y"\nerror = "kappa"\n' for _ in range(50)), ("at most",)),
    (lambda: BASE + "\n" + "\n".join(f'[[angle]]\nname = "a{k}"\n' for k in range(1000)), ("at most",)),
    (lambda: "x = " + "[" * 100_000 + "]" * 100_000 + "\n", ("s.toml",)),
    (lambda: b"\xff\xfe[stand]\n", ("UTF-8",)),
    (lambda: "x" * 2_000_000, ("bytes",)),
])
def test_oversized_or_undecodable_description_refused_fast(tmp_path, capsys, make, words):
    data = make()
    path = tmp_path / "s.toml"
    path.write_bytes(data if isinstance(data, bytes) else data.encode())
    refused(["plan", "--model", path], capsys, *words)


@pytest.mark.slow
def test_description_with_bom_is_read(tmp_path, capsys):
    (tmp_path / "s.toml").write_bytes(b"\xef\xbb\xbf" + BASE.encode())
    code, err = run(["derive", tmp_path / "s.toml", "--out", tmp_path / "out"], capsys)
    assert code == 0, err


# ---------------------------------------------------------------- positions CSV (estimate)

GOOD_ROW = "0,0,0,0,9.81"
PLAN10 = two_axis.PLAN_DEG.tolist()


@pytest.mark.parametrize("content, words", [
    (b"", ("empty",)),
    (b"alpha_deg,beta_deg,f1,f2,f3\n", ("no data rows",)),
    (b"\xff\xfe\x00a", ("UTF-8",)),
    (b"alpha_deg,beta_deg,f1,f2,f3,f1\n0,0,0,0,9.81,1\n", ("duplicate",)),
    (("alpha_deg,beta_deg,f1,f2,f3\n0,0,0,0," + "9" * 200_000 + "\n").encode(), ("d.csv",)),
    (b"alpha_deg,beta_deg,f1,f2,f3\n0,0,0,0,nan\n", ("not a finite number",)),
    (("alpha_deg,beta_deg,f1,f2,f3\n" + "".join(f"{a:g},{b:g},0,0,1e308\n" for a, b in PLAN10)).encode(),
     ("differs from the model",)),
    (b"alpha_deg,beta_deg,f1,f2\n0,0,0,0\n", ("missing column",)),
    (b"alpha_deg,beta_deg,f1,f2,f3\n0,0,0,0\n", ("fields",)),
])
def test_bad_positions_file(tmp_path, capsys, content, words):
    path = tmp_path / "d.csv"
    path.write_bytes(content)
    out = tmp_path / "r.json"
    refused(["estimate", "--model", "two-axis", path, "--sigma", "1e-5", "--json", out], capsys, "d.csv", *words,
            outputs=[out])


@pytest.mark.parametrize("option, value", [("--sigma", "nan"), ("--sigma", "inf"), ("--sigma", "0"),
                                           ("--sigma", "-1e-5"), ("--g", "inf"), ("--g", "nan")])
def test_non_finite_numbers_refused(tmp_path, capsys, option, value):
    path = tmp_path / "d.csv"
    path.write_text("alpha_deg,beta_deg,f1,f2,f3\n" + GOOD_ROW + "\n")
    argv = ["estimate", "--model", "two-axis", str(path), "--sigma", "1e-5", "--g", "9.81"]
    argv[argv.index(option) + 1] = value
    with pytest.raises(SystemExit) as e:
        main(argv)
    err = capsys.readouterr().err.strip().splitlines()
    assert e.value.code == 2 and len(err) == 1 and option in err[0]


@pytest.mark.slow
def test_output_paths_checked_before_any_work(tmp_path, capsys):
    sim = tmp_path / "d.csv"
    assert main(["simulate", "--model", "two-axis", "--plan", "optimal10", "--sigma", "1e-5", "-o", str(sim)]) == 0
    capsys.readouterr()
    refused(["estimate", "--model", "two-axis", sim, "--sigma", "1e-5", "--json", "/nonexistent/r.json"],
            capsys, "/nonexistent")
    json_out = tmp_path / "r.json"
    refused(["diagnose", "--model", "two-axis", sim, "--sigma", "1e-5", "--json", json_out,
             "--plot", "/nonexistent/p.png"], capsys, "/nonexistent", outputs=[json_out])
    refused(["estimate", "--model", "two-axis", sim, "--sigma", "1e-5", "--json", tmp_path], capsys, "folder")


# ---------------------------------------------------------------- raw logs (calibrate-norm)

def _log(n=2000, dt=0.01, t0=0.0):
    t = t0 + dt * np.arange(n)
    return t, np.tile([0.0, 0.0, 9.81], (n, 1))


def _csv(path, header, cols):
    lines = [header] + [",".join(repr(float(v)) for v in row) for row in np.column_stack(cols)]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("fmt, make, words", [
    ("csv", lambda p: p.write_text(""), ("empty",)),
    ("openaxes", lambda p: p.write_text(""), ("empty",)),
    ("csv", lambda p: p.write_text("time_s,x,y,z\n"), ("no data rows",)),
    ("openaxes", lambda p: p.write_text("TIME;ACCEL_ADXL355_0;ACCEL_ADXL355_1;ACCEL_ADXL355_2\n"), ("no data rows",)),
    ("csv", lambda p: _csv(p, "time_s,x,y,z", [np.zeros(2000), *_log()[1].T]), ("constant",)),
    ("csv", lambda p: _csv(p, "time_s,x,y,z", [_log(dt=10.0)[0], *_log()[1].T]), ("time_ms",)),
    ("csv", lambda p: _csv(p, "time_s,x,y,z", [np.r_[_log(1000)[0], _log(1000)[0]], *_log()[1].T]), ("goes back",)),
    ("csv", lambda p: _csv(p, "x,y,z", [*_log()[1].T]), ("time column",)),
    ("csv", lambda p: _csv(p, "time_s,x,x,z", [_log()[0], *_log()[1].T]), ("duplicate",)),
    ("imu_tk", lambda p: p.write_bytes(b"0 1 2 \xff\n" * 200), ("not a number",)),
    ("imu_tk", lambda p: p.write_text("0 1 2 3\n" * 50), ("only 50 samples",)),
    # A 1e308 reading ended in "found only 0 still interval(s)", which named no cause
    ("imu_tk", lambda p: p.write_text("".join(f"{k} 0 0 9.81\n" for k in range(300)) + "300 1e308 0 0\n"),
     ("line 301: 1e+308 is beyond any reading",)),
])
def test_bad_log(tmp_path, capsys, fmt, make, words):
    path = tmp_path / "log.txt"
    make(path)
    out = tmp_path / "c.json"
    refused(["calibrate-norm", path, "--format", fmt, "--json", out], capsys, "log.txt", *words, outputs=[out])


def test_time_column_anywhere_and_in_milliseconds(tmp_path):
    from garant.verify.io import recordings
    t, f = _log()
    log = recordings.read_log(_csv(tmp_path / "a.csv", "x,y,z,time_ms", [*f.T, 1000 * t]), "csv")
    np.testing.assert_allclose(log.t, t - t[0], atol=1e-12)
    np.testing.assert_allclose(log.raw, f)


def test_repeated_time_stamps_are_counted(tmp_path, capsys):
    # Every stamp written three times (median step 0): one line with the count, in csv and OpenAXES alike
    # (it used to say "median step of 0 ... name the column time_ms"). A few repeats are kept and counted.
    from garant.verify.io import recordings
    t, f = _log(3000)
    t3 = np.repeat(t[::3], 3)
    refused(["calibrate-norm", _csv(tmp_path / "a.csv", "time_s,x,y,z", [t3, *f.T]), "--format", "csv"], capsys,
            "2000 of 2999 time steps are 0")
    rows = ["TIME;ACCEL_BMI160_0;ACCEL_BMI160_1;ACCEL_BMI160_2"] + [f"{int(u * 1e6)};0;0;16384" for u in t3]
    (tmp_path / "b.csv").write_text("\n".join(rows) + "\n")
    refused(["calibrate-norm", tmp_path / "b.csv", "--format", "openaxes", "--sensor", "bmi160"], capsys,
            "time steps are 0")
    t[100:150] = t[99]
    t[150:] += 1e-3
    log = recordings.read_log(_csv(tmp_path / "c.csv", "time_s,x,y,z", [t, *f.T]), "csv")
    assert "50 time stamp(s) repeat the one before" in log.note


@pytest.mark.parametrize("option", ["--delta-sigma", "--window", "--g"])
def test_non_finite_log_options_refused(option, capsys):
    with pytest.raises(SystemExit) as e:
        main(["calibrate-norm", "x.txt", option, "nan"])
    assert e.value.code == 2 and len(capsys.readouterr().err.strip().splitlines()) == 1


def test_a_failed_write_leaves_nothing(tmp_path):
    # Atomic writes: a write that fails part-way leaves neither the file nor its temporary .part beside
    # it (dropping the clean-up of the temporary file turns this red).
    from garant.verify.io.report import write_text
    with pytest.raises(TypeError):
        write_text(tmp_path / "out.json", 12345)          # not text: fails inside the write
    assert list(tmp_path.iterdir()) == []


def _good_rows(n):
    """n copies of the clean reading at (0, 0) with zero errors, m/s^2 (the exact model of 000)."""
    f = two_axis.readings(0.0, 0.0, np.zeros(len(two_axis.PARAMETER_NAMES)), 9.81)
    return np.tile(f, (n, 1))


def _plan_rows():
    P = np.array([(a, b) for a in range(0, 360, 45) for b in range(0, 360, 45)], float)
    return P, two_axis.readings(*np.deg2rad(P).T, np.zeros(len(two_axis.PARAMETER_NAMES)), 9.81).T


@pytest.mark.parametrize("case", ["two rows 1000 sigma apart", "one outlier among 100,000 copies"])
def test_repeated_readings_that_disagree_refute_sigma(tmp_path, capsys, case):
    # Two rows at (0, 0) with f3 of +0.1 and -0.1 m/s^2 (1000 sigma each), or one 0.05 g
    # outlier among 100,000 copies of a good row, were averaged away ("consistent ... 0.96 sigma", exit 0).
    # Readings at one position are each within sigma of the same value: they may differ by 2 sigma at most.
    P, f = _plan_rows()
    if case.startswith("two"):
        extra_f = _good_rows(2) + np.array([[0, 0, 0.1], [0, 0, -0.1]])
    else:
        extra_f = _good_rows(100_000)
        extra_f[500, 0] += 0.05 * 9.81
    angles = np.vstack([P, np.zeros((len(extra_f), 2))])
    path = tmp_path / "d.csv"
    rows = np.column_stack([angles, np.vstack([f, extra_f])])
    np.savetxt(path, rows, delimiter=",", header="alpha_deg,beta_deg,f1,f2,f3", comments="")
    out = tmp_path / "e.json"
    assert main(["estimate", "--model", "two-axis", str(path), "--sigma", "1e-5", "--json", str(out)]) == 3
    text = capsys.readouterr().out
    assert text.startswith("INCONSISTENT: readings repeated at one position disagree") and "position 1 (0, 0)" in text
    d = json.loads(out.read_text())
    worst = d["repeated_disagree"][0]
    assert d["consistent"] is False and "guaranteed_error" not in d
    assert worst["position"] == 1 and worst["component"] == (3 if case.startswith("two") else 1)
    assert worst["spread"] == pytest.approx(0.2 / 9.81 if case.startswith("two") else 0.05, rel=1e-6)


def test_repeated_readings_within_two_sigma_are_averaged(tmp_path):
    # The other side of the check: repeats that differ by 1.9 sigma are consistent with sigma.
    P, f = _plan_rows()
    extra_f = _good_rows(2) + np.array([[0, 0, 0.95e-5 * 9.81], [0, 0, -0.95e-5 * 9.81]])
    path = tmp_path / "d.csv"
    np.savetxt(path, np.column_stack([np.vstack([P, np.zeros((2, 2))]), np.vstack([f, extra_f])]), delimiter=",",
               header="alpha_deg,beta_deg,f1,f2,f3", comments="")
    assert main(["estimate", "--model", "two-axis", str(path), "--sigma", "1e-5"]) == 0


@pytest.mark.parametrize("argv, words", [
    (["simulate", "--model", "two-axis", "--plan", "quarter", "--effect", "bias_drift=inf,0,0", "--sigma", "1e-5",
      "-o", "{tmp}/d.csv"], "must be finite numbers"),
    (["estimate", "--model", "two-axis", "{data}", "--sigma", "1e-5", "--prior", "2", "--save", "{tmp}/c.json"],
      "must be < 1"),
    (["estimate", "--model", "two-axis", "{data}", "--sigma", "1e-5", "--g-uncertainty", "1", "--json",
      "{tmp}/r.json"], "must be < 1"),
    (["diagnose", "--model", "two-axis", "{data}", "--sigma", "1e-5", "--report", "{tmp}/afile/y"],
      "is not a writable folder"),
    (["plan", "--model", "norm", "--certificates", "{tmp}/c", "--grid", "5"], "apply to a stand with angles"),
    (["calibrate-norm", "{data}", "--delta-sigma", "1e308", "--json", "{tmp}/r.json"], "must be < 1"),
    # Each of these ended in a traceback or a message that named no cause.
    (["estimate", "--model", "two-axis", "{data}", "--sigma", "1e-5", "--g", "5e-324", "--json", "{tmp}/r.json"],
     "must be a gravity in m/s^2 between 0.1 and 100"),
    (["simulate", "--model", "two-axis", "--plan", "quarter", "--sigma", "1e-5", "--seed", "-1", "-o", "{tmp}/d.csv"],
     "--seed: '-1' must be a whole number >= 0"),
    (["simulate", "--model", "two-axis", "--plan", "quarter", "--sigma", "1e-5", "--size", "1e308", "-o",
      "{tmp}/d.csv"], "--size: the bound '1e308' must be a number >= 0 and < 1"),
    (["simulate", "--model", "two-axis", "--plan", "grid:0.0009765625", "--sigma", "1e-5", "-o", "{tmp}/d.csv"],
     "--plan grid:0.0009765625 has 1.36e+11 positions, over the limit of 1,000,000"),
    (["plan", "--model", "two-axis", "--grid", "0.0009765625", "--json", "{tmp}/p.json"],
     "--grid 0.000976562 has 1.36e+11 positions, over the limit of 10,000: use a coarser step, or raise "
     "--max-candidates"),
    (["plan", "--model", "two-axis", "--grid", "1", "--max-candidates", "129599", "--json", "{tmp}/p.json"],
     "--grid 1 has 1.3e+05 positions, over the limit of 129,599"),
    (["estimate", "--model", "two-axis", "{data}", "--sigma", "1e308"], "--sigma: '1e308' must be < 1"),
    (["repeatability", "--format", "means", "{data}", "--rate", "1e-300"], "must be a sample rate in Hz"),
])
def test_a_failing_command_writes_nothing(tmp_path, capsys, argv, words):
    # simulate with an infinite effect said "nothing written" and left d.csv full of inf; --prior 2
    # wrote a calibration apply refuses; diagnose --report under a file ran the whole diagnosis first.
    P, f = _plan_rows()
    data = tmp_path / "in" / "d.csv"
    data.parent.mkdir()
    np.savetxt(data, np.column_stack([P, f]), delimiter=",", header="alpha_deg,beta_deg,f1,f2,f3", comments="")
    (tmp_path / "afile").write_text("a file, not a folder\n")
    before = sorted(p.name for p in tmp_path.iterdir())
    try:
        code = main([a.format(tmp=tmp_path, data=data) for a in argv])
    except SystemExit as e:                            # argparse refuses an option's value: exit 2
        code = e.code
    err = capsys.readouterr().err
    assert code == 2 and words in err and err.count("\n") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == before


@pytest.mark.slow
def test_a_table_with_120_degree_detents_derives_plans_and_certifies(tmp_path, capsys):
    # Detents [0, 120] stopped code generation with "Exceeds the limit (4300 digits) for integer
    # string conversion": H on the reachable set grew integers of 650,000 digits from unsimplified radicals.
    text = (STANDS_DIR / "single_axis.toml").read_text().replace("detents_deg = [0, 90, 180, 270]",
                                                                  "detents_deg = [0, 120]")
    stand = tmp_path / "table120.toml"
    stand.write_text(text)
    assert main(["plan", "--model", str(stand), "--certificates", str(tmp_path / "c")]) == 0
    out = capsys.readouterr().out
    assert "(0, +x+y+z), (120, +x+y+z)" in out
    certs = sorted((tmp_path / "c").glob("*.json"))
    assert len(certs) == 14 and main(["check-certificate", *map(str, certs)]) == 0
    assert "14 of 14 certificates hold" in capsys.readouterr().out


def test_a_window_longer_than_the_log_is_refused_by_name(tmp_path, capsys):
    # --window 1e308 ended in "OverflowError: cannot convert float infinity to integer".
    path = _csv(tmp_path / "log.csv", "time_s,x,y,z", [_log()[0], *_log()[1].T])
    refused(["calibrate-norm", path, "--window", "1e308", "--json", tmp_path / "r.json"], capsys,
            "--window 1e+308 s: the moving-variance window must be under a quarter of the log's 19.99 s",
            outputs=[tmp_path / "r.json"])


def test_remount_on_a_stand_where_26_does_not_hold_names_the_cause(tmp_path, capsys):
    # `remount = true` on the 90-degree wedge stopped in derive with the internal
    # "Gamma + hat(theta) is not G(q) ..." and a matrix; it must say what to change in the file.
    desc = tmp_path / "w.toml"
    desc.write_text((STANDS / "wedge90.toml").read_text() + "\n[estimation]\nremount = "
        "true\n")
    refused(["derive", desc, "--out", tmp_path / "out"], capsys, "w.toml: remount = true", "set remount = false",
            outputs=[tmp_path / "out"])


# ---------------------------------------------------------------- calibration files, inputs and outputs

def _calibration(tmp_path):
    """A good norm calibration near the identity, every field as calibrate-norm writes it (the files
    calibrate-norm and estimate write themselves pass through the same reader in test_calibration_files)."""
    cal = {"format": "garant-calibration-1", "kind": "norm", "model": "a = M (raw - b)", "raw_unit": "m/s^2",
           "M": [[1.001, 0, 0], [1e-4, 0.999, 0], [-2e-4, 3e-4, 1.0]], "b": [0.01, -0.02, 0.03],
           "bound_matrix": [[1e-3, 0, 0], [1e-3, 1e-3, 0], [1e-3, 1e-3, 1e-3]], "bound_bias": [1e-3] * 3,
           "bound_delta": [0.0] * 3, "pendulosity_axes": [2, 3, 1], "g": 9.81, "source": "test", "note": "",
           "premises": "the bounds hold if ..."}
    return cal


def _log_file(tmp_path, scale=1.0):
    t, raw = _log()
    raw = raw + np.random.default_rng(0).normal(0, 1e-3, raw.shape)
    return _csv(tmp_path / "log.csv", "time_s,x,y,z", [t, *(scale * raw).T])


@pytest.mark.parametrize("change, words", [
    ({"kind": "banana"}, "kind: 'banana': must be one of ['norm', 'stand']"),
    ({"g": True}, "g: True: must be of type number"),
    ({"M": [[0] * 3] * 3}, "M is singular or ill-conditioned (condition number inf"),
    ({"M": [[1e308, 0, 0], [0, 1e308, 0], [0, 0, 1e308]]}, "M[0][0]: 1e+308: must be <= 1e+12"),
    ({"M": [[1, 0, 0], [0, 1, 0], [0, 0, 1e-6]]}, "condition number 1e+06"),
    ({"b": ["a", "b", "c"]}, "b[0]: 'a': must be of type number"),
    ({"M": [[True] * 3] * 3}, "M[0][0]: True: must be of type number"),
    ({"bound_bias": [-1, -1, -1]}, "bound_bias[0]: -1: must be >= 0"),
    ({"bound_delta": [-1e-3, 0, 0]}, "bound_delta[0]: -0.001: must be >= 0"),
    ({"pendulosity_axes": [0, 0, 0]}, "pendulosity_axes[0]: 0: must be >= 1"),
    ({"pendulosity_axes": [1.7, 2.2, 3.9]}, "pendulosity_axes[0]: 1.7: must be of type integer"),
    ({"pendulosity_axes": [4, 4, 4]}, "pendulosity_axes[0]: 4: must be <= 3"),
    ({"pendulosity_axes": [-100, 1, 2]}, "pendulosity_axes[0]: -100: must be >= 1"),
    ({"kind": "\x1b[31mred\n"}, "kind: '\\x1b[31mred\\n': must be one of"),
    ({"source": "fake\nPASS"}, "source: 'fake\\nPASS' holds control characters"),
    ({"extra": 1}, "unknown field(s): 'extra'"),
    ({"bound_matrix": [[0.6, 0.5, 0], [0, 0, 0], [0, 0, 0]]}, "each row of bound_matrix must sum below 1"),
    ("g-400-digits", "g: inf: must be <= 100"),
    ("M-entry-400-digits", "M[0][0]: inf: must be <= 1e+12"),
    ("g-5000-digits", "g: inf: must be <= 100"),
    ("NaN", "not a JSON calibration file (NaN is not a number JSON allows)"),
])
def test_a_calibration_file_is_checked_against_its_schema(tmp_path, capsys, change, words):
    # apply accepted kind "banana", g true, a singular or 1e308 M, strings and booleans, negative
    # bounds, pendulosity axes that wrap or truncate, and printed ANSI escapes; 400-digit integers ended in
    # tracebacks. Each is one line naming the field (schema docs/schemas/calibration.schema.json).
    cal = _calibration(tmp_path)
    if isinstance(change, dict):
        cal.update(change)
        text = json.dumps(cal)
    else:
        text = json.dumps(cal)
        big = "1" * (5000 if "5000" in change else 401)
        text = {"g-400-digits": text.replace('"g": 9.81', f'"g": {big}'),
                "g-5000-digits": text.replace('"g": 9.81', f'"g": {big}'),
                "M-entry-400-digits": text.replace('"M": [[1.001', f'"M": [[{big}'),
                "NaN": text.replace('"g": 9.81', '"g": NaN')}[change]
    path = tmp_path / "c.json"
    path.write_text(text)
    log = _log_file(tmp_path)
    before = log.read_bytes()
    refused(["apply", path, log, "-o", tmp_path / "o.csv"], capsys, "c.json", words, outputs=[tmp_path / "o.csv"])
    assert log.read_bytes() == before


def test_the_calibration_schema_passes_a_good_file_and_the_api_checks_a_dictionary_alike(tmp_path):
    # The other side: the good file above passes; the API's dictionary goes through the same checks (a
    # singular M given as a dictionary used to be applied).
    from garant.verify.io import calibration, schemas
    schemas.validate(_calibration(tmp_path), "calibration", "c.json")
    path = tmp_path / "c.json"
    path.write_text(json.dumps(_calibration(tmp_path)))
    assert calibration.read(path)["kind"] == "norm"
    import garant
    bad = {**_calibration(tmp_path), "M": np.zeros((3, 3))}
    with pytest.raises(garant.DataError, match="M is singular or ill-conditioned"):
        garant.apply(bad, str(_log_file(tmp_path)))
    t, a, bound = garant.apply({**_calibration(tmp_path), "M": np.eye(3)}, str(_log_file(tmp_path)))
    assert a.shape == bound.shape == (len(t), 3)


@pytest.mark.parametrize("scale, unit, looks", [(1000.0, "m/s^2", "raw counts"), (1.0, "count", "m/s^2")])
def test_apply_refuses_a_log_of_another_unit_unless_told(tmp_path, capsys, scale, unit, looks):
    # A calibration made in m/s^2 applied to a raw-count log (and the reverse), silently.
    cal = _calibration(tmp_path)
    cal["raw_unit"] = unit
    path = tmp_path / "c.json"
    path.write_text(json.dumps(cal))
    log = _log_file(tmp_path, scale)
    refused(["apply", path, log, "-o", tmp_path / "o.csv"], capsys, f"look like {looks}", "--trust-units",
            outputs=[tmp_path / "o.csv"])
    assert main(["apply", str(path), str(log), "-o", str(tmp_path / "o.csv"), "--trust-units"]) == 0


def _positions(tmp_path):
    P, f = _plan_rows()
    data = tmp_path / "d.csv"
    np.savetxt(data, np.column_stack([P, f]), delimiter=",", header="alpha_deg,beta_deg,f1,f2,f3", comments="")
    return data


@pytest.mark.parametrize("make_argv, words", [
    (lambda d, t: ["estimate", "--model", "two-axis", d, "--sigma", "1e-5", "--json", d], "over an input"),
    (lambda d, t: ["estimate", "--model", "two-axis", d, "--sigma", "1e-5", "--json", t / "link.csv"],
     "is a symbolic link"),
    (lambda d, t: ["estimate", "--model", "two-axis", d, "--sigma", "1e-5", "--plot", d], "over an input"),
    (lambda d, t: ["estimate", "--model", "two-axis", d, "--sigma", "1e-5", "--save", t / "c.json",
                   "--export-imu-tk", t / "c.json"], "name the same file"),
    (lambda d, t: ["estimate", "--model", "two-axis", d, "--sigma", "1e-5", "--json", t / "r.json",
                   "--plot", t / "r.json"], "name the same file"),
    (lambda d, t: ["estimate", "--model", "two-axis", d, "--sigma", "1e-5", "--json", f"{t}/out.json/"],
     "remove the trailing slash"),
    (lambda d, t: ["estimate", "--model", "two-axis", d, "--sigma", "1e-5", "--json", t / "fifo"], "over a FIFO"),
    (lambda d, t: ["estimate", "--model", "two-axis", d, "--sigma", "1e-5", "--json", "/proc/self/fd/1"],
     "/proc/self/fd/1"),
    (lambda d, t: ["estimate", "--model", "two-axis", t / "fifo", "--sigma", "1e-5"], "not a FIFO"),
    (lambda d, t: ["estimate", "--model", "two-axis", "/dev/zero", "--sigma", "1e-5"], "not a character device"),
    (lambda d, t: ["calibrate-norm", "/dev/zero"], "not a character device"),
    (lambda d, t: ["plan", "--model", "two-axis", "-o", t / "fifo"], "over a FIFO"),
    (lambda d, t: ["simulate", "--model", t / "s.toml", "--plan", "quarter", "--sigma", "1e-5", "-o", t / "s.toml"],
     "over an input"),
    (lambda d, t: ["plan", "--model", t / "s.toml", "-o", t / "s.toml"], "over an input"),
])
def test_no_output_ever_replaces_an_input_or_a_special_file(tmp_path, capsys, make_argv, words):
    # Every command wrote over its own input when an output option named it (also through a
    # symlink), onto a FIFO or /proc/self/fd/1; two outputs to one path kept one silently; a FIFO input
    # hung forever and /dev/zero never ended.
    import os
    data = _positions(tmp_path)
    (tmp_path / "link.csv").symlink_to(data)
    os.mkfifo(tmp_path / "fifo")
    (tmp_path / "s.toml").write_text(BASE)
    inputs = {p: p.read_bytes() for p in (data, tmp_path / "s.toml")}
    names = sorted(p.name for p in tmp_path.iterdir())
    refused(make_argv(data, tmp_path), capsys, words)
    assert {p: p.read_bytes() for p in inputs} == inputs
    assert sorted(p.name for p in tmp_path.iterdir()) == names


def test_a_means_file_is_refused_by_size_and_by_rows_before_it_is_read_whole(tmp_path, capsys, monkeypatch):
    # A 60 MB means file of 30 M short lines needed 4.9 GB before the row limit refused it. The
    # same file made small: the limits lowered 30,000 times; a sparse file stands for the large one.
    from garant.verify.io import means
    monkeypatch.setattr(means, "MAX_ROWS", 1000)
    monkeypatch.setattr(means, "MAX_BYTES", 200_000)
    short = tmp_path / "short.csv"
    short.write_text("f_x,f_y,f_z,std_x,std_y,std_z,n_samples\n" + "1\n" * 5000)
    refused(["repeatability", "--format", "means", short], capsys, "short.csv: more than 1,000 rows (line 1002)")
    sparse = tmp_path / "sparse.csv"
    with open(sparse, "wb") as fh:
        fh.truncate(300_000)
    refused(["repeatability", "--format", "means", sparse], capsys,
            "the means file is 0.3 MB, over the limit of 0.2 MB")


# ---------------------------------------------------------------- forged plan certificates



@pytest.fixture(scope="module")
def wedge_certificates(tmp_path_factory):
    """The plan certificates of the 45-degree wedge table (detents 0, 90, 180, 270), as `garant plan` writes them."""
    folder = tmp_path_factory.mktemp("wedge")
    (folder / "wedge45.toml").write_text((STANDS / "wedge45.toml").read_text())
    assert main(["plan", "--model", str(folder / "wedge45.toml"), "--certificates", str(folder / "c")]) == 0
    return folder


def _forged(folder, name, edit):
    cert = json.loads((folder / "c" / name).read_text())
    edit(cert)
    path = folder / f"forged_{name}"
    path.write_text(json.dumps(cert))
    return path


def _checked(path, capsys):
    code = main(["check-certificate", str(path)])
    return code, capsys.readouterr().out


@pytest.mark.slow
def test_the_plan_certificates_of_a_detent_stand_hold(wedge_certificates, capsys):
    # The other side of the forgeries below: what `garant plan --certificates` wrote holds.
    for path in sorted((wedge_certificates / "c").glob("*.json")):
        assert _checked(path, capsys)[0] == 0, path.name


def _shift_position(cert):
    # A position 1e-15 off a detent (pi/2 (1 + 10^-15)): nsimplify used to identify it with pi/2.
    k = next(i for i, p in enumerate(cert["domain"]["positions"]) if p == ["pi/2"])
    cert["domain"]["positions"][k] = ["pi/2*(1 + 1/1000000000000000)"]


def _drop_a_detent(cert):
    # A domain of 3 of the 4 detents, chosen by the file: its optimum is no optimum of the stand.
    cert["domain"]["positions"] = [p for p in cert["domain"]["positions"] if p != ["pi"]]
    cert["primal"] = [t for t in cert["primal"] if t["at"] != ["pi"]]


def _relabel(cert):
    cert["claim"] = cert["claim"].replace("candidate positions of the plan search", "positions of any stand")


def _fake_lines(cert):
    cert["claim"] += "\n  PASS (0) model: fine\n\x1b[2Kcertificate holds"


@pytest.mark.parametrize("edit, words", [
    (_shift_position, "is not a detent of the stand"),
    (_drop_a_detent, "the domain leaves out the reachable position (180) degrees"),
    (_relabel, "the claim says 'on the 4 positions of any stand' but the domain is the 4 candidate positions"),
    (_fake_lines, "the claim is not of the form"),
])
def test_a_forged_plan_certificate_is_rejected(wedge_certificates, capsys, edit, words):
    # Each of these passed `check-certificate` (exit 0).
    name = sorted(p.name for p in (wedge_certificates / "c").glob("*.json"))[0]
    code, out = _checked(_forged(wedge_certificates, name, edit), capsys)
    assert code == 1 and "certificate REJECTED" in out and words in flat(out), out
    lines = out.splitlines()
    assert "\x1b" not in out
    assert not any(line.lstrip().startswith("PASS") or line == "certificate holds" for line in lines)


@pytest.mark.slow
def test_a_box_certificate_relabelled_as_the_plan_candidates_is_rejected(tmp_path, capsys):
    # single-axis q15's certificate over the whole box of angles (2 + sqrt(2), from 45-degree
    # positions) relabelled "on the 12 candidate positions of the plan search", where the detent optimum is 4.
    from garant.verify.papers.certificates import certificates
    assert all(r.passed for r in certificates(tmp_path / "c"))      # what `garant verify --certificates` writes
    path = tmp_path / "c" / "single-axis_q15.json"
    cert = json.loads(path.read_text())
    cert["claim"] = cert["claim"].replace("the whole box of angles", "the 12 candidate positions of the plan search")
    path.write_text(json.dumps(cert))
    code, out = _checked(path, capsys)
    assert code == 1 and "but the domain is the whole box of angles" in flat(out)


def test_an_angle_named_pi_is_refused_in_a_description_and_a_certificate(tmp_path, capsys, wedge_certificates):
    # An angle named `pi` was read as the constant by the certificate grammar.
    desc = tmp_path / "p.toml"
    desc.write_text((STANDS / "wedge45.toml").read_text().replace('name = "phi"', 'name = "pi"')
                    .replace("phi", "pi"))
    refused(["plan", "--model", desc], capsys, "'pi' is reserved")
    name = sorted(p.name for p in (wedge_certificates / "c").glob("*.json"))[0]
    path = _forged(wedge_certificates, name, lambda c: c["domain"].update(names=["pi"]))
    refused(["check-certificate", path], capsys, "'pi' is a constant or function of the expression grammar")


def test_a_certificate_with_a_5000_digit_integer_is_one_line(tmp_path, capsys):
    # "Exceeds the limit (4300 digits) for integer string conversion" named no file.
    path = tmp_path / "c.json"
    path.write_text('{"format": "garant-certificate-1", "junk": ' + "1" * 5000 + "}")
    refused(["check-certificate", path], capsys, "c.json: not a valid certificate: an integer of 5000 digits")


@pytest.mark.parametrize("change, words", [
    (lambda c: c.update(extra=1), "unknown field(s): 'extra'"),
    (lambda c: c["primal"][0].update(row=-1), "primal[0].row"),
    (lambda c: c.update(value=1), "value"),
    (lambda c: c["domain"].update(kind="box"), "domain.kind"),
    (lambda c: c.update(format="garant-certificate-2"), "format"),
    # A 44 MB certificate was validated item by item for 32 s before its length was refused;
    # sqrt(-1) was read as I and the check went on.
    (lambda c: c.update(primal=c["primal"] * 6_000), "primal: has 12,000 items, at most 10,000"),
    (lambda c: c.update(primal=c["primal"] * 20_000), "over the limit of 2 MB"),
    (lambda c: c["dual"].__setitem__(0, "sqrt(-1)"), "dual[0]: the square root of a negative number"),
    (lambda c: c.update(value="sqrt(10**16000 + 1)"), "value: exponent 16000 is beyond 16"),
])
def test_a_certificate_is_checked_against_its_published_schema(tmp_path, capsys, change, words):
    # docs/schemas/certificate.schema.json: the form first, in one line naming the field (and the
    # schema where it decides), exit 2 (malformed), before any exact check.
    from garant.verify.proof import build
    cert = json.loads((build.COMMITTED / "two-axis_q1.json").read_text())
    change(cert)
    path = tmp_path / "c.json"
    path.write_text(json.dumps(cert))
    refused(["check-certificate", path], capsys, words)


def _mountings(n):
    import itertools
    out = []
    for perm in itertools.permutations("xyz"):
        for signs in itertools.product("+-", repeat=3):
            M = np.zeros((3, 3))
            for i, (a, s) in enumerate(zip(perm, signs)):
                M[i, "xyz".index(a)] = 1 if s == "+" else -1
            if round(np.linalg.det(M)) == 1:
                out.append("".join(s + a for a, s in zip(perm, signs)))
    return out[:n]


@pytest.mark.slow
def test_a_plan_search_beyond_its_budget_keeps_its_plan_with_a_proven_floor(tmp_path, capsys):
    # A four-detent table in all 24 mountings ran for minutes with no word. The search now says
    # its size first, keeps its best plan after --search-nodes (work, not seconds, so the same on
    # every machine), and says it is not proven the fewest. Twelve of the mountings (48 candidates, past the
    # bit masks) take the same road as 24, with a quarter of the derivation.
    old = 'mountings = ["+x+y+z", "+y+z+x", "+z+x+y"]'
    assert old in BASE
    (tmp_path / "m12.toml").write_text(BASE.replace(old, "mountings = " + json.dumps(_mountings(12))))
    out = tmp_path / "p.json"
    code = main(["plan", "--model", str(tmp_path / "m12.toml"), "--search-nodes", "1", "--json", str(out)])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert "48 candidate positions" in captured.err
    d = json.loads(out.read_text())
    assert "not proven the fewest" in captured.out and "after --search-nodes 1;" in captured.out
    assert d["min_positions_at_least"] < d["min_positions"] and not d["stopped_by_clock"]
    assert d["min_positions_at_least"] >= 5        # 15 q need 15 independent readings, 3 per position


@pytest.mark.slow
def test_certificates_of_a_stand_outside_the_exact_field_are_refused_before_the_search(tmp_path, capsys):
    # An axis of 15-digit components searched for 12 s, wrote the plan's JSON, then failed on
    # sqrt(1000110612605718049052708272757) with no word of why.
    text = (STANDS / "tilted_inner.toml").read_text()
    assert "axis = [0, 1, 1]" in text
    (tmp_path / "t.toml").write_text(text.replace("axis = [0, 1, 1]", "axis = [0.123456789012345, 0.234567890123456, "
                                                                    "0.964285714285714]"))
    refused(["plan", "--model", tmp_path / "t.toml", "--certificates", tmp_path / "c", "--json", tmp_path / "p.json"],
            capsys,
            "--certificates: H is not exact in Q(sqrt2, sqrt3)", outputs=[tmp_path / "c", tmp_path / "p.json"])


def test_more_runs_than_the_limit_are_refused_by_name(tmp_path, capsys):
    # 1,000 runs in a means file ran past 60 s (the effect test grows with their square).
    rows = ["exp,imu,f_x,f_y,f_z,std_x,std_y,std_z,n_samples"]
    for run_ in range(1, 61):
        rows += [f"{run_},1,{9.81 * x},{9.81 * y},{9.81 * z},0.01,0.01,0.01,1000"
                 for x, y, z in np.eye(3).tolist() + (-np.eye(3)).tolist()]
    (tmp_path / "m.csv").write_text("\n".join(rows) + "\n")
    refused(["repeatability", "--format", "means", tmp_path / "m.csv", "--imu", "1"], capsys,
            "60 runs, over the limit of 50", "--max-runs")


def test_a_positions_file_over_its_row_limit_is_refused_before_parsing(tmp_path, capsys, monkeypatch):
    # 1e7 distinct positions ended in a MemoryError traceback. The cap (2e6 rows) is made 100 here.
    from garant.verify.io import positions
    monkeypatch.setattr(positions, "MAX_ROWS", 100)
    path = tmp_path / "d.csv"
    path.write_text("alpha_deg,beta_deg,f1,f2,f3\n" + "0,0,0.0001,0.0001,9.81\n" * 150)
    refused(["estimate", "--model", "two-axis", path, "--sigma", "1e-5"], capsys, "more than 100 rows")


@pytest.mark.parametrize("command", [
    lambda p: ["estimate", "--model", "two-axis", p, "--sigma", "1e-5"],
    lambda p: ["calibrate-norm", p, "--format", "csv"],
])
def test_a_header_line_of_a_megabyte_is_refused_by_every_reader(tmp_path, capsys, command):
    # A data row hidden after 1 MB of spaces in the header was read by one reader and not the other.
    path = tmp_path / "d.csv"
    path.write_text("alpha_deg,beta_deg,f1,f2,f3" + " " * (1 << 20) + "0,0,0,0,9.81\n0,90,0,0,9.81\n")
    refused(command(str(path)), capsys, "the header line is longer than 65,536 characters")


def test_out_of_memory_is_one_line(tmp_path, capsys, monkeypatch):
    from garant.verify.io import positions

    def exhausted(*args, **kwargs):
        raise MemoryError
    monkeypatch.setattr(positions, "read_positions", exhausted)
    P, f = _plan_rows()
    np.savetxt(tmp_path / "d.csv", np.column_stack([P, f]), delimiter=",", header="alpha_deg,beta_deg,f1,f2,f3",
               comments="")
    refused(["estimate", "--model", "two-axis", tmp_path / "d.csv", "--sigma", "1e-5"], capsys, "out of memory")


def test_a_log_sampled_once_a_minute_is_refused_for_what_it_is(tmp_path, capsys):
    # A seconds column with 60 s steps was refused as "not a sample interval in seconds": it is one, too sparse
    # for the still intervals' moving window.
    t = np.arange(0, 60.0 * 5000, 60.0)
    path = tmp_path / "slow.csv"
    np.savetxt(path, np.column_stack([t, np.zeros_like(t), np.zeros_like(t), np.full_like(t, 9.81)]), delimiter=",",
               header="time_s,ax,ay,az", comments="")
    assert main(["calibrate-norm", str(path)]) == 2
    err = capsys.readouterr().err
    assert "median step of 60 s" in err and "at least every 0.5 s" in err and "not a sample interval" not in err
