"""The notebook API and the commands go through the same functions: the same results for
the same inputs, data as arrays as well as files, and docs/api.md's example runs as written."""
import json

import numpy as np
import pytest

import garant
from conftest import G_REAL, REAL, ROOT, needs_real, write_csv
from garant.verify.cli import main

STANDS = ROOT / "tests" / "data" / "stands"


@pytest.mark.slow
@pytest.mark.parametrize("model", ["two-axis", "single-axis", str(STANDS / "tilted_inner.toml"), "norm"])
def test_plan_of_the_api_is_the_plan_of_the_command(tmp_path, capsys, model):
    # tilted_inner: the exchange positions are candidates there; garant.plan gave 8 positions with errors
    # 3.0, 1.414, ... where `garant plan` gave 10 with 2.414, 1.0, ... (the step lived in the command).
    out = tmp_path / "p.json"
    # the search and the count are budgeted by work: the same JSON, whatever the machine's load
    assert main(["plan", "--model", model, "--json", str(out), "--count-nodes", "5"]) == 0
    assert garant.plan(model, count_nodes=5) == json.loads(out.read_text())


@pytest.mark.slow
def test_estimate_takes_an_array_or_a_file_alike(tmp_path):
    from garant.generated import two_axis as mod
    P = np.array([(a, b) for a in range(0, 360, 45) for b in range(0, 360, 45)], float)
    p = np.random.default_rng(1).uniform(-1e-4, 1e-4, len(mod.PARAMETER_NAMES))
    f = mod.readings(*np.deg2rad(P).T, p, 9.81).T
    from_file = garant.estimate("two-axis", str(write_csv(tmp_path / "d.csv", P, f)), 1e-5)
    from_array = garant.estimate("two-axis", np.column_stack([P, f]), 1e-5)
    assert from_file["q"] == pytest.approx(from_array["q"], rel=1e-12, abs=1e-15)
    with pytest.raises(garant.DataError, match=r"data: expected an array of shape \(N, 5\)"):
        garant.estimate("two-axis", np.zeros((4, 3)), 1e-5)
    with pytest.raises(garant.DataError, match="sigma: -1.0 must be a finite number > 0"):
        garant.estimate("two-axis", np.column_stack([P, f]), -1.0)


@pytest.mark.slow
def test_results_are_objects_with_the_documented_fields(tmp_path):
    # Like scipy's OptimizeResult: fields as keys and attributes, arrays kept as arrays, to_dict() the
    # command's JSON itself (the same code path), a short repr, an HTML table; docs/api.md lists every field
    # each kind documents (dropping one from the docs, or a field from the result, turns this red).
    from garant.generated import two_axis as mod
    from garant.verify.io import results
    P = np.array([(a, b) for a in range(0, 360, 45) for b in range(0, 360, 45)], float)
    f = mod.readings(*np.deg2rad(P).T, np.zeros(len(mod.PARAMETER_NAMES)), 9.81).T
    data = write_csv(tmp_path / "d.csv", P, f)
    out = tmp_path / "e.json"
    assert main(["estimate", "--model", "two-axis", str(data), "--sigma", "1e-5", "--json", str(out)]) == 0
    res = garant.estimate("two-axis", str(data), 1e-5)
    assert isinstance(res, results.Estimate) and res.q is res["q"] and isinstance(res.residual, np.ndarray)
    assert res.to_dict() == json.loads(out.read_text())
    assert json.loads(res.to_json()) == res.to_dict()
    text = repr(res)
    assert text.startswith("Estimate(\n  consistent: True") and len(text.splitlines()) < 60
    assert "<table>" in res._repr_html_() and "guaranteed_error" in res._repr_html_()
    rows = res.table("q", "guaranteed_error", "units").splitlines()       # a row per q, the fields side by side
    assert rows[0].split() == ["name", "q", "guaranteed_error", "units"] and len(rows) == 1 + len(mod.Q_NAMES)
    assert rows[7].split()[0] == "q7" and float(rows[7].split()[2]) == pytest.approx(res.guaranteed_error["q7"], 1e-5)
    with pytest.raises(AttributeError, match="no field 'nope'"):
        res.nope
    assert set(res) <= set(results.Estimate.FIELDS)           # every field of the result is one of its schema's
    assert "guaranteed_error" in results.Estimate.FIELDS and "information set" in results.Estimate.FIELDS[
        "guaranteed_error"]
    api, fields = (ROOT / "docs" / "api.md").read_text(), (ROOT / "docs" / "fields.md").read_text()
    for kind in (results.Plan, results.Estimate, results.NormCalibration, results.Diagnosis, results.NextPosition):
        assert f"`{kind.__name__}`" in api
        assert all(f"| `{name}`" in fields for name in kind.FIELDS), kind.__name__
    assert all(f"`{name}`" in api for name in results.Correction.FIELDS)


