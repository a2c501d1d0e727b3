"""The garant command as a user runs it: plan, estimate, verify, and one-line errors on bad input."""
import json
import subprocess
import sys

import numpy as np
import pytest

from conftest import REAL, needs_real, simulate, write_csv, flat, command_line
from garant.verify import models
from garant.verify.cli import COMMANDS, main

SIGMA = 1e-5
PLAN10 = [(0, 0), (0, 180), (180, 90), (180, 270), (90, 90), (270, 90), (90, 270), (90, 180), (270, 180), (90, 0)]


def truth(seed=0, size=1e-4):
    return np.random.default_rng(seed).uniform(-size, size, 21)


def run(argv, capsys):
    rc = main(argv)
    out = capsys.readouterr()
    return rc, out.out, out.err


@pytest.mark.slow
def test_plan_json(tmp_path, capsys):
    rc, out, _ = run(["plan", "--model", "two-axis", "--json", str(tmp_path / "p.json")], capsys)
    d = json.loads((tmp_path / "p.json").read_text())
    assert rc == 0
    assert d["q_names"] == [f"q{i}" for i in range(1, 16)]
    assert d["guaranteed_errors"] == [1.0] * 15          # 000, section 4: sigma for every q
    assert d["min_positions"] == 10 and d["optimal_plans_count"] == 64
    assert d["plan"] == [list(p) for p in PLAN10]


@pytest.mark.parametrize("positions, seed", [(PLAN10, 1),
                                             ([(a, b) for a in range(0, 360, 30) for b in range(0, 360, 45)], 2)])
def test_estimate_recovers_q_within_bound(tmp_path, capsys, mod, positions, seed):
    p = truth(seed)
    f = simulate(mod, positions, p, SIGMA, seed=seed)
    path = write_csv(tmp_path / "d.csv", positions, f, extra={"note": ["x"] * len(positions)})
    rc, out, err = run(["estimate", "--model", "two-axis", str(path), "--sigma", str(SIGMA),
                        "--json", str(tmp_path / "e.json")], capsys)
    assert rc == 0, err
    d = json.loads((tmp_path / "e.json").read_text())
    q_true = models.q_of(mod, p)
    q_hat = np.array([d["q"][n] for n in mod.Q_NAMES])
    bound = np.array([d["guaranteed_error"][n] for n in mod.Q_NAMES])
    linear = np.array([d["guaranteed_error_linear"][n] for n in mod.Q_NAMES])
    # The guaranteed bound includes the proven linearisation remainder: no allowance added here.
    a_priori = np.array([d["a_priori"]["guaranteed_error"][n] for n in mod.Q_NAMES])
    assert d["consistent"] and np.all(np.abs(q_hat - q_true) <= bound)
    # what the readings prove never exceeds what the plan guarantees, which holds its linear part
    assert np.all(bound <= a_priori) and np.all(a_priori >= linear) and d["remainder_left_bound"] > 0
    if positions == PLAN10:
        # 000, section 4: sigma for every q, for H of (3); the estimate linearises at the exact fit, where
        # H differs from (3) by the size of the errors (1e-4 here), and the optimum by as much.
        np.testing.assert_allclose(linear, SIGMA, rtol=1e-3)
    assert 0 <= d["minimax_residual"] <= SIGMA


def write(tmp_path, text):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    return str(path)


GOOD = "".join(f"{a},{b},0,0,9.81\n" for a, b in PLAN10)


@pytest.mark.parametrize("text, message", [
    ("alpha_deg,beta_deg,f1,f2\n0,0,0,0\n", "missing column(s) f3"),
    ("alpha_deg,beta_deg,f1,f2,f3\n0,0,0,nan,9.81\n" + GOOD, "line 2: column f2: nan is not a finite"),
    ("alpha_deg,beta_deg,f1,f2,f3\n0,0,0,abc,9.81\n", "line 2: column f2: 'abc' is not a number"),
    ("alpha_deg,beta_deg,f1,f2,f3\n" + "".join(f"{np.deg2rad(a)},{np.deg2rad(b)},0,0,9.81\n" for a, b in PLAN10),
     "look like radians"),
    ("alpha_deg,beta_deg,f1,f2,f3\n0,0,0,0,9.81\n0,180,0,0,9.81\n0,0,0,0,9.81\n", "cannot identify"),
    ("alpha_deg,beta_deg,f1,f2,f3\n", "no data rows"),
    ("", "empty file"),
])
def test_bad_input_one_line_exit_2(tmp_path, capsys, text, message):
    rc, out, err = run(["estimate", "--model", "two-axis", write(tmp_path, text), "--sigma", "1e-5"], capsys)
    assert rc == 2
    assert message in err and err.count("\n") == 1 and "Traceback" not in err


