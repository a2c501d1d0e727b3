"""Identifiability service and limiting accuracy (003)."""
import json

import numpy as np
import pytest
import sympy as sp

from garant.derive import identifiability as I
from garant.verify.papers import redundancy_003
from garant.verify.workflows import redundancy as rd
from garant.verify.cli import main
from conftest import STANDS


def test_example1_dependent_with_printed_relation():
    # 003, Example 1: phi2 + phi4 - a phi3 + phi6 = 0 (theta_d, theta_x, c_x, theta_y).
    res = I.analyse_example("003-example1")
    assert [r.text() for r in res["relations"]] == ["-a*phi[c_x] + phi[theta_d] + phi[theta_x] + phi[theta_y] = 0"]


def test_example2_additive_independent_degenerate_on_alpha_const():
    res = I.analyse_example("003-example2", multiplicative=False)
    assert res["relations"] == []
    assert [t for t, _ in res["degenerate"]] == ["alpha = const"]


def test_example2_full_basis_has_common_scale_relation():
    # 003 says "independent"; x dV/dx + R dV/dR = V = 0 on the constraint (Euler, degree 1 in x, R).
    res = I.analyse_example("003-example2")
    assert [r.text() for r in res["relations"]] == ["phi[theta_R] + phi[theta_x] = 0"]


def test_two_axis_relations_explain_q():
    from garant.derive.derivation import derive
    from garant.derive.builtin import TWO_AXIS_MODEL
    rel, groups = I.explain_stand(derive(TWO_AXIS_MODEL))
    assert {"Delta_g", "Gamma11", "Gamma22", "Gamma33"} in [set(g) for g in groups]
    assert "phi[Delta_g] + phi[Gamma11] + phi[Gamma22] + phi[Gamma33] = 0" in [r.text() for r in rel]


def test_identify_cli_with_plan(tmp_path, capsys):
    plan = tmp_path / "plan.csv"
    plan.write_text("alpha_deg,beta_deg\n0,0\n0,180\n180,90\n180,270\n90,90\n")
    out = tmp_path / "i.json"
    assert main(["identify", "--model", "two-axis", "--plan", str(plan), "--json", str(out)]) == 0
    res = json.loads(out.read_text())
    assert [s.split(" =")[0] for s in res["plan"]["not_identifiable"]] == ["q6", "q10", "q13"]
    assert main(["identify", "--model", "two-axis", "--plan", str(tmp_path / "missing.csv")]) == 2


@pytest.mark.parametrize("r, q, N", [(3, 1, 4), (4, 2, 5), (6, 4, 3)])
def test_trace_identity_exact_random_geometries(r, q, N):
    # 003, (5): trace(B_C^-1) = N (r - q) / sigma^2 whatever the geometry.
    rng = np.random.default_rng(r * 100 + q * 10 + N)
    for _ in range(2):
        B = rd.covariance_4(rd.random_rational_geometry(r, q, N, rng), sp.Integer(1))
        assert B.inv().trace() == N * (r - q)
        assert all(v * N >= 1 for v in B.diagonal())        # (7): never below sigma^2/N


@pytest.mark.parametrize("group", [g for g, _ in redundancy_003.all_groups()])
def test_003_checks_pass(group):
    rows = list(group())
    assert rows and all(r.passed for r in rows), [r for r in rows if not r.passed]


# A table of 72 x 72 detents spent minutes in nsimplify on every reachable position. An angle
# with at least 2d + 1 detents (d: the highest harmonic of it in J) sees what its whole circle sees, so
# the analysis on detents runs only over the angles with fewer; these tests check that claim exactly.

DETENT_STANDS = ["single-axis", *(str(STANDS / f"{n}.toml")
                                  for n in ("wedge45", "wedge90", "table120"))]


@pytest.mark.slow
@pytest.mark.parametrize("name", DETENT_STANDS)
def test_detents_that_see_the_whole_circle_give_the_rank_of_every_reachable_position(name):
    from itertools import product

    from garant.derive import combinations
    from garant.derive.derivation import derive, reachable_positions
    from garant.verify.models import stand_model
    m = stand_model(name)
    d = derive(m)
    assert reachable_positions(m, d.J) is None          # every angle has at least 2d + 1 detents
    values = [[sp.pi * sp.Rational(str(v)) / 180 for v in a.detents_deg] for a in m.stand.angles]
    every = [dict(zip(m.angle_symbols, c)) for c in product(*values)]
    finite = combinations.identify(d.J, list(d.names), m.preferred, m.angle_symbols, positions=every)
    assert finite.R.rows == d.ident.R.rows


def test_two_detents_a_half_turn_apart_hide_combinations(tmp_path):
    # Two detents, first harmonic: cos and sin cannot both be seen (2 <= 2d), so the analysis on the
    # detents runs and finds fewer combinations than the circle would give.
    from garant.derive.derivation import derive, reachable_positions
    from garant.verify.models import stand_model
    text = (STANDS / "wedge90.toml").read_text()
    assert "detents_deg = [0, 90, 180, 270]" in text
    (tmp_path / "half.toml").write_text(text.replace("detents_deg = [0, 90, 180, 270]", "detents_deg = [0, 180]"))
    (tmp_path / "full.toml").write_text(text.replace("detents_deg = [0, 90, 180, 270]", "detents_deg = []")
                                        .replace('name = "wedge90"', 'name = "wedge90_full"'))
    half, full = stand_model(str(tmp_path / "half.toml")), stand_model(str(tmp_path / "full.toml"))
    assert len(reachable_positions(half, derive(half).J)) == 2
    assert derive(half).ident.R.rows < derive(full).ident.R.rows