def test_api_errors_name_the_api_arguments(tmp_path):
    # The readers say "--imu 9" to a command's user; the API's caller wrote imu=9 and reads that name.
    log = tmp_path / "log.txt"
    log.write_text("".join(f"{k * 0.01:.2f} 0 0 9.81\n" for k in range(100)))
    with pytest.raises(garant.DataError) as err:
        garant.calibrate_norm(str(log), imu=9)
    assert "imu" in str(err.value) and "--imu" not in str(err.value)


@needs_real
@pytest.mark.slow
def test_calibrate_norm_and_apply_of_the_api_are_the_commands(tmp_path, capsys):
    # One function per job (workflows/jobs.py): the still-interval options, the calibration, the diagnosis
    # and the correction are the command's own. Before, garant.calibrate_norm had no window/k/min_still and
    # no diagnosis, and its calibration was made in api.py.
    log = str(REAL / "repeat_session2_acc.txt")
    out, cal, corrected = tmp_path / "c.json", tmp_path / "cal.json", tmp_path / "a.csv"
    assert main(["calibrate-norm", log, "--g", "9.81744", "--k", "12", "--diagnose", "--json", str(out),
                 "--save", str(cal)]) == 0
    res = garant.calibrate_norm(log, g=9.81744, k=12, diagnose=True)
    assert res.to_dict() == json.loads(out.read_text())
    assert res.calibration == json.loads(cal.read_text()) and "diagnosis" in res
    assert main(["apply", str(cal), log, "-o", str(corrected)]) == 0
    t, a, bound = garant.apply(res.calibration, log)
    table = np.loadtxt(corrected, delimiter=",", skiprows=1)
    assert np.allclose(table[:, 1:4], a, rtol=1e-7, atol=1e-9) and np.all(table[:, 4:] >= bound * (1 - 1e-3))
    # an array (time, x, y, z) is a log too
    raw = np.loadtxt(log)[:, :4]
    assert np.allclose(garant.calibrate_norm(raw, g=9.81744, k=12).matrix, res.matrix, rtol=1e-9, atol=1e-12)
    with pytest.raises(garant.DataError, match=r"log: expected an array of shape \(N, 4\)"):
        garant.calibrate_norm(raw[:, :3])


@pytest.mark.slow
def test_diagnose_of_the_api_is_the_command(tmp_path, capsys):
    from garant.generated import two_axis as mod
    P = np.array([(a, b) for a in range(0, 360, 45) for b in range(0, 360, 45)], float)
    f = mod.readings(*np.deg2rad(P).T, np.zeros(len(mod.PARAMETER_NAMES)), 9.81).T
    data, out = write_csv(tmp_path / "d.csv", P, f), tmp_path / "d.json"
    assert main(["diagnose", "--model", "two-axis", str(data), "--sigma", "1e-5", "--json", str(out)]) == 0
    res = garant.diagnose("two-axis", np.column_stack([P, f]), 1e-5)
    assert res.to_dict() == json.loads(out.read_text()) and "_study" not in res and res.study is not None


@needs_real
def test_a_npy_log_calibrates_as_its_text(tmp_path):
    # Binary input for large logs: the same samples as .npy give the same calibration; an object
    # array is refused, never unpickled (a file is data).
    log = REAL / "repeat_session2_acc.txt"
    np.save(tmp_path / "s.npy", np.loadtxt(log)[:, :4])
    text, binary = garant.calibrate_norm(str(log), g=9.81744), garant.calibrate_norm(str(tmp_path / "s.npy"), g=9.81744)
    assert binary.format == "npy" and np.allclose(binary.matrix, text.matrix, rtol=1e-12, atol=1e-15)
    np.save(tmp_path / "o.npy", np.array([{"a": 1}], dtype=object), allow_pickle=True)
    with pytest.raises(garant.DataError, match="not a NumPy array of numbers"):
        garant.calibrate_norm(str(tmp_path / "o.npy"))


def test_an_estimates_q_and_bounds_come_as_named_arrays(tmp_path):
    # Estimate.q and its bounds as arrays, in the order of the names beside them.
    from garant.generated import two_axis as mod
    P = np.array([(a, b) for a in range(0, 360, 45) for b in range(0, 360, 45)], float)
    f = mod.readings(*np.deg2rad(P).T, np.zeros(len(mod.PARAMETER_NAMES)), 9.81).T
    r = garant.estimate("two-axis", np.column_stack([P, f]), 1e-5)
    assert r.names == mod.Q_NAMES
    assert np.array_equal(r.array("q"), [r.q[n] for n in mod.Q_NAMES])
    assert np.array_equal(r.array("guaranteed_error"), [r.guaranteed_error[n] for n in mod.Q_NAMES])
    with pytest.raises(KeyError):
        r.array("premises")


