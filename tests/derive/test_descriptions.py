"""Stand descriptions (TOML): the built-in stands derive, plan and round-trip; bad files are named."""
import json

import numpy as np
import pytest

from garant.derive.builtin import MODELS, STANDS_DIR
from garant.verify import models
from garant.verify.solve import plans
from garant.verify.cli import main

SIGMA, G = 1e-5, 9.81


def test_two_axis_description_reproduces_the_spine(mod):
    # The TOML of 000 gives the published (3) and (4) (tests/derive/test_derivation.py) and the same plans.
    r = plans.search(mod)
    assert r.min_positions == 10 and len(r.optimal_plans) == 64 and all(r.proven)


@pytest.mark.slow
@pytest.mark.parametrize("name, m, n_min", [("single-axis", 15, 8), ("three-axis", 17, 9)])
def test_builtin_stands_plan(name, m, n_min, tmp_path, capsys):
    # --count-nodes 0: the fewest positions proven and one plan, no count of the others
    out = tmp_path / "p.json"
    assert main(["plan", "--model", name, "--json", str(out), "--count-nodes", "0"]) == 0
    res = json.loads(out.read_text())
    assert len(res["q_names"]) == m and res["min_positions"] == n_min and res["min_positions_proven"]
    assert all(e >= 1 for e in res["guaranteed_errors"])
    assert len(res["optimal_plans"]) == 1 and res["count_method"].startswith("a mixed-integer program, the plan")
    assert "not counted (--count-nodes 0)" in capsys.readouterr().out


def write_multi_csv(path, angles, mounts, names, mount_names, f):
    cols = [f"{a}_deg" for a in names] + ["f1", "f2", "f3"] + (["mount"] if len(mount_names) > 1 else [])
    with open(path, "w") as fh:
        fh.write(",".join(cols) + "\n")
        for a, k, row in zip(angles, mounts, f):
            cells = [repr(float(v)) for v in a] + [repr(float(v)) for v in row]
            fh.write(",".join(cells + ([mount_names[k]] if len(mount_names) > 1 else [])) + "\n")
    return path


@pytest.mark.slow
@pytest.mark.parametrize("name", ["single-axis", "three-axis"])
def test_simulate_estimate_round_trip(name, tmp_path):
    mod = models.load(name)
    names, mount_names = models.layout(mod)
    r = plans.search(mod, count_limit=1)
    plan = list(r.optimal_plans[0])
    angles, mounts = r.angles_deg[plan], r.mounts[plan]
    rng = np.random.default_rng(3)
    p = rng.uniform(-1e-4, 1e-4, len(mod.PARAMETER_NAMES))
    rad = np.deg2rad(angles)
    kw = {"mount": mounts} if len(mount_names) > 1 else {}
    f = mod.readings(*rad.T, p, G, **kw).T + G * rng.uniform(-SIGMA, SIGMA, (len(plan), 3))
    path = write_multi_csv(tmp_path / "d.csv", angles, mounts, names, mount_names, f)
    out = tmp_path / "e.json"
    assert main(["estimate", "--model", name, str(path), "--sigma", str(SIGMA), "--json", str(out)]) == 0
    res = json.loads(out.read_text())
    q_hat = np.array([res["q"][q] for q in mod.Q_NAMES])
    bound = np.array([res["guaranteed_error"][q] for q in mod.Q_NAMES])
    linear = np.array([res["guaranteed_error_linear"][q] for q in mod.Q_NAMES])
    # optimal on this plan, for H at zero errors; linearised at the fit, H moves by the errors (1e-4)
    np.testing.assert_allclose(linear, SIGMA * np.array(r.errors), rtol=1e-3)
    assert np.all(np.abs(q_hat - models.q_of(mod, p)) <= bound)             # remainder included


@pytest.mark.slow
def test_description_file_as_model(tmp_path, capsys):
    src = STANDS_DIR / "single_axis.toml"
    assert main(["derive", str(src), "--out", str(tmp_path)]) == 0
    assert (tmp_path / "single_axis.py").exists() and (tmp_path / "derivation_single_axis.md").exists()
    assert main(["plan", "--model", str(src)]) == 0
    assert "minimal number of positions" in capsys.readouterr().out


BASE = (STANDS_DIR / "single_axis.toml").read_text()


