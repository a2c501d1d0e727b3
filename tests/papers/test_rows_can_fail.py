"""Every row of `garant verify` can fail: for each check group, a wrong input (a perturbed
value, a wrong count, a broken estimator) turns its rows red. Each test names the wrong input."""
import pytest
import json
import dataclasses
import types

import numpy as np

from garant.verify import models
from garant.verify.papers import certificates, norm_001, redundancy_003, stand_000
from garant.verify.solve import plans
from conftest import ROOT

TWO_AXIS = models.load("two-axis")
REMOUNT = models.load_remount("two-axis")
NORM = models.load("norm")


def variant(mod, **changes):
    """A copy of a generated module with some attributes replaced (the module itself is untouched)."""
    return types.SimpleNamespace(**{**vars(mod), **changes})


def failed(rows):
    rows = list(rows)
    assert rows, "the group yielded no row"
    return [r for r in rows if not r.passed]


# The baseline the tests below break, every row passing on the shipped modules, is `garant verify` itself:
# tests/cli/test_cli.py::test_garant_verify_console_script runs it and requires every row to pass.


# ---------------------------------------------------------------- 000

def _broken_estimator(mod, nu=4):
    terms = [list(t) for t in mod.ESTIMATOR_TERMS]
    s, p, num, den = terms[nu][0]
    terms[nu] = [(s, p, 2 * num, den)] + terms[nu][1:]         # one weight doubled
    return variant(mod, ESTIMATOR_TERMS=terms)


def test_closed_forms_red_on_a_broken_estimator():
    bad = failed(stand_000.closed_forms(_broken_estimator(TWO_AXIS)))
    assert [r.name for r in bad] == ["derived estimator of q5: unbiased, sum|Psi| (exact)"]


def test_continuum_optimum_red_on_wrong_entry_bounds():
    assert len(failed(stand_000.continuum_optimum(variant(TWO_AXIS, H_SUP=2 * TWO_AXIS.H_SUP)))) == 15


def test_continuum_optimum_red_on_a_broken_estimator():
    assert [r.name for r in failed(stand_000.continuum_optimum(_broken_estimator(TWO_AXIS)))] == [
        "optimal guaranteed error of q5 on the continuum (units of sigma)"]


def test_grid_lp_red_on_a_scaled_H():
    H = TWO_AXIS.H
    assert len(failed(stand_000.grid_lp(variant(TWO_AXIS, H=lambda a, b: 2 * H(a, b)), step=45))) == 15


def test_plan_checks_red_on_a_wrong_count_and_a_wrong_table():
    r = plans.search(TWO_AXIS, np.array(plans.QUARTER_DEG, float))
    fewer = dataclasses.replace(r, optimal_plans=r.optimal_plans[:-1])
    names = {x.name for x in failed(stand_000.plan_checks(TWO_AXIS, fewer))}
    assert "number of optimal 10-position plans on the quarter-turn grid (16 positions, exact count)" in names
    bigger = dataclasses.replace(r, min_positions=11)
    assert "minimal number of positions optimal for all 15 q (quarter-turn grid)" in {
        x.name for x in failed(stand_000.plan_checks(TWO_AXIS, bigger))}


def test_additivity_red_on_wrong_entry_bounds():
    assert len(failed(stand_000.additivity(variant(TWO_AXIS, H_SUP=2 * TWO_AXIS.H_SUP)))) == 3


def test_remount_red_on_a_wrong_recovery():
    wrong = variant(REMOUNT, recovery_matrix=lambda m, g: 1.01 * REMOUNT.recovery_matrix(m, g))
    assert failed(stand_000.remount_round_trip(TWO_AXIS, wrong))


def test_remount_red_on_a_neglected_term_dropped():
    wrong = variant(REMOUNT, neglected=lambda m, dg, db, g: 0 * REMOUNT.neglected(m, dg, db, g))
    assert failed(stand_000.remount_round_trip(TWO_AXIS, wrong))


def test_realised_plan_red_when_the_docs_quote_other_figures(monkeypatch):
    monkeypatch.setattr(stand_000, "DOCS_REALISED_1DEG", (1.04, 1.03))
    assert failed(stand_000.realised_plan(TWO_AXIS))


def test_realised_plan_figures_are_the_ones_the_docs_quote():
    text = (ROOT / "docs" / "mountings_and_realised_plans.md").read_text()
    a, b = stand_000.DOCS_REALISED_1DEG
    assert f"about {a} sigma" in text and f"about {b} sigma" in text


def test_section6_red_on_a_broken_full_model_estimator():
    assert [r.name for r in failed(stand_000.ignoring_the_stand(_broken_estimator(TWO_AXIS), REMOUNT))] == [
        "ignoring the stand: optimal estimators of q5 biased by stand errors"]


def test_section6_red_when_the_counts_disagree(monkeypatch):
    from garant.verify.papers import section6
    true = section6.brute_force
    monkeypatch.setattr(section6, "brute_force", lambda mod, idx: {**true(mod, idx), "q4": (16, 13)})
    assert [r.name for r in failed(stand_000.ignoring_the_stand(TWO_AXIS, REMOUNT))] == [
        "ignoring the stand: optimal estimators of q4 biased by stand errors"]


# ---------------------------------------------------------------- 001

def test_norm_estimators_red_on_a_broken_estimator():
    terms = [list(t) for t in NORM.ESTIMATOR_TERMS]
    k, num, den = terms[3][0]
    terms[3][0] = (k, -num, den)
    assert failed(norm_001.estimators(variant(NORM, ESTIMATOR_TERMS=terms)))


