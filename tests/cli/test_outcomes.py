"""Outcomes declared once (verify/outcomes.py, verify/errors.py): a result's status, the command's exit status, a
solver failure with the solver's own status, H not exact as an exception caught by name."""
from pathlib import Path

import numpy as np
import pytest

from conftest import ROOT
from garant.verify import errors
from garant.verify.outcomes import Exit, Status, exit_sentence


def test_every_exit_status_is_said_and_distinct():
    assert len({int(e) for e in Exit}) == len(Exit) and all(e.meaning for e in Exit)
    assert exit_sentence().startswith("Exit status: 0 done; 1 ") and "; 3 the data refute" in exit_sentence()
    assert Status.PREMISE_REFUTED == "premise refuted" and f"{Status.REFUTED}" == "refuted"


def test_a_solver_failure_carries_the_solvers_status_and_is_said_by_it():
    # An LP with no feasible point: HiGHS's "Infeasible" reaches the command as LPFailed.status, and the line the
    # user reads is chosen by that status (it was chosen by matching the message's text).
    from garant.verify.cli import _plain
    from garant.verify.solve import highs
    with pytest.raises(errors.LPFailed) as e:                 # x >= 1 and x <= -1
        highs.minimize([1.0], np.array([[1.0]]), [1.0], [-1.0], -10.0, 10.0, "a test LP")
    assert e.value.status == "infeasible"
    assert "no unbiased estimator exists on them" in _plain(e.value)
    assert "did not reach an optimum" in _plain(errors.LPFailed("a test LP: Infeasible in its text", "time limit"))


def test_h_not_exact_is_its_own_exception_caught_by_name():
    # "not exact" was a bare ValueError caught broadly (a ValueError of any other cause took the same road).
    from garant.verify import models
    from garant.verify.solve import exact, plans
    mod = models.load("two-axis")
    with pytest.raises(errors.NotExact):
        exact.exact_columns(mod, np.array([[10.0, 0.0]]), None)
    cols = plans.columns(mod, np.array([[10.0, 0.0]]), None)      # the floating-point fallback
    assert cols.dtype == float and cols.shape[0] == 1


def test_a_parameter_a_stand_cannot_observe_is_said_from_the_exception_not_its_text(tmp_path):
    # diagnose named why a catalogue effect is out of a stand's reach by splitting the derivation's message at ": ".
    from garant.derive import description
    from garant.derive.derivation import derive
    text = (Path(__file__).resolve().parents[1] / "data" / "stands" / "tilted_inner.toml").read_text()
    (tmp_path / "t.toml").write_text(text.replace('[[link]]\naxis = "y"\nerror = "kappa"',
                                                  '[[link]]\naxis = "z"\nerror = "kappa"'))
    with pytest.raises(description.Unobservable) as e:
        derive(description.load(tmp_path / "t.toml"))
    assert e.value.names == ("kappa",) and "cannot be observed" in e.value.why and ": " not in e.value.why[:9]


@pytest.mark.slow
def test_no_status_or_verdict_is_spelt_as_a_string_outside_outcomes():
    # A status or verdict compared with, or given as a status/verdict, a bare string ("premise refuted", "pass")
    # drifts from the one declaration; red when a module writes `row["status"] == "refuted"`, `status="done"` or
    # {"verdict": "retest"} again.
    import ast

    from garant.verify.outcomes import Verdict
    words = {str(s) for s in Status} | {str(v) for v in Verdict}

    def word(node):
        return isinstance(node, ast.Constant) and node.value in words

    found = []
    for path in sorted((ROOT / "verify").rglob("*.py")):
        if path.name == "outcomes.py":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Compare) and any(map(word, [node.left, *node.comparators])):
                found.append(f"{path.relative_to(ROOT)}:{node.lineno}")
            elif isinstance(node, ast.keyword) and node.arg in ("status", "verdict") and word(node.value):
                found.append(f"{path.relative_to(ROOT)}:{node.lineno}")
            elif isinstance(node, ast.Dict):
                found += [f"{path.relative_to(ROOT)}:{node.lineno}" for k, v in zip(node.keys, node.values)
                          if isinstance(k, ast.Constant) and k.value in ("status", "verdict") and word(v)]
    assert not found, found
