"""Hostile inputs, round three: one writer for every output (never through a link, never over
an input, nothing left by a failing command), the API checking its arguments as the command checks its
options, and the silent, hanging and traceback cases of the round, each one line and exit status 2."""
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import REAL
from test_hostile_inputs import _calibration, _log_file, _plan_rows, _positions, refused, run

import garant
from garant.derive.builtin import STANDS_DIR
from garant.verify.cli import main
from garant.verify.io import files


def _untouched(paths):
    return {Path(p): Path(p).read_bytes() for p in paths}


# ---------------------------------------------------------------- outputs: links, inputs, collisions

@pytest.mark.parametrize("make", ["data named as the module", "symlink", "hard link"])
def test_a_report_folder_never_replaces_an_input_or_follows_a_link(tmp_path, capsys, make, monkeypatch):
    # diagnose --report wrote the generated module two_axis.py in place, over the data file of
    # that name, through a symlink or a hard link to the data: refused now before any work, data unchanged.
    monkeypatch.chdir(tmp_path)
    data = _positions(tmp_path)
    if make == "data named as the module":
        data = data.rename(tmp_path / "two_axis.py")
        folder, words = ".", "an input of this command lies in the report folder"
    else:
        folder = "rep"
        (tmp_path / "rep").mkdir()
        if make == "symlink":
            (tmp_path / "rep" / "two_axis.py").symlink_to(data)
            words = "a symbolic link in the report folder"
        else:
            os.link(data, tmp_path / "rep" / "two_axis.py")
            words = "an input of this command lies in the report folder"
    before = _untouched([data])
    refused(["diagnose", "--model", "two-axis", data.name, "--sigma", "1e-5", "--report", folder], capsys, words)
    assert _untouched([data]) == before


def test_derive_never_writes_over_its_description_through_a_hard_link(tmp_path, capsys):
    # `derive s.toml --out out` with out/single_axis.py hard-linked to s.toml replaced it.
    stand = tmp_path / "s.toml"
    stand.write_text((STANDS_DIR / "single_axis.toml").read_text())
    (tmp_path / "out").mkdir()
    os.link(stand, tmp_path / "out" / "single_axis.py")
    before = _untouched([stand])
    refused(["derive", stand, "--out", tmp_path / "out"], capsys, "an input of this command")
    assert _untouched([stand]) == before


def test_an_output_that_is_a_link_is_refused_even_one_to_standard_output(tmp_path, capsys):
    # --json dev/stdout, dev/stdout a link to /proc/self/fd/1, replaced the link.
    data = _positions(tmp_path)
    (tmp_path / "dev").mkdir()
    (tmp_path / "dev" / "stdout").symlink_to("/proc/self/fd/1")
    refused(["estimate", "--model", "two-axis", data, "--sigma", "1e-5", "--json", tmp_path / "dev" / "stdout"],
            capsys, "is a symbolic link")
    assert (tmp_path / "dev" / "stdout").is_symlink()


@pytest.mark.parametrize("argv, words", [
    (["diagnose", "--model", "two-axis", "{data}", "--sigma", "1e-5", "--report", "{t}/rep", "--json",
      "{t}/rep/index.html"], "lies inside the report folder"),
    (["plan", "--model", "two-axis", "--certificates", "{t}/c", "--json", "{t}/c/two-axis_plan_q1.json"],
     "lies inside the certificate folder"),
    (["verify", "--certificates", "{t}/certs", "--json", "{t}/certs/two-axis_q1.json"],
     "lies inside the certificate folder"),
    (["estimate", "--model", "two-axis", "{data}", "--sigma", "1e-5", "--report", "{t}/rep", "--plot",
      "{t}/rep/residuals.png"], "lies inside the report folder"),
])
def test_two_outputs_of_one_command_never_collide(tmp_path, capsys, argv, words):
    # An output inside another's folder was overwritten by the folder's own file, exit 0.
    data = _positions(tmp_path)
    for sub in ("rep", "c", "certs"):
        (tmp_path / sub).mkdir()
    refused([a.format(t=tmp_path, data=data) for a in argv], capsys, words)
    assert not any(any((tmp_path / sub).iterdir()) for sub in ("rep", "c", "certs"))