def test_an_error_names_the_option_as_the_caller_spells_it(tmp_path, capsys):
    # workflows wrote "--imu" into errors and the API rewrote them by regex ("choose one with --imu K"
    # came out "imu K"). An error now marks its options (errors.opt): the command prints --imu and --run,
    # the API imu= and which_run=, and the error carries the parameter it is about.
    from garant.verify.cli import main
    data = write_csv(tmp_path / "d.csv", [(a, b) for a in range(0, 360, 90) for b in range(0, 360, 90)],
                     np.tile([0.0, 0.0, 9.81], (16, 1)))
    with pytest.raises(garant.DataError) as e:
        garant.estimate("two-axis", str(data), 1e-5, which_run="3")
    assert str(e.value).startswith("imu= and which_run= apply to a means file") and e.value.param == "imu"
    assert main(["estimate", "--model", "two-axis", str(data), "--sigma", "1e-5", "--run", "3"]) == 2
    assert "--imu and --run apply to a means file" in capsys.readouterr().err


@pytest.mark.slow
def test_every_result_has_a_status_and_its_message(tmp_path):
    # Like scipy's OptimizeResult, every result says what came out in a word and a line.
    from garant.verify.io import results
    from garant.verify.outcomes import Status
    for cls in (results.Plan, results.Estimate, results.NormCalibration, results.Diagnosis, results.Correction,
                results.NextPosition):
        assert cls.STATUSES and all(isinstance(v, str) and v for v in cls.STATUSES.values())
        assert all(isinstance(k, Status) for k in cls.STATUSES), cls        # declared once: outcomes.Status
    P = np.array([(a, b) for a in range(0, 360, 45) for b in range(0, 360, 45)], float)
    from garant.generated import two_axis as mod
    f = mod.readings(*np.deg2rad(P).T, np.zeros(len(mod.PARAMETER_NAMES)), 9.81).T
    good = garant.estimate("two-axis", np.column_stack([P, f]), 1e-5)
    spike = f.copy()
    spike[3, 0] += 0.01                                  # one reading 100 sigma off: no unit fits it
    bad = garant.estimate("two-axis", np.column_stack([P, spike]), 1e-5)
    assert (good.status, bad.status) == ("consistent", "refuted") and "no bound" in bad.message
    assert (good.status, bad.status) == (Status.CONSISTENT, Status.REFUTED) and str(bad.status) == "refuted"
    assert garant.plan("two-axis").status == "done"


def test_docs_api_states_each_function_as_it_is():
    """docs/api.md's table gives each function of the API with its signature as Python reports it (options
    keyword-only, one order): red if an option is added, renamed or reordered and the page is not."""
    import inspect
    api = (ROOT / "docs" / "api.md").read_text()
    inputs = {"plan": ["model"], "next_position": ["model", "data", "sigma"], "estimate": ["model", "data", "sigma"],
              "calibrate_norm": ["log"], "calibrate_many": ["logs"], "diagnose": ["model", "data", "sigma"],
              "apply": ["calibration", "log"]}
    for name, given in inputs.items():
        sig = inspect.signature(getattr(garant, name))
        assert sig.return_annotation is not sig.empty and all(      # typed at the seam; the page shows the names
            p.annotation is not p.empty for p in sig.parameters.values()), name
        sig = sig.replace(parameters=[p.replace(annotation=p.empty) for p in sig.parameters.values()],
                          return_annotation=sig.empty)
        assert f"`garant.{name}{str(sig).replace(chr(39), chr(34))}`" in api, name
        positional = [p.name for p in sig.parameters.values() if p.kind != p.KEYWORD_ONLY]
        assert positional == given, (name, positional)                 # every option by its name
        options = [p for p in sig.parameters if p not in given]
        premises = [p for p in ("g", "g_uncertainty", "prior", "bound") if p in options]
        assert options[:len(premises)] == premises, name                # the premises first, in one order


@needs_real
@pytest.mark.slow
def test_apply_returns_what_docs_api_says_for_each_kind_of_log(tmp_path):
    # garant.apply(cal, DataFrame) returned a DataFrame while docs/api.md's table said a Correction that unpacks:
    # the table now says what each input gives, and each is called as documented.
    pd = pytest.importorskip("pandas")
    text = (ROOT / "docs" / "api.md").read_text()
    row = next(line for line in text.splitlines() if line.startswith("| `garant.apply("))
    assert "a path or an array: `Correction`" in row and "a pandas DataFrame: a corrected copy" in row
    log = REAL / "repeat_session2_acc.txt"
    cal = garant.calibrate_norm(str(log), g=G_REAL).calibration
    t, a, bound = garant.apply(cal, str(log))                      # a path: a Correction that unpacks
    from garant.verify.workflows import jobs
    raw = jobs.read_log(str(log))
    c = garant.apply(cal, np.column_stack([raw.t, raw.raw]))      # an array: the same
    assert np.allclose(c.a, a) and len(t) == len(c.t)
    df = pd.DataFrame({"time_s": raw.t, "acc_x": raw.raw[:, 0], "acc_y": raw.raw[:, 1], "acc_z": raw.raw[:, 2]})
    out = garant.apply(cal, df)                                    # a DataFrame: a corrected copy with bounds
    assert isinstance(out, pd.DataFrame) and {"bound_x", "bound_y", "bound_z"} <= set(out.columns)
    assert np.allclose(out[["acc_x", "acc_y", "acc_z"]].to_numpy(), a)
    pieces = list(garant.apply(cal, str(log), chunk=5000))         # with chunk: Corrections, piece by piece
    assert sum(len(p.t) for p in pieces) == len(t)