@pytest.mark.slow
def test_norm_continuum_red_on_a_wrong_dual():
    duals = np.array(NORM.DUALS, float)
    duals[9, 7] = 0.0                                    # the Chebyshev polynomial loses a term
    assert failed(norm_001.continuum(variant(NORM, DUALS=duals)))


def test_norm_grid_lp_red_on_a_scaled_H():
    H = NORM.H
    assert len(failed(norm_001.grid_lp(variant(NORM, H=lambda n: 2 * H(n)), step=15))) == 12


@pytest.mark.slow
def test_norm_plans_red_on_a_plan_missing_a_direction():
    # A 29-direction plan: the LP on it no longer reaches the optimal errors, and the count differs.
    names = {r.name for r in failed(norm_001.plans(variant(NORM, PLAN=NORM.PLAN[:-1])))}
    assert "fewest directions optimal for all 12 parameters: every touching direction is needed" in names


def test_norm_remainder_rows_red_on_a_weaker_bound_or_a_looser_print():
    low = variant(NORM, remainder_bound=lambda **b: 0.4 * NORM.remainder_bound(**b))
    assert len([r for r in failed(norm_001.remainder_bounds(low)) if "derived >= worst" in r.name]) == 2
    loose = variant(NORM, published_bound=lambda **b: 1.1 * NORM.published_bound(**b))
    assert {r.name for r in failed(norm_001.remainder_bounds(loose))} == {
        "printed bound (2.4), MEMS box", "printed bound (2.4), MEMS box, at the audit's counterexample"}


def test_norm_a_priori_red_on_a_scaled_H():
    H = NORM.H
    assert failed(norm_001.a_priori(variant(NORM, H=lambda n: 0.5 * H(n))))


def test_norm_cone_red_when_the_published_bound_is_tighter(monkeypatch):
    true = norm_001.published_cone_bound
    monkeypatch.setattr(norm_001, "published_cone_bound", lambda *a: 0.5 * true(*a))
    assert len(failed(norm_001.cone(NORM, starts=10, ascent=20))) == 3


# ---------------------------------------------------------------- 003

def test_003_examples_red_when_the_service_finds_another_relation(monkeypatch):
    from garant.derive import identifiability as I
    true = I.analyse_example

    def wrong(name, multiplicative=True):
        out = dict(true(name, multiplicative))
        out["relations"] = out["relations"][:0]
        return out
    monkeypatch.setattr(I, "analyse_example", wrong)
    assert len(failed(redundancy_003.examples())) == 2


def test_003_examples_red_on_a_wrong_combination_count(monkeypatch):
    from garant.derive import published
    monkeypatch.setattr(published, "Q_000", published.Q_000[:-1])
    assert [r.name for r in failed(redundancy_003.examples())] == [
        "two-axis stand: relations among the basis functions, each J r = 0 exactly"]


def test_003_trace_and_limits_red_on_a_wrong_covariance(monkeypatch):
    from garant.verify.workflows import redundancy as rd
    true = rd.covariance_4
    monkeypatch.setattr(rd, "covariance_4", lambda P, s2: 2 * true(P, s2))
    assert len(failed(redundancy_003.trace_identity())) == 4
    assert failed(redundancy_003.limits())


def test_003_monte_carlo_red_on_a_wrong_covariance(monkeypatch):
    from garant.verify.workflows import redundancy as rd
    true = rd.covariance_4
    monkeypatch.setattr(rd, "covariance_4", lambda P, s2: 1.2 * true(P, s2))
    assert len(failed(redundancy_003.monte_carlo(runs=2000))) == 2


# ---------------------------------------------------------------- certificates

def _committed_copy(tmp_path, monkeypatch):
    """The committed certificates copied to tmp_path, which `garant verify` then reads instead."""
    import shutil
    from garant.verify.proof import build
    shutil.copytree(build.COMMITTED, tmp_path / "c")
    monkeypatch.setattr(build, "COMMITTED", tmp_path / "c")
    monkeypatch.setattr(certificates, "MODELS", {"two-axis": "two_axis"})
    return tmp_path / "c"


def test_certificate_rows_red_on_a_tampered_certificate(tmp_path, monkeypatch):
    folder = _committed_copy(tmp_path, monkeypatch)
    cert = json.loads((folder / "two-axis_q1.json").read_text())
    cert["value"] = "1/2"                                      # the claim no longer matches its proof
    (folder / "two-axis_q1.json").write_text(json.dumps(cert))
    bad = failed(certificates.certificates())
    assert [r.name.split(":")[0] for r in bad] == ["certificate two-axis q1"]


def test_certificate_rows_red_on_a_swapped_certificate(tmp_path, monkeypatch):
    folder = _committed_copy(tmp_path, monkeypatch)
    (folder / "two-axis_q1.json").write_text((folder / "two-axis_q2.json").read_text())
    assert [r.name for r in failed(certificates.certificates())][:1] == ["certificate two-axis q1"]


def test_certificate_rows_red_on_a_missing_certificate(tmp_path, monkeypatch):
    folder = _committed_copy(tmp_path, monkeypatch)
    (folder / "two-axis_q1.json").unlink()
    assert [r.name for r in failed(certificates.certificates())] == ["certificates two-axis: every optimal value "
                                                                     "certified"]