def test_unidentifiable_plan_names_the_combinations(tmp_path, capsys):
    text = "alpha_deg,beta_deg,f1,f2,f3\n" + "".join(f"{a},{b},0,0,9.81\n" for a, b in PLAN10[:4])
    rc, _, err = run(["estimate", "--model", "two-axis", write(tmp_path, text), "--sigma", "1e-5"], capsys)
    assert rc == 2 and "q5 = Gamma11 - Delta_g" in err


def test_missing_file(capsys):
    rc, _, err = run(["estimate", "--model", "two-axis", "/nonexistent.csv", "--sigma", "1e-5"], capsys)
    assert rc == 2 and "cannot read" in err


@pytest.mark.slow
def test_garant_verify_console_script(tmp_path):
    out = subprocess.run([sys.executable, "-m", "verify", "--json", str(tmp_path / "v.json")],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stdout[-2000:] + out.stderr
    d = json.loads((tmp_path / "v.json").read_text())
    assert d["checks"] and all(set(c) == {"name", "source", "expected", "got", "passed"} for c in d["checks"])
    assert all(c["passed"] for c in d["checks"])


def test_tables_state_their_model_and_human_units(tmp_path, capsys, mod):
    # Every printed table states its model equation and units; --units human adds ppm, urad/mrad
    # and mg/ug beside SI. 2e-4 as a scale error is +200 ppm; 1e-4 rad is +100 urad; a bias of 1e-3 g is 1 mg.
    from garant.verify.io.report import human
    assert human(2e-4, "1") == "+200 ppm" and human(1e-4, "rad") == "+100 urad" and human(2e-3, "rad") == "+2 mrad"
    assert human(1e-3, "1", bias=True) == "+1 mg" and human(9.80665e-6, "m/s^2", bias=True) == "+1 ug"
    assert human(1.2e-2, "1") == "+1.2 %" and human(-1.2e-4, "1") == "-120 ppm"     # not +1.2e+04 ppm
    p = truth(4)
    f = simulate(mod, PLAN10, p, SIGMA, seed=4)
    path = write_csv(tmp_path / "d.csv", PLAN10, f)
    rc, out, err = run(["estimate", "--model", "two-axis", str(path), "--sigma", str(SIGMA), "--units", "human"],
                       capsys)
    assert rc == 0, err
    assert "model: z = f/g - u(angles) = H^T q + rho, (1)-(3) of 000" in out
    assert " urad " in out and " ppm " in out and (" ug " in out or " mg " in out)


def test_docs_cli_is_the_parser():
    # docs/cli.md is generated from argparse (python -m verify.cli.doc --write); it drifts, this fails.
    from garant.verify.cli import doc
    assert doc.PATH.read_text() == doc.markdown()
    assert all(f"## garant {name}" in doc.markdown() for name in doc.COMMANDS)


def test_docs_fields_are_the_schemas():
    # docs/fields.md is generated from docs/schemas/ (python -m verify.cli.doc --write): a field added to a schema
    # and not to the page, or the other way round, turns it red.
    from garant.verify.cli import doc
    from garant.verify.io import schemas
    assert doc.FIELDS_PATH.read_text() == doc.fields_markdown()
    assert "| `sigma_fit` |" in doc.fields_markdown() and "## next.schema.json" in doc.fields_markdown()
    assert doc.main(["--check"]) == 0
    assert list(schemas.fields("estimate"))[0] == "consistent"


def test_lines_wrap_at_100_columns_on_a_terminal_into_a_file_and_into_a_pipe():
    # estimate printed lines of 330 characters, verify 659, and into a pipe or a file (a log kept with `tee`)
    # calibrate-norm 937. Every line now wraps at 100 columns (continuations indented), a word longer than that
    # (a path) is not cut; a command to run wraps with the shell's continuation, so it still runs when pasted.
    import io
    import shlex

    from garant.verify.cli import WIDTH, _Output, wrap
    line = "premises: " + " ".join(["the bounds hold if every residual component"] * 12)
    wrapped = wrap(line).splitlines()
    assert WIDTH == 100 and len(wrapped) > 1 and max(map(len, wrapped)) <= 100
    assert all(x.startswith("  ") for x in wrapped[1:]) and " ".join(w.strip() for w in wrapped) == line
    assert wrap("/" + "x" * 150) == "/" + "x" * 150
    command = "  add them: garant calibrate-norm " + " ".join(f"/data/log{k}.csv" for k in range(12)) + " --g 9.81"
    said = wrap(command)
    assert max(map(len, said.splitlines())) <= 100 and command_line(said, "add them:") == command.strip()
    assert shlex.split(said.replace(" \\\n", " "))[-2:] == ["--g", "9.81"]
    quoted = "  add them: garant calibrate-norm " + " ".join(f"'/my data/log {k}.csv'" for k in range(8)) + " --g 9.81"
    said = wrap(quoted)                                  # a path with a space is never cut inside its quotes
    assert max(map(len, said.splitlines())) <= 100
    assert all(line.count("'") % 2 == 0 for line in said.splitlines())           # no line ends inside quotes
    assert shlex.split(said.replace(" \\\n", " "))[4:12] == [f"/my data/log {k}.csv" for k in range(8)]

    class Tty(io.StringIO):
        def isatty(self):
            return True
    tty, plain = Tty(), io.StringIO()
    for stream in (tty, plain):
        out = _Output(stream)
        out.write(line[:50])
        out.write(line[50:] + "\nshort\n")
        assert max(map(len, stream.getvalue().splitlines())) <= 100
        assert flat(stream.getvalue()) == flat(line + "\nshort\n")


@needs_real
@pytest.mark.slow
def test_no_command_prints_a_line_over_100_columns_into_a_pipe(tmp_path):
    # The widest outputs of the issue (estimate --units human --mount, calibrate-norm, plan), run as a user
    # runs them with their output into a pipe.
    import subprocess
    import sys
    from pathlib import Path
    data = tmp_path / "d.csv"
    run = [str(Path(sys.executable).with_name("garant"))]
    subprocess.run([*run, "simulate", "--model", "two-axis", "--plan", "quarter", "--sigma", "1e-5", "-o", str(data)],
                   check=True, capture_output=True)
    # each file by a short name in its own folder, as a user types it: a path longer than the width is one word,
    # never broken (a clone at a longer path would print it whole on a line of its own)
    for args, where in ((["estimate", "--model", "two-axis", "d.csv", "--sigma", "1e-5", "--units", "human", "--mount",
                          "+x+y+z"], tmp_path), (["plan", "--model", "two-axis"], tmp_path),
                        (["identify", "--model", "two-axis"], tmp_path),
                        (["calibrate-norm", "repeat_session2_acc.txt", "--g", "9.81744", "--units", "human"], REAL)):
        out = subprocess.run([*run, *args], capture_output=True, text=True, check=True, cwd=where).stdout
        assert out and max(map(len, out.splitlines())) <= 100, args


@needs_real
@pytest.mark.slow
def test_apply_without_output_says_how_and_writes_standard_output_on_dash(tmp_path, capsys):
    # `apply CAL LOG` without -o was an error that did not say where the corrected log could go; -o - now writes
    # the CSV to standard output (the line saying what was written to standard error). A norm calibration of a
    # log whose format has no sensor (imu_tk's) says none, not adxl355.
    log = REAL / "imu_tk_xsens_acc.txt"
    cal = tmp_path / "c.json"
    assert main(["calibrate-norm", str(log), "--save", str(cal), "--json", str(tmp_path / "r.json")]) == 0
    assert json.loads((tmp_path / "r.json").read_text())["sensor"] is None
    capsys.readouterr()
    assert main(["apply", str(cal), str(log)]) == 2
    assert "-o - writes it to standard output" in capsys.readouterr().err
    assert main(["apply", str(cal), str(log), "-o", "-"]) == 0
    out, err = capsys.readouterr()
    assert out.startswith("time_s,ax,ay,az,bound_x,bound_y,bound_z\n") and out.count("\n") > 1000
    assert err.startswith("wrote standard output:")


@pytest.mark.slow
def test_verify_prints_a_summary_and_every_row_with_verbose(capsys):
    # `garant verify` printed every one of its rows, ~240 lines: now each group's count and the failing rows, every
    # row with --verbose (the JSON always holds every row).
    assert main(["verify"]) == 0
    out = capsys.readouterr().out
    assert "group of checks" in out and "certificates.certificates" in out and "passed, 0 failed" in out
    assert out.count("\n") < 40 and "(--verbose prints every check" in out
    assert main(["verify", "--verbose"]) == 0
    assert capsys.readouterr().out.count("PASS") > 200


def test_one_spelling_of_the_model_and_of_each_kind_of_output_across_commands():
    # The model was positional in plan and identify and --model elsewhere; a data file was --csv in plan and -o
    # elsewhere; the degree in T was --temperature beside --temperatures.
    from garant.verify import cli
    spelled = {"json": ["--json"], "plot": ["--plot"], "output": ["-o", "--output"], "report": ["--report"],
               "save": ["--save"], "out": ["--out"], "certificates": ["--certificates"], "markdown": ["--markdown"],
               "thermal_plot": ["--thermal-plot"], "model": ["--model"], "temperature": ["--thermal-degree"]}
    commands = cli.parser()._subparsers._group_actions[0].choices
    for name, sub in commands.items():
        for action in sub._actions:
            if action.dest in spelled:
                assert action.option_strings == spelled[action.dest], (name, action.option_strings)
            assert action.dest not in ("csv", "stand_model") and "--temperature" not in action.option_strings, name
    assert all(any(a.dest == "model" for a in commands[c]._actions) for c in
               ("plan", "identify", "estimate", "next", "simulate", "diagnose"))


def test_every_command_lists_its_options_in_one_order():
    # Each command added its options in its own order (estimate: --sigma, --g, --format, ..., --g-uncertainty;
    # plan: --json second). Now every --help reads: inputs, the model, how they are read, the noise bound, g and
    # the premises, the command's own options, what it writes, the calibration files.
    from garant.verify import cli
    expected = ["--model", "--format", "--imu", "--sigma", "--g", "--g-uncertainty", "--bound", "--prior",
                "--thermal-degree", "--json", "--plot", "--report", "--save", "--export-imu-tk"]
    text = cli.parser("estimate")._subparsers._group_actions[0].choices["estimate"].format_help()
    at = [text.index(f"\n  {flag} ") for flag in expected]
    assert at == sorted(at)
    plan = cli.parser("plan")._subparsers._group_actions[0].choices["plan"].format_help()
    assert plan.index("\n  --grid ") < plan.index("\n  --json ") < plan.index("\n  -o PLAN.csv, --output")


@pytest.mark.parametrize("command", ["", *COMMANDS])
def test_every_help_is_at_most_100_columns_on_a_wide_terminal(command, capsys, monkeypatch):
    # `garant --help` was 128 columns (the list of commands as one word), repeatability's 104 (--format's choices);
    # argparse takes any terminal's width. Now every --help is at most 100 columns, the commands one a line.
    monkeypatch.setenv("COLUMNS", "200")
    with pytest.raises(SystemExit):
        main([command, "--help"] if command else ["--help"])
    out = capsys.readouterr().out
    assert out and max(map(len, out.splitlines())) <= 100, max(out.splitlines(), key=len)


@pytest.mark.parametrize("argv, meant", [
    (["estimat"], "did you mean estimate?"),
    (["calibrate-norn", "x.txt"], "did you mean calibrate-norm?"),
    (["estimate", "--model", "two-axis", "d.csv", "--sigma", "1e-5", "--sgima", "3"], "did you mean --sigma?"),
    (["calibrate-norm", "x.txt", "--thermal-degreee", "1"], "did you mean --thermal-degree?"),
])
def test_a_mistyped_command_or_option_is_told_the_close_name(argv, meant, capsys):
    # A mistyped command or option got "invalid choice" or "unrecognized arguments" and nothing more.
    with pytest.raises(SystemExit) as e:
        main(argv)
    err = capsys.readouterr().err
    assert e.value.code == 2 and err.count("\n") == 1 and meant in err, err


def test_effect_help_names_every_effect_of_the_catalogue(capsys):
    # `--effect`'s help listed 7 of the 14 effects calibrate-norm can add (a hand-kept list that drifted). It lists
    # defaults.NORM_EFFECTS now, which must be the generated catalogue's names in its order.
    from garant.generated import norm
    from garant.verify.defaults import NORM_EFFECTS
    assert NORM_EFFECTS == tuple(norm.EFFECTS)
    with pytest.raises(SystemExit):
        main(["calibrate-norm", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert all(name in text for name in norm.EFFECTS)