def test_a_folder_swapped_for_a_link_during_the_run_is_not_written_through(tmp_path):
    # Swapping rep/ for a symlink while the command ran sent the report elsewhere.
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    with pytest.raises(garant.DataError, match="changed during the run"):
        with files.staged():
            folder = files.make_folder(tmp_path / "rep")
            folder.rmdir()
            folder.symlink_to(elsewhere)
            files.write(folder / "report.md", ["text"], "w")
    assert not any(elsewhere.iterdir())


def test_a_result_never_writes_over_the_file_it_was_computed_from(tmp_path):
    # garant.estimate(...).to_json("d.csv") replaced the data; the result remembers its inputs.
    data = _positions(tmp_path)
    before = _untouched([data])
    res = garant.estimate("two-axis", str(data), 1e-5)
    with pytest.raises(garant.DataError, match="over an input"):
        res.to_json(str(data))
    assert _untouched([data]) == before
    res.to_json(tmp_path / "r.json")
    assert json.loads((tmp_path / "r.json").read_text())["consistent"] is True


# ---------------------------------------------------------------- a failing command writes nothing

@pytest.mark.slow
def test_a_command_that_fails_after_writing_leaves_every_old_file_and_no_new_one(tmp_path, capsys, monkeypatch):
    # estimate wrote r.json and residuals.png, then failed on the report, leaving them (and the
    # report folder) behind. Now each output is held complete beside its name until the command succeeds.
    from garant.verify.io import report
    data = _positions(tmp_path)
    (tmp_path / "r.json").write_text("old\n")

    def broken(*args, **kwargs):
        raise garant.DataError("the report failed")
    monkeypatch.setattr(report, "write_page", broken)
    refused(["estimate", "--model", "two-axis", data, "--sigma", "1e-5", "--json", tmp_path / "r.json", "--plot",
             tmp_path / "p.png", "--report", tmp_path / "rep"], capsys, "the report failed")
    assert (tmp_path / "r.json").read_text() == "old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.csv", "r.json"]     # no p.png, rep/, .part