@needs_real
def test_calibrate_norm_returns_what_docs_api_says_for_a_path_an_array_and_a_dataframe():
    # docs/api.md: calibrate_norm gives a NormCalibration whatever the log's kind; each kind called as documented
    # gives the same calibration.
    pd = pytest.importorskip("pandas")
    from garant.verify.io.results import NormCalibration
    from garant.verify.workflows import jobs
    row = next(line for line in (ROOT / "docs" / "api.md").read_text().splitlines()
               if line.startswith("| `garant.calibrate_norm("))
    assert "`NormCalibration`" in row
    log = REAL / "repeat_session2_acc.txt"
    raw = jobs.read_log(str(log))
    df = pd.DataFrame({"time_s": raw.t, "acc_x": raw.raw[:, 0], "acc_y": raw.raw[:, 1], "acc_z": raw.raw[:, 2]})
    got = [garant.calibrate_norm(x, g=G_REAL) for x in (str(log), np.column_stack([raw.t, raw.raw]), df)]
    assert all(isinstance(r, NormCalibration) for r in got)
    assert all(np.allclose(r.matrix, got[0].matrix) for r in got)


@needs_real
@pytest.mark.parametrize("kwargs, name", [
    ({"effects": "nope"}, "effects="), ({"effects": "bias_drift,bias_drift"}, "effects="),
    ({"bound": {"foo": 0.1}}, "bound="), ({"thermal_degree": 1, "effects": "bias_drift"}, "thermal_degree="),
])
def test_api_errors_speak_python_argument_names_not_the_commands_flags(kwargs, name):
    # 28 errors the API could raise spelt the command's flags (--effect, --bound, --thermal-degree) to a Python
    # caller; they name the argument as the caller wrote it now (the command still prints its flag).
    with pytest.raises(garant.DataError) as e:
        garant.calibrate_norm(str(REAL / "repeat_session2_acc.txt"), g=9.81744, **kwargs)
    assert name in str(e.value) and "--" not in str(e.value), str(e.value)


@needs_real
def test_the_sensor_is_taken_in_any_case_by_the_api_as_by_the_command(capsys):
    # `garant calibrate-norm --sensor BMI160` took the name in any case; the API refused sensor="BMI160". Both take
    # it now through one check (options.sensor) and give the same calibration as the lower-case name; an unknown
    # sensor is refused naming the argument, or the option.
    log = str(REAL / "openaxes_imu9.csv")
    upper, lower = (garant.calibrate_norm(log, sensor=s, g=9.81744) for s in ("BMI160", "bmi160"))
    assert np.array_equal(upper.matrix, lower.matrix)
    with pytest.raises(garant.DataError, match="sensor: 'BMX' is not one of adxl355, bmi160"):
        garant.calibrate_norm(log, sensor="BMX", g=9.81744)
    with pytest.raises(SystemExit) as e:                  # the command: the same check (options.sensor), exit 2
        main(["calibrate-norm", log, "--sensor", "BMX", "--g", "9.81744"])
    assert e.value.code == 2 and "--sensor: 'BMX' is not one of adxl355, bmi160" in capsys.readouterr().err


@needs_real
def test_the_apis_format_is_the_commands_and_the_old_fmt_is_taken_with_a_warning():
    # The API spelt the command's --format `fmt=`; it is `format=` now, `fmt=` taken for a release with a
    # DeprecationWarning (api.RENAMED); an unknown format is refused naming `format`.
    import warnings
    log = str(REAL / "repeat_session2_acc.txt")
    new = garant.calibrate_norm(log, g=9.81744, format="imu_tk")
    with pytest.warns(DeprecationWarning, match="fmt= is now format="):
        old = garant.calibrate_norm(log, g=9.81744, fmt="imu_tk")
    assert np.array_equal(new.matrix, old.matrix)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(garant.DataError, match=r"^format: 'csv2' is not one of") as e:
            garant.calibrate_norm(log, g=9.81744, format="csv2")
    assert e.value.param == "format"
