"""The notebook API and the commands go through the same functions (issue 24): the same results for
the same inputs, data as arrays as well as files, and docs/api.md's example runs as written."""
import json
from pathlib import Path

import numpy as np
import pytest

import garant
from conftest import write_csv
from garant.verify.cli import main

ROOT = Path(__file__).resolve().parents[1]
STANDS = ROOT / "tests" / "data" / "stands"


@pytest.mark.parametrize("model", ["two-axis", "single-axis", str(STANDS / "tilted_inner.toml"), "norm"])
def test_plan_of_the_api_is_the_plan_of_the_command(tmp_path, capsys, model):
    # tilted_inner: the exchange positions are candidates there; garant.plan gave 8 positions with errors
    # 3.0, 1.414, ... where `garant plan` gave 10 with 2.414, 1.0, ... (the step lived in the command).
    out = tmp_path / "p.json"
    assert main(["plan", model, "--json", str(out)]) == 0
    assert _deterministic(garant.plan(model)) == _deterministic(json.loads(out.read_text()))


def _deterministic(d):
    """A plan's JSON without what a time-limited count leaves to the clock (--count-seconds): when the count
    stopped, how many optimal plans it had listed by then (the first, the plan itself, is fixed)."""
    if d.get("optimal_plans_count") is None and d.get("optimal_plans"):
        d = {**d, "optimal_plans": d["optimal_plans"][:1]}
        d.pop("optimal_plans_on_quarter_turns", None)
    return d


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
    with pytest.raises(garant.DataError, match="sigma must be a finite number > 0"):
        garant.estimate("two-axis", np.column_stack([P, f]), -1.0)