@pytest.mark.parametrize("edit, message", [
    (lambda t: t.replace('axis = "y"\nerror = "kappa"', 'axis = "y"\nerror = "kappa"\nangel = "phi"'),
     "link[1]: unknown key 'angel'"),
    (lambda t: t.replace('axis = "y"\nerror = "kappa"', 'axis = [0, 0, 0]\nerror = "kappa"'),
     "link[1].axis: an axis of zero length"),
    (lambda t: t.replace('axis = "y"\nerror = "kappa"', 'axis = "w"\nerror = "kappa"'),
     "link[1].axis: 'w' is not an axis"),
    (lambda t: t.replace("detents_deg = [0, 90, 180, 270]", "detents_deg = [0, 90, 400]"),
     "angle[1].detents_deg: 400 is outside the range"),
    (lambda t: t.replace('offset = "Delta_phi"', 'offset = "Delta_psi"'),
     "link[2].offset: parameter 'Delta_psi' is not declared"),
    (lambda t: t.replace('axis = "y"\nerror = "kappa"', 'axis = "z"\nerror = "kappa"'),
     "link[1].error: parameter 'kappa' cannot be observed"),
    (lambda t: t + "\n[extra]\nx = 1\n", "extra: unknown table"),
    (lambda t: t.replace("[stand]", "[stand"), "not valid TOML"),
])
def test_bad_description_names_the_place(tmp_path, capsys, edit, message):
    path = tmp_path / "bad.toml"
    path.write_text(edit(BASE))
    assert main(["derive", str(path), "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and "Traceback" not in err


def test_builtin_files_are_the_registered_models():
    # The registered models are the built-in descriptions, each read from its own file: stand errors
    # counted by hand from the files (two-axis: the nine of q_b in section 2 of 000; six-face: the fixture's
    # three misalignments and dg). A model registered from the wrong file, or a file left out, turns this red.
    stand_errors = {"two_axis": 9, "single_axis": 6, "three_axis": 10, "six_face": 4}
    assert set(MODELS) == set(stand_errors) and {p.stem for p in STANDS_DIR.glob("*.toml")} == set(stand_errors)
    for key, m in MODELS.items():
        assert m.stand.name == key and len(m.stand.parameters) == stand_errors[key]
        assert str(m.source_file).endswith(f"stands/{key}.toml")


@pytest.mark.slow
@pytest.mark.parametrize("name", ["single-axis", "two-axis"])
def test_plan_file_travels_to_simulate_and_the_truth_is_saved(name, tmp_path, capsys):
    # `plan -o` writes the plan, `simulate --plan FILE` reads it and saves the truth beside
    # the data; `estimate` on the data then bounds every q of the saved truth.
    plan, data, est = tmp_path / "p.csv", tmp_path / "d.csv", tmp_path / "e.json"
    assert main(["plan", "--model", name, "-o", str(plan)]) == 0
    assert main(["simulate", "--model", name, "--plan", str(plan), "--sigma", str(SIGMA), "-o", str(data)]) == 0
    truth = json.loads((tmp_path / "d.truth.json").read_text())
    assert main(["estimate", "--model", name, str(data), "--sigma", str(SIGMA), "--json", str(est)]) == 0
    res = json.loads(est.read_text())
    assert res["positions"] == len(plan.read_text().splitlines()) - 1
    for q, v in truth["q"].items():
        assert abs(res["q"][q] - v) <= res["guaranteed_error"][q]


def test_identify_any_stand_and_effect_checks_the_angle(tmp_path, capsys):
    # identify works for every stand; an encoder effect on an angle the stand lacks is named as such.
    assert main(["identify", "--model", "single-axis"]) == 0
    assert "Delta_g + phi[Gamma11]" in capsys.readouterr().out.replace("phi[Delta_g] + phi[Gamma11]", "Delta_g + "
        "phi[Gamma11]")
    assert main(["simulate", "--model", "single-axis", "--plan", "quarter", "--effect", "beta_encoder_harmonic=1e-5,0",
                 "--sigma", "1e-5", "-o", str(tmp_path / "x.csv")]) == 2
    err = capsys.readouterr().err
    assert "encoder of angle 'beta'" in err and "b_s" not in err


@pytest.mark.slow
def test_any_identifier_a_user_picks_works(tmp_path, capsys):
    # t1 (tilt 1) and all-capital names (K, DG) were refused as "reserved" because the generated
    # code used such names itself. Now the code keeps its own names apart: the single-axis description
    # with its angle named g, its parameters named t1, DG, K and np, derives, plans, simulates and estimates.
    import re
    text = BASE
    for old, new in (("phi", "g"), ("kappa", "t1"), ("Delta_phi", "DG"), ("theta1", "K"), ("theta2", "t2"),
                     ("Delta_g", "np")):
        text = re.sub(rf"\b{old}\b", new, text)
    stand = tmp_path / "odd.toml"
    stand.write_text(text)
    mod = models.load(str(stand))
    assert mod.ANGLES == ("g",) and {"t1", "t2", "DG", "K", "np"} <= set(mod.PARAMETER_NAMES)
    plan, data = tmp_path / "p.csv", tmp_path / "d.csv"
    assert main(["plan", "--model", str(stand), "-o", str(plan)]) == 0
    assert main(["simulate", "--model", str(stand), "--plan", str(plan), "--sigma", "1e-5", "-o", str(data)]) == 0
    assert main(["estimate", "--model", str(stand), str(data), "--sigma", "1e-5", "--json",
                 str(tmp_path / "e.json")]) == 0
    res, truth = json.loads((tmp_path / "e.json").read_text()), json.loads((tmp_path / "d.truth.json").read_text())
    assert all(abs(res["q"][q] - truth["q"][q]) <= res["guaranteed_error"][q] for q in mod.Q_NAMES)
    capsys.readouterr()
    for bad in ("def", "Gamma11", "bias2"):
        (tmp_path / "bad.toml").write_text(re.sub(r"\bkappa\b", bad, BASE))
        assert main(["derive", str(tmp_path / "bad.toml"), "--out", str(tmp_path)]) == 2
        assert "is reserved" in capsys.readouterr().err


@pytest.mark.slow
def test_a_description_is_derived_once_and_again_when_it_changes(tmp_path, monkeypatch, capsys):
    # A TOML stand was re-derived by SymPy on every command (6-15 s for three angles). Its module
    # is now cached by the SHA-256 of the description and of the generator: the second load derives nothing
    # (derivation made to fail shows it), an edited description is derived again, and the module
    # `garant derive --out` writes is accepted as --model.
    from garant.derive import codegen
    monkeypatch.setenv("GARANT_CACHE", str(tmp_path / "cache"))
    stand = tmp_path / "s.toml"
    stand.write_text(BASE)
    first = models.load(str(stand))
    real = codegen.model_files
    monkeypatch.setattr(codegen, "model_files", lambda *a, **k: (_ for _ in ()).throw(AssertionError("derived")))
    second = models.load(str(stand))
    assert second.Q_DEFINITIONS == first.Q_DEFINITIONS and len(list((tmp_path / "cache").glob("*.py"))) == 1
    stand.write_text(BASE + "\n# edited\n")
    with pytest.raises(AssertionError, match="derived"):
        models.load(str(stand))
    monkeypatch.setattr(codegen, "model_files", real)
    assert main(["derive", str(stand), "--out", str(tmp_path / "out")]) == 0
    (module,) = (tmp_path / "out").glob("*.py")
    assert models.load(str(module)).Q_DEFINITIONS == first.Q_DEFINITIONS
    (tmp_path / "x.py").write_text("import os\n")
    with pytest.raises(Exception, match="no garant header"):
        models.load(str(tmp_path / "x.py"))
    # a module of an older garant (before every stand module had MOUNTINGS and the shared runtime) is refused
    # with what to do, rather than failing later on a missing name
    old = module.read_text().replace("\nMOUNTINGS = ", "\nMOUNTS_OLD = ")
    (tmp_path / "old.py").write_text(old)
    with pytest.raises(Exception, match="written by an older garant; derive it again"):
        models.load(str(tmp_path / "old.py"))
    # every name of the stand protocol (generated/__init__.py API) is checked at load, not found missing later
    (tmp_path / "no_sup.py").write_text(module.read_text().replace("\nH_SUP = ", "\nH_SUP_OLD = "))
    with pytest.raises(Exception, match=r"not a stand model of this garant \(no H_SUP\); derive it again"):
        models.load(str(tmp_path / "no_sup.py"))