@pytest.mark.slow
def test_a_write_past_ulimit_f_keeps_the_old_file(tmp_path):
    # `ulimit -f` truncated an output in place (and killed the process with SIGXFSZ).
    import resource
    data = _positions(tmp_path)
    out = tmp_path / "r.json"
    out.write_text("old\n")
    limit = lambda: resource.setrlimit(resource.RLIMIT_FSIZE, (2048, 2048))      # noqa: E731
    r = subprocess.run([sys.executable, "-c", "import sys; from garant.verify.cli import main; sys.exit(main())",
                        "estimate", "--model", "two-axis", str(data),
                        "--sigma", "1e-5", "--json", str(out)], capture_output=True, text=True, preexec_fn=limit,
                       env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"})
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert "r.json: cannot be written (File too large)" in r.stderr
    assert out.read_text() == "old\n" and sorted(p.name for p in tmp_path.iterdir()) == ["d.csv", "r.json"]


# ---------------------------------------------------------------- calibration files

def test_a_calibration_with_a_key_twice_is_refused(tmp_path, capsys):
    # Duplicate keys were accepted, the last one winning.
    text = json.dumps(_calibration(tmp_path))
    path = tmp_path / "c.json"
    path.write_text(text.replace('"g": 9.81', '"g": 9.81, "g": 1.0'))
    refused(["apply", path, _log_file(tmp_path), "-o", tmp_path / "o.csv"], capsys,
            "the key 'g' appears twice in one object", outputs=[tmp_path / "o.csv"])


def test_nan_in_a_calibrations_bounds_is_refused_by_name(tmp_path):
    # NaN passed the schema (it compares false against minimum and maximum) and gave NaN bounds.
    cal = _calibration(tmp_path)
    cal["bound_bias"][1] = float("nan")
    t = np.arange(3000) * 0.01
    with pytest.raises(garant.DataError, match=r"bound_bias\[1\]: NaN"):
        garant.apply(cal, np.column_stack([t, np.zeros((3000, 2)), np.full(3000, 9.81)]))


# ---------------------------------------------------------------- the API checks as the command does

_P, _F = _plan_rows()
_DATA = np.column_stack([_P, _F])
_LOG = np.column_stack([np.arange(3000) * 0.01, np.zeros((3000, 2)), np.full(3000, 9.81)])


@pytest.mark.parametrize("call, words", [
    (lambda: garant.estimate("two-axis", _DATA.astype(complex), 1e-5), "complex numbers are not readings"),
    (lambda: garant.estimate("two-axis", _DATA.astype(object).tolist()[:3] + [[0, 0, "x", 0, 9.81]], 1e-5),
     "every value must be a real number"),
    (lambda: garant.estimate("two-axis", _DATA, float("nan")), "sigma: nan must be a finite number > 0"),
    (lambda: garant.estimate("two-axis", _DATA, -1e-5), "sigma: -1e-05 must be a finite number > 0"),
    (lambda: garant.estimate("two-axis", _DATA, "1e-5"), "sigma: must be a number, not the text '1e-5'"),
    (lambda: garant.estimate("two-axis", _DATA, True), "sigma: must be a real number, not bool"),
    (lambda: garant.estimate("two-axis", _DATA, 5e-324), "sigma: 5e-324 must be at least 1e-12"),
    (lambda: garant.estimate("two-axis", _DATA, 1e-5, g_uncertainty=float("nan")), "g_uncertainty: nan"),
    (lambda: garant.estimate("two-axis", _DATA, 1e-5, prior=2), "prior: 2 must be < 1"),
    (lambda: garant.estimate("two-axis", _DATA, 1e-5, gamma="x"), "gamma: 'x' is not one of lower, symmetric"),
    (lambda: garant.estimate("two-axis", _DATA[:0], 1e-5), "0 distinct positions cannot identify"),
    (lambda: garant.plan("two-axis", count_seconds=float("nan")), "count_seconds: nan"),
    (lambda: garant.plan("two-axis", search_seconds=-1), "search_seconds: -1 must be a finite number > 0"),
    (lambda: garant.plan("two-axis", grid=30, max_candidates=0), "max_candidates: 0 must be a whole number >= 1"),
    (lambda: garant.plan("two-axis", grid=5e-324), "more than 1e18 positions"),
    (lambda: garant.next_position("two-axis", _DATA[:10], 1e-5, grid=2), "over the limit of 10,000"),
    (lambda: garant.calibrate_norm(_LOG, window=float("nan")), "window: nan must be a finite number > 0"),
    (lambda: garant.calibrate_norm(_LOG, delta_sigma=float("nan")), "delta_sigma: nan"),
    (lambda: garant.calibrate_norm(_LOG, sensor="../../etc"), "sensor: '../../etc' is not one of"),
    (lambda: garant.calibrate_norm(_LOG, params=7), "params: 7 is not one of 9, 12"),
    (lambda: garant.apply({}, _LOG, sensor="../../etc"), "sensor: '../../etc' is not one of"),
])
def test_the_api_refuses_what_the_command_refuses_with_a_data_error(call, words):
    # The API accepted complex arrays (imaginary part dropped), NaN or negative sigma and
    # seconds, max_candidates=0, a sensor "../../etc", sigma as text, and ended in TypeError,
    # ZeroDivisionError or a hang; the same check (verify/options.py) now serves the option and the argument.
    with pytest.raises(garant.DataError, match=words.replace("(", r"\(").replace(")", r"\)")
                       .replace("[", r"\[").replace("]", r"\]")):
        call()


# ---------------------------------------------------------------- silent, hanging and traceback cases

def test_a_route_at_a_speed_of_5e_324_is_refused(tmp_path, capsys):
    # A speed of 5e-324 deg/s gave a 1-position route and "total 0 s".
    text = (STANDS_DIR / "two_axis.toml").read_text().replace("[[angle]]\n", "[[angle]]\nspeed_deg_s = 5e-324\n", 1)
    (tmp_path / "s.toml").write_text(text)
    refused(["plan", "--model", tmp_path / "s.toml", "--route"], capsys, "speed_deg_s: 5e-324 is not a deg/s figure")


@pytest.mark.slow
def test_plan_norm_draws_its_plot_and_refuses_a_route(tmp_path, capsys):
    # `plan norm --route --plot` ignored both options.
    refused(["plan", "--model", "norm", "--route"], capsys, "--route applies to a stand with angles")
    assert main(["plan", "--model", "norm", "--plot", str(tmp_path / "n.png")]) == 0
    assert (tmp_path / "n.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.slow
def test_next_draws_its_plot_when_done(tmp_path, capsys):
    # `next` at "done" ignored --plot.
    data = _positions(tmp_path)
    assert main(["next", "--model", "two-axis", str(data), "--sigma", "1e-5", "--target", "1",
                 "--plot", str(tmp_path / "n.png")]) == 0
    assert "done" in capsys.readouterr().out
    assert (tmp_path / "n.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.slow
def test_next_stops_when_repeated_readings_already_refute_sigma(tmp_path, capsys):
    # Readings repeated 2000 sigma apart, before every q has an estimator, still gave a position.
    P, f = _plan_rows()
    rows = np.column_stack([P[:5], f[:5]])
    rows = np.vstack([rows, rows[:1] + [0, 0, 0, 0, 2000 * 1e-5 * 9.81]])
    data = tmp_path / "d.csv"
    np.savetxt(data, rows, delimiter=",", header="alpha_deg,beta_deg,f1,f2,f3", comments="")
    code, _ = run(["next", "--model", "two-axis", data, "--sigma", "1e-5", "--json", tmp_path / "n.json"], capsys)
    res = json.loads((tmp_path / "n.json").read_text())
    assert code == 3 and res["consistent"] is False and res["next"] is None


def test_next_finds_20000_measured_positions_among_the_candidates_in_one_pass():
    # `next` on 20,000 positions ran past 30 s: each measured position was looked for by a scan
    # of every candidate and appended one vstack at a time. Now one look-up each (workflows/next.py).
    from garant.verify.workflows.next import _with_measured
    grid = np.array([(a, b) for a in np.arange(0, 360, 2.5) for b in np.arange(0, 360, 2.5)])
    measured = np.vstack([grid[::2], [[1.25, 1.25], [1.25, 1.25]]])
    P, M, fixed = _with_measured(grid, np.zeros(len(grid), int), measured, np.zeros(len(measured), int))
    assert len(P) == len(grid) + 1 and fixed[:3] == [0, 2, 4] and fixed[-1] == len(grid)
    assert len(fixed) == len(set(fixed)) == len(grid[::2]) + 1


@pytest.mark.parametrize("argv, words", [
    (["plan", "--model", "two-axis", "--grid", "5e-324"], "more than 1e18 positions"),
    (["next", "--model", "two-axis", "{huge}", "--sigma", "1e-5"], "alpha_deg holds 1e+300 degrees"),
    (["calibrate-norm", "{npy}"], "which the file's bytes do not hold"),
    (["check-certificate", "{radical}"], "the root sqrt(5) is not sqrt(2), sqrt(3) or sqrt(6)"),
    (["check-certificate", "{sine}"], "sin(1) is not a number of Q(sqrt2, sqrt3)"),
])
def test_overflow_hang_and_heavy_radical_inputs_end_in_one_line(tmp_path, capsys, argv, words):
    # OverflowError (a 5e-324 grid; a .npy header with a 30-digit dimension), a hang (sigma
    # 5e-324), AssertionError (an angle of 1e300), a certificate with heavy radicals checked for 30 s.
    data = _positions(tmp_path)
    (tmp_path / "huge.csv").write_text("alpha_deg,beta_deg,f1,f2,f3\n1e300,0,0,0,9.81\n")
    header = "{'descr': '<f8', 'fortran_order': False, 'shape': (100000000000000000000000000000, 4), }"
    header += " " * (118 - len(header)) + "\n"
    (tmp_path / "x.npy").write_bytes(b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header.encode())
    cert = json.loads(next(Path(garant.__file__).parent.glob("verify/proof/certificates/two-axis_q1.json"))
                      .read_text())
    for name, value in (("radical", "sqrt(5)"), ("sine", "sin(1)")):
        (tmp_path / f"{name}.json").write_text(json.dumps({**cert, "value": value}))
    refused([a.format(data=data, huge=tmp_path / "huge.csv", npy=tmp_path / "x.npy", radical=tmp_path / "radical.json",
                      sine=tmp_path / "sine.json") for a in argv], capsys, words)


def test_a_noise_bound_below_what_doubles_resolve_is_refused(tmp_path, capsys):
    # `estimate --sigma 5e-324` hung; the floor is options.SIGMA_MIN (1e-12 of g).
    with pytest.raises(SystemExit) as e:
        main(["estimate", "--model", "two-axis", str(_positions(tmp_path)), "--sigma", "5e-324"])
    err = capsys.readouterr().err
    assert e.value.code == 2 and err.count("\n") == 1 and "'5e-324' must be at least 1e-12" in err


@pytest.mark.slow
def test_a_file_name_of_nested_mathtext_draws_as_written(tmp_path, capsys):
    # A file name with nested $\sqrt{...}$ ended every plot in RecursionError.
    name = "a$" + "\\sqrt{" * 30 + "x" + "}" * 30 + "$.csv"
    data = _positions(tmp_path).rename(tmp_path / name)
    assert main(["estimate", "--model", "two-axis", str(data), "--sigma", "1e-5", "--plot",
                 str(tmp_path / "p.png")]) == 0
    assert (tmp_path / "p.png").read_bytes()[:4] == b"\x89PNG"


def test_every_option_that_names_a_file_to_write_is_checked_as_an_output():
    """Every option of every command whose metavar names a file or folder to write (FILE.png, FILE.parm, DIR,
    CAL.json of --save, ...) is in cli.OUTPUTS or the export registry, so it is never taken for an input and never
    written over one.
    Red when a new output option is added without its entry (--thermal-plot was taken for an input: a second
    run refused to replace the first run's plot)."""
    from garant.verify import cli
    outputs = {attr for attr, _, _ in cli.OUTPUTS + cli.exports.outputs()}
    writes = ("plot", "json", "output", "report", "certificates", "out", "save", "csv", "markdown")
    missing = []
    for name, sub in cli.parser()._subparsers._group_actions[0].choices.items():
        for action in sub._actions:
            dest = action.dest
            if (dest in writes or dest.startswith("export_") or dest.endswith("_plot")) and dest not in outputs:
                missing.append(f"{name} --{dest.replace('_', '-')}")
    assert not missing, missing


def test_the_thermal_outputs_never_replace_an_input(tmp_path, capsys):
    """--thermal-plot or --export-ardupilot naming the positions file: one line, exit 2, the file unchanged."""
    data = tmp_path / "d.csv"
    data.write_text("alpha_deg,beta_deg,f1,f2,f3,temp_c\n0,0,0,0,9.81,20\n")
    before = data.read_bytes()
    for option in ("--thermal-plot", "--export-ardupilot"):
        assert main(["estimate", "--model", "two-axis", str(data), "--sigma", "1e-4", "--thermal-degree", "1",
                     option, str(data)]) == 2
        assert "would be written over an input of this command" in capsys.readouterr().err
    assert data.read_bytes() == before


# ---------------------------------------------------------------- round four (issue 57)

REAL_LOG = REAL / "repeat_session2_acc.txt"
IMUCAL_DIR = Path(__file__).resolve().parents[1] / "data" / "imucal"


def test_an_imucal_session_is_refused_for_another_stands_model(capsys):
    # `estimate --format imucal --model two-axis` printed a consistent estimate of the two-axis stand's q from a
    # session held on the faces of a cube: the six-face model's. Refused before any work, through the API too.
    refused(["estimate", "--format", "imucal", "--model", "two-axis", IMUCAL_DIR / "example_ferraris_session.csv",
             "--sections", IMUCAL_DIR / "example_ferraris_session_list.json", "--sigma", "1e-2"], capsys,
            "give --model six-face")
    with pytest.raises(garant.DataError, match="give --model six-face"):
        garant.estimate("two-axis", str(IMUCAL_DIR / "example_ferraris_session.csv"), 1e-2, format="imucal",
                        sections=str(IMUCAL_DIR / "example_ferraris_session_list.json"))


def test_imucal_gyro_is_checked_before_any_work_and_never_ignored(tmp_path, capsys):
    # --imucal-gyro with fields of the wrong shape was copied into the export; without --export-imucal it was
    # accepted and ignored.
    gyro = tmp_path / "g.json"
    gyro.write_text(json.dumps({"K_g": [1, 2], "R_g": np.eye(3).tolist(), "K_ga": np.eye(3).tolist(),
                                "b_g": [0, 0, 0]}))
    out = tmp_path / "i.json"
    refused(["calibrate-norm", REAL_LOG, "--imucal-gyro", gyro, "--export-imucal", out], capsys,
            "K_g must be 3 x 3 finite numbers", outputs=[out])
    good = tmp_path / "good.json"
    good.write_text(json.dumps({"K_g": np.eye(3).tolist(), "R_g": np.eye(3).tolist(), "K_ga": np.zeros((3, 3))
                                .tolist(), "b_g": [0, 0, 0]}))
    refused(["calibrate-norm", REAL_LOG, "--imucal-gyro", good], capsys, "goes with --export-imucal")


@pytest.mark.parametrize("name, magic", [("p.svg", b"<?xml"), ("p.pdf", b"%PDF"), ("p.png", b"\x89PNG")])
@pytest.mark.slow
def test_a_plot_is_written_in_the_format_its_name_says(tmp_path, capsys, name, magic):
    # `plan --plot p.svg` wrote PNG bytes under an .svg name.
    assert main(["plan", "--model", "two-axis", "--plot", str(tmp_path / name)]) == 0
    assert (tmp_path / name).read_bytes().startswith(magic)
    # the same input gives the same file: no date, the same svg ids (red without svg.hashsalt: ids are random)
    assert main(["plan", "--model", "two-axis", "--plot", str(tmp_path / ("again_" + name))]) == 0
    assert (tmp_path / ("again_" + name)).read_bytes() == (tmp_path / name).read_bytes()


def test_a_plot_of_another_format_is_refused_before_any_work(tmp_path, capsys):
    refused(["plan", "--model", "two-axis", "--plot", tmp_path / "p.txt", "--json", tmp_path / "p.json"], capsys,
            "name the file .png, .svg or .pdf", outputs=[tmp_path / "p.txt", tmp_path / "p.json"])


@pytest.mark.slow
def test_a_folder_in_the_way_of_a_report_file_is_named(tmp_path, capsys):
    # A report folder whose residuals.png is a folder gave an error naming a temporary .part path.
    (tmp_path / "rep" / "residuals.png").mkdir(parents=True)
    err = refused(["calibrate-norm", REAL_LOG, "--report", tmp_path / "rep"], capsys, "residuals.png",
                  "a folder or another non-file is in the way")
    assert ".part" not in err


@pytest.mark.parametrize("make, said", [
    (lambda d: os.symlink(d / "nowhere", d / "out"), "a link to nowhere (or a loop of links)"),
    (lambda d: os.symlink(d / "out", d / "out"), "a link to nowhere (or a loop of links)"),
])
def test_a_batch_out_that_cannot_hold_the_files_is_refused_before_any_log(tmp_path, capsys, monkeypatch, make,
                                                                         said):
    # A dangling --out answered "lk: File exists", and a link loop likewise, after every log was calibrated.
    from garant.verify.workflows import batch
    make(tmp_path)
    monkeypatch.setattr(batch, "calibrate_many", lambda *a, **k: pytest.fail("calibrated before --out was checked"))
    refused(["calibrate-norm", REAL_LOG, REAL_LOG, "--out", tmp_path / "out", "--jobs", "1"], capsys, said)


def test_a_batch_out_given_as_a_link_is_followed_once(tmp_path, capsys):
    # A symlinked --out was refused as "changed during the run" (its docstring says a link is followed once).
    (tmp_path / "real").mkdir()
    os.symlink(tmp_path / "real", tmp_path / "out")
    assert main(["calibrate-norm", str(REAL_LOG), str(REAL_LOG), "--out", str(tmp_path / "out"), "--jobs", "1"]) == 0
    assert (tmp_path / "real" / "summary.csv").exists()
    assert capsys.readouterr().err.count("calibrate-norm: ") == 2       # off a terminal: a line a step, no \r


def test_the_api_takes_what_its_docstrings_offer_and_raises_only_data_errors():
    # calibrate_many turned DataFrames and arrays into error rows; apply with a list, estimate on the norm model,
    # a DataFrame with a column twice or of several levels, and diagnose on zero rows gave tracebacks or were
    # accepted silently. Each is now a DataError naming its argument (param), or the result asked for.
    pd = pytest.importorskip("pandas")
    from garant.verify.workflows import jobs
    data = jobs.read_log(str(REAL_LOG))
    arr = np.column_stack([data.t, data.raw])
    df = pd.DataFrame({"t": data.t, "acc_x": data.raw[:, 0], "acc_y": data.raw[:, 1], "acc_z": data.raw[:, 2]})
    rows = garant.calibrate_many([arr, df], jobs=1)
    assert [r["log"] for r in rows] == ["log 1 (in memory)", "log 2 (in memory)"]
    assert [r["status"] for r in rows] == ["consistent", "consistent"]
    twice = df.copy()
    twice.columns = ["t", "acc_x", "acc_x", "acc_z"]
    levels = df.copy()
    levels.columns = pd.MultiIndex.from_tuples([("a", "t"), ("a", "acc_x"), ("b", "acc_y"), ("b", "acc_z")])
    for call, param, said in (
            (lambda: garant.apply([1, 2, 3], str(REAL_LOG)), "calibration", "not list"),
            (lambda: garant.estimate("norm", str(REAL_LOG), 1e-3, thermal_degree=1), "model", "calibrate_norm"),
            (lambda: garant.calibrate_norm(twice), "log", "the column acc_x more than once"),
            (lambda: garant.calibrate_norm(levels), "log", "several levels"),
            (lambda: garant.diagnose("two-axis", np.zeros((0, 5)), 1e-4), "data", "no positions"),
            (lambda: garant.estimate("two-axis", str(REAL_LOG), 1e-4, g=-1), "g", "must be a finite number")):
        with pytest.raises(garant.DataError, match=said) as e:
            call()
        assert e.value.param == param, (param, e.value.param)


def test_the_api_answers_the_same_with_any_blas_thread_count():
    # The command pins one BLAS thread; the API did not, so a set that is nearly a point gave bounds that moved
    # with the machine's thread count. Each API call now runs on one BLAS thread (threadpoolctl), whatever the
    # caller set: a job run through the API's wrapper sees one thread under a caller's limit of 4.
    from threadpoolctl import threadpool_info, threadpool_limits

    from garant.verify import api
    from garant.verify.options import constraints
    seen = api._api(constraints()(lambda: [x["num_threads"] for x in threadpool_info()]))
    with threadpool_limits(limits=4):
        inside = seen()
    assert inside and set(inside) == {1}, inside


def test_a_spec_of_deeply_nested_arrays_is_one_line_before_any_log(tmp_path, capsys, monkeypatch):
    # A --spec with arrays nested 2,000 deep ended in an uncaught RecursionError.
    from garant.verify.workflows import batch
    monkeypatch.setattr(batch, "calibrate_many", lambda *a, **k: pytest.fail("calibrated before --spec was read"))
    spec = tmp_path / "deep.toml"
    spec.write_text("[limits]\nscale = " + "[" * 2000 + "]" * 2000 + "\n")
    refused(["calibrate-norm", REAL_LOG, REAL_LOG, "--out", tmp_path / "out", "--spec", spec], capsys,
            "deep.toml", outputs=[tmp_path / "out"])


@pytest.mark.parametrize("old, new", [
    ("axis = [0, 1, 1]", "axis = [0.123456789012345, 0.98765432109876, 0.5555555555555]"),
    ("axis = [0, 1, 1]", "axis = [999983, 999979, 999961]"),
])
@pytest.mark.slow
def test_a_turning_axis_of_many_digits_derives(tmp_path, capsys, old, new):
    # These axes took 49 s and 18.5 s to derive: each is now an ordinary derivation (the work bounded by the
    # derivation's own budgets, not timed here).
    text = (Path(__file__).resolve().parents[1] / "data" / "stands" / "tilted_inner.toml").read_text()
    assert old in text
    (tmp_path / "t.toml").write_text(text.replace(old, new))
    code, err = run(["derive", tmp_path / "t.toml", "--out", tmp_path / "out"], capsys)
    assert code == 0, err
