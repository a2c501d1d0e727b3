"""Fixed turns of any angle (a wedge), tilted unit-vector axes, detents and ranges
honoured by simulate and diagnose. Each generated model is checked against a rotation chain written
here independently in numpy (passive rotations, C1-C3 of section 2 of 000; Rodrigues for a tilted axis)."""

import numpy as np
import pytest

from garant.verify import models
from garant.verify.cli import main
from garant.verify.errors import DataError
from garant.verify.workflows import simulate
from conftest import C, STANDS




def theta_turn(t):
    return C([0, 0, 1], t[2]) @ C([0, 1, 0], t[1]) @ C([1, 0, 0], t[0])


def _physical(mod, **values):
    p = np.zeros(len(mod.PARAMETER_NAMES))
    for k, v in values.items():
        p[mod.PARAMETER_NAMES.index(k)] = v
    return p


def test_wedge_readings_match_an_independent_chain():
    """base -> 45-degree wedge about x (error w) -> tilts kappa1 (x), kappa2 (y) -> table z (phi - dphi)."""
    mod = models.load(str(STANDS / "wedge45.toml"))
    e = dict(w=2e-3, kappa1=-1e-3, kappa2=5e-4, dphi=3e-4, theta1=1e-4, theta2=-2e-4, theta3=3e-4, dg=1e-4)
    for phi in np.deg2rad([0, 90, 180, 270, 33]):
        chain = (C([0, 0, 1], phi - e["dphi"]) @ C([0, 1, 0], e["kappa2"]) @ C([1, 0, 0], e["kappa1"])
                 @ C([1, 0, 0], np.pi / 4 + e["w"]))
        want = 9.81 * (1 - e["dg"]) * theta_turn([e["theta1"], e["theta2"], e["theta3"]]) @ chain @ [0, 0, 1]
        got = mod.readings(phi, _physical(mod, **e), 9.81)
        np.testing.assert_allclose(got, want, atol=1e-12)
        np.testing.assert_allclose(mod.up_nominal(phi), C([0, 0, 1], phi) @ C([1, 0, 0], np.pi / 4) @ [0, 0, 1],
                                   atol=1e-15)


def test_tilted_axis_readings_match_rodrigues():
    mod = models.load(str(STANDS / "tilted_inner.toml"))
    n = [0, 1, 1]
    e = dict(kappa=1e-3, da=-2e-3, db=1e-3, theta1=2e-4, theta2=0, theta3=-1e-4, dg=0)
    for a, b in np.deg2rad([[0, 0], [30, 90], [200, 170]]):
        chain = C(n, b - e["db"]) @ C([1, 0, 0], a - e["da"]) @ C([0, 1, 0], e["kappa"])
        want = 9.81 * theta_turn([e["theta1"], e["theta2"], e["theta3"]]) @ chain @ [0, 0, 1]
        np.testing.assert_allclose(mod.readings(a, b, _physical(mod, **e), 9.81), want, atol=1e-12)


def test_wedge_derivation_has_the_exact_irrational_entries():
    mod = models.load(str(STANDS / "wedge45.toml"))
    assert any("sqrt(2)" in d for d in mod.Q_DEFINITIONS)
    H = np.moveaxis(models.H_at(mod, np.deg2rad([[0.0], [90.0]])), -1, 0)
    assert np.isclose(np.abs(H).max(), np.sqrt(2)) or np.any(np.isclose(np.abs(H), np.sqrt(0.5)))


def test_simulate_honours_detents_and_ranges(tmp_path):
    wedge = models.load(str(STANDS / "wedge45.toml"))
    P, _ = simulate.plan_positions(wedge, "quarter")
    assert sorted(P[:, 0].tolist()) == [0, 90, 180, 270]
    P, _ = simulate.plan_positions(wedge, "grid:30")                  # detents win over the grid
    assert sorted(P[:, 0].tolist()) == [0, 90, 180, 270]
    (tmp_path / "p.csv").write_text("phi_deg\n0\n30\n")
    with pytest.raises(DataError, match="phi = 30 deg is not reachable"):
        simulate.plan_positions(wedge, str(tmp_path / "p.csv"))
    tilted = models.load(str(STANDS / "tilted_inner.toml"))
    P, _ = simulate.plan_positions(tilted, "grid:45")
    assert P[:, 1].max() <= 180 and P[:, 1].min() >= 0


@pytest.mark.parametrize("stand, plan", [("wedge45.toml", "quarter"), ("tilted_inner.toml", "grid:45")])
def test_simulate_estimate_each_q_inside_its_bound(tmp_path, stand, plan):
    import json
    data = tmp_path / "d.csv"
    assert main(["simulate", "--model", str(STANDS / stand), "--plan", plan, "--sigma", "1e-5",
                 "--seed", "3", "-o", str(data)]) == 0
    out = tmp_path / "e.json"
    assert main(["estimate", "--model", str(STANDS / stand), str(data), "--sigma", "1e-5", "--json", str(out)]) == 0
    res, truth = json.loads(out.read_text()), json.loads((tmp_path / "d.truth.json").read_text())
    assert set(res["q"]) == set(truth["q"])
    for name, q in res["q"].items():
        assert abs(q - truth["q"][name]) <= res["guaranteed_error"][name], name


@pytest.mark.slow
def test_diagnose_advises_only_reachable_positions(tmp_path, capsys):
    data = tmp_path / "d.csv"
    assert main(["simulate", "--model", str(STANDS / "wedge45.toml"), "--plan", "quarter", "--sigma", "1e-6",
                 "--effect", "bias_drift=1e-8,0,0", "-o", str(data)]) == 0
    capsys.readouterr()
    main(["diagnose", "--model", str(STANDS / "wedge45.toml"), str(data), "--sigma", "1e-6"])
    advice = [line for line in capsys.readouterr().out.splitlines() if "measure at" in line]
    for line in advice:
        for deg in [float(v) for v in __import__("re").findall(r"\((-?\d+(?:\.\d+)?)\)", line)]:
            assert deg in (0, 90, 180, 270)


@pytest.mark.slow
def test_identifiability_on_the_reachable_set(tmp_path):
    """A wedge table with one detent reaches one position: 3 readings, so 3 combinations (not the 9 of
    the free angle), and estimate identifies every one of them there."""
    import json
    toml = tmp_path / "one.toml"
    toml.write_text((STANDS / "wedge45.toml").read_text().replace("detents_deg = [0, 90, 180, 270]",
                                                                 "detents_deg = [0]"))
    mod = models.load(str(toml))
    assert len(mod.Q_NAMES) == 3
    assert len(models.load(str(STANDS / "wedge45.toml")).Q_NAMES) == 9
    data = tmp_path / "d.csv"
    assert main(["simulate", "--model", str(toml), "--plan", "quarter", "--sigma", "1e-5", "-o", str(data)]) == 0
    out = tmp_path / "e.json"
    assert main(["estimate", "--model", str(toml), str(data), "--sigma", "1e-5", "--json", str(out)]) == 0
    res, truth = json.loads(out.read_text()), json.loads((tmp_path / "d.truth.json").read_text())
    for q, v in res["q"].items():
        assert abs(v - truth["q"][q]) <= res["guaranteed_error"][q]
